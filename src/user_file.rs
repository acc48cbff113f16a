//! What a user names in a setting (the config file, device profiles, background images and
//! videos, capture folders): opened one way everywhere, so that a wrong path gets one clear
//! sentence instead of hanging, flooding or starving the host app. A file is opened without
//! blocking (a FIFO or a device node never hangs the open) and read only when it is a regular
//! file within its kind's size bound; an image's size is checked from its header before any
//! pixel is decoded (see `image`).

use std::fs::{File, Metadata};
use std::io::{ErrorKind, Read};
use std::os::unix::fs::{FileTypeExt, OpenOptionsExt};
use std::path::Path;
use std::time::Duration;

/// Config files, device profiles, calibration: text far smaller than this.
pub const TEXT_BYTES: u64 = 1 << 20;
/// Background images and panoramas, and each PNG frame of a video folder.
pub const IMAGE_BYTES: u64 = 64 << 20;
/// The widest and tallest image decoded (a 16384x16384 RGBA image is 1 GiB).
pub const MAX_SIDE: u32 = 16384;
/// The longest a read of the config or profiles may take on the app's thread.
pub const APP_THREAD_READ: Duration = Duration::from_millis(50);

/// `n` bytes for a person: "8 GiB", "200 MiB", "1.5 KiB", "12 bytes".
pub fn size_text(n: u64) -> String {
    const UNITS: [(u64, &str); 3] = [(1 << 30, "GiB"), (1 << 20, "MiB"), (1 << 10, "KiB")];
    for (unit, name) in UNITS {
        if n >= unit {
            let whole = n / unit;
            let tenths = (n % unit) * 10 / unit;
            return match tenths {
                0 => format!("{whole} {name}"),
                t => format!("{whole}.{t} {name}"),
            };
        }
    }
    format!("{n} bytes")
}

/// What a path is when it is not what was meant: "a FIFO", "a folder", ...
fn kind_of(meta: &Metadata) -> &'static str {
    let t = meta.file_type();
    if t.is_dir() {
        "a folder"
    } else if t.is_fifo() {
        "a FIFO"
    } else if t.is_char_device() {
        "a character device"
    } else if t.is_block_device() {
        "a block device"
    } else if t.is_socket() {
        "a socket"
    } else if t.is_file() {
        "a file"
    } else {
        "not a regular file"
    }
}

/// Why `path` could not be looked at, in words ("does not exist", "is a loop of links", ...).
fn lookup_failure(path: &Path, e: &std::io::Error) -> String {
    match e.kind() {
        ErrorKind::NotFound if std::fs::symlink_metadata(path).is_ok() => {
            "is a link to nothing".into()
        }
        ErrorKind::NotFound => "does not exist".into(),
        ErrorKind::PermissionDenied => "cannot be read (permission denied)".into(),
        _ if e.raw_os_error() == Some(libc::ELOOP) => "is a loop of symbolic links".into(),
        _ => format!("cannot be opened ({e})"),
    }
}

/// The checks on a regular file's metadata: its kind and its size.
fn check_file(meta: &Metadata, max_bytes: u64) -> Result<(), String> {
    if !meta.file_type().is_file() {
        return Err(format!("is {}, not a file", kind_of(meta)));
    }
    if meta.len() > max_bytes {
        return Err(format!(
            "is {}, more than {}",
            size_text(meta.len()),
            size_text(max_bytes)
        ));
    }
    Ok(())
}

/// Opens a regular file of at most `max_bytes` for reading, without blocking: the kind is
/// checked before the open (opening a device can have effects) and again on the open file.
/// The error says why in words that follow the path: "is a FIFO, not a file".
pub fn open(path: &Path, max_bytes: u64) -> Result<File, String> {
    let meta = metadata(path).map_err(|e| lookup_failure(path, &e))?;
    check_file(&meta, max_bytes)?;
    let file = std::fs::OpenOptions::new()
        .read(true)
        .custom_flags(libc::O_NONBLOCK | libc::O_CLOEXEC)
        .open(path)
        .map_err(|e| lookup_failure(path, &e))?;
    let meta = file
        .metadata()
        .map_err(|e| format!("cannot be read ({e})"))?;
    check_file(&meta, max_bytes)?;
    Ok(file)
}

