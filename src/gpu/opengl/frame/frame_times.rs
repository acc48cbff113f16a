//! The GPU time of each frame's work in the app's context, from two GL_TIMESTAMP queries
//! (glQueryCounter) around it: the first is written once the app's earlier commands are
//! complete, the second once the frame's own are. Results are read at later frames, only
//! where the driver has them (GL_QUERY_RESULT_AVAILABLE), so measuring never waits for the
//! GPU; a frame that finds every slot still waiting is not measured.

use crate::gpu::opengl::device::functions::{self as gl, Gl};
use std::collections::VecDeque;
use std::time::Duration;

/// Frames whose results may be outstanding at once.
const SLOTS: usize = 4;
/// Frames' times kept for the layer to take (a layer that takes none keeps no more).
const KEPT: usize = 1024;

#[derive(Default)]
pub struct FrameTimes {
    /// SLOTS pairs of query names (start, end), made at the first frame.
    queries: Vec<[u32; 2]>,
    /// The slot whose start was written and whose end was not yet.
    open: Option<usize>,
    /// Slots whose both timestamps were written, oldest first.
    pending: VecDeque<usize>,
    /// Frames' times read and not yet taken, oldest first.
    times: Vec<Duration>,
}

impl FrameTimes {
    /// Writes the start timestamp into a free slot (none where every slot still waits).
    ///
    /// # Safety
    /// The context the queries were made in (or will be) is current.
    pub(super) unsafe fn start(&mut self, g: &Gl) {
        if self.queries.is_empty() {
            let mut names = [0u32; 2 * SLOTS];
            // SAFETY: valid output for 2 * SLOTS names; deleted in `destroy`.
            unsafe { (g.gen_queries)(names.len() as i32, names.as_mut_ptr()) };
            self.queries = names.chunks(2).map(|p| [p[0], p[1]]).collect();
        }
        // A frame that failed before its end reuses its slot.
        let free = self
            .open
            .or_else(|| (0..SLOTS).find(|s| !self.pending.contains(s)));
        self.open = free;
        if let Some(slot) = free {
            // SAFETY: a query name of this context, not waiting for a result (free above).
            unsafe { (g.query_counter)(self.queries[slot][0], gl::TIMESTAMP) };
        }
    }

    /// Writes the end timestamp of the frame `start` opened.
    ///
    /// # Safety
    /// As `start`.
    pub(super) unsafe fn end(&mut self, g: &Gl) {
        if let Some(slot) = self.open.take() {
            // SAFETY: as in `start`.
            unsafe { (g.query_counter)(self.queries[slot][1], gl::TIMESTAMP) };
            self.pending.push_back(slot);
        }
    }

    /// Reads the finished frames' times, oldest first, stopping at the first not yet
    /// available. Skipped while the app has a query buffer bound (results would be written
    /// into it instead of returned).
    ///
    /// # Safety
    /// As `start`.
    pub(super) unsafe fn collect(&mut self, g: &Gl) {
        let mut bound = 0;
        // SAFETY: a single-valued query (GL 4.4; the engine's contexts are 4.5).
        unsafe { (g.get_integerv)(gl::QUERY_BUFFER_BINDING, &mut bound) };
        if bound != 0 {
            return;
        }
        while let Some(&slot) = self.pending.front() {
            let [start, end] = self.queries[slot];
            let mut available = 0u64;
            // SAFETY: queries of this context whose counters were written (pending).
            unsafe { (g.get_query_objectui64v)(end, gl::QUERY_RESULT_AVAILABLE, &mut available) };
            if available == 0 {
                break;
            }
            let (mut t0, mut t1) = (0u64, 0u64);
            // SAFETY: as above; available, so these do not wait (the start came first).
            unsafe {
                (g.get_query_objectui64v)(start, gl::QUERY_RESULT, &mut t0);
                (g.get_query_objectui64v)(end, gl::QUERY_RESULT, &mut t1);
            }
            self.pending.pop_front();
            self.times.push(Duration::from_nanos(t1.saturating_sub(t0)));
            if self.times.len() > KEPT {
                self.times.remove(0);
            }
        }
    }

    /// The frames' times read since the last call, oldest first.
    pub(super) fn take(&mut self) -> Vec<Duration> {
        std::mem::take(&mut self.times)
    }

    /// Deletes the query names.
    ///
    /// # Safety
    /// As `start`.
    pub(super) unsafe fn destroy(&mut self, g: &Gl) {
        let names: Vec<u32> = self.queries.drain(..).flatten().collect();
        if !names.is_empty() {
            // SAFETY: names this context made.
            unsafe { (g.delete_queries)(names.len() as i32, names.as_ptr()) };
        }
        self.open = None;
        self.pending.clear();
    }
}
