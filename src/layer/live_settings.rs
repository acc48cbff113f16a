//! The layer's settings: resolved by [`crate::config`] from the config file and the
//! `CONTRASTXR_*` environment variables, and kept current per instance by a watcher thread
//! ([`crate::config::Live`]). Sessions take newer settings at xrEndFrame, never waiting.

use crate::config::Live;
pub use crate::config::{is_off, Capture, Settings};
use std::collections::HashMap;
use std::sync::{Arc, Mutex, MutexGuard, OnceLock};

fn lives() -> MutexGuard<'static, HashMap<u64, Arc<Live>>> {
    static LIVES: OnceLock<Mutex<HashMap<u64, Arc<Live>>>> = OnceLock::new();
    let m = LIVES.get_or_init(Default::default);
    // Only map operations happen under this lock: a panic cannot leave it inconsistent.
    m.lock().unwrap_or_else(|p| p.into_inner())
}

/// Keeps an instance's live settings (its watcher runs until [`forget_live`]).
pub fn register_live(instance: u64, live: Arc<Live>) {
    lives().insert(instance, live);
}

/// The live settings of an instance, if the layer is active on it.
pub fn live(instance: u64) -> Option<Arc<Live>> {
    lives().get(&instance).cloned()
}

/// Stops an instance's watcher thread.
pub fn forget_live(instance: u64) {
    let removed = lives().remove(&instance);
    if let Some(live) = removed {
        live.stop();
    }
}
