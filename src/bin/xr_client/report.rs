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
