//! A session's background source: opened at xrCreateSession, reopened on a helper thread when
//! the config names another (frames pass through meanwhile), closed with the session.

use super::log;
use super::settings;
use super::state::SessionState;
use crate::camera::{self, Background, CaptureConfig};
use openxr_sys as xr;
use std::collections::HashMap;
use std::sync::mpsc::{self, Receiver, TryRecvError};
use std::sync::{Mutex, MutexGuard, OnceLock};

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
            drop(old);
            let _ = tx.send(open_background_logged(&spec, &camera));
        });
    match spawned {
        Ok(_) => {
            reopening().insert(session.into_raw(), rx);
        }
        Err(e) => log::info(&format!("cannot reopen the background ({e})")),
    }
}

/// A reopened background, if the helper thread has finished.
fn take_reopened(session: xr::Session, s: &mut SessionState) {
    let mut pending = reopening();
    let Some(rx) = pending.get(&session.into_raw()) else {
        return;
    };
    match rx.try_recv() {
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
    let Some(live) = settings::live(s.instance.into_raw()) else {
        return;
    };
    let Some(newer) = live.newer(s.settings.generation) else {
        return;
    };
    let source_changed =
        newer.background != s.settings.background || newer.camera != s.settings.camera;
    if source_changed && s.processor.is_some() {
        start_reopen(
            session,
            s.background.take(),
            newer.background.clone(),
            newer.camera.clone(),
        );
    }
    s.settings = newer;
}
