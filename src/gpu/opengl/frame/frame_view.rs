//! One view the OpenGL engine enhances: which texture, where in it, and how its pixels map
//! onto the camera.

use crate::algorithm::mapping::CameraMapping;

/// Where a view's texels are in the app's texture.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GlTarget {
    Texture2D,
    /// A layer of a 2D array texture.
    Texture2DArray {
        layer: u32,
    },
}

/// One view to enhance: a region of one of the app's textures.
#[derive(Clone, Copy, Debug)]
pub struct GlView {
    /// The texture's name in the app's context.
    pub texture: u32,
    pub target: GlTarget,
    /// Its internal format (GL_RGBA8, GL_SRGB8_ALPHA8, GL_RGBA16, GL_RGBA16F, GL_RGB10_A2).
    pub internal_format: u32,
    /// The region, in texels, as GL counts them: (x, y) its lower left corner, then width and
    /// height (an OpenXR imageRect of an OpenGL swapchain as it is).
    pub rect: (u32, u32, u32, u32),
    /// Display uv (v from the view's top edge) to camera uv, as the Vulkan path takes it.
    pub mapping: CameraMapping,
    /// The view's display pixels per degree (the perceptual model's frequency needs it).
    pub pixels_per_degree: f64,
}