/// A regular file's bytes, at most `max_bytes` (also when it grows while read).
pub fn read(path: &Path, max_bytes: u64) -> Result<Vec<u8>, String> {
    let file = open(path, max_bytes)?;
    let mut bytes = Vec::new();
    file.take(max_bytes + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| format!("cannot be read ({e})"))?;
    if bytes.len() as u64 > max_bytes {
        return Err(format!("grew past {} while read", size_text(max_bytes)));
    }
    Ok(bytes)
}

/// A text file of at most [`TEXT_BYTES`], as UTF-8.
pub fn read_text(path: &Path) -> Result<String, String> {
    let bytes = read(path, TEXT_BYTES)?;
    String::from_utf8(bytes).map_err(|_| "is not UTF-8 text".into())
}

/// [`read_text`] within `limit` of wall time: the read runs on a helper thread and a read that
/// takes longer (a stalled network or FUSE file system) is refused; its thread ends on its own
/// when the read returns. For the app's thread, which must never wait long.
pub fn read_text_within(path: &Path, limit: Duration) -> Result<String, String> {
    let owned = path.to_path_buf();
    within(&path.to_string_lossy(), limit, move || read_text(&owned))
}

/// Whether `path` is a regular file (following links), asked within `limit` as
/// [`read_text_within`] reads: a look-up that takes longer is an error in words.
pub fn is_file_within(path: &Path, limit: Duration) -> Result<bool, String> {
    let owned = path.to_path_buf();
    let key = format!("stat {}", path.display());
    within(&key, limit, move || {
        Ok(metadata(&owned).is_ok_and(|m| m.is_file()))
    })
}

/// `std::fs::metadata` through the fault point `stalled-file-system` (a hung network or FUSE
/// mount: every look-up of a user's file takes 2 s).
pub fn metadata(path: &Path) -> std::io::Result<Metadata> {
    stall();
    std::fs::metadata(path)
}

/// Sleeps 2 s when the fault point `stalled-file-system` is armed: a file operation on a hung
/// mount. Called where the layer looks up or opens a user's file.
pub fn stall() {
    if crate::fault::hit("stalled-file-system") {
        std::thread::sleep(Duration::from_secs(2));
    }
}

/// The most helper threads left behind by reads that took too long (each still waits for its
/// file system). A key's later reads are refused at once while its earlier one has not
/// returned, so a hung mount costs one thread per file, not one per try.
const MOST_STUCK: usize = 4;

/// Keys whose reader was given up on and has not returned yet.
fn stuck() -> std::sync::MutexGuard<'static, Vec<String>> {
    static STUCK: std::sync::Mutex<Vec<String>> = std::sync::Mutex::new(Vec::new());
    STUCK.lock().unwrap_or_else(|p| p.into_inner())
}

/// `work`'s answer if it comes within `limit`, run on a thread of its own. `key` names what it
/// reads: while an earlier read of the same key is still stuck, or [`MOST_STUCK`] are, the read
/// is refused at once and no thread is started.
pub fn within<T: Send + 'static>(
    key: &str,
    limit: Duration,
    work: impl FnOnce() -> Result<T, String> + Send + 'static,
) -> Result<T, String> {
    within_as(key, limit, ("read", "read"), work)
}

/// [`within`] for a write: its errors say "write" ("took more than 1000 ms to write").
pub fn within_writing<T: Send + 'static>(
    key: &str,
    limit: Duration,
    work: impl FnOnce() -> Result<T, String> + Send + 'static,
) -> Result<T, String> {
    within_as(key, limit, ("write", "written"), work)
}

