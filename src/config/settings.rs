//! The layer's effective settings: what one app's sessions run with.

use crate::algorithm::params::Params;
use crate::algorithm::registration::{CameraProfile, Lens, Nudge, Pose};
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
    /// The display's true blend mode is ADDITIVE though its runtime may report another
    /// (`environment_blend_mode = "additive"`); false: trust the runtime.
    pub additive_display: bool,
    /// The headset has a colour camera the layer can use as its background (false in the
    /// shipped profiles of glasses without one: a `v4l2:` background then needs a camera of
    /// the user's own).
    pub colour_camera: bool,
    /// Also enhance quad layers.
    pub quad_layers: bool,
    /// Whether the app's images are enhanced in place (read when a swapchain is created).
    pub in_place: InPlace,
    /// How the image-copy path brings a view back into the app's image (read when a swapchain
    /// is created).
    pub copy_back: CopyBack,
    pub copy_in: CopyIn,
    /// `pipelines = "wait"`: the first frame that needs a pipeline waits for its build instead
    /// of passing through.
    pub wait_for_pipelines: bool,
    /// The method's settings, with `mode` (what the layer shows).
    pub params: Params,
    /// Background source spec: `v4l2:auto` (default), `v4l2:/dev/videoN`, `image:PATH`,
    /// `video:PATH` or `color:#RRGGBB`.
    pub background: String,
    /// How a camera source is opened: wanted size and rate, temporal smoothing.
    pub camera: CaptureConfig,
    /// Where the camera is and what it sees: per-view registration, per-eye corrections.
    pub registration: Registration,
    /// Keeping the background on the world while the head moves.
    pub motion: Motion,
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

/// Whether views are enhanced in place in the app's images (`in_place`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum InPlace {
    /// In place, except on CPU drivers (their image copies are cheaper than storage-image
    /// access, measured in docs/performance.md).
    Auto,
    /// In place wherever the runtime and the device allow it.
    On,
    /// Always through a copy of each view.
    Off,
}

impl InPlace {
    pub fn parse(text: &str) -> Option<InPlace> {
        match text.trim().to_ascii_lowercase().as_str() {
            "auto" => Some(InPlace::Auto),
            "on" | "1" | "true" | "yes" => Some(InPlace::On),
            "off" | "0" | "false" | "no" => Some(InPlace::Off),
            _ => None,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            InPlace::Auto => "auto",
            InPlace::On => "on",
            InPlace::Off => "off",
        }
    }
}

/// How a view enhanced through an image of the layer's own comes back into the app's image
/// (`copy_back`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CopyBack {
    /// The whole region copied back (vkCmdCopyImage).
    Region,
    /// Only the tiles the enhancement listed, drawn into the app's image (a render pass).
    Tiles,
}

impl CopyBack {
    pub fn parse(text: &str) -> Option<CopyBack> {
        match text.trim().to_ascii_lowercase().as_str() {
            "region" => Some(CopyBack::Region),
            "tiles" => Some(CopyBack::Tiles),
            _ => None,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            CopyBack::Region => "region",
            CopyBack::Tiles => "tiles",
        }
    }
}

/// How a view enhanced through an image of the layer's own gets the app's pixels (`copy_in`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CopyIn {
    /// Sampled on a GPU, region on a CPU driver (docs/performance.md says why).
    Auto,
    /// The region copied into the layer's image first (vkCmdCopyImage).
    Region,
    /// Read through a sampled view of the app's image (8-bit sRGB), the listed tiles drawn
    /// back.
    Sampled,
}

impl CopyIn {
    pub fn parse(text: &str) -> Option<CopyIn> {
        match text.trim().to_ascii_lowercase().as_str() {
            "auto" => Some(CopyIn::Auto),
            "region" => Some(CopyIn::Region),
            "sampled" => Some(CopyIn::Sampled),
            _ => None,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            CopyIn::Auto => "auto",
            CopyIn::Region => "region",
            CopyIn::Sampled => "sampled",
        }
    }
}

