//! The pipeline-cache file is data anyone with access to the folder controls: reading it never
//! hangs or floods the app, and writing it always leaves a whole file, also with two writers in
//! separate PID namespaces (two sandboxed apps) at once.

use contrastxr::gpu::core::cache_files::{
    read_file, remove_old_foreign, write_atomically, MAX_FILE_BYTES,
};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

const CHILD: &str = "CONTRASTXR_CACHE_WRITER";

fn scratch(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("cache-files")
        .join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Runs `f` on a thread and fails the test if it does not return within 10 s.
fn within_10s<T: Send + 'static>(f: impl FnOnce() -> T + Send + 'static) -> T {
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || tx.send(f()));
    rx.recv_timeout(Duration::from_secs(10))
        .expect("it hung (no answer within 10 s)")
}

#[test]
fn a_fifo_a_link_to_dev_zero_and_a_huge_file_are_refused_without_hanging() {
    let dir = scratch("read");
    let fifo = dir.join("fifo.bin");
    assert!(Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .unwrap()
        .success());
    let zero = dir.join("zero.bin");
    std::os::unix::fs::symlink("/dev/zero", &zero).unwrap();
    let huge = dir.join("huge.bin");
    std::fs::File::create(&huge)
        .unwrap()
        .set_len(MAX_FILE_BYTES + 1)
        .unwrap();
    let whole = dir.join("whole.bin");
    std::fs::write(&whole, b"bytes").unwrap();
    for (path, says) in [
        (fifo, "not a regular file"),
        (zero, "cannot open it"),
        (huge, "more than"),
    ] {
        let shown = path.display().to_string();
        let got = within_10s(move || read_file(&path));
        let e = got.expect_err(&shown);
        assert!(e.contains(says), "{shown}: {e}");
    }
    assert_eq!(read_file(&whole), Ok(Some(b"bytes".to_vec())));
    assert_eq!(read_file(&dir.join("absent.bin")), Ok(None));
}

#[test]
fn a_read_only_folder_fails_cleanly_and_keeps_the_old_file() {
    // Read-only for root too: a read-only bind mount in a mount namespace of its own.
    let dir = scratch("read-only");
    std::fs::write(dir.join("pipelines-x.bin"), b"old").unwrap();
    let me = std::env::current_exe().unwrap();
    let script = format!(
        "mount --bind '{d}' '{d}' && mount -o remount,bind,ro '{d}' && exec '{me}' \
         child_writer --exact --nocapture",
        d = dir.display(),
        me = me.display()
    );
    let out = Command::new("unshare")
        .args(["--mount", "sh", "-c", &script])
        .env(CHILD, format!("readonly:{}", dir.display()))
        .output()
        .unwrap();
    let text =
        String::from_utf8_lossy(&out.stdout).into_owned() + &String::from_utf8_lossy(&out.stderr);
    if !out.status.success() && text.contains("mount:") {
        println!("cannot make a read-only mount here, skipped: {text}");
        return;
    }
    assert!(out.status.success(), "{text}");
    assert!(text.contains("refused: cannot write"), "{text}");
    assert_eq!(std::fs::read(dir.join("pipelines-x.bin")).unwrap(), b"old");
}

#[test]
fn other_drivers_files_older_than_30_days_are_removed() {
    let dir = scratch("old");
    for name in [
        "pipelines-mine.bin",
        "pipelines-old.bin",
        "pipelines-new.bin",
        "notes.txt",
    ] {
        std::fs::write(dir.join(name), b"x").unwrap();
    }
    for name in ["pipelines-mine.bin", "pipelines-old.bin", "notes.txt"] {
        let ok = Command::new("touch")
            .args(["-d", "31 days ago"])
            .arg(dir.join(name))
            .status()
            .unwrap();
        assert!(ok.success());
    }
    remove_old_foreign(&dir, "pipelines-mine.bin");
    let mut left: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    left.sort();
    assert_eq!(
        left,
        ["notes.txt", "pipelines-mine.bin", "pipelines-new.bin"]
    );
}

/// Bytes of writer `w`'s round `r`: the same byte throughout, so a torn file shows.
fn content(w: u8, r: u32) -> Vec<u8> {
    vec![w.wrapping_mul(31).wrapping_add(r as u8); 256 * 1024]
}

#[test]
fn two_writers_in_separate_pid_namespaces_leave_a_whole_file() {
    let dir = scratch("two-writers");
    let me = std::env::current_exe().unwrap();
    let start = Instant::now();
    let children: Vec<_> = (1..=2u8)
        .map(|w| {
            Command::new("unshare")
                .args(["--pid", "--fork"])
                .arg(&me)
                .args(["child_writer", "--exact", "--nocapture"])
                .env(CHILD, format!("write:{w}:{}", dir.display()))
                .stdout(std::process::Stdio::piped())
                .stderr(std::process::Stdio::piped())
                .spawn()
                .unwrap()
        })
        .collect();
    for c in children {
        let out = c.wait_with_output().unwrap();
        let text = String::from_utf8_lossy(&out.stdout).into_owned()
            + &String::from_utf8_lossy(&out.stderr);
        assert!(out.status.success(), "{text}");
        assert!(
            text.contains("as pid 1"),
            "not in a PID namespace of its own: {text}"
        );
    }
    let bytes = std::fs::read(dir.join("pipelines-x.bin")).unwrap();
    assert_eq!(bytes.len(), 256 * 1024);
    assert!(bytes.iter().all(|&b| b == bytes[0]), "a torn file");
    let left: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .filter_map(|e| e.ok())
        .map(|e| e.file_name())
        .collect();
    assert_eq!(left.len(), 1, "temporary files left: {left:?}");
    println!(
        "two writers, 200 writes each: whole file in {:?}",
        start.elapsed()
    );
}

#[test]
fn child_writer() {
    let Ok(job) = std::env::var(CHILD) else {
        return; // a normal run: the tests above start this in a child process
    };
    let parts: Vec<&str> = job.splitn(3, ':').collect();
    match parts[0] {
        "write" => {
            let w: u8 = parts[1].parse().unwrap();
            let dir = Path::new(parts[2]);
            println!("writer {w} as pid {}", std::process::id());
            for r in 0..200 {
                write_atomically(dir, "pipelines-x.bin", &content(w, r)).unwrap();
            }
        }
        "readonly" => {
            let dir = Path::new(parts[1]);
            let e = write_atomically(dir, "pipelines-x.bin", b"new").unwrap_err();
            println!("refused: {e}");
        }
        other => panic!("unknown job {other}"),
    }
}