/// [`within`], its errors in the words `(verb, participle)`.
fn within_as<T: Send + 'static>(
    key: &str,
    limit: Duration,
    (verb, participle): (&str, &str),
    work: impl FnOnce() -> Result<T, String> + Send + 'static,
) -> Result<T, String> {
    {
        let stuck = stuck();
        if stuck.iter().any(|k| k == key) {
            return Err(format!(
                "is still being {participle}: an earlier {verb} has not returned"
            ));
        }
        if stuck.len() >= MOST_STUCK {
            return Err(format!(
                "cannot be {participle} now: {MOST_STUCK} earlier {verb}s have not returned"
            ));
        }
    }
    // Whether the caller gave up on this read; the reader clears its key when it returns.
    let given_up = std::sync::Arc::new(std::sync::Mutex::new(false));
    let (tx, rx) = std::sync::mpsc::channel();
    let reader_given_up = given_up.clone();
    let reader_key = key.to_string();
    let reader = std::thread::Builder::new()
        .name("contrastxr-read".into())
        .spawn(move || {
            let result = work();
            let given_up = reader_given_up.lock().unwrap_or_else(|p| p.into_inner());
            if *given_up {
                let mut stuck = stuck();
                if let Some(at) = stuck.iter().position(|k| *k == reader_key) {
                    stuck.swap_remove(at);
                }
            } else {
                let _ = tx.send(result);
            }
        })
        .map_err(|e| format!("cannot be {participle} (no thread: {e})"))?;
    let answer = rx.recv_timeout(limit);
    let mut gave_up = given_up.lock().unwrap_or_else(|p| p.into_inner());
    // The answer may have come between the timeout and the lock.
    match answer.or_else(|_| rx.try_recv()) {
        Ok(result) => {
            drop(gave_up);
            let _ = reader.join();
            result
        }
        Err(_) => {
            *gave_up = true;
            stuck().push(key.to_string());
            Err(format!("took more than {} ms to {verb}", limit.as_millis()))
        }
    }
}

/// Writes `path` without following a link or blocking, and without writing through anything
/// already there: the bytes go to a new file beside it (`O_CREAT | O_EXCL | O_NOFOLLOW |
/// O_NONBLOCK`) named for this process, which is then renamed to `path`. What was at `path` (an
/// earlier file, a link planted there, a FIFO) is replaced, never written into; a folder there,
/// or a name another user holds in a shared folder, fails in words.
pub fn write_replacing(path: &Path, bytes: &[u8]) -> Result<(), String> {
    use std::io::Write;
    stall();
    let failed = |e: std::io::Error| format!("cannot write {}: {e}", path.display());
    let Some(name) = path.file_name() else {
        return Err(format!("cannot write {}: no file name", path.display()));
    };
    let fresh = path.with_file_name(format!(
        ".{}.{}.new",
        name.to_string_lossy(),
        std::process::id()
    ));
    let mut file = std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .mode(0o644)
        .custom_flags(libc::O_NOFOLLOW | libc::O_NONBLOCK | libc::O_CLOEXEC)
        .open(&fresh)
        .map_err(failed)?;
    let written = file.write_all(bytes).and_then(|()| {
        drop(file);
        std::fs::rename(&fresh, path)
    });
    if let Err(e) = written {
        let _ = std::fs::remove_file(&fresh);
        return Err(failed(e));
    }
    Ok(())
}

/// Checks that `path` is a folder (following links), for a setting that names one.
pub fn folder(path: &Path) -> Result<(), String> {
    let meta = std::fs::metadata(path).map_err(|e| lookup_failure(path, &e))?;
    if meta.is_dir() {
        Ok(())
    } else {
        Err(format!("is {}, not a folder", kind_of(&meta)))
    }
}

