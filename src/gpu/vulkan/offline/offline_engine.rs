//! The engine on a device of its own, for the command-line tool and the tests: upload, record,
//! submit, wait, read back.

use crate::algorithm::mapping::CameraMapping;
use crate::algorithm::params::Params;
use crate::gpu::core::blurred_texels::{BlurTaps, BlurredTexels};
use crate::gpu::core::{CameraRect, ClassifyChoice, CubeRoots};
use crate::gpu::core::{OfflineBackend, PixelFormat, PixelLayout};
use crate::gpu::vulkan::device::{barrier, Commands, DeviceOptions, GpuDevice, GpuError};
use crate::gpu::vulkan::pipelines::BuildMode;
use crate::gpu::vulkan::record::{
    CameraResources, PixelsIn, Placement, Recorder, ViewShape, ViewTarget,
};
use crate::gpu::vulkan::texels::staging_buffer;
use crate::image::RgbaImage;
use ash::vk;
use std::cell::RefCell;

pub struct VkOffline {
    pub(super) engine: Recorder,
    /// RefCell: `submit` records through `&self` (the engine and device are only read).
    commands: RefCell<Commands>,
    /// Enhance with the background's texels prepared on the CPU and copied in, as the layer
    /// does for live sources, instead of the decode and blur passes (`set_cpu_background`).
    cpu_background: bool,
    // Declared last: dropped after the objects above are destroyed in Drop.
    pub gpu: GpuDevice,
}

/// The prepared background read back from the GPU: the blurred camera image, linear light,
/// on the camera grid (row-major).
pub struct BackgroundReadBack {
    pub width: u32,
    pub height: u32,
    pub linear: Vec<[f32; 3]>,
    /// The second texel of each entry: its right neighbour (itself in the last column).
    pub right: Vec<[f32; 3]>,
}

fn words_to_bytes(words: &[u32]) -> Vec<u8> {
    words.iter().flat_map(|w| w.to_le_bytes()).collect()
}

/// `unpack_linear` of shaders/common.wgsl: three LINEAR_BITS-bit codes over [0, 1] in two
/// little-endian u32 words.
fn unpack_linear(bytes: &[u8]) -> [f32; 3] {
    use crate::gpu::core::interface::{LINEAR_BITS, LINEAR_MAX};
    let packed = u64::from_le_bytes(bytes.try_into().expect("8 bytes"));
    std::array::from_fn(|k| {
        ((packed >> (LINEAR_BITS as usize * k)) & u64::from(LINEAR_MAX)) as f32 / LINEAR_MAX as f32
    })
}

impl VkOffline {
    /// The first Vulkan device (or `CONTRASTXR_VK_DEVICE`), validation per `CONTRASTXR_VK_VALIDATION`.
    pub fn new() -> Result<VkOffline, GpuError> {
        Self::with_options(&DeviceOptions::from_env())
    }

    pub fn with_options(options: &DeviceOptions) -> Result<VkOffline, GpuError> {
        Self::with_views(options, 4)
    }

    /// As `with_options`, holding up to `max_views` views at once (each takes a descriptor
    /// set of the engine's pool, which refuses more on every driver).
    pub fn with_views(options: &DeviceOptions, max_views: u32) -> Result<VkOffline, GpuError> {
        let gpu = GpuDevice::create(options)?;
        let engine = Recorder::new(&gpu, max_views, BuildMode::Inline, None)?;
        let commands = RefCell::new(Commands::new(&gpu)?);
        Ok(VkOffline {
            engine,
            commands,
            cpu_background: false,
            gpu,
        })
    }

    /// From now on, enhances with the background's texels prepared on the CPU
    /// (crate::gpu::core::blurred_texels) and copied into the sampled image, as the layer does for live
    /// sources, instead of the GPU's decode and blur passes; false goes back to those.
    pub fn set_cpu_background(&mut self, on: bool) {
        self.cpu_background = on;
    }

    /// Whether views whose mapping allows it take the shared-fetch `enhance` variant (on by
    /// default; gpu/core/shared_fetch.rs); off, every view takes the general one, to compare them.
    pub fn set_shared_fetch(&mut self, on: bool) {
        self.engine.set_shared_fetch(on);
    }

    /// How views take the CIELAB cube roots: the device's way by default
    /// (`CubeRoots::for_device`); the other, to compare them or to test it on this device.
    pub fn set_cube_roots(&mut self, roots: CubeRoots) {
        self.engine.set_cube_roots(roots);
    }

