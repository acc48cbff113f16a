//! A session's background source: opened at xrCreateSession, reopened on a helper thread when
//! the config names another (frames pass through meanwhile), closed with the session.

use super::live_settings;
use super::log;
use super::state::SessionState;
use crate::camera::{self, Background, CaptureConfig};
use openxr_sys as xr;
use std::collections::HashMap;
use std::sync::mpsc::{self, Receiver, RecvTimeoutError, TryRecvError};
use std::sync::{Mutex, MutexGuard, OnceLock};
use std::time::{Duration, Instant};

fn open_background(spec: &str, camera: &CaptureConfig) -> Result<Background, String> {
    let source = camera::parse_source(spec)?;
    Background::open(&source, camera).map_err(|e| e.to_string())
}

/// Opens the background, logging once why not: the session then passes frames through until
/// the config names a source that opens.
pub(super) fn open_background_logged(spec: &str, camera: &CaptureConfig) -> Option<Background> {
    match open_background(spec, camera) {
        Ok(bg) => Some(bg),
        Err(e) => {
            log::info(&format!(
                "no background ({e}): passing frames through untouched"
            ));
            None
        }
    }
}

/// Background sources being reopened after a config change, by session: the helper thread
/// closes the old source, opens the new one and sends it (None if it failed).
pub(super) fn reopening() -> MutexGuard<'static, HashMap<u64, Receiver<Option<Background>>>> {
    static REOPENING: OnceLock<Mutex<HashMap<u64, Receiver<Option<Background>>>>> = OnceLock::new();
    let m = REOPENING.get_or_init(Default::default);
    // Only map operations happen under this lock.
    m.lock().unwrap_or_else(|p| p.into_inner())
}

fn start_reopen(
    session: xr::Session,
    old: Option<Background>,
    spec: String,
    camera: CaptureConfig,
) {
    let (tx, rx) = mpsc::channel();
    let spawned = std::thread::Builder::new()
        .name("contrastxr-reopen".into())
        .spawn(move || {
            // The old camera is closed before the new one opens (it may be the same device).
            if let Some(old) = old {
                old.close();
            }
            let _ = tx.send(open_background_logged(&spec, &camera));
        });
    match spawned {
        Ok(_) => {
            reopening().insert(session.into_raw(), rx);
        }
        Err(e) => log::info(&format!("cannot reopen the background ({e})")),
    }
}

/// Wall time without an enhanced frame after which the background closes (a camera's light
/// goes off; it opens again at the next frame the layer acts on).
const CLOSE_AFTER_IDLE: Duration = Duration::from_secs(2);

/// How long a frame call with `pipelines = "wait"` waits for the background to open: a source
/// on a hung file system (a network or FUSE mount) or a device that does not answer costs the
/// app's thread this once, and frames pass through until it has opened.
const OPEN_WAIT: Duration = Duration::from_secs(1);

/// Opens the session's background at the first frame the layer acts on, on a helper thread:
/// with `pipelines = "wait"` (every frame enhanced) the frame call waits for it up to
/// [`OPEN_WAIT`], else frames pass through meanwhile. A source that failed to open is tried
/// again only when the config changes.
pub(super) fn open_when_needed(s: &mut SessionState) {
    s.idle_since = None;
    if s.background.is_some() || s.background_requested {
        return;
    }
    s.background_requested = true;
    let spec = s.settings.background.clone();
    let camera = super::motion::camera_config(&s.settings, &s.motion);
    start_reopen(s.handle, None, spec, camera);
    if s.settings.wait_for_pipelines {
        wait_for_opened(s, OPEN_WAIT);
    }
}

/// Waits up to `limit` for the background the helper thread is opening; past that it is left
/// to the frame calls that come after (`take_reopened`), said once.
fn wait_for_opened(s: &mut SessionState, limit: Duration) {
    let session = s.handle.into_raw();
    // Not waited for under the map's lock: other sessions' frame calls take it.
    let Some(rx) = reopening().remove(&session) else {
        return;
    };
    match rx.recv_timeout(limit) {
        Ok(bg) => s.background = bg,
        Err(RecvTimeoutError::Timeout) => {
            log::once(
                "background-open-wait",
                &format!(
                    "the background did not open within {} s: frames pass through until it has",
                    limit.as_secs_f64()
                ),
            );
            reopening().insert(session, rx);
        }
        Err(RecvTimeoutError::Disconnected) => {}
    }
}

/// Notes a frame the layer did not act on, and closes the background CLOSE_AFTER_IDLE after
/// the last enhanced frame, also one still opening then (it is dropped when it arrives).
/// Closing never waits: the capture thread closes the device on its own.
pub(super) fn close_when_idle(s: &mut SessionState) {
    let since = *s.idle_since.get_or_insert_with(Instant::now);
    if since.elapsed() >= CLOSE_AFTER_IDLE && s.background_requested {
        if s.background.is_some() {
            log::info("no frame enhanced for 2 s: the background is closed until the next one");
        }
        s.background = None;
        s.background_requested = false;
    }
}

/// A reopened background, if the helper thread has finished.
fn take_reopened(session: xr::Session, s: &mut SessionState) {
    let mut pending = reopening();
    let Some(rx) = pending.get(&session.into_raw()) else {
        return;
    };
    match rx.try_recv() {
        // Opened after the session went idle: closed at once (without waiting).
        Ok(_) if !s.background_requested => {
            pending.remove(&session.into_raw());
        }
        Ok(bg) => {
            if let Some(bg) = &bg {
                log::info(&format!("background is now {}", bg.description()));
            }
            s.background = bg;
            pending.remove(&session.into_raw());
        }
        Err(TryRecvError::Empty) => {}
        Err(TryRecvError::Disconnected) => {
            pending.remove(&session.into_raw());
        }
    }
}

/// Takes newer settings from the config watcher, if any, without waiting.
pub(super) fn pick_up_settings(session: xr::Session, s: &mut SessionState) {
    take_reopened(session, s);
    let Some(live) = live_settings::live(s.instance.into_raw()) else {
        return;
    };
    let Some(newer) = live.newer(s.settings.generation) else {
        return;
    };
    let source_changed =
        newer.background != s.settings.background || newer.camera != s.settings.camera;
    // A background not opened yet opens with the new settings when it is first needed.
    if source_changed && s.graphics.is_some() && s.background_requested {
        start_reopen(
            session,
            s.background.take(),
            newer.background.clone(),
            super::motion::camera_config(&newer, &s.motion),
        );
    }
    s.settings = newer;
}