/// Checks an image's declared size before anything is allocated for its pixels.
pub fn check_dimensions(width: u32, height: u32) -> Result<(), String> {
    if width == 0 || height == 0 {
        return Err(format!("declares {width}x{height} pixels"));
    }
    if width > MAX_SIDE || height > MAX_SIDE {
        return Err(format!(
            "declares {width}x{height} pixels, more than {MAX_SIDE}x{MAX_SIDE}"
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn temp_dir(name: &str) -> crate::scratch::ScratchDir {
        crate::scratch::ScratchDir::new(&format!("user-file-{name}"))
    }

    fn mkfifo(path: &Path) {
        let c = std::ffi::CString::new(path.as_os_str().as_encoded_bytes()).unwrap();
        // SAFETY: `c` is a valid NUL-terminated path that outlives the call.
        assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
    }

    #[test]
    fn sizes_read_as_people_write_them() {
        assert_eq!(size_text(8 << 30), "8 GiB");
        assert_eq!(size_text(200 << 20), "200 MiB");
        assert_eq!(size_text(1536), "1.5 KiB");
        assert_eq!(size_text(12), "12 bytes");
    }

    #[test]
    fn what_is_not_a_file_is_named() {
        let dir = temp_dir("kinds");
        let fifo = dir.join("fifo");
        mkfifo(&fifo);
        let err = |p: &Path| read(p, TEXT_BYTES).unwrap_err();
        assert_eq!(err(&fifo), "is a FIFO, not a file");
        assert_eq!(
            err(Path::new("/dev/zero")),
            "is a character device, not a file"
        );
        assert_eq!(err(&dir), "is a folder, not a file");
        assert_eq!(err(&dir.join("missing")), "does not exist");
        std::os::unix::fs::symlink(dir.join("nothing"), dir.join("dangling")).unwrap();
        assert_eq!(err(&dir.join("dangling")), "is a link to nothing");
        std::os::unix::fs::symlink(dir.join("loop"), dir.join("loop")).unwrap();
        assert_eq!(err(&dir.join("loop")), "is a loop of symbolic links");
        assert_eq!(folder(&fifo).unwrap_err(), "is a FIFO, not a folder");
        assert!(folder(&dir).is_ok());
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn a_file_over_its_bound_is_refused_before_it_is_read() {
        let dir = temp_dir("size");
        let big = dir.join("big");
        File::create(&big).unwrap().set_len(8 << 30).unwrap();
        assert_eq!(
            read(&big, IMAGE_BYTES).unwrap_err(),
            "is 8 GiB, more than 64 MiB"
        );
        std::fs::write(dir.join("small"), "a = 1\n").unwrap();
        assert_eq!(read_text(&dir.join("small")).unwrap(), "a = 1\n");
        std::fs::write(dir.join("latin1"), [0xE9, b'\n']).unwrap();
        assert_eq!(
            read_text(&dir.join("latin1")).unwrap_err(),
            "is not UTF-8 text"
        );
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn a_read_on_the_apps_thread_is_bounded() {
        let dir = temp_dir("within");
        std::fs::write(dir.join("c.toml"), "x = 1\n").unwrap();
        let text = read_text_within(&dir.join("c.toml"), Duration::from_secs(5)).unwrap();
        assert_eq!(text, "x = 1\n");
        let err = read_text_within(Path::new("/dev/zero"), APP_THREAD_READ).unwrap_err();
        assert_eq!(err, "is a character device, not a file");
        // A read that stalls (a hung network mount) is given up on at the bound.
        let stalled = || {
            std::thread::sleep(Duration::from_millis(400));
            Ok(())
        };
        let start = std::time::Instant::now();
        assert_eq!(
            within("stalled", APP_THREAD_READ, stalled).unwrap_err(),
            "took more than 50 ms to read"
        );
        assert!(start.elapsed() < Duration::from_millis(400));
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// Reads of a stalled file that time out leave one stuck thread, not one per try, and
    /// the file is read again once that thread has returned.
    #[test]
    fn stalled_reads_leave_one_thread_per_file() {
        use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
        use std::sync::Arc;
        let started = Arc::new(AtomicUsize::new(0));
        let release = Arc::new(AtomicBool::new(false));
        let stalled = || {
            let (started, release) = (started.clone(), release.clone());
            move || {
                started.fetch_add(1, Ordering::SeqCst);
                while !release.load(Ordering::SeqCst) {
                    std::thread::sleep(Duration::from_millis(5));
                }
                Ok(7)
            }
        };
        let limit = Duration::from_millis(20);
        for _ in 0..10 {
            assert!(within("hung mount/c.toml", limit, stalled()).is_err());
        }
        assert_eq!(started.load(Ordering::SeqCst), 1, "one reader per file");
        release.store(true, Ordering::SeqCst);
        let deadline = std::time::Instant::now() + Duration::from_secs(5);
        let again = loop {
            match within("hung mount/c.toml", Duration::from_secs(5), stalled()) {
                Ok(v) => break v,
                Err(_) if std::time::Instant::now() < deadline => {
                    std::thread::sleep(Duration::from_millis(5))
                }
                Err(e) => panic!("{e}"),
            }
        };
        assert_eq!(again, 7);
    }

    #[test]
    fn declared_sizes_are_bounded() {
        assert!(check_dimensions(16384, 16384).is_ok());
        assert_eq!(
            check_dimensions(40000, 40000).unwrap_err(),
            "declares 40000x40000 pixels, more than 16384x16384"
        );
        assert_eq!(check_dimensions(0, 5).unwrap_err(), "declares 0x5 pixels");
    }
}
