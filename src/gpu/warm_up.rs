//! The warm-up of a CPU driver's shader compiles. lavapipe (and other CPU Vulkan drivers built
//! on llvmpipe) compiles a compute shader to machine code at its first dispatch, not at
//! vkCreateComputePipelines: on the app's queue that would be seconds inside the app's
//! xrEndFrame. So the building thread first dispatches each shader once on a device of its
//! own (its own instance, the same kind of physical device, its own queue): the compile
//! happens there, and the driver's shader disk cache hands the result to the app's device.

use super::commands::Commands;
use super::device::DeviceKind;
use super::device::{DeviceOptions, GpuDevice};
use super::engine::{BackgroundFrame, Engine, Placement, ViewTarget};
use super::error::GpuError;
use super::format::{PixelFormat, PixelLayout};
use super::pipelines::{self, BuildMode, PushConstants, ShaderId, WarmUpHook};
use crate::algorithm::mapping::CameraMapping;
use crate::algorithm::params::Params;
use ash::vk;
use std::collections::HashSet;
use std::sync::{Mutex, OnceLock};

/// The shaders warmed up in this process, per device kind: the driver's disk cache has them,
/// so later sessions skip them (and make no device of their own at all).
fn warmed() -> std::sync::MutexGuard<'static, HashSet<(DeviceKind, ShaderId)>> {
    static WARMED: OnceLock<Mutex<HashSet<(DeviceKind, ShaderId)>>> = OnceLock::new();
    let m = WARMED.get_or_init(Default::default);
    // Only set operations happen under this lock.
    m.lock().unwrap_or_else(|p| p.into_inner())
}

/// Side of the camera frame and view the warm-up dispatches work on.
const SIZE: (u32, u32) = (8, 8);
/// How long one warm-up dispatch may take (a compile included).
const TIMEOUT_NS: u64 = 120_000_000_000;

pub struct WarmUp {
    engine: Engine,
    commands: Commands,
    background: BackgroundFrame,
    view: ViewTarget,
    /// The sampled image has been moved to GENERAL.
    image_ready: bool,
    // Last: dropped after everything above was destroyed in Drop.
    gpu: GpuDevice,
}

impl WarmUp {
    /// The hook that warms each shader up before it is built for `gpu`, where its driver
    /// compiles at first dispatch (the warm-up's device is made at the first shader that needs
    /// it); None for other drivers.
    pub fn hook(gpu: &GpuDevice) -> Option<WarmUpHook> {
        if !WarmUp::needed(gpu) {
            return None;
        }
        let kind = DeviceKind::of(gpu);
        let mut slot: Option<WarmUp> = None;
        Some(Box::new(move |id| WarmUp::once(&mut slot, kind, id)))
    }

    /// Whether a device compiles at first dispatch (a CPU driver).
    pub fn needed(gpu: &GpuDevice) -> bool {
        // SAFETY: physical belongs to this instance.
        let props = unsafe { gpu.instance.get_physical_device_properties(gpu.physical) };
        props.device_type == vk::PhysicalDeviceType::CPU
    }

    /// A device of the same kind as `key`'s, with a camera frame and a view (the widest pixel
    /// format, so every variant stays inside the buffers) zero-filled.
    pub fn new(key: DeviceKind) -> Result<WarmUp, GpuError> {
        // CONTRASTXR_VK_VALIDATION=1 validates the warm-up's own device too.
        let options = DeviceOptions {
            matching: Some(key),
            ..DeviceOptions::from_env()
        };
        let gpu = GpuDevice::create(&options)?;
        let mut engine = Engine::new(&gpu, 1, BuildMode::Inline, None)?;
        let parts = Commands::new(&gpu).and_then(|commands| {
            let mut bg = engine.create_background(&gpu, SIZE, Placement::OFFLINE)?;
            let format = PixelFormat {
                layout: PixelLayout::Rgba16Float,
                srgb: false,
            };
            match engine.create_view(&gpu, SIZE, format, &bg, Placement::OFFLINE) {
                Ok(view) => Ok((commands, bg, view)),
                Err(e) => {
                    bg.destroy(&gpu);
                    Err(e)
                }
            }
        });
        let (commands, mut background, mut view) = match parts {
            Ok(p) => p,
            Err(e) => {
                engine.destroy(&gpu);
                return Err(e);
            }
        };
        for b in [
            &mut background.camera,
            &mut background.blurred,
            &mut view.pixels,
            &mut view.tiles,
        ] {
            if let Some(m) = b.mapped_mut() {
                m.fill(0);
            }
        }
        Ok(WarmUp {
            engine,
            commands,
            background,
            view,
            image_ready: false,
            gpu,
        })
    }

    /// Warms `id` up unless this process already did, making the device in `slot` first if
    /// needed. Failures are not fatal: the compile then happens at first dispatch.
    pub fn once(slot: &mut Option<WarmUp>, key: DeviceKind, id: ShaderId) {
        if warmed().contains(&(key, id)) {
            return;
        }
        if slot.is_none() {
            *slot = WarmUp::new(key).ok();
        }
        if let Some(w) = slot {
            if w.run(id).is_ok() {
                warmed().insert((key, id));
            }
        }
    }

    /// Dispatches one workgroup of the shader and waits for it (its compile).
    pub fn run(&mut self, id: ShaderId) -> Result<(), GpuError> {
        let gpu = &self.gpu;
        let pipeline = self.engine.pipelines.get(id)?;
        self.commands.begin(gpu)?;
        let cmd = self.commands.cmd;
        let (bg_set, image) = Engine::background_parts(&self.background);
        if !self.image_ready {
            record_to_general(gpu, cmd, image);
            self.image_ready = true;
        }
        let set = match pipelines::reads_camera(id) {
            true => bg_set,
            false => Engine::view_set(&self.view),
        };
        let push = PushConstants::new(&Params::default(), SIZE, SIZE, &CameraMapping::IDENTITY);
        // A grid of one workgroup.
        self.engine.dispatch(gpu, cmd, pipeline, set, &push, (1, 1));
        self.commands.submit(gpu)?;
        self.commands.wait(gpu, TIMEOUT_NS)
    }
}

fn record_to_general(gpu: &GpuDevice, cmd: vk::CommandBuffer, image: vk::Image) {
    let barrier = [vk::ImageMemoryBarrier::default()
        .old_layout(vk::ImageLayout::UNDEFINED)
        .new_layout(vk::ImageLayout::GENERAL)
        .dst_access_mask(vk::AccessFlags::SHADER_READ)
        .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .image(image)
        .subresource_range(
            vk::ImageSubresourceRange::default()
                .aspect_mask(vk::ImageAspectFlags::COLOR)
                .level_count(1)
                .layer_count(1),
        )];
    // SAFETY: cmd is recording; the image is the warm-up's own.
    unsafe {
        gpu.device.cmd_pipeline_barrier(
            cmd,
            vk::PipelineStageFlags::TOP_OF_PIPE,
            vk::PipelineStageFlags::COMPUTE_SHADER,
            vk::DependencyFlags::empty(),
            &[],
            &[],
            &barrier,
        )
    };
}

impl Drop for WarmUp {
    fn drop(&mut self) {
        let _ = self.commands.wait(&self.gpu, TIMEOUT_NS);
        self.engine.destroy_view(&self.gpu, &mut self.view);
        self.background.destroy(&self.gpu);
        self.engine.destroy(&self.gpu);
        self.commands.destroy(&self.gpu);
    }
}
