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