impl Default for Settings {
    fn default() -> Self {
        Settings {
            enabled: true,
            force: false,
            additive_display: false,
            colour_camera: true,
            quad_layers: false,
            in_place: InPlace::Auto,
            copy_back: CopyBack::Region,
            copy_in: CopyIn::Auto,
            wait_for_pipelines: false,
            params: Params::default(),
            background: "v4l2:auto".into(),
            camera: CaptureConfig::default(),
            registration: Registration::default(),
            motion: Motion::default(),
            capture_dir: None,
            capture_frames: 1,
            capture_skip: 0,
            indicator: true,
            indicator_seconds: 3.0,
            generation: 0,
        }
    }
}

/// The camera profile and the per-eye corrections, as the config gives them.
#[derive(Clone, Debug, PartialEq)]
pub struct Registration {
    /// The camera's full field of view [horizontal, vertical], degrees; [0, 0]: not given.
    pub camera_fov: [f32; 2],
    /// [fx, fy, cx, cy, width, height], pixels (OpenCV's); all 0: not given. Beats camera_fov.
    pub camera_intrinsics: [f32; 6],
    /// The camera's position relative to the head (OpenXR VIEW space: the point between the
    /// eyes, +x right, +y up, -z forward), metres.
    pub camera_position: [f32; 3],
    /// [pitch, yaw, roll] of the camera relative to the head, degrees.
    pub camera_rotation: [f32; 3],
    /// The distance registered exactly, metres (> 0).
    pub scene_distance: f32,
    /// Per-eye corrections on top of the mapping (see [`Nudge`]): [left, right].
    pub eye_offset: [[f32; 2]; 2],
    /// Per-eye scale of the background picture (> 0): [left, right].
    pub eye_scale: [[f32; 2]; 2],
}

impl Default for Registration {
    fn default() -> Self {
        Registration {
            camera_fov: [0.0, 0.0],
            camera_intrinsics: [0.0; 6],
            camera_position: [0.0; 3],
            camera_rotation: [0.0; 3],
            scene_distance: 2.0,
            eye_offset: [[0.0, 0.0]; 2],
            eye_scale: [[1.0, 1.0]; 2],
        }
    }
}

/// Motion compensation: the camera frame's capture time and the head's pose then.
#[derive(Clone, Debug, PartialEq)]
pub struct Motion {
    /// Map each view from the camera at capture to the eye at display (false: head-fixed).
    pub compensation: bool,
    /// Added to each camera frame's age: for cameras whose timestamps are late, milliseconds.
    pub camera_latency_ms: f32,
}

impl Default for Motion {
    fn default() -> Self {
        Motion {
            compensation: true,
            camera_latency_ms: 0.0,
        }
    }
}

/// The eyes as the config names them; a projection layer's view 0 is the left eye, 1 the right.
pub const EYES: [&str; 2] = ["left", "right"];

impl Registration {
    /// The camera profile, if the config gives the camera's lens.
    pub fn profile(&self) -> Option<CameraProfile> {
        let f = |x: f32| f64::from(x);
        let lens = match Lens::from_intrinsics(self.camera_intrinsics) {
            Some(lens) => lens,
            None if self.camera_fov != [0.0, 0.0] => Lens::Fov {
                horizontal: f(self.camera_fov[0]).to_radians(),
                vertical: f(self.camera_fov[1]).to_radians(),
            },
            None => return None,
        };
        Some(CameraProfile {
            lens,
            pose: Pose::from_position_pitch_yaw_roll(
                self.camera_position.map(f),
                self.camera_rotation.map(f),
            ),
            scene_distance: f(self.scene_distance),
        })
    }

    /// The correction of eye `eye` (0 left, 1 right); none for other views.
    pub fn nudge(&self, eye: usize) -> Nudge {
        match (self.eye_offset.get(eye), self.eye_scale.get(eye)) {
            (Some(o), Some(s)) => Nudge {
                offset: glam::DVec2::new(f64::from(o[0]), f64::from(o[1])),
                scale: glam::DVec2::new(f64::from(s[0]), f64::from(s[1])),
            },
            _ => Nudge::NONE,
        }
    }
}

impl Settings {
    /// Whether `fov_scale`/`fov_offset` differ from their defaults: the manual mapping then
    /// overrides the camera profile. (By value, not by where it was written: the example
    /// config, which spells out every default, must not switch registration off.)
    pub fn manual_mapping_set(&self) -> bool {
        let defaults = Params::default();
        self.params.fov_scale != defaults.fov_scale || self.params.fov_offset != defaults.fov_offset
    }

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
}
