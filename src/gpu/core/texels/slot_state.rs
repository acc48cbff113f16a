//! The bookkeeping of the ring's slots, under the lock of `TexelSlots`: what each image holds,
//! which submission last sampled it, whether a write is under way, and so which slot either
//! side may write now.

use super::mapped_rows::MappedRows;
use crate::gpu::core::CameraRect;

/// What a frame's texels need: the slot that holds them, whether the source wrote it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Taken {
    pub slot: usize,
    pub by_source: bool,
}

pub(super) struct Slot {
    pub(super) rows: MappedRows,
    /// The texels (`BlurredTexels::serial`) and rectangle the image holds.
    pub(super) holds: Option<(u64, CameraRect)>,
    /// The last submission that sampled it (the engine's `Commands` numbering).
    pub(super) read_by: u64,
    /// A write is under way (by the engine or the source).
    pub(super) writing: bool,
    /// Its texels were written by the source's thread.
    pub(super) by_source: bool,
}

pub(super) struct State {
    pub(super) slots: Vec<Slot>,
    pub(super) size: (u32, u32),
    /// Submissions up to this one have finished.
    pub(super) finished: u64,
    /// The slot the frame being recorded (or the last one) samples.
    pub(super) sampled: Option<usize>,
    /// The slot written last.
    pub(super) newest: Option<usize>,
    /// The texels the last frame sampled (None: none yet).
    pub(super) wanted: Option<CameraRect>,
    pub(super) closed: bool,
}

impl State {
    /// A slot either side may write now: not sampled by a submission that may still run nor
    /// by the frame being recorded, nor written, and not `keep`.
    pub(super) fn free(&self, keep: Option<usize>) -> Option<usize> {
        (0..self.slots.len()).find(|&i| {
            let s = &self.slots[i];
            !s.writing && s.read_by <= self.finished && Some(i) != self.sampled && Some(i) != keep
        })
    }

    /// The frame being recorded, to be submitted as `submission`, samples `slot`.
    pub(super) fn sample(&mut self, slot: usize, submission: u64) -> Taken {
        self.sampled = Some(slot);
        let s = &mut self.slots[slot];
        s.read_by = s.read_by.max(submission);
        Taken {
            slot,
            by_source: s.by_source,
        }
    }
}
