//! Engines of OpenGL sessions that ended while the app's context was current on another thread
//! (an app destroying its session on a thread other than its render thread): their GL objects
//! can only be deleted with that context current, so they wait here, closed to their sources,
//! and are deleted the next time the layer has the same context current (a frame call of a
//! later session on it). At most [`KEPT`] wait; past that the oldest is given up, its objects
//! left to its context, said once. An engine is deleted only when its own labelled framebuffer
//! shows the current context to be the one it was made in: a context destroyed meanwhile (its
//! objects gone with it) and another made at the same address are told apart, and the
//! app's objects of the same names are never touched.

use crate::gpu::opengl::GlFrameRunner;
use crate::layer::log;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Mutex, MutexGuard};

/// How many left engines wait at most, across the process.
pub const KEPT: usize = 4;

/// Which app context: its display (X display or EGLDisplay) and context, as the binding gave
/// them.
pub type ContextKey = (usize, usize);

struct Left {
    key: ContextKey,
    engine: GlFrameRunner,
}

// SAFETY: a left engine makes GL calls only in `delete_left_on`, with its context current on
// the calling thread, under the list's lock; its sources were closed before it came here.
unsafe impl Send for Left {}

static LEFT: Mutex<Vec<Left>> = Mutex::new(Vec::new());
/// The list's length, read without the lock by every frame call.
static WAITING: AtomicUsize = AtomicUsize::new(0);

fn lock() -> MutexGuard<'static, Vec<Left>> {
    LEFT.lock().unwrap_or_else(|e| e.into_inner())
}

/// Keeps `engine`, made on the context `key`, until the layer has that context current again.
pub fn keep(key: ContextKey, mut engine: GlFrameRunner) {
    engine.close_to_sources();
    let mut left = lock();
    if left.len() >= KEPT {
        left.remove(0);
        static SAID: AtomicBool = AtomicBool::new(false);
        if !SAID.swap(true, Ordering::Relaxed) {
            log::info(&format!(
                "more than {KEPT} OpenGL sessions ended with their context current on another thread and not used by the layer since: the oldest one's OpenGL objects are left to its context"
            ));
        }
    }
    left.push(Left { key, engine });
    WAITING.store(left.len(), Ordering::Relaxed);
}

/// Deletes the objects of the engines left on the context `key`, which is current on this
/// thread; those made in a context no longer there are dropped with no GL call. Nothing to do
/// costs one atomic load.
///
/// # Safety
/// The context `key` names is current on this thread.
pub unsafe fn delete_left_on(key: ContextKey) {
    if WAITING.load(Ordering::Relaxed) == 0 {
        return;
    }
    let mut left = lock();
    let mut i = 0;
    while i < left.len() {
        if left[i].key != key {
            i += 1;
            continue;
        }
        let mut engine = left.remove(i).engine;
        // SAFETY: the context `key` is current (this call's contract); the engine's objects
        // are deleted only when it was made in this very context.
        unsafe {
            if engine.made_in_current_context() {
                engine.destroy();
            }
        }
    }
    WAITING.store(left.len(), Ordering::Relaxed);
}

/// How many left engines wait (for the tests).
#[cfg(test)]
pub fn waiting() -> usize {
    lock().len()
}
