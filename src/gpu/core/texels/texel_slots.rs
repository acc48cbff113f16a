//! The frame engine's mapped texel images (gpu/vulkan/texels/texel_ring.rs) as slots shared with a
//! live source's thread, which writes each new frame's texels into one of them before it
//! publishes the frame (`TexelSink`): the app's frame call then only binds that image. What
//! each slot holds is slot_state.rs's; where its texels lie in memory, mapped_rows.rs's. Either
//! side writes an image only when no submission may still sample it, the frame being recorded
//! does not sample it, and no other write is under way in it. The engine frees the memory only
//! after `close`, which waits for a write under way; a closed ring takes no more writes.

use super::mapped_rows::MappedRows;
use super::slot_state::{Slot, State, Taken};
use crate::gpu::core::blurred_texels::{BlurredTexels, TexelSink};
use crate::gpu::core::CameraRect;
use std::sync::{Condvar, Mutex, MutexGuard};

/// The ring's slots, shared by the engine (an `Arc` it keeps) and a source's thread (as its
/// `TexelSink`).
pub struct TexelSlots {
    state: Mutex<State>,
    /// Signalled when a write ends (for `close`).
    written: Condvar,
}

impl TexelSlots {
    pub(crate) fn new(size: (u32, u32), rows: Vec<MappedRows>) -> TexelSlots {
        let slots = rows
            .into_iter()
            .map(|rows| Slot {
                rows,
                holds: None,
                read_by: 0,
                writing: false,
                by_source: false,
            })
            .collect();
        let state = State {
            slots,
            size,
            finished: 0,
            sampled: None,
            newest: None,
            wanted: None,
            closed: false,
        };
        TexelSlots {
            state: Mutex::new(state),
            written: Condvar::new(),
        }
    }

    fn lock(&self) -> MutexGuard<'_, State> {
        self.state.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Submissions up to `n` have finished: the slots they sampled may be written again.
    pub fn finished_through(&self, n: u64) {
        let mut state = self.lock();
        state.finished = state.finished.max(n);
    }

    /// Makes the frame to be submitted as `submission` sample a slot holding `rect` of the
    /// texels `serial`, when one does: no write.
    pub fn take(&self, serial: u64, rect: &CameraRect, submission: u64) -> Option<Taken> {
        let mut state = self.lock();
        state.wanted = Some(*rect);
        let held = |s: &Slot| {
            !s.writing
                && s.holds
                    .is_some_and(|(n, done)| n == serial && done.contains(rect))
        };
        let slot = (0..state.slots.len()).find(|&i| held(&state.slots[i]))?;
        Some(state.sample(slot, submission))
    }

    /// Writes `rect` of `texels` (with what a slot already holds of them) into a free slot, and
    /// makes the frame to be submitted as `submission` sample it. None, with nothing written,
    /// when no slot is free.
    pub fn write_for_frame(
        &self,
        texels: &BlurredTexels,
        rect: &CameraRect,
        submission: u64,
    ) -> Option<Taken> {
        let mut state = self.lock();
        state.wanted = Some(*rect);
        let rect = state
            .slots
            .iter()
            .filter_map(|s| s.holds.filter(|(n, _)| *n == texels.serial))
            .fold(*rect, |r, (_, done)| r.union(&done));
        // Keeping the newest when another is free: it may be the source's, for the next frame.
        let slot = state.free(state.newest).or_else(|| state.free(None))?;
        state.slots[slot].writing = true;
        drop(state);
        Some(self.write_claimed(slot, texels, &rect, Some(submission)))
    }

    /// The submission `submission` samples `slot` too (a frame of several submissions).
    pub fn sampled_by(&self, slot: usize, submission: u64) {
        let mut state = self.lock();
        if let Some(s) = state.slots.get_mut(slot) {
            s.read_by = s.read_by.max(submission);
        }
    }

