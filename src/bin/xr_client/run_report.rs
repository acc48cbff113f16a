//! The final report: one summary line, or one JSON line with `--json`.

use serde::{Serialize, Serializer};

use crate::frame_loop::Stats;
pub use crate::memory::Sample;

#[derive(Serialize, Debug, Default)]
pub struct Report {
    /// True when the session ran to its end (or to --stop-file's file, or --until-modified's
    /// count) with no OpenXR/Vulkan error and no validation error.
    pub ok: bool,
    pub frames_requested: u32,
    pub frames_submitted: u32,
    pub frames_ended: u32,
    /// The runtime's frame period (xrWaitFrame's predictedDisplayPeriod at the last frame), ms.
    pub display_period_ms: f64,
    /// With --stop-file: the run ended before --frames because the file appeared.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub stopped_by_file: bool,
    /// With --until-modified: the run ended before --frames because that many frames were
    /// found changed.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub stopped_by_modified: bool,
    pub reached_focused: bool,
    /// The session's graphics API: "vulkan" or "opengl".
    pub graphics: String,
    /// With --graphics opengl: the context's GL version and renderer.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gl: Option<String>,
    /// With --graphics opengl: the session's binding, "xlib" or "egl" (--gl-binding).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gl_binding: Option<String>,
    pub format: String,
    pub layout: String,
    pub views: u32,
    pub view_size: [u32; 2],
    pub quad: bool,
    pub blend_mode: String,
    pub runtime: String,
    /// The runtime lists XR_KHR_convert_timespec_time (the client never enables it).
    pub timespec_offered: bool,
    /// xrGetInstanceProcAddr's result for xrConvertTimespecTimeToTimeKHR.
    pub timespec_lookup: String,
    pub vk_validation: bool,
    pub vk_validation_errors: u32,
    pub vk_validation_warnings: u32,
    pub errors: Vec<String>,
    pub sessions_run: u32,
    /// With --check-untouched: images read back, and the frames whose image had changed.
    pub frames_checked: u32,
    pub frames_modified: Vec<u32>,
    /// With --check-gl-state: the xrEndFrame calls around which the GL state was checked, and
    /// every item one of them changed (empty when all held).
    pub gl_state_checked: u32,
    pub gl_state_changed: Vec<crate::gl_state::Change>,
    /// With --egl-bind-es: the xrEndFrame calls (EGL_OPENGL_ES_API bound before each) after
    /// which eglQueryAPI was read, and the frames after which it answered another API (empty
    /// when it never did).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub egl_api_checked: Option<u32>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub egl_api_changed: Option<Vec<u32>>,
    /// With --x-errors-elsewhere: the X errors the client's thread made, and those its handler
    /// saw.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub x_errors_made: Option<u64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub x_errors_seen: Option<u64>,
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
    /// The longest xrDestroySession and xrDestroyInstance, in ms (the layer's teardown).
    pub teardown_ms: Teardown,
    /// Calls of the vkGetInstanceProcAddr the client gave the runtime, made inside its
    /// xrCreateSession calls (by the runtime and the API layers).
    pub vk_gipa_calls_in_create_session: u32,
    /// With --linger-ms: what of the layer is left after the last xrDestroyInstance.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub after_instances: Option<crate::leftovers::Leftovers>,
}

/// The longest destroy calls of the run, in milliseconds.
#[derive(Serialize, Debug, Default)]
pub struct Teardown {
    #[serde(rename = "xrDestroySession")]
    pub destroy_session: f64,
    #[serde(rename = "xrDestroyInstance")]
    pub destroy_instance: f64,
}

impl Teardown {
    pub fn session(&mut self, took: std::time::Duration) {
        self.destroy_session = self.destroy_session.max(took.as_secs_f64() * 1e3);
    }

    pub fn instance(&mut self, took: std::time::Duration) {
        self.destroy_instance = self.destroy_instance.max(took.as_secs_f64() * 1e3);
    }
}

/// Per-frame times in milliseconds over the frames after the first `warm_up` (the steady
/// state), then what the first frames cost (start-up).
#[derive(Serialize, Debug, Default)]
pub struct Timing {
    pub frames: usize,
    pub warm_up: usize,
    pub end_frame_ms_median: f64,
    pub end_frame_ms_p95: f64,
    pub drain_ms_median: f64,
    pub drain_ms_p95: f64,
    /// Each frame-loop call's wall time over every frame, warm-up included, by call name
    /// (`xrWaitFrame`, ..., a quad's swapchain calls with ` (quad)` after the name).
    pub calls: CallTable,
    /// xrCreateInstance, xrCreateSession and xrCreateSwapchain (the projection's, with the
    /// client's set-up of its images), each session's, by call name.
    pub create_calls: CallTable,
    /// Seconds from xrCreateSession returning (the first session's) to the return of each of the
    /// first 30 submitted frames' xrEndFrame.
    pub first_frames_s: Vec<f64>,
    /// Seconds from xrCreateSession returning to the last submitted frame's xrEndFrame, and the
    /// submitted frames per second over that time (null without a submitted frame).
    pub session_to_last_frame_s: Option<f64>,
    pub frames_per_second: Option<f64>,
    /// Seconds from the client's start to its report.
    pub run_s: f64,
}

