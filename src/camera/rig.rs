//! What a `world:` source shares with its consumer: the simulated camera on the head, and the
//! head poses the source asks for and the consumer (which tracks the head) answers. Apart from
//! world.rs, so that the capture settings can name it without depending on the source.

use crate::algorithm::registration::{CameraProfile, Pose};
use std::collections::VecDeque;
use std::sync::{Arc, Mutex};

/// Located poses kept for the camera thread to take (older ones are dropped).
const KEPT_POSES: usize = 512;

/// The head poses a `world:` source asks for and the consumer answers.
#[derive(Default)]
pub struct HeadPoses {
    book: Mutex<PoseBook>,
}

#[derive(Default)]
struct PoseBook {
    wanted: Vec<i64>,
    located: VecDeque<(i64, Option<Pose>)>,
}

impl HeadPoses {
    fn book(&self) -> std::sync::MutexGuard<'_, PoseBook> {
        self.book.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// The capture times (CLOCK_MONOTONIC ns) whose head pose is wanted, taken away.
    pub fn wanted(&self) -> Vec<i64> {
        std::mem::take(&mut self.book().wanted)
    }

    /// The head's pose in the world at `time` (None: it could not be located).
    pub fn record(&self, time: i64, pose: Option<Pose>) {
        let mut book = self.book();
        book.located.push_back((time, pose));
        while book.located.len() > KEPT_POSES {
            book.located.pop_front();
        }
    }

    pub(crate) fn want(&self, time: i64) {
        self.book().wanted.push(time);
    }

    /// The recorded answer for `time`: None while not answered.
    pub(crate) fn take(&self, time: i64) -> Option<Option<Pose>> {
        let mut book = self.book();
        let at = book.located.iter().position(|(t, _)| *t == time)?;
        book.located.remove(at).map(|(_, pose)| pose)
    }
}

/// What a `world:` source needs besides the panorama: the simulated camera (lens and mount on
/// the head) and where the head's poses come from.
#[derive(Clone)]
pub struct WorldRig {
    pub profile: CameraProfile,
    pub poses: Arc<HeadPoses>,
}

impl PartialEq for WorldRig {
    fn eq(&self, other: &Self) -> bool {
        self.profile == other.profile && Arc::ptr_eq(&self.poses, &other.poses)
    }
}

impl std::fmt::Debug for WorldRig {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "WorldRig({:?})", self.profile)
    }
}
