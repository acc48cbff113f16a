//! The engine's cache files (the Vulkan pipeline cache, the OpenGL program binaries): where
//! they live, their checksummed wrapping, and reading and writing them within bounds (data
//! anyone with access to the folder controls, on a folder that may be a stalled network or
//! FUSE mount).

use std::io::{Read, Write};
use std::os::unix::fs::OpenOptionsExt;
use std::path::{Path, PathBuf};

/// The file starts with this, then the data's length and checksum (u64 little-endian each).
const MAGIC: &[u8; 8] = b"CXRPIPE1";
const FILE_HEADER: usize = 8 + 8 + 8;

/// `$XDG_CACHE_HOME/contrastxr`, else `~/.cache/contrastxr`; None without either variable.
pub fn directory() -> Option<PathBuf> {
    let base = std::env::var_os("XDG_CACHE_HOME")
        .filter(|v| !v.is_empty())
        .map(PathBuf::from)
        .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".cache")))?;
    Some(base.join("contrastxr"))
}

/// FNV-1a, 64 bits: enough to tell a torn or damaged file from a whole one.
fn checksum(data: &[u8]) -> u64 {
    data.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
    })
}

pub fn file_bytes(data: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(FILE_HEADER + data.len());
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&(data.len() as u64).to_le_bytes());
    out.extend_from_slice(&checksum(data).to_le_bytes());
    out.extend_from_slice(data);
    out
}

/// The largest cache file read (lavapipe's and hardware drivers' caches for the engine's few
/// shaders are far smaller).
pub const MAX_FILE_BYTES: u64 = 64 << 20;

/// Files of other drivers are removed once this old.
const FOREIGN_MAX_AGE: std::time::Duration = std::time::Duration::from_secs(30 * 24 * 3600);

/// The longest a cache file's read may take: it is made on the app's thread (at
/// xrCreateSession, and for an OpenGL app inside a frame call), so a cache folder on a stalled
/// network or FUSE mount must not hold it.
pub const READ_LIMIT: std::time::Duration = std::time::Duration::from_secs(1);

/// A cache file's bytes; None if there is none. Only a regular file of at most
/// MAX_FILE_BYTES is read, opened without following links and without blocking (a FIFO or a
/// device there never hangs or floods the app), on a helper thread within [`READ_LIMIT`]
/// (`user_file::within`: a read that takes longer is an error, its thread left to end).
pub fn read_file(path: &Path) -> Result<Option<Vec<u8>>, String> {
    let owned = path.to_path_buf();
    let key = format!("cache {}", path.display());
    crate::user_file::within(&key, READ_LIMIT, move || read_file_now(&owned))
}

fn read_file_now(path: &Path) -> Result<Option<Vec<u8>>, String> {
    crate::user_file::stall();
    let file = match std::fs::OpenOptions::new()
        .read(true)
        .custom_flags(libc::O_NOFOLLOW | libc::O_NONBLOCK | libc::O_CLOEXEC)
        .open(path)
    {
        Ok(f) => f,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(e) => return Err(format!("cannot open it ({e})")),
    };
    let meta = file.metadata().map_err(|e| e.to_string())?;
    if !meta.file_type().is_file() {
        return Err("not a regular file".into());
    }
    if meta.len() > MAX_FILE_BYTES {
        return Err(format!("{} bytes, more than {MAX_FILE_BYTES}", meta.len()));
    }
    let mut bytes = Vec::with_capacity(meta.len() as usize);
    file.take(MAX_FILE_BYTES + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| e.to_string())?;
    if bytes.len() as u64 > MAX_FILE_BYTES {
        return Err("grew past the size limit while read".into());
    }
    Ok(Some(bytes))
}

/// Writes `dir`/`name` whole or not at all: through a temporary file of a random name in the
/// same folder (created exclusively, never through a link; unique also across PID namespaces),
/// renamed over the old one. Not synced: it is written inside an app's xrDestroySession, and a
/// file the system lost part of in a crash fails its length and checksum at the next load,
/// which then starts from an empty cache.
///
/// Made on a helper thread within [`WRITE_LIMIT`] (`user_file::within_writing`): a cache
/// folder on a stalled network or FUSE mount never holds the caller longer (the app's thread,
/// or the pipeline thread that xrDestroySession joins); a write that takes longer is an error,
/// its thread left to finish or fail on its own.
pub fn write_atomically(dir: &Path, name: &str, bytes: &[u8]) -> Result<(), String> {
    let (dir, name, bytes) = (dir.to_path_buf(), name.to_string(), bytes.to_vec());
    let key = format!("cache {}", dir.join(&name).display());
    let limit =
        std::time::Duration::from_millis(WRITE_LIMIT_MS.load(std::sync::atomic::Ordering::Relaxed));
    crate::user_file::within_writing(&key, limit, move || {
        write_atomically_now(&dir, &name, &bytes)
    })
}