/// One call's wall times over the run.
#[derive(Serialize, Debug)]
pub struct CallTime {
    pub median_ms: f64,
    pub p95_ms: f64,
    pub max_ms: f64,
    pub count: usize,
}

/// Serialised as one JSON object keyed by call name, in frame-loop order.
#[derive(Debug, Default)]
pub struct CallTable(pub Vec<(String, CallTime)>);

impl Serialize for CallTable {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        serializer.collect_map(self.0.iter().map(|(name, time)| (name, time)))
    }
}

impl CallTable {
    fn new(calls: &crate::timing::Calls) -> CallTable {
        let time = |ms: &[f64]| CallTime {
            median_ms: percentile(ms, 0.5),
            p95_ms: percentile(ms, 0.95),
            max_ms: percentile(ms, 1.0),
            count: ms.len(),
        };
        CallTable(
            calls
                .in_loop_order()
                .into_iter()
                .map(|(name, ms)| (name.to_string(), time(ms)))
                .collect(),
        )
    }
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
    /// `run_s`: the client's wall time so far.
    pub fn new(stats: &Stats, run_s: f64) -> Timing {
        let skip = WARM_UP_FRAMES.min(stats.end_frame_ms.len() / 2);
        let (e, d) = (&stats.end_frame_ms[skip..], &stats.drain_ms[skip..]);
        let startup = &stats.startup;
        // Microseconds are plenty for start-up, and keep the JSON line short.
        let first_frames_s = startup.first_frames_s.iter();
        Timing {
            frames: e.len(),
            warm_up: skip,
            end_frame_ms_median: percentile(e, 0.5),
            end_frame_ms_p95: percentile(e, 0.95),
            drain_ms_median: percentile(d, 0.5),
            drain_ms_p95: percentile(d, 0.95),
            calls: CallTable::new(&stats.calls),
            create_calls: CallTable::new(&stats.create_calls),
            first_frames_s: first_frames_s.map(|s| (s * 1e6).round() / 1e6).collect(),
            session_to_last_frame_s: startup.last_frame_s,
            frames_per_second: startup
                .last_frame_s
                .map(|s| f64::from(stats.frames_submitted) / s),
            run_s,
        }
    }

    /// The same, for people: a few lines.
    pub fn text(&self) -> String {
        let mut text = format!(
            "timing: xrEndFrame {:.3} ms median, {:.3} ms p95; drain after it {:.3} ms median, \
             {:.3} ms p95 ({} frames after {} warm-up)\n",
            self.end_frame_ms_median,
            self.end_frame_ms_p95,
            self.drain_ms_median,
            self.drain_ms_p95,
            self.frames,
            self.warm_up
        );
        for (name, t) in self.calls.0.iter().chain(&self.create_calls.0) {
            text += &format!(
                "  {name:<31} median {:>8.3} ms, p95 {:>8.3} ms, max {:>8.3} ms, {} calls\n",
                t.median_ms, t.p95_ms, t.max_ms, t.count
            );
        }
        let firsts: Vec<_> = self
            .first_frames_s
            .iter()
            .map(|s| format!("{s:.3}"))
            .collect();
        text += &format!(
            "  first frames ended, s after xrCreateSession: {}\n",
            firsts.join(" ")
        );
        let or_na =
            |v: Option<f64>, digits: usize| v.map_or("n/a".into(), |v| format!("{v:.digits$}"));
        text + &format!(
            "  session to last frame {} s, {} frames/s; run {:.3} s",
            or_na(self.session_to_last_frame_s, 3),
            or_na(self.frames_per_second, 2),
            self.run_s
        )
    }
}

impl Report {
    pub fn summary(&self) -> String {
        format!(
            "contrastxr-xr-client: {} - {} of {} frames submitted{}, {} {} {}x{}{}, blend {}, \
             runtime {}, vulkan validation {} errors {} warnings{}",
            if self.ok { "ok" } else { "FAILED" },
            self.frames_submitted,
            self.frames_requested,
            if self.stopped_by_file {
                " (ended by --stop-file)"
            } else if self.stopped_by_modified {
                " (ended by --until-modified)"
            } else {
                ""
            },
            self.format,
            self.layout,
            self.view_size[0],
            self.view_size[1],
            if self.quad { " + quad" } else { "" },
            self.blend_mode,
            self.runtime,
            self.vk_validation_errors,
            self.vk_validation_warnings,
            self.errors
                .iter()
                .map(|e| format!("; error: {e}"))
                .collect::<String>(),
        )
    }

    pub fn json(&self) -> String {
        serde_json::to_string(self).expect("the report serialises")
    }
}