    /// Takes no more writes, and waits for one under way to end: then the memory may go.
    pub fn close(&self) {
        let mut state = self.lock();
        state.closed = true;
        while state.slots.iter().any(|s| s.writing) {
            state = self.written.wait(state).unwrap_or_else(|e| e.into_inner());
        }
    }

    /// Writes into `slot`, claimed by the caller (`writing`), then records what it holds and
    /// gives the claim back; for the engine's frame (`reader`: the submission that will read
    /// it), marks the slot the frame's in the same critical section, so that no other write
    /// can claim it in between.
    fn write_claimed(
        &self,
        slot: usize,
        texels: &BlurredTexels,
        rect: &CameraRect,
        reader: Option<u64>,
    ) -> Taken {
        // The claim keeps the slot and its memory (`close` waits) for this write alone; the
        // guard gives it up if the write panics, so that `close` never waits for ever.
        let unwinding = Unwinding { slots: self, slot };
        let rows = self.lock().slots[slot].rows;
        rows.write(texels, rect);
        std::mem::forget(unwinding);
        let mut state = self.lock();
        let s = &mut state.slots[slot];
        s.holds = Some((texels.serial, *rect));
        s.by_source = reader.is_none();
        s.writing = false;
        state.newest = Some(slot);
        let taken = match reader {
            Some(submission) => state.sample(slot, submission),
            None => Taken {
                slot,
                by_source: true,
            },
        };
        drop(state);
        self.written.notify_all();
        taken
    }
}

/// Gives a slot's `writing` claim back, holding nothing, when a write panics (dropped while
/// unwinding; a finished write forgets it and gives the claim back itself).
struct Unwinding<'a> {
    slots: &'a TexelSlots,
    slot: usize,
}

impl Drop for Unwinding<'_> {
    fn drop(&mut self) {
        let mut state = self.slots.lock();
        let s = &mut state.slots[self.slot];
        s.holds = None;
        s.writing = false;
        drop(state);
        self.slots.written.notify_all();
    }
}

/// Texels around what the last frame sampled that the source writes too, on each side: the
/// views' mappings move with the head between frames (about 30 texels of a 640-wide camera per
/// 30 Hz frame at 100 degrees per second). A frame that samples beyond writes them itself.
pub const SOURCE_MARGIN: u32 = 48;