/// Writes `dir`/`name` as [`write_atomically`] does, with the bytes `merge` makes of the file
/// as it is at that moment (None: no file, or one that cannot be read), while this process
/// holds an exclusive lock (flock) on `dir`/`.name.lock`: two processes that each merge their
/// entries into the file take turns, so neither writes over what the other added since it read.
/// Within [`WRITE_LIMIT`], waiting for the lock included.
pub fn merge_atomically(
    dir: &Path,
    name: &str,
    merge: impl FnOnce(Option<Vec<u8>>) -> Vec<u8> + Send + 'static,
) -> Result<(), String> {
    let (dir, name) = (dir.to_path_buf(), name.to_string());
    let key = format!("cache {}", dir.join(&name).display());
    let limit =
        std::time::Duration::from_millis(WRITE_LIMIT_MS.load(std::sync::atomic::Ordering::Relaxed));
    crate::user_file::within_writing(&key, limit, move || {
        let _lock = lock(&dir, &name)?;
        let now = read_file_now(&dir.join(&name)).ok().flatten();
        write_atomically_now(&dir, &name, &merge(now))
    })
}

/// The exclusive lock on `dir`/`.name.lock`, held until the file it returns is closed.
fn lock(dir: &Path, name: &str) -> Result<std::fs::File, String> {
    use std::os::fd::AsRawFd;
    let path = dir.join(format!(".{name}.lock"));
    let fail = |e: std::io::Error| format!("cannot lock {}: {e}", path.display());
    std::fs::create_dir_all(dir).map_err(fail)?;
    let file = std::fs::OpenOptions::new()
        .write(true)
        .create(true)
        .truncate(false)
        .mode(0o644)
        .custom_flags(libc::O_NOFOLLOW | libc::O_NONBLOCK | libc::O_CLOEXEC)
        .open(&path)
        .map_err(fail)?;
    // SAFETY: flock on a file descriptor this function owns; it blocks until the lock is free.
    if unsafe { libc::flock(file.as_raw_fd(), libc::LOCK_EX) } != 0 {
        return Err(fail(std::io::Error::last_os_error()));
    }
    // Its age is its last use: another driver's lock unused for FOREIGN_MAX_AGE is removed.
    let _ = file.set_modified(std::time::SystemTime::now());
    Ok(file)
}

/// The longest a cache file's write may take inside an app (see [`write_atomically`]): the
/// writes happen in xrDestroySession, which returns within 1 s in all.
pub const WRITE_LIMIT: std::time::Duration = std::time::Duration::from_millis(250);

/// The bound in force, in milliseconds: [`WRITE_LIMIT`], or longer in a process of the tool's
/// own ([`writes_may_wait`]), whose exit would lose a write left to finish.
static WRITE_LIMIT_MS: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(250);

/// For a process of the tool's own (`contrastxr gl-programs`): cache writes may take up to a
/// minute, since nobody waits on them and its exit would lose one given up on.
pub fn writes_may_wait() {
    WRITE_LIMIT_MS.store(60_000, std::sync::atomic::Ordering::Relaxed);
}

fn write_atomically_now(dir: &Path, name: &str, bytes: &[u8]) -> Result<(), String> {
    crate::user_file::stall();
    let fail = |e: std::io::Error| format!("cannot write {}: {e}", dir.join(name).display());
    std::fs::create_dir_all(dir).map_err(fail)?;
    let tmp = dir.join(format!(".{name}.{:016x}.tmp", random_u64()));
    let written = (|| {
        let mut file = std::fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .mode(0o644)
            .custom_flags(libc::O_NOFOLLOW | libc::O_CLOEXEC)
            .open(&tmp)?;
        file.write_all(bytes)?;
        std::fs::rename(&tmp, dir.join(name))
    })();
    written.map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        fail(e)
    })
}

/// 64 random bits from the kernel; the time and the process as a fallback.
fn random_u64() -> u64 {
    let mut buf = [0u8; 8];
    // SAFETY: getrandom writes at most buf.len() bytes into buf.
    let n = unsafe { libc::getrandom(buf.as_mut_ptr().cast(), buf.len(), 0) };
    if n == buf.len() as isize {
        return u64::from_le_bytes(buf);
    }
    let now = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH);
    now.map_or(0, |d| d.as_nanos() as u64) ^ (u64::from(std::process::id()) << 32)
}

