//! The OpenGL swapchains of `--graphics opengl` ([`super::gl_run`]): the GL formats the
//! client fills and their names, the choice among those the runtime offers, and a swapchain
//! whose textures take the test pattern by uploads each frame.

use crate::error::{Context, Result};
use crate::glx::{self, GlContext, Texture};
use crate::pattern::{image_bytes, LayerContent, Rows};
use crate::swapchain_format::SwapchainFormat;
use crate::untouched::Untouched;
use openxr as xr;

/// A swapchain format by its GL internal format, with the client's encoding of it (the same
/// bytes as the Vulkan format of that layout) and the (format, type) of its pixel transfers.
pub struct GlFormat {
    pub internal: u32,
    pub encoding: SwapchainFormat,
    pub transfer: (u32, u32),
}

/// The GL colour formats the client fills.
fn gl_formats() -> [GlFormat; 5] {
    let by = |name| SwapchainFormat::by_name(name).expect("a known format");
    [
        GlFormat {
            internal: 0x8C43,
            encoding: by("R8G8B8A8_SRGB"),
            transfer: (glx::GL_RGBA, glx::GL_UNSIGNED_BYTE),
        },
        GlFormat {
            internal: 0x8058,
            encoding: by("R8G8B8A8_UNORM"),
            transfer: (glx::GL_RGBA, glx::GL_UNSIGNED_BYTE),
        },
        GlFormat {
            internal: 0x881A,
            encoding: by("R16G16B16A16_SFLOAT"),
            transfer: (glx::GL_RGBA, glx::GL_HALF_FLOAT),
        },
        GlFormat {
            internal: 0x805B,
            encoding: by("R16G16B16A16_UNORM"),
            transfer: (glx::GL_RGBA, glx::GL_UNSIGNED_SHORT),
        },
        GlFormat {
            internal: 0x8059,
            encoding: by("A2B10G10R10_UNORM"),
            transfer: (glx::GL_RGBA, glx::GL_UNSIGNED_INT_2_10_10_10_REV),
        },
    ]
}

/// The GL name of a format (for --list-formats and errors).
pub fn gl_name(internal: u32) -> String {
    match internal {
        0x8C43 => "GL_SRGB8_ALPHA8".into(),
        0x8058 => "GL_RGBA8".into(),
        0x881A => "GL_RGBA16F".into(),
        0x805B => "GL_RGBA16".into(),
        0x8059 => "GL_RGB10_A2".into(),
        0x81A5 => "GL_DEPTH_COMPONENT16".into(),
        0x8CAC => "GL_DEPTH_COMPONENT32F".into(),
        0x88F0 => "GL_DEPTH24_STENCIL8".into(),
        0x8CAD => "GL_DEPTH32F_STENCIL8".into(),
        other => format!("GL format 0x{other:04x}"),
    }
}

/// The swapchain format of the run: `wanted` if offered, else (auto) the first offered that
/// the client can fill.
pub fn choose(wanted: Option<SwapchainFormat>, offered: &[u32]) -> Result<GlFormat> {
    // In the runtime's order: `auto` takes the first one the client can fill.
    let known = offered
        .iter()
        .filter_map(|&o| gl_formats().into_iter().find(|f| f.internal == o));
    let found = match wanted {
        Some(w) => known.into_iter().find(|f| f.encoding == w),
        None => known.into_iter().next(),
    };
    found.ok_or_else(|| {
        let names: Vec<_> = offered.iter().map(|&f| gl_name(f)).collect();
        crate::error::ClientError(format!(
            "no wanted GL format among those offered: {}",
            names.join(" ")
        ))
    })
}

/// A runtime swapchain whose GL textures the client fills with the test pattern by uploads
/// (the GL counterpart of pattern_swapchain.rs).
pub struct GlSwapchain {
    pub handle: xr::Swapchain<xr::OpenGL>,
    pub images: Vec<u32>,
    pub texture: Texture,
    /// Every layer's pattern, rows bottom first.
    pub pattern: Vec<u8>,
    pub transfer: (u32, u32),
    pub texel_bytes: usize,
    /// With --check-untouched: what became of each image after its release.
    pub check: Option<Untouched>,
    pub scratch: Vec<u8>,
}

impl GlSwapchain {
    pub fn new(
        session: &xr::Session<xr::OpenGL>,
        format: &GlFormat,
        size: (u32, u32),
        content: &[LayerContent],
        check: bool,
    ) -> Result<GlSwapchain> {
        let layers = content.len() as u32;
        let handle = session
            .create_swapchain(&xr::SwapchainCreateInfo {
                create_flags: xr::SwapchainCreateFlags::EMPTY,
                usage_flags: xr::SwapchainUsageFlags::COLOR_ATTACHMENT
                    | xr::SwapchainUsageFlags::SAMPLED,
                format: format.internal,
                sample_count: 1,
                width: size.0,
                height: size.1,
                face_count: 1,
                array_size: layers,
                mip_count: 1,
            })
            .ctx(&format!(
                "xrCreateSwapchain ({} {}x{}, arraySize {layers})",
                gl_name(format.internal),
                size.0,
                size.1
            ))?;
        let images = handle
            .enumerate_images()
            .ctx("xrEnumerateSwapchainImages")?;
        Ok(GlSwapchain {
            check: check.then(|| Untouched::new(images.len())),
            handle,
            images,
            texture: Texture {
                size,
                layers,
                array: layers > 1,
            },
            pattern: image_bytes(format.encoding, size, content, Rows::BottomFirst),
            transfer: format.transfer,
            texel_bytes: format.encoding.bytes_per_texel(),
            scratch: Vec::new(),
        })
    }

    /// Acquires and waits for the next image, checks it against what it was released with,
    /// writes `frame`'s pattern into it and releases it.
    pub fn draw(&mut self, gl: &GlContext, frame: u32) -> Result<()> {
        let index = self.handle.acquire_image().ctx("xrAcquireSwapchainImage")?;
        self.handle
            .wait_image(xr::Duration::INFINITE)
            .ctx("xrWaitSwapchainImage")?;
        let image = self.images[index as usize];
        if let Some(log) = &mut self.check {
            let same = match log.written_before(index) {
                true => {
                    let (texture, transfer) = (self.texture, self.transfer);
                    gl.read(
                        image,
                        texture,
                        transfer,
                        &mut self.scratch,
                        self.texel_bytes,
                    )?;
                    Some(self.scratch == self.pattern)
                }
                false => None,
            };
            log.record(index, frame, same);
        }
        gl.upload(image, self.texture, self.transfer, &self.pattern)?;
        self.handle.release_image().ctx("xrReleaseSwapchainImage")
    }
}

/// Whether a GL internal format is a depth (or depth-stencil) format.
pub fn is_gl_depth(format: u32) -> bool {
    matches!(format, 0x81A5 | 0x81A6 | 0x81A7 | 0x8CAC | 0x88F0 | 0x8CAD)
}
