//! With --timing: the wall time of every OpenXR call of the frame loop, and when the first frames
//! reached the runtime. Start-up (pipeline compiles, first allocations, in the runtime or in a
//! layer) shows only here: the per-frame medians of the report leave the first frames out.

use std::time::Instant;

/// Submitted frames whose end time is kept: start-up is over well before.
pub const FIRST_FRAMES: usize = 30;

/// Milliseconds of each call, by call name, in the order the calls were first made. Records
/// nothing unless on (--timing): the lists grow with every frame, and the report's memory
/// samples would see them.
#[derive(Default, Debug)]
pub struct Calls {
    on: bool,
    times: Vec<(String, Vec<f64>)>,
}

impl Calls {
    pub fn new(on: bool) -> Calls {
        Calls {
            on,
            times: Vec::new(),
        }
    }

    /// Runs `call`, recording its wall time under `name` when on.
    pub fn time<T>(&mut self, name: &str, call: impl FnOnce() -> T) -> T {
        if !self.on {
            return call();
        }
        let start = Instant::now();
        let result = call();
        self.record(name, start.elapsed().as_secs_f64() * 1e3);
        result
    }

    /// Records a time measured by the caller (xrEndFrame's, which the report also keeps apart).
    pub fn record(&mut self, name: &str, ms: f64) {
        if !self.on {
            return;
        }
        match self.times.iter_mut().find(|(n, _)| n == name) {
            Some((_, times)) => times.push(ms),
            None => self.times.push((name.to_string(), vec![ms])),
        }
    }

    /// Adds `other`'s times (a swapchain's), each name followed by `suffix`, so that a second
    /// swapchain's calls (the quad's) stay apart from the projection's.
    pub fn absorb(&mut self, other: &Calls, suffix: &str) {
        for (name, times) in &other.times {
            let name = format!("{name}{suffix}");
            times.iter().for_each(|&ms| self.record(&name, ms));
        }
    }

    /// (name, times) in frame-loop order; names of no known call last.
    pub fn in_loop_order(&self) -> Vec<(&str, &[f64])> {
        const ORDER: [&str; 6] = [
            "xrWaitFrame",
            "xrBeginFrame",
            "xrAcquireSwapchainImage",
            "xrWaitSwapchainImage",
            "xrReleaseSwapchainImage",
            "xrEndFrame",
        ];
        let rank = |name: &str| ORDER.iter().position(|o| name.starts_with(o));
        let mut calls: Vec<_> = self
            .times
            .iter()
            .map(|(n, t)| (n.as_str(), t.as_slice()))
            .collect();
        // Stable: a swapchain's calls stay before the quad's of the same kind.
        calls.sort_by_key(|(n, _)| rank(n).unwrap_or(ORDER.len()));
        calls
    }
}

/// When the first session was created, and when the first frames and the last frame ended
/// after it: how long start-up took, and the rate over the whole run.
#[derive(Default, Debug)]
pub struct Startup {
    session_created: Option<Instant>,
    /// Seconds after `session_created` that each of the first FIRST_FRAMES xrEndFrame returned.
    pub first_frames_s: Vec<f64>,
    pub last_frame_s: Option<f64>,
}

impl Startup {
    /// Called as xrCreateSession returns; with --sessions only the first one counts, so the
    /// rate covers the whole run.
    pub fn session_created(&mut self) {
        self.session_created.get_or_insert_with(Instant::now);
    }

    /// Called as the xrEndFrame of a submitted frame returns.
    pub fn frame_ended(&mut self, at: Instant) {
        let Some(created) = self.session_created else {
            return;
        };
        let s = (at - created).as_secs_f64();
        if self.first_frames_s.len() < FIRST_FRAMES {
            self.first_frames_s.push(s);
        }
        self.last_frame_s = Some(s);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn records_only_when_on_and_keeps_loop_order() {
        let mut off = Calls::new(false);
        off.record("xrEndFrame", 1.0);
        assert_eq!(off.time("xrWaitFrame", || 7), 7);
        assert!(off.in_loop_order().is_empty());
        let mut calls = Calls::new(true);
        calls.record("xrEndFrame", 3.0);
        calls.record("xrWaitFrame", 1.0);
        let mut swapchain = Calls::new(true);
        swapchain.record("xrAcquireSwapchainImage", 2.0);
        calls.absorb(&swapchain, " (quad)");
        calls.absorb(&swapchain, "");
        calls.record("xrWaitFrame", 4.0);
        let names: Vec<_> = calls.in_loop_order().iter().map(|(n, _)| *n).collect();
        assert_eq!(
            names,
            [
                "xrWaitFrame",
                "xrAcquireSwapchainImage (quad)",
                "xrAcquireSwapchainImage",
                "xrEndFrame"
            ]
        );
        assert_eq!(calls.in_loop_order()[0].1, [1.0, 4.0]);
    }

    #[test]
    fn keeps_the_first_frames_and_the_last() {
        let mut startup = Startup::default();
        startup.frame_ended(Instant::now());
        assert!(startup.last_frame_s.is_none(), "no session yet");
        startup.session_created();
        for _ in 0..FIRST_FRAMES + 5 {
            startup.frame_ended(Instant::now());
        }
        assert_eq!(startup.first_frames_s.len(), FIRST_FRAMES);
        assert!(startup.last_frame_s.unwrap() >= startup.first_frames_s[FIRST_FRAMES - 1]);
    }
}