/// Removes the cache files of other drivers (and stray temporary files) not touched for
/// FOREIGN_MAX_AGE; links and other kinds of file are left alone.
pub fn remove_old_foreign(dir: &Path, keep: &str) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for e in entries.filter_map(|e| e.ok()) {
        let name = e.file_name().to_string_lossy().into_owned();
        let ours = name.starts_with("pipelines-") || name.starts_with(".pipelines-");
        let Ok(meta) = e.metadata() else { continue };
        let age = meta.modified().ok().and_then(|m| m.elapsed().ok());
        let kept = name == keep || name == format!(".{keep}.lock");
        if ours && !kept && meta.is_file() && age.is_some_and(|a| a > FOREIGN_MAX_AGE) {
            let _ = std::fs::remove_file(e.path());
        }
    }
}

/// The data a cache file wraps, if it is whole (its length and checksum right).
pub fn file_data(bytes: &[u8]) -> Result<&[u8], String> {
    let word = |at: usize| {
        bytes
            .get(at..at + 8)
            .map(|b| u64::from_le_bytes(b.try_into().unwrap()))
    };
    if bytes.len() < FILE_HEADER || &bytes[..8] != MAGIC {
        return Err("not a contrastxr pipeline cache".into());
    }
    let data = &bytes[FILE_HEADER..];
    if word(8) != Some(data.len() as u64) || word(16) != Some(checksum(data)) {
        return Err("damaged (length or checksum wrong)".into());
    }
    Ok(data)
}

#[cfg(test)]
mod tests {
    /// With the file system stalled (`stalled-file-system`: each look-up 2 s), a cache file's
    /// read gives up at READ_LIMIT, and its write at WRITE_LIMIT. Run in a child process of this test binary, where the
    /// fault is armed.
    #[test]
    fn a_stalled_cache_read_is_given_up_at_its_bound() {
        const NAME: &str =
            "gpu::core::cache_files::tests::a_stalled_cache_read_is_given_up_at_its_bound";
        if std::env::var_os("CONTRASTXR_FAULT").is_none() {
            let out = std::process::Command::new(std::env::current_exe().unwrap())
                .args(["--exact", NAME, "--nocapture", "--test-threads=1"])
                .env("CONTRASTXR_FAULT", "stalled-file-system")
                .output()
                .expect("run the child");
            let text = String::from_utf8_lossy(&out.stdout).into_owned()
                + &String::from_utf8_lossy(&out.stderr);
            assert!(out.status.success(), "{text}");
            assert!(text.contains("1 passed"), "{text}");
            return;
        }
        let scratch = crate::scratch::ScratchDir::new("stalled");
        let path = scratch.join("pipelines-x.bin");
        std::fs::write(&path, b"cache").unwrap();
        let t = std::time::Instant::now();
        let read = super::read_file(&path);
        let took = t.elapsed();
        assert!(
            took < std::time::Duration::from_millis(1500),
            "took {took:?}"
        );
        assert_eq!(read.unwrap_err(), "took more than 1000 ms to read");
        // A write too.
        // Into a folder not yet there, as before a session's first save.
        let dir = scratch.join("w");
        let t = std::time::Instant::now();
        let written = super::write_atomically(&dir, "pipelines-x.bin", b"cache");
        let took = t.elapsed();
        assert!(
            took < std::time::Duration::from_millis(1500),
            "took {took:?}"
        );
        assert_eq!(written.unwrap_err(), "took more than 250 ms to write");
        // The scratch folder goes once the stalled write is over.
        std::thread::sleep(std::time::Duration::from_millis(1500));
    }

    /// A merge reads the file only once it holds the file's lock: what another holder of the
    /// lock wrote meanwhile is in what it merges, not written over.
    #[test]
    fn a_merge_reads_the_file_once_it_holds_the_lock() {
        let scratch = crate::scratch::ScratchDir::new("merge");
        let dir = scratch.join("cache");
        super::write_atomically_now(&dir, "pipelines-m.bin", b"first").unwrap();
        // Another process holds the lock (flock: per open file, so also within a process).
        let held = super::lock(&dir, "pipelines-m.bin").unwrap();
        let (tx, rx) = std::sync::mpsc::channel();
        let d = dir.clone();
        let merging = std::thread::spawn(move || {
            super::merge_atomically(&d, "pipelines-m.bin", move |now| {
                let _ = tx.send(());
                [now.unwrap_or_default(), b"+mine".to_vec()].concat()
            })
        });
        std::thread::sleep(std::time::Duration::from_millis(100));
        assert!(rx.try_recv().is_err(), "merged while another held the lock");
        super::write_atomically_now(&dir, "pipelines-m.bin", b"second").unwrap();
        drop(held);
        // The caller may have given up waiting (WRITE_LIMIT); the merge ends all the same.
        let _ = merging.join();
        let path = dir.join("pipelines-m.bin");
        let since = std::time::Instant::now();
        while std::fs::read(&path).unwrap() != b"second+mine" {
            assert!(since.elapsed().as_secs() < 10, "{:?}", std::fs::read(&path));
            std::thread::sleep(std::time::Duration::from_millis(10));
        }
    }
}
