//! The states of a swapchain's images as the runtime sees them (OpenXR 1.x, "Swapchain Image
//! Management"): acquired images wait in a FIFO, xrWaitSwapchainImage waits the oldest, at most
//! one image is waited at a time, and xrReleaseSwapchainImage releases the waited one. The layer
//! forwards every acquire and wait at once and records what the runtime answered; the only call
//! it ever delays is a release, and only one the runtime would accept (an image is waited).
//! While a release is held the runtime still counts that image as waited; the app does not.
//!
//! Pure bookkeeping: no FFI, no locks. `super::swapchain` acts on the decisions.

use std::collections::VecDeque;

/// What to do with the app's xrReleaseSwapchainImage.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ReleasePlan {
    /// Keep the release until xrEndFrame (answer XR_SUCCESS, as the runtime would).
    Hold(u32),
    /// Enhance the waited image now (the app already acquired its next one, so xrEndFrame
    /// comes too late), then forward the release.
    EnhanceThenForward(u32),
    /// An earlier release is held: hand that one over first, so the runtime sees the app's
    /// own state and answers this release itself.
    FlushHeldThenForward(u32),
    /// Forward as it is (nothing waited: the runtime's own error reaches the app).
    Forward,
}

#[derive(Clone, Debug, Default)]
pub struct ImageStates {
    /// Acquired, not yet waited, oldest first (the runtime's FIFO).
    acquired: VecDeque<u32>,
    /// The image the runtime counts as waited (the app's, or one whose release is held).
    waited: Option<u32>,
    /// The waited image's release was made by the app and is held by the layer.
    held: bool,
    /// The wait answered plain XR_SUCCESS. After another success code (XR_SESSION_LOSS_PENDING)
    /// the runtime may answer a release with that code too, which a held release could not.
    plain_wait: bool,
}

impl ImageStates {
    /// The image whose release the layer holds, if any.
    pub fn held(&self) -> Option<u32> {
        self.waited.filter(|_| self.held)
    }

    /// The app's xrAcquireSwapchainImage returned `index` (a success code).
    pub fn acquired(&mut self, index: u32) {
        self.acquired.push_back(index);
    }

    /// The app's xrWaitSwapchainImage succeeded (`plain`: with XR_SUCCESS itself): the oldest
    /// acquired image is waited.
    pub fn waited(&mut self, plain: bool) {
        if let Some(i) = self.acquired.pop_front() {
            self.waited = Some(i);
            self.held = false;
            self.plain_wait = plain;
        }
    }

    /// A release reached the runtime and it succeeded: no image is waited any more.
    pub fn released(&mut self) {
        self.waited = None;
        self.held = false;
    }

    /// The layer took the app's release of the waited image.
    pub fn hold(&mut self) {
        debug_assert!(self.waited.is_some() && !self.held);
        self.held = true;
    }

    /// How to treat the app's release. `holdable`: the swapchain is one the layer enhances.
    pub fn plan_release(&self, holdable: bool) -> ReleasePlan {
        match (self.waited, self.held) {
            (Some(i), true) => ReleasePlan::FlushHeldThenForward(i),
            (Some(i), false) if holdable && self.acquired.is_empty() && self.plain_wait => {
                ReleasePlan::Hold(i)
            }
            (Some(i), false) if holdable => ReleasePlan::EnhanceThenForward(i),
            _ => ReleasePlan::Forward,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_plain_frame_is_held_until_end_frame() {
        let mut s = ImageStates::default();
        s.acquired(2);
        assert_eq!(s.plan_release(true), ReleasePlan::Forward, "not waited yet");
        s.waited(true);
        assert_eq!(s.plan_release(true), ReleasePlan::Hold(2));
        s.hold();
        assert_eq!(s.held(), Some(2));
        s.released();
        assert_eq!(s.held(), None);
    }

    #[test]
    fn nothing_is_held_for_swapchains_the_layer_leaves_alone() {
        let mut s = ImageStates::default();
        s.acquired(0);
        s.waited(true);
        assert_eq!(s.plan_release(false), ReleasePlan::Forward);
    }

    #[test]
    fn a_release_after_the_next_acquire_is_enhanced_at_once() {
        let mut s = ImageStates::default();
        s.acquired(0);
        s.waited(true);
        s.acquired(1);
        assert_eq!(s.plan_release(true), ReleasePlan::EnhanceThenForward(0));
    }

    #[test]
    fn a_second_release_flushes_the_held_one_first() {
        let mut s = ImageStates::default();
        s.acquired(0);
        s.waited(true);
        s.hold();
        assert_eq!(s.plan_release(true), ReleasePlan::FlushHeldThenForward(0));
    }

    #[test]
    fn waiting_without_an_acquired_image_changes_nothing() {
        let mut s = ImageStates::default();
        s.waited(true);
        assert_eq!(s.plan_release(true), ReleasePlan::Forward);
        assert_eq!(s.held(), None);
    }

    #[test]
    fn a_release_after_another_success_code_is_not_held() {
        let mut s = ImageStates::default();
        s.acquired(0);
        s.waited(false);
        assert_eq!(s.plan_release(true), ReleasePlan::EnhanceThenForward(0));
    }

    #[test]
    fn images_are_waited_oldest_first() {
        let mut s = ImageStates::default();
        s.acquired(1);
        s.acquired(2);
        s.waited(true);
        assert_eq!(s.plan_release(true), ReleasePlan::EnhanceThenForward(1));
        s.released();
        s.waited(true);
        assert_eq!(s.plan_release(true), ReleasePlan::Hold(2));
    }
}