impl TexelSink for TexelSlots {
    /// On the source's thread: what the last frame sampled, grown by SOURCE_MARGIN (the whole
    /// frame before any), into a free slot other than the newest (which the next frame may
    /// take), when the ring is open and of the texels' size; else nothing.
    fn offer(&self, texels: &BlurredTexels) {
        let mut state = self.lock();
        let size = (texels.width, texels.height);
        if state.closed || state.size != size {
            return;
        }
        let newest = state.newest;
        let Some(slot) = state.free(newest) else {
            return;
        };
        state.slots[slot].writing = true;
        let rect = state
            .wanted
            .map_or(CameraRect::full(size), |r| r.grown(SOURCE_MARGIN, size));
        drop(state);
        self.write_claimed(slot, texels, &rect, None);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gpu::core::blurred_texels::BlurTaps;
    use crate::gpu::core::blurred_texels::TEXEL_BYTES;
    use crate::image::RgbaImage;
    use std::sync::Arc;

    const SIZE: (u32, u32) = (8, 4);

    /// Texels of a flat camera frame of grey `code` (distinct codes give distinct bytes).
    fn texels(code: u8) -> BlurredTexels {
        let camera = RgbaImage::new(SIZE.0, SIZE.1, [code, code, code, 255]);
        BlurredTexels::prepare(&camera, BlurTaps::of(&Default::default()))
    }

    /// Three slots over host memory laid out as a padded linear image (pitch > row).
    struct Memory {
        bytes: Vec<Vec<u8>>,
    }

    const PITCH: usize = SIZE.0 as usize * TEXEL_BYTES + 32;

    /// Slots over `bytes`, one buffer each, rows from `offset` every `row_pitch` bytes.
    fn rows_over(bytes: &mut [Vec<u8>], offset: usize, row_pitch: usize) -> Vec<MappedRows> {
        let rows = bytes.iter_mut().map(|b| MappedRows {
            ptr: b.as_mut_ptr(),
            len: b.len(),
            offset,
            row_pitch,
        });
        rows.collect()
    }

    impl Memory {
        fn new() -> Memory {
            let len = 16 + PITCH * SIZE.1 as usize;
            Memory {
                bytes: (0..3).map(|_| vec![0u8; len]).collect(),
            }
        }

        fn slots(&mut self) -> TexelSlots {
            TexelSlots::new(SIZE, rows_over(&mut self.bytes, 16, PITCH))
        }

        /// Whether slot `i` holds all of `t`, row by row.
        fn holds(&self, i: usize, t: &BlurredTexels) -> bool {
            let row = SIZE.0 as usize * TEXEL_BYTES;
            (0..SIZE.1 as usize).all(|y| {
                let at = 16 + y * PITCH;
                self.bytes[i][at..at + row] == t.bytes[y * row..(y + 1) * row]
            })
        }
    }

    fn all() -> CameraRect {
        CameraRect::full(SIZE)
    }

    #[test]
    fn the_source_writes_a_frame_the_engine_then_takes_without_a_write() {
        let mut memory = Memory::new();
        let slots = memory.slots();
        let a = texels(40);
        slots.offer(&a);
        let taken = slots.take(a.serial, &all(), 1).expect("held");
        assert!(taken.by_source);
        drop(slots);
        assert!(memory.holds(taken.slot, &a));
    }

    #[test]
    fn no_write_lands_in_a_slot_a_submission_may_still_sample() {
        let mut memory = Memory::new();
        let slots = memory.slots();
        let frames: Vec<BlurredTexels> = (0..8).map(|k| texels(20 * k + 10)).collect();
        slots.offer(&frames[0]);
        let first = slots.take(frames[0].serial, &all(), 1).unwrap().slot;
        // Submission 1 runs (never finished): the source keeps offering new frames, and the
        // next frames (submissions 2, 3) take them.
        for (k, t) in frames[1..].iter().enumerate() {
            slots.offer(t);
            if k % 3 == 0 {
                slots.take(t.serial, &all(), 2 + k as u64 / 3);
            }
        }
        drop(slots);
        assert!(memory.holds(first, &frames[0]), "sampled slot overwritten");
    }

    #[test]
    fn the_source_keeps_the_newest_frame_and_writes_past_finished_submissions() {
        let mut memory = Memory::new();
        let slots = memory.slots();
        let (a, b, c) = (texels(10), texels(90), texels(170));
        slots.offer(&a);
        let sa = slots.take(a.serial, &all(), 1).unwrap().slot;
        slots.offer(&b);
        slots.offer(&c);
        // b was the newest when c came: c went into the third slot, and neither a (in flight)
        // nor b was touched.
        let sb = slots.take(b.serial, &all(), 2).expect("b kept").slot;
        assert_ne!(sa, sb);
        slots.finished_through(1);
        let d = texels(250);
        slots.offer(&d);
        let sc = slots.take(c.serial, &all(), 3);
        let sd = slots
            .take(d.serial, &all(), 3)
            .expect("d written where a was")
            .slot;
        assert_eq!(sd, sa, "only a's slot was free");
        assert!(sc.is_some(), "c was the newest when d came: kept");
        drop(slots);
        assert!(memory.holds(sd, &d));
        assert!(memory.holds(sb, &b));
    }

    #[test]
    fn the_engine_writes_what_no_slot_holds_and_unites_rectangles() {
        let mut memory = Memory::new();
        let slots = memory.slots();
        let a = texels(60);
        let left = CameraRect {
            x: 0,
            y: 0,
            width: 4,
            height: SIZE.1,
        };
        let right = CameraRect { x: 4, ..left };
        let first = slots.write_for_frame(&a, &left, 1).unwrap();
        assert!(!first.by_source);
        assert!(
            slots.take(a.serial, &right, 2).is_none(),
            "right half not written"
        );
        slots.finished_through(1);
        let both = slots.write_for_frame(&a, &right, 2).unwrap();
        assert_ne!(
            both.slot, first.slot,
            "slot 1 is sampled by the frame before"
        );
        assert!(slots.take(a.serial, &all(), 3).is_some());
        drop(slots);
        assert!(memory.holds(both.slot, &a), "both halves in one slot");
    }

    #[test]
    fn a_closed_ring_or_a_frame_of_another_size_takes_no_write() {
        let mut memory = Memory::new();
        let slots = memory.slots();
        let other = BlurredTexels::prepare(
            &RgbaImage::new(4, 4, [1, 2, 3, 255]),
            BlurTaps::of(&Default::default()),
        );
        slots.offer(&other);
        assert!(slots
            .take(other.serial, &CameraRect::full((4, 4)), 1)
            .is_none());
        slots.close();
        let a = texels(30);
        slots.offer(&a);
        assert!(slots.take(a.serial, &all(), 1).is_none());
    }

    #[test]
    fn the_source_writes_what_the_last_frame_sampled_and_a_margin() {
        let size = (256u32, 4u32);
        let pitch = size.0 as usize * TEXEL_BYTES;
        let mut bytes: Vec<Vec<u8>> = (0..3).map(|_| vec![0u8; pitch * 4]).collect();
        let slots = TexelSlots::new(size, rows_over(&mut bytes, 0, pitch));
        let blur = BlurTaps::of(&Default::default());
        let camera = |code| BlurredTexels::prepare(&RgbaImage::new(256, 4, [code; 4]), blur);
        let (a, b) = (camera(10), camera(200));
        let sampled = CameraRect {
            x: 100,
            y: 0,
            width: 40,
            height: 4,
        };
        slots.write_for_frame(&a, &sampled, 1).unwrap();
        slots.offer(&b);
        // 52 = 100 - SOURCE_MARGIN, a multiple of 4; 188 = 140 + SOURCE_MARGIN.
        let near = CameraRect {
            x: 52,
            width: 188 - 52,
            ..sampled
        };
        let beyond = CameraRect { x: 48, ..near };
        assert!(slots.take(b.serial, &beyond, 2).is_none());
        let taken = slots.take(b.serial, &near, 2).expect("within the margin");
        assert!(taken.by_source);
        drop(slots);
        let written =
            |x: usize| bytes[taken.slot][x * TEXEL_BYTES..(x + 1) * TEXEL_BYTES] != [0; 16];
        assert!(written(52) && written(187));
        assert!(!written(51) && !written(188), "beyond the margin");
    }

    #[test]
    fn a_write_that_panics_gives_its_slot_back() {
        // Memory too short for the frame: the write panics on its first row.
        let mut short = vec![vec![0u8; 16]; 3];
        let slots = TexelSlots::new(SIZE, rows_over(&mut short, 0, PITCH));
        let a = texels(70);
        let offered = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| slots.offer(&a)));
        assert!(offered.is_err(), "the write did not panic");
        assert!(
            slots.take(a.serial, &all(), 1).is_none(),
            "holds a torn write"
        );
        // Returns: no claim is left behind.
        slots.close();
    }

    #[test]
    fn close_waits_for_a_write_under_way() {
        let mut memory = Memory::new();
        let slots = Arc::new(memory.slots());
        let frames: Arc<Vec<BlurredTexels>> = Arc::new((0..4).map(|k| texels(50 * k)).collect());
        let writer = {
            let (slots, frames) = (slots.clone(), frames.clone());
            std::thread::spawn(move || {
                for k in 0..2000 {
                    slots.offer(&frames[k % 4]);
                    slots.finished_through(k as u64);
                }
            })
        };
        std::thread::sleep(std::time::Duration::from_millis(2));
        slots.close();
        // No write is under way after close returns, and none starts: the memory is stable.
        let copy = memory.bytes.clone();
        writer.join().unwrap();
        drop(slots);
        assert!(copy == memory.bytes, "a write after close");
    }
}