    pub fn cube_roots(&self) -> CubeRoots {
        self.engine.cube_roots()
    }

    /// The benchmark's ablations (interface.rs ABLATE_*; 0 for none): from now on views take
    /// the ablated `enhance` (the paper's or the perceptual method on RGBA8 sRGB only), whose
    /// output is not an enhancement.
    pub fn set_ablation(&mut self, ablate: u32) {
        self.engine.set_ablation(ablate);
    }

    /// Which `classify` views take (their method's own by default; `ClassifyChoice`).
    pub fn set_classify(&mut self, choice: ClassifyChoice) {
        self.engine.set_classify(choice);
    }

    pub fn device_name(&self) -> &str {
        &self.gpu.name
    }

    /// Whether the device is a CPU driver (lavapipe).
    pub fn is_cpu(&self) -> bool {
        self.gpu.is_cpu()
    }

    /// Runs `record` in the command buffer, submits it and waits.
    pub(super) fn submit(
        &self,
        record: impl FnOnce(vk::CommandBuffer) -> Result<(), GpuError>,
    ) -> Result<(), GpuError> {
        let mut commands = self.commands.borrow_mut();
        commands.begin(&self.gpu)?;
        record(commands.cmd)?;
        barrier(
            &self.gpu,
            commands.cmd,
            vk::PipelineStageFlags::ALL_COMMANDS,
            vk::PipelineStageFlags::HOST,
        );
        commands.submit(&self.gpu)?;
        commands.wait(&self.gpu, u64::MAX)
    }

    /// Uploads a camera frame and makes one view bound to it; the caller destroys both.
    fn stage(
        &self,
        camera: &RgbaImage,
        region: (u32, u32),
        format: PixelFormat,
    ) -> Result<(CameraResources, ViewTarget), GpuError> {
        let shape = ViewShape {
            format,
            width: region.0,
            pixels_in: PixelsIn::Buffer,
        };
        self.stage_shaped(camera, (shape, region.1))
    }

    /// The camera frame uploaded and a view of `shape` and height made over it (bound to the
    /// background); nothing is left allocated on an error.
    pub(super) fn stage_shaped(
        &self,
        camera: &RgbaImage,
        (shape, height): (ViewShape, u32),
    ) -> Result<(CameraResources, ViewTarget), GpuError> {
        let mut bg = self.engine.create_background(
            &self.gpu,
            (camera.width, camera.height),
            Placement::OFFLINE,
        )?;
        let uploaded = bg.upload(&camera.pixels);
        let view = uploaded.and_then(|_| {
            self.engine
                .create_shaped_view(&self.gpu, (shape, height), &bg, Placement::OFFLINE)
        });
        match view {
            Ok(view) => Ok((bg, view)),
            Err(e) => {
                bg.destroy(&self.gpu);
                Err(e)
            }
        }
    }

    fn release(&self, mut bg: CameraResources, mut view: ViewTarget) {
        self.engine.destroy_view(&self.gpu, &mut view);
        bg.destroy(&self.gpu);
    }

    /// Enhances raw pixels of any supported format (1 or 2 u32 per pixel) against a camera frame,
    /// with the manual FoV mapping of `params`.
    pub fn enhance_raw(
        &mut self,
        pixels: &[u32],
        region: (u32, u32),
        format: PixelFormat,
        camera: &RgbaImage,
        params: &Params,
    ) -> Result<Vec<u32>, GpuError> {
        let mapping = params.camera_mapping();
        self.enhance_raw_mapped(pixels, (region, format), camera, &mapping, params)
    }

