//! The frame engine's one `TexelSink` for its whole life: a live source is connected to it once,
//! and it passes each frame's texels on to the texel ring's slots of the moment (none before
//! the ring is made, after it is closed or while it is remade at another size).

use super::texel_slots::TexelSlots;
use crate::gpu::core::blurred_texels::{BlurredTexels, TexelSink};
use std::sync::{Arc, Mutex};

#[derive(Default)]
pub struct RingSink {
    /// The slots the next offer goes to. Taken out under the lock and written outside it, so
    /// the engine's frame never waits here for a write; a write into slots closed meanwhile is
    /// dropped by the slots themselves (`TexelSlots::close`).
    slots: Mutex<Option<Arc<TexelSlots>>>,
}

impl RingSink {
    /// Where offers go from now on (None: nowhere).
    pub(crate) fn connect(&self, slots: Option<Arc<TexelSlots>>) {
        *self.slots.lock().unwrap_or_else(|e| e.into_inner()) = slots;
    }
}

impl TexelSink for RingSink {
    fn offer(&self, texels: &BlurredTexels) {
        let slots = self.slots.lock().unwrap_or_else(|e| e.into_inner()).clone();
        if let Some(slots) = slots {
            slots.offer(texels);
        }
    }
}
