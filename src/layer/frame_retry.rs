//! Frames the session's graphics could not reach for a reason that may pass (the app's OpenGL
//! context current on another thread for a while): each passes through untouched and the
//! session keeps its engine. The layer tries again at the next frame, then after 2, 4, 8 …
//! frames, at most every [`LONGEST_WAIT`] frames, so a cause that lasts costs one try in 64
//! frames and one that passes costs a few frames. It logs when such frames begin and when
//! enhancement resumes, each at most once a minute per session.

use super::log;
use std::time::{Duration, Instant};

/// The most frames between two tries.
pub const LONGEST_WAIT: u64 = 64;

/// The least time between two lines of the same kind.
const LINE_EVERY: Duration = Duration::from_secs(60);

/// A session's frames passed through for a cause that may pass.
#[derive(Default)]
pub struct FrameRetry {
    /// Frames passed through since the last enhanced frame (0: none).
    passed: u64,
    /// Tries that failed in a row.
    failed_tries: u32,
    /// Frames left to pass through before the next try.
    wait: u64,
    /// The cause, as the last failed try said it.
    why: String,
    /// When each kind of line was last logged: a run of failures beginning, enhancement
    /// resuming.
    logged: [Option<Instant>; 2],
}

impl FrameRetry {
    /// Whether this frame tries the graphics; when not, it passes through (and is counted).
    pub fn due(&mut self) -> bool {
        if self.wait == 0 {
            return true;
        }
        self.wait -= 1;
        self.passed += 1;
        false
    }

    /// This frame's try failed for `why`: the frame passes through, the next try waits.
    pub fn failed(&mut self, why: &str) {
        if self.failed_tries == 0 {
            let line = format!(
                "{why}: {} at the next frame, then after 2, 4, 8 ... frames (at most {LONGEST_WAIT})",
                log::TRIES_AGAIN
            );
            self.log(0, &line);
        }
        self.passed += 1;
        self.failed_tries = self.failed_tries.saturating_add(1);
        self.wait = (1u64 << (self.failed_tries - 1).min(6)).min(LONGEST_WAIT) - 1;
        self.why = why.to_string();
    }

    /// A frame was enhanced: a run of passed frames, if any, ends.
    pub fn enhanced(&mut self) {
        if self.failed_tries == 0 {
            return;
        }
        let line = format!(
            "{} {} frames passed through ({})",
            log::ENHANCING_AGAIN,
            self.passed,
            self.why
        );
        self.log(1, &line);
        *self = FrameRetry {
            logged: self.logged,
            ..FrameRetry::default()
        };
    }

    /// Logs `line` unless a line of kind `kind` was logged in the last minute.
    fn log(&mut self, kind: usize, line: &str) {
        let now = Instant::now();
        if self.logged[kind].is_some_and(|t| now.duration_since(t) < LINE_EVERY) {
            return;
        }
        self.logged[kind] = Some(now);
        log::info(line);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Which of `frames` frames try, when every try fails.
    fn tries(frames: u64) -> Vec<u64> {
        let mut retry = FrameRetry::default();
        let mut tried = Vec::new();
        for frame in 0..frames {
            if retry.due() {
                tried.push(frame);
                retry.failed("the cause");
            }
        }
        tried
    }

    #[test]
    fn tries_wait_twice_as_long_each_time_up_to_the_longest_wait() {
        assert_eq!(tries(64), [0, 1, 3, 7, 15, 31, 63]);
        let late = tries(64 * 6);
        let gaps: Vec<u64> = late.windows(2).map(|w| w[1] - w[0]).collect();
        assert_eq!(gaps, [1, 2, 4, 8, 16, 32, 64, 64, 64, 64, 64]);
    }

    #[test]
    fn an_enhanced_frame_ends_the_run_and_the_next_failure_is_tried_again_at_once() {
        let mut retry = FrameRetry::default();
        assert!(retry.due());
        retry.failed("the cause");
        assert!(retry.due());
        retry.failed("the cause");
        assert!(!retry.due());
        assert_eq!(retry.passed, 3);
        assert!(retry.due());
        retry.enhanced();
        assert_eq!((retry.passed, retry.failed_tries, retry.wait), (0, 0, 0));
        assert!(retry.logged[0].is_some() && retry.logged[1].is_some());
        assert!(retry.due());
        retry.failed("the cause");
        assert!(retry.due());
    }
}
