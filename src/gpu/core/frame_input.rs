//! What a frame gives every backend besides its views: the background.

use crate::gpu::core::blurred_texels::BlurredTexels;
use crate::image::RgbaImage;

/// The background of a frame: the newest camera image, its texels when its source prepared
/// them (gpu/vulkan/frame/prepared_background.rs), and its sequence number (a new number is a new camera
/// frame).
pub struct BackgroundInput<'a> {
    pub image: &'a RgbaImage,
    pub prepared: Option<&'a BlurredTexels>,
    pub sequence: u64,
}
