//! Hot reload: a thread polls the config file's metadata and, when it changes, resolves the
//! settings again and publishes them. Readers (the render thread, at xrEndFrame) never wait:
//! they compare a generation counter and take the new `Arc<Settings>` with `try_lock`; if the
//! watcher holds the lock at that instant, the next frame takes it.

use super::keys::KEYS;
use super::load::load_for;
use super::path::{self, Env};
use super::resolve::{Resolved, Who};
use super::settings::Settings;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex, TryLockError};
use std::thread::JoinHandle;
use std::time::{Duration, SystemTime};

/// How often the file is checked: a change applies within this plus one frame.
pub const POLL: Duration = Duration::from_millis(200);

/// The longest [`Live::stop`] waits for the watcher thread.
pub const STOP_WAIT: Duration = Duration::from_millis(100);

pub type Sink = Box<dyn Fn(&str) + Send + Sync>;

/// The settings of one app, kept current by the watcher thread.
pub struct Live {
    app: String,
    env: Env,
    /// The system's name once the app has created a session: its `[device."..."]` table applies.
    device: Mutex<Option<String>>,
    /// The generation of `current`; written after `current`.
    generation: AtomicU64,
    current: Mutex<Arc<Settings>>,
    stop: AtomicBool,
    thread: Mutex<Option<JoinHandle<()>>>,
}

/// What identifies a version of the file: replacing it (rename) or writing it changes this.
#[derive(Clone, Debug, PartialEq)]
struct Fingerprint {
    path: PathBuf,
    modified: Option<SystemTime>,
    len: u64,
    inode: u64,
}

/// The config file's fingerprint, looked up on the calling thread however long it takes.
fn fingerprint(env: &Env) -> Option<Fingerprint> {
    use std::os::unix::fs::MetadataExt;
    let path = path::find_waiting(env)?;
    let meta = crate::user_file::metadata(&path).ok()?;
    Some(Fingerprint {
        modified: meta.modified().ok(),
        len: meta.len(),
        inode: meta.ino(),
        path,
    })
}

struct Watcher {
    /// None until known: a look-up that stalled at the start is taken again on the watcher's
    /// thread, as the file's first version (no reload).
    seen: Option<Option<Fingerprint>>,
    sink: Sink,
    live: Arc<Live>,
}

impl Live {
    /// Resolves the settings for `app` and starts watching the file. Returns the first
    /// resolution for the caller to log.
    pub fn start(app: &str, env: Env, sink: Sink) -> (Arc<Live>, Resolved) {
        // Looked up on a helper thread, within the bound of the app's thread's reads.
        let looked_up = env.clone();
        let seen = crate::user_file::within(
            "the config file's fingerprint",
            crate::user_file::APP_THREAD_READ,
            move || Ok(fingerprint(&looked_up)),
        )
        .ok();
        let resolved = load_for(Who { app, device: None }, &env);
        let live = Arc::new(Live {
            app: app.to_string(),
            env,
            device: Mutex::new(None),
            generation: AtomicU64::new(0),
            current: Mutex::new(Arc::new(resolved.settings.clone())),
            stop: AtomicBool::new(false),
            thread: Mutex::new(None),
        });
        let mut watcher = Watcher {
            seen,
            sink,
            live: live.clone(),
        };
        let spawned = std::thread::Builder::new()
            .name("contrastxr-config".into())
            .spawn(move || watcher.run());
        match spawned {
            Ok(handle) => *lock(&live.thread) = Some(handle),
            Err(e) => (watcher_failed())(&format!(
                "cannot start the config watcher ({e}): no hot reload"
            )),
        }
        (live, resolved)
    }

    /// Resolves again for the app on the system named `device` (its `[device."..."]` table)
    /// and publishes the result if it changed anything. Returns the resolution for the log,
    /// with only the problems that the device table adds (the others were logged at start);
    /// None if the device is the one already in use.
    pub fn set_device(&self, device: &str) -> Option<Resolved> {
        let mut current = lock(&self.device);
        if current.as_deref() == Some(device) {
            return None;
        }
        let before = current.replace(device.to_string());
        drop(current);
        let known = load_for(
            Who {
                app: &self.app,
                device: before.as_deref(),
            },
            &self.env,
        )
        .problems;
        let mut r = self.resolve();
        r.problems.retain(|p| !known.contains(p));
        let old = self.current();
        if !old.same_values(&r.settings) {
            self.publish(r.settings.clone());
        }
        Some(r)
    }