    /// `enhance_raw` with the view's camera mapping given (a registered view's homography).
    pub fn enhance_raw_mapped(
        &mut self,
        pixels: &[u32],
        (region, format): ((u32, u32), PixelFormat),
        camera: &RgbaImage,
        mapping: &CameraMapping,
        params: &Params,
    ) -> Result<Vec<u32>, GpuError> {
        params.validate().map_err(GpuError::Unsupported)?;
        let words = (region.0 * region.1 * format.bytes_per_pixel() / 4) as usize;
        if pixels.len() != words {
            return Err(GpuError::Unsupported(
                "pixel data does not match the region".into(),
            ));
        }
        let (bg, mut view) = self.stage(camera, region, format)?;
        let staging = match self.cpu_background.then(|| {
            let texels = BlurredTexels::prepare(camera, BlurTaps::of(params));
            staging_buffer(&self.gpu, &texels)
        }) {
            None => None,
            Some(Ok(buffer)) => Some(buffer),
            Some(Err(e)) => {
                self.release(bg, view);
                return Err(e);
            }
        };
        let result = view.pixels.write(&words_to_bytes(pixels)).and_then(|_| {
            self.submit(|cmd| {
                let rect = CameraRect::sampled_by(&[*mapping], bg.size);
                match &staging {
                    Some(texels) => self
                        .engine
                        .record_texels_upload(&self.gpu, cmd, &bg, texels, &rect),
                    None => self
                        .engine
                        .record_background(&self.gpu, cmd, &bg, params, &rect)?,
                }
                self.engine
                    .record_enhance(&self.gpu, cmd, &view, params, mapping)
            })
        });
        if let Some(mut texels) = staging {
            texels.destroy(&self.gpu);
        }
        let out = result.and_then(|_| {
            let bytes = view
                .pixels
                .mapped()
                .ok_or_else(|| GpuError::Unsupported("result buffer is not host-visible".into()))?;
            Ok(bytes[..words * 4]
                .as_chunks::<4>()
                .0
                .iter()
                .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
                .collect())
        });
        self.release(bg, view);
        out
    }

    /// Runs only the background preparation (once per camera frame: decode and blur on the
    /// camera grid) and reads it back (for conformance tests).
    pub fn prepare_background(
        &mut self,
        camera: &RgbaImage,
        params: &Params,
    ) -> Result<BackgroundReadBack, GpuError> {
        let rect = CameraRect::full((camera.width, camera.height));
        self.prepare_background_in(camera, params, &rect)
    }

    /// The same for the texels of `rect` only, as the layer prepares them (the views sample
    /// part of the camera): texels outside it are not meaningful.
    pub fn prepare_background_in(
        &mut self,
        camera: &RgbaImage,
        params: &Params,
        rect: &CameraRect,
    ) -> Result<BackgroundReadBack, GpuError> {
        params.validate().map_err(GpuError::Unsupported)?;
        let (width, height) = (camera.width, camera.height);
        let (bg, view) = self.stage(camera, (1, 1), PixelFormat::SRGB8)?;
        let result = self.submit(|cmd| {
            self.engine
                .record_background(&self.gpu, cmd, &bg, params, rect)
        });
        let n = (width * height) as usize;
        let out = result.and_then(|_| {
            let bytes = bg.blurred.mapped().ok_or_else(|| {
                GpuError::Unsupported("background buffers are not host-visible".into())
            })?;
            let entries = bytes[..n * 16].as_chunks::<16>().0.iter();
            let (linear, right) = entries
                .map(|e| (unpack_linear(&e[..8]), unpack_linear(&e[8..])))
                .unzip();
            Ok(BackgroundReadBack {
                width,
                height,
                linear,
                right,
            })
        });
        self.release(bg, view);
        out
    }

    pub fn validation_errors(&self) -> u32 {
        self.gpu.validation_errors()
    }
}

impl OfflineBackend for VkOffline {
    fn api(&self) -> &'static str {
        "vulkan"
    }

    fn on_cpu(&self) -> bool {
        self.is_cpu()
    }

    fn pixel_formats(&self) -> Vec<PixelFormat> {
        use PixelLayout::*;
        [Rgba8, Bgra8, Rgba16Unorm, Rgba16Float, A2b10g10r10]
            .into_iter()
            .flat_map(|layout| [true, false].map(|srgb| PixelFormat { layout, srgb }))
            .filter(|f| !f.srgb || matches!(f.layout, Rgba8 | Bgra8))
            .collect()
    }

    fn enhance_pixels(
        &mut self,
        pixels: &[u32],
        shape: ((u32, u32), PixelFormat),
        camera: &RgbaImage,
        mapping: &CameraMapping,
        params: &Params,
    ) -> Result<Vec<u32>, String> {
        self.enhance_raw_mapped(pixels, shape, camera, mapping, params)
            .map_err(|e| e.to_string())
    }

    fn validation_errors(&self) -> u32 {
        VkOffline::validation_errors(self)
    }
}

impl Drop for VkOffline {
    fn drop(&mut self) {
        if self.commands.get_mut().destroy(&self.gpu).is_err() {
            // The GPU may still use the engine's objects: leave them alive.
            self.gpu.abandon();
            return;
        }
        self.engine.destroy(&self.gpu);
    }
}
