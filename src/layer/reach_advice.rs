//! When most content is out of reach (docs/algorithm.md, *What it reports*): once a minute the
//! layer reads a frame's views back (a capture's read-back, without files), the capture thread
//! makes their perception report and, when more than half of a view's content stays below the
//! target contrast, logs one line saying what would help. At most one such line a minute in a
//! process. The app's thread only looks at a clock here; the report and the line are the
//! capture thread's.

use super::log;
use crate::algorithm::params::{Params, ViewMode};
use crate::evaluate::perception_report::PerceptionReport;
use std::sync::{Mutex, MutexGuard};
use std::time::{Duration, Instant};

/// How often the views are read back for the check, and the least time between two lines.
pub const MINUTE: Duration = Duration::from_secs(60);

/// The minute under the fault point `short-minute`, for the tests.
pub const SHORT_MINUTE: Duration = Duration::from_secs(2);

/// The debug line of each read-back for the check (`CONTRASTXR_LOG=debug`).
pub const READ_BACK_LINE: &str = "views read back for the out-of-reach check";

/// The share of a view's content out of reach above which the line is logged.
pub const MOST: f64 = 0.5;

fn minute() -> Duration {
    if crate::fault::hit("short-minute") {
        SHORT_MINUTE
    } else {
        MINUTE
    }
}

/// A clock that says yes at most once per `every`.
#[derive(Clone, Copy, Debug, Default)]
struct Every {
    last: Option<Instant>,
}

impl Every {
    /// True, and the clock restarted, when `every` has passed since the last yes, or at the
    /// first call with `first`.
    fn now(&mut self, now: Instant, every: Duration, first: bool) -> bool {
        let yes = match self.last {
            None => first,
            Some(t) => now.saturating_duration_since(t) >= every,
        };
        if yes || self.last.is_none() {
            self.last = Some(now);
        }
        yes
    }
}

fn lock(m: &'static Mutex<Every>) -> MutexGuard<'static, Every> {
    // A plain instant: a panic while holding the lock leaves it usable.
    m.lock().unwrap_or_else(|p| p.into_inner())
}

/// Whether this frame's views are read back for the check (app's thread: a clock, nothing
/// more). The first enhanced frame starts the clock; only the method's output (mode
/// `enhance`) is checked.
pub fn read_back_due(params: &Params) -> bool {
    static READ_BACK: Mutex<Every> = Mutex::new(Every { last: None });
    params.mode == ViewMode::Enhance && lock(&READ_BACK).now(Instant::now(), minute(), false)
}

/// Logs the advice when `report` (of a view enhanced with `params`) has most of its content out
/// of reach and no such line was logged in the last minute (capture thread).
pub fn consider(report: &PerceptionReport, params: &Params) {
    static LOGGED: Mutex<Every> = Mutex::new(Every { last: None });
    if params.mode != ViewMode::Enhance || report.out_of_reach_fraction <= MOST {
        return;
    }
    if lock(&LOGGED).now(Instant::now(), minute(), true) {
        log::info(&advice(report, params));
    }
}

/// The line: how much is out of reach, against what, and the settings that would help.
pub fn advice(report: &PerceptionReport, params: &Params) -> String {
    let s = &params.perceptual;
    format!(
        "most content is out of reach: {:.0} % of it stays below the target contrast {} \
         against {:.0} cd/m² of world at the eye (display_peak_nits {}, world_nits {}, \
         transmittance {}); what would help: a brighter display setting (and \
         display_peak_nits set to it), a darker lens (lower transmittance), or a lower \
         world_nits if the scene is darker than configured",
        100.0 * report.out_of_reach_fraction,
        report.target_contrast,
        report.mean_world_luminance,
        s.display_peak_nits,
        s.world_nits,
        params.transmittance
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_read_back_clock_says_yes_once_per_minute_after_the_first_call() {
        let (t0, mut clock) = (Instant::now(), Every::default());
        let at = |s: u64| t0 + Duration::from_secs(s);
        assert!(
            !clock.now(t0, MINUTE, false),
            "the first frame only starts it"
        );
        assert!(!clock.now(at(59), MINUTE, false));
        assert!(clock.now(at(60), MINUTE, false));
        assert!(!clock.now(at(61), MINUTE, false));
        assert!(!clock.now(at(119), MINUTE, false));
        assert!(clock.now(at(125), MINUTE, false));
    }

    #[test]
    fn the_line_comes_at_most_once_a_minute() {
        let (t0, mut limit) = (Instant::now(), Every::default());
        let at = |ms: u64| t0 + Duration::from_millis(ms);
        let said: Vec<u64> = (0..300_000)
            .step_by(700)
            .filter(|&ms| limit.now(at(ms), MINUTE, true))
            .collect();
        assert_eq!(
            said.first(),
            Some(&0),
            "the first out-of-reach view is said at once"
        );
        assert!(said.windows(2).all(|w| w[1] - w[0] >= 60_000), "{said:?}");
        assert_eq!(said.len(), 5, "{said:?}");
    }

    #[test]
    fn the_advice_names_what_would_help() {
        let report = PerceptionReport {
            perceived_contrast_before: 0.01,
            perceived_contrast_after: 0.02,
            perceived_contrast_gain: 2.0,
            perceived_contrast_log2_gain: 1.0,
            target_contrast: 0.05,
            left_alone_fraction: 0.1,
            brought_to_target_fraction: 0.1,
            out_of_reach_fraction: 0.8,
            frequency: "blur".into(),
            frequency_cpd: vec![2.0],
            mean_world_luminance: 4000.0,
        };
        let line = advice(&report, &Params::default());
        for says in [
            "80 %",
            "4000 cd/m²",
            "display_peak_nits",
            "transmittance",
            "world_nits",
        ] {
            assert!(line.contains(says), "{says}: {line}");
        }
    }
}