    /// The settings the app would have on the system named `device`, without changing the
    /// device in use (for calls made before a session exists).
    pub fn on_device(&self, device: &str) -> Settings {
        let who = Who {
            app: &self.app,
            device: Some(device),
        };
        load_for(who, &self.env).settings
    }

    fn resolve(&self) -> Resolved {
        let device = lock(&self.device).clone();
        let who = Who {
            app: &self.app,
            device: device.as_deref(),
        };
        load_for(who, &self.env)
    }

    /// The settings now in force (may wait for the watcher; not for the render thread).
    pub fn current(&self) -> Arc<Settings> {
        lock(&self.current).clone()
    }

    /// Settings newer than generation `have`, without waiting.
    pub fn newer(&self, have: u64) -> Option<Arc<Settings>> {
        if self.generation.load(Ordering::Acquire) == have {
            return None;
        }
        match self.current.try_lock() {
            Ok(current) => Some(current.clone()),
            Err(TryLockError::Poisoned(p)) => Some(p.into_inner().clone()),
            Err(TryLockError::WouldBlock) => None,
        }
    }

    /// Stops the watcher thread and waits for it at most [`STOP_WAIT`]: one still waiting for
    /// the file system (a hung mount) is left to end on its own when its look-up returns.
    pub fn stop(&self) {
        self.stop.store(true, Ordering::Release);
        if let Some(handle) = lock(&self.thread).take() {
            handle.thread().unpark();
            let waited = std::time::Instant::now();
            while !handle.is_finished() && waited.elapsed() < STOP_WAIT {
                std::thread::sleep(Duration::from_millis(1));
            }
            if handle.is_finished() {
                let _ = handle.join();
            }
        }
    }

    fn publish(&self, mut settings: Settings) {
        let mut current = lock(&self.current);
        settings.generation = current.generation + 1;
        let generation = settings.generation;
        *current = Arc::new(settings);
        drop(current);
        self.generation.store(generation, Ordering::Release);
    }
}

fn watcher_failed() -> fn(&str) {
    |line| eprintln!("contrastxr: {line}")
}

fn lock<T>(m: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|p| p.into_inner())
}

impl Watcher {
    fn run(&mut self) {
        let body = std::panic::AssertUnwindSafe(|| {
            while !self.live.stop.load(Ordering::Acquire) {
                std::thread::park_timeout(POLL);
                let now = fingerprint(&self.live.env);
                let Some(seen) = &self.seen else {
                    self.seen = Some(now);
                    continue;
                };
                if now != *seen && !self.live.stop.load(Ordering::Acquire) {
                    self.seen = Some(now);
                    self.reload();
                }
            }
        });
        if std::panic::catch_unwind(body).is_err() {
            (self.sink)("internal error in the config watcher: no more hot reload");
        }
    }

    fn reload(&self) {
        let r = self.live.resolve();
        let file = r
            .file
            .as_ref()
            .map_or("(no file)".into(), |p| p.display().to_string());
        for p in &r.problems {
            (self.sink)(p);
        }
        if r.file_failed && r.file.as_ref().is_some_and(|p| p.is_file()) {
            // Most likely caught half-written: keep what runs; the finished write reloads.
            (self.sink)(&format!(
                "config {file} changed but cannot be used: keeping the settings in use"
            ));
            return;
        }
        let old = self.live.current();
        let changes: Vec<String> = KEYS
            .iter()
            .enumerate()
            .filter(|(_, k)| k.get(&old) != k.get(&r.settings))
            .map(|(i, k)| {
                let (was, now) = (k.get(&old), k.get(&r.settings));
                format!("{} {was} -> {now} ({})", k.name, r.origins[i])
            })
            .collect();
        if changes.is_empty() {
            (self.sink)(&format!("config {file} reloaded: no setting changed"));
            return;
        }
        (self.sink)(&format!("config {file} reloaded: {}", changes.join("; ")));
        self.live.publish(r.settings);
    }
}
