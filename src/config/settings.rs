//! The layer's effective settings: what one app's sessions run with.

use crate::algorithm::params::Params;
use crate::camera::CaptureConfig;
use std::path::PathBuf;

#[derive(Clone, Debug, PartialEq)]
pub struct Capture {
    pub dir: PathBuf,
    /// How many frames to capture, after `skip` frames have passed.
    pub frames: u64,
    pub skip: u64,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Settings {
    /// False when CONTRASTXR is 0/false/off/empty: everything passes through, no GPU work.
    /// Read from the environment only: the loader's switch for the implicit layer.
    pub enabled: bool,
    /// Act on any environment blend mode, not only ADDITIVE.
    pub force: bool,
    /// Also enhance quad layers.
    pub quad_layers: bool,
    /// The method's settings, with `mode` (what the layer shows).
    pub params: Params,
    /// Background source spec: `v4l2:auto` (default), `v4l2:/dev/videoN`, `image:PATH`,
    /// `video:PATH` or `color:#RRGGBB`.
    pub background: String,
    /// How a camera source is opened: wanted size and rate, temporal smoothing.
    pub camera: CaptureConfig,
    /// Where captures go; None: no capture.
    pub capture_dir: Option<PathBuf>,
    pub capture_frames: u64,
    pub capture_skip: u64,
    /// Show the mode and lambda_e in the eye image for `indicator_seconds` after the first
    /// processed frame and after each change of settings.
    pub indicator: bool,
    pub indicator_seconds: f32,
    /// Grows by one with each reload that changed a value: a session holding an older
    /// generation picks up the newer settings at its next xrEndFrame.
    pub generation: u64,
}

impl Default for Settings {
    fn default() -> Self {
        Settings {
            enabled: true,
            force: false,
            quad_layers: false,
            params: Params::default(),
            background: "v4l2:auto".into(),
            camera: CaptureConfig::default(),
            capture_dir: None,
            capture_frames: 1,
            capture_skip: 0,
            indicator: true,
            indicator_seconds: 3.0,
            generation: 0,
        }
    }
}

impl Settings {
    pub fn capture(&self) -> Option<Capture> {
        self.capture_dir.as_ref().map(|dir| Capture {
            dir: dir.clone(),
            frames: self.capture_frames,
            skip: self.capture_skip,
        })
    }

    /// Equal apart from `generation`: whether a reload changed anything.
    pub fn same_values(&self, other: &Settings) -> bool {
        Settings {
            generation: other.generation,
            ..self.clone()
        } == *other
    }

    /// The one startup line's parameter part.
    pub fn describe(&self) -> String {
        let p = &self.params;
        format!(
            "mode={} method={} lambda_e={} lambda_jnd_scaled={} transmittance={} achromatic_boost={} luminance_cap={} blur={}x{}/{} fov_scale={:?} fov_offset={:?} fov={} background={} force={} quad_layers={} capture={}",
            p.mode.name(),
            p.method.name(),
            p.lambda_e,
            p.lambda_jnd_scaled,
            p.transmittance,
            p.achromatic_boost,
            p.luminance_cap,
            if p.blur { p.blur_size } else { 1 },
            if p.blur { p.blur_size } else { 1 },
            p.blur_sigma,
            p.fov_scale,
            p.fov_offset,
            p.fov,
            self.background,
            self.force,
            self.quad_layers,
            self.capture_dir
                .as_ref()
                .map_or("off".into(), |d| d.display().to_string()),
        )
    }
}
