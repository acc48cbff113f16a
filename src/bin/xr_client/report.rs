//! The final report: one summary line, or one JSON line with `--json`.

use serde::Serialize;

#[derive(Serialize, Debug, Default)]
pub struct Report {
    /// True when the session ran to its end with no OpenXR/Vulkan error and no validation error.
    pub ok: bool,
    pub frames_requested: u32,
    pub frames_submitted: u32,
    pub frames_ended: u32,
    pub reached_focused: bool,
    pub format: String,
    pub layout: String,
    pub views: u32,
    pub view_size: [u32; 2],
    pub quad: bool,
    pub blend_mode: String,
    pub runtime: String,
    pub vk_validation: bool,
    pub vk_validation_errors: u32,
    pub vk_validation_warnings: u32,
    pub errors: Vec<String>,
    pub sessions_run: u32,
    /// With --check-untouched: images read back, and the frames whose image had changed.
    pub frames_checked: u32,
    pub frames_modified: Vec<u32>,
    /// Every 50 submitted frames.
    pub memory: Vec<Sample>,
    /// After each session was destroyed.
    pub sessions: Vec<Sample>,
    /// With --churn-swapchains: swapchains created and destroyed by the second thread.
    pub swapchains_churned: u32,
    /// With --script: each op and the XrResult it got (`acquire SUCCESS 0`).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub script: Vec<String>,
    /// With --timing.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub timing: Option<Timing>,
}

/// The process's resident memory and open file descriptors at one moment.
#[derive(Serialize, Debug, Default, Clone)]
pub struct Sample {
    pub frames: u32,
    pub rss_kb: u64,
    pub fds: u64,
}

impl Sample {
    pub fn now(frames: u32) -> Sample {
        let statm = std::fs::read_to_string("/proc/self/statm").unwrap_or_default();
        let pages: u64 = statm
            .split_whitespace()
            .nth(1)
            .and_then(|v| v.parse().ok())
            .unwrap_or(0);
        // SAFETY: sysconf has no preconditions.
        let page = unsafe { libc::sysconf(libc::_SC_PAGESIZE) }.max(0) as u64;
        let fds = std::fs::read_dir("/proc/self/fd").map_or(0, |d| d.count() as u64);
        Sample {
            frames,
            rss_kb: pages * page / 1024,
            fds,
        }
    }
}

/// Per-frame times in milliseconds over the frames after the first `warm_up`.
#[derive(Serialize, Debug, Default)]
pub struct Timing {
    pub frames: usize,
    pub warm_up: usize,
    pub end_frame_ms_median: f64,
    pub end_frame_ms_p95: f64,
    pub drain_ms_median: f64,
    pub drain_ms_p95: f64,
}

/// Frames left out of the timing (pipeline compiles, first allocations).
const WARM_UP_FRAMES: usize = 10;

fn percentile(v: &[f64], p: f64) -> f64 {
    let mut v = v.to_vec();
    v.sort_by(f64::total_cmp);
    v.get(((v.len() as f64 - 1.0) * p).round() as usize)
        .copied()
        .unwrap_or(f64::NAN)
}

impl Timing {
    pub fn new(end_frame_ms: &[f64], drain_ms: &[f64]) -> Timing {
        let skip = WARM_UP_FRAMES.min(end_frame_ms.len() / 2);
        let (e, d) = (&end_frame_ms[skip..], &drain_ms[skip..]);
        Timing {
            frames: e.len(),
            warm_up: skip,
            end_frame_ms_median: percentile(e, 0.5),
            end_frame_ms_p95: percentile(e, 0.95),
            drain_ms_median: percentile(d, 0.5),
            drain_ms_p95: percentile(d, 0.95),
        }
    }
}

impl Report {
    pub fn summary(&self) -> String {
        format!(
            "contrastxr-xr-client: {} - {} of {} frames submitted, {} {} {}x{}{}, blend {}, runtime {}, \
             vulkan validation {} errors {} warnings{}",
            if self.ok { "ok" } else { "FAILED" },
            self.frames_submitted,
            self.frames_requested,
            self.format,
            self.layout,
            self.view_size[0],
            self.view_size[1],
            if self.quad { " + quad" } else { "" },
            self.blend_mode,
            self.runtime,
            self.vk_validation_errors,
            self.vk_validation_warnings,
            self.errors.iter().map(|e| format!("; error: {e}")).collect::<String>(),
        )
    }

    pub fn json(&self) -> String {
        serde_json::to_string(self).expect("the report serialises")
    }
}
