//! The app's queue is shared with the runtime. OpenXR gives the runtime the queue inside
//! xrEndFrame and the swapchain acquire, wait and release calls, where the layer submits too;
//! but a runtime may also submit in xrCreateSwapchain (Monado does: the new images' layout
//! change), which an app may call on another thread at the same time. Vulkan requires queue
//! submissions to be externally synchronised, so the layer's submits on an app's queue and
//! the runtime calls it forwards that may touch the queue hold this one lock, and never
//! overlap. One lock for the process: sessions of one process rarely run at once, and each
//! holder keeps it only for one call.

use std::sync::{Mutex, MutexGuard, PoisonError};

static APP_QUEUE: Mutex<()> = Mutex::new(());

/// Held while submitting on an app's queue or forwarding a call that may submit on it.
pub fn hold() -> MutexGuard<'static, ()> {
    APP_QUEUE.lock().unwrap_or_else(PoisonError::into_inner)
}

/// Whether someone holds it now (the fake runtime's check).
#[cfg(test)]
pub(crate) fn is_held() -> bool {
    matches!(
        APP_QUEUE.try_lock(),
        Err(std::sync::TryLockError::WouldBlock)
    )
}
