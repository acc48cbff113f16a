//! The engine on a device of its own, for the command-line tool and the tests: upload, record,
//! submit, wait, read back.

use super::commands::Commands;
use super::device::{DeviceOptions, GpuDevice};
use super::engine::{barrier, BackgroundFrame, Engine, Placement, ViewTarget};
use super::error::GpuError;
use super::format::PixelFormat;
use crate::algorithm::params::Params;
use crate::image::RgbaImage;
use ash::vk;
use std::cell::RefCell;

pub struct OfflineEngine {
    pub(super) engine: Engine,
    /// RefCell: `submit` records through `&self` (the engine and device are only read).
    commands: RefCell<Commands>,
    // Declared last: dropped after the objects above are destroyed in Drop.
    pub gpu: GpuDevice,
}

/// The prepared background read back from the GPU (display grid, one entry per pixel).
pub struct GpuBackground {
    pub linear: Vec<[f32; 4]>,
    /// B (L', a', b'), unpacked from the shader's 8-byte form.
    pub scaled: Vec<[f32; 3]>,
}

fn words_to_bytes(words: &[u32]) -> Vec<u8> {
    words.iter().flat_map(|w| w.to_le_bytes()).collect()
}

fn bytes_to_vec4(bytes: &[u8], n: usize) -> Vec<[f32; 4]> {
    bytes[..n * 16]
        .chunks_exact(16)
        .map(|c| {
            std::array::from_fn(|k| f32::from_le_bytes(c[4 * k..4 * k + 4].try_into().unwrap()))
        })
        .collect()
}

/// Mirrors `unpack_background` in shaders/common.wgsl: three 21-bit fixed-point codes in two
/// little-endian u32 words, 2^19 steps per unit, code 2^20 = 0.
fn unpack_background(bytes: &[u8], n: usize) -> Vec<[f32; 3]> {
    bytes[..n * 8]
        .chunks_exact(8)
        .map(|c| {
            let packed = u64::from_le_bytes(c.try_into().unwrap());
            std::array::from_fn(|k| {
                let code = (packed >> (21 * k)) & 0x1f_ffff;
                (code as f32 - 1_048_576.0) / 524_288.0
            })
        })
        .collect()
}

impl OfflineEngine {
    /// The first Vulkan device (or `CONTRASTXR_VK_DEVICE`), validation per `CONTRASTXR_VK_VALIDATION`.
    pub fn new() -> Result<OfflineEngine, GpuError> {
        Self::with_options(&DeviceOptions::from_env())
    }

    pub fn with_options(options: &DeviceOptions) -> Result<OfflineEngine, GpuError> {
        let gpu = GpuDevice::create(options)?;
        let engine = Engine::new(&gpu, 4)?;
        let commands = RefCell::new(Commands::new(&gpu)?);
        Ok(OfflineEngine {
            engine,
            commands,
            gpu,
        })
    }

    pub fn device_name(&self) -> &str {
        &self.gpu.name
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
    ) -> Result<(BackgroundFrame, ViewTarget), GpuError> {
        let mut bg = self.engine.create_background(
            &self.gpu,
            (camera.width, camera.height),
            Placement::OFFLINE,
        )?;
        let uploaded = bg.upload(&camera.pixels);
        let view = uploaded.and_then(|_| {
            self.engine
                .create_view(&self.gpu, region, format, &bg, Placement::OFFLINE)
        });
        match view {
            Ok(view) => Ok((bg, view)),
            Err(e) => {
                bg.destroy(&self.gpu);
                Err(e)
            }
        }
    }

    fn release(&self, mut bg: BackgroundFrame, mut view: ViewTarget) {
        self.engine.destroy_view(&self.gpu, &mut view);
        bg.destroy(&self.gpu);
    }

    /// Enhances raw pixels of any supported format (1 or 2 u32 per pixel) against a camera frame.
    pub fn enhance_raw(
        &mut self,
        pixels: &[u32],
        region: (u32, u32),
        format: PixelFormat,
        camera: &RgbaImage,
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
        let result = view.pixels.write(&words_to_bytes(pixels)).and_then(|_| {
            self.submit(|cmd| {
                self.engine
                    .record_background(&self.gpu, cmd, &bg, &[&view], params)?;
                self.engine.record_enhance(&self.gpu, cmd, &view, params)
            })
        });
        let out = result.and_then(|_| {
            let bytes = view
                .pixels
                .mapped()
                .ok_or_else(|| GpuError::Unsupported("result buffer is not host-visible".into()))?;
            Ok(bytes[..words * 4]
                .chunks_exact(4)
                .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
                .collect())
        });
        self.release(bg, view);
        out
    }

    /// Enhances an 8-bit sRGB display image against a camera frame of any size.
    pub fn enhance(
        &mut self,
        display: &RgbaImage,
        camera: &RgbaImage,
        params: &Params,
    ) -> Result<RgbaImage, GpuError> {
        let words: Vec<u32> = display
            .pixels
            .iter()
            .map(|p| u32::from_le_bytes(*p))
            .collect();
        let region = (display.width, display.height);
        let out = self.enhance_raw(&words, region, PixelFormat::SRGB8, camera, params)?;
        Ok(RgbaImage {
            pixels: out.iter().map(|w| w.to_le_bytes()).collect(),
            ..display.clone()
        })
    }

    /// Runs only the background preparation and reads it back (for conformance tests).
    pub fn prepare_background(
        &mut self,
        camera: &RgbaImage,
        region: (u32, u32),
        params: &Params,
    ) -> Result<GpuBackground, GpuError> {
        params.validate().map_err(GpuError::Unsupported)?;
        let (bg, view) = self.stage(camera, region, PixelFormat::SRGB8)?;
        let result = self.submit(|cmd| {
            self.engine
                .record_background(&self.gpu, cmd, &bg, &[&view], params)
        });
        let n = (region.0 * region.1) as usize;
        let out = result.and_then(|_| {
            let lin = view.bg_linear.mapped();
            let sc = view.bg_scaled.mapped();
            match (lin, sc) {
                (Some(l), Some(s)) => Ok(GpuBackground {
                    linear: bytes_to_vec4(l, n),
                    scaled: unpack_background(s, n),
                }),
                _ => Err(GpuError::Unsupported(
                    "background buffers are not host-visible".into(),
                )),
            }
        });
        self.release(bg, view);
        out
    }

    pub fn validation_errors(&self) -> u32 {
        self.gpu.validation_errors()
    }
}

impl Drop for OfflineEngine {
    fn drop(&mut self) {
        self.commands.get_mut().destroy(&self.gpu);
        self.engine.destroy(&self.gpu);
    }
}
