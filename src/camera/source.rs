//! Source specs (`CONTRASTXR_BACKGROUND`) and capture settings.

use std::path::PathBuf;
use std::time::Duration;

/// Which background to use, parsed from a spec string by [`parse_source`].
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum SourceSpec {
    /// `v4l2:/dev/videoN`: this capture device.
    V4l2Device(PathBuf),
    /// `v4l2:auto`: the first capture device, looked up again on each reopen.
    V4l2Auto,
    /// `image:PATH`: one PNG or JPEG, static.
    Image(PathBuf),
    /// `video:PATH`: a folder of numbered PNG frames or a Y4M file, looped.
    Video(PathBuf),
    /// `color:#RRGGBB`: a flat sRGB colour, static.
    Color([u8; 3]),
    /// `world:PATH`: a simulated head-mounted camera looking at an equirectangular panorama
    /// (PNG or JPEG) fixed in the world.
    World(PathBuf),
}

/// Parses a background spec such as `v4l2:/dev/video0` or `color:#204080`.
pub fn parse_source(spec: &str) -> Result<SourceSpec, String> {
    let spec = spec.trim();
    let Some((kind, rest)) = spec.split_once(':') else {
        return Err(format!(
            "background source '{spec}' has no kind: use v4l2:, image:, video:, world: or color:"
        ));
    };
    if rest.is_empty() {
        return Err(format!(
            "background source '{spec}' is missing what follows '{kind}:'"
        ));
    }
    match kind {
        "v4l2" if rest == "auto" => Ok(SourceSpec::V4l2Auto),
        "v4l2" => Ok(SourceSpec::V4l2Device(PathBuf::from(rest))),
        "image" => Ok(SourceSpec::Image(PathBuf::from(rest))),
        "video" => Ok(SourceSpec::Video(PathBuf::from(rest))),
        "world" => Ok(SourceSpec::World(PathBuf::from(rest))),
        "color" | "colour" => parse_color(rest).map(SourceSpec::Color),
        _ => Err(format!(
            "background source kind '{kind}' is unknown: use v4l2:, image:, video:, world: or color:"
        )),
    }
}

fn parse_color(text: &str) -> Result<[u8; 3], String> {
    let hex = text.strip_prefix('#').unwrap_or(text);
    let valid = hex.len() == 6 && hex.chars().all(|c| c.is_ascii_hexdigit());
    if !valid {
        return Err(format!(
            "background colour '{text}' is not of the form #RRGGBB"
        ));
    }
    let byte = |i: usize| u8::from_str_radix(&hex[i..i + 2], 16).expect("checked hex digits");
    Ok([byte(0), byte(2), byte(4)])
}

/// The largest camera width or height a setting may ask for. A file source is made at the
/// camera size (a `color:` background, a `world:` camera) or shrunk to it (`image:`, `video:`),
/// so this bounds what one of its frames costs: 8192 x 8192 RGBA is 256 MiB.
pub const MAX_CAMERA_SIDE: u32 = 8192;

/// How to open and supervise a source. `Default` gives the documented defaults.
#[derive(Clone, Debug, PartialEq)]
pub struct CaptureConfig {
    /// Wanted camera width; the smallest offered size at least this wide is chosen (640).
    /// The settings take at most [`MAX_CAMERA_SIDE`].
    pub width: u32,
    /// Wanted camera height (480), at most [`MAX_CAMERA_SIDE`] as the width.
    pub height: u32,
    /// Wanted camera rate in frames per second; the lowest offered rate >= this (30).
    pub fps: u32,
    /// Frame rate of a `video:` folder of PNG frames (Y4M files carry their own) (30).
    pub video_fps: f64,
    /// No new camera frame for this long counts as a stall: the stream is reopened (1 s).
    pub stall_timeout: Duration,
    /// How long the last good frame is kept after a loss or stall before `Lost` (2 s).
    pub grace: Duration,
    /// Longest wait between reopen attempts; waits double from 100 ms up to this (2 s).
    pub max_backoff: Duration,
    /// Temporal smoothing: weight of the newest frame in an exponential moving average of
    /// the background, in (0, 1]; `None` (the default) is off.
    pub smoothing: Option<f32>,
    /// Fixed exposure, white balance and gain (None: the camera's automatic control).
    pub controls: CameraControls,
    /// The cameras `v4l2:auto` takes before any other, best first (the headset's own camera,
    /// named by its device profile); empty: none.
    pub usb_ids: Vec<super::usb_id::UsbId>,
    /// `world:` source: milliseconds between a frame's capture and its delivery (50).
    pub world_latency_ms: f32,
    /// `world:` source: the simulated camera and the head poses it is carried by (set by the
    /// consumer when it opens the source; None in settings).
    pub world: Option<super::rig::WorldRig>,
    /// The blur a still background (`image:`, `color:`) is prepared with as it is loaded, on
    /// the loading thread (set by the consumer when it opens the source; None in settings:
    /// the consumer prepares it).
    pub still_blur: Option<crate::gpu::core::blurred_texels::BlurTaps>,
}

/// Camera settings that otherwise drift (automatic exposure, white balance, gain), each either
/// left to the camera (None) or fixed, so that a drift does not become a change of tint.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CameraControls {
    /// Exposure time in microseconds.
    pub exposure_us: Option<u32>,
    /// White balance as a colour temperature in kelvin.
    pub white_balance_k: Option<u32>,
    /// Gain, in the camera's own units.
    pub gain: Option<u32>,
}

impl Default for CaptureConfig {
    fn default() -> Self {
        CaptureConfig {
            width: 640,
            height: 480,
            fps: 30,
            video_fps: 30.0,
            stall_timeout: Duration::from_secs(1),
            grace: Duration::from_secs(2),
            max_backoff: Duration::from_secs(2),
            smoothing: None,
            controls: CameraControls::default(),
            usb_ids: Vec::new(),
            world_latency_ms: 50.0,
            world: None,
            still_blur: None,
        }
    }
}

impl CaptureConfig {
    /// The size a file source's frames are made at or shrunk to: the wanted camera size, each
    /// side within 1..=[`MAX_CAMERA_SIDE`] also when the config was built by hand, not from
    /// the settings.
    pub fn frame_size(&self) -> (u32, u32) {
        let side = |n: u32| n.clamp(1, MAX_CAMERA_SIDE);
        (side(self.width), side(self.height))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_each_kind() {
        assert_eq!(parse_source("v4l2:auto"), Ok(SourceSpec::V4l2Auto));
        assert_eq!(
            parse_source("v4l2:/dev/video2"),
            Ok(SourceSpec::V4l2Device("/dev/video2".into()))
        );
        assert_eq!(
            parse_source("image:a.png"),
            Ok(SourceSpec::Image("a.png".into()))
        );
        assert_eq!(
            parse_source(" video:/x/y.y4m "),
            Ok(SourceSpec::Video("/x/y.y4m".into()))
        );
        assert_eq!(
            parse_source("color:#FF8001"),
            Ok(SourceSpec::Color([255, 128, 1]))
        );
        assert_eq!(
            parse_source("world:/p/pano.jpg"),
            Ok(SourceSpec::World("/p/pano.jpg".into()))
        );
    }

    #[test]
    fn rejects_bad_specs_with_a_sentence() {
        for bad in [
            "",
            "webcam",
            "v4l2:",
            "color:#12345",
            "color:#GG0000",
            "file:x",
        ] {
            let err = parse_source(bad).unwrap_err();
            assert!(err.starts_with("background "), "{bad}: {err}");
        }
    }
}
