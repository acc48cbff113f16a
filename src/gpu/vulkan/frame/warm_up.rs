//! The warm-up of a CPU driver's shader compiles. lavapipe (and other CPU Vulkan drivers built
//! on llvmpipe) compiles a compute shader to machine code at its first dispatch, not at
//! vkCreateComputePipelines: on the app's queue that would be seconds inside the app's
//! xrEndFrame. So the building thread first dispatches each shader once on a device of the
//! layer's own (the app's instance and physical device, its own queue): the compile happens
//! there, and the driver's shader disk cache hands the result to the app's device.
//!
//! That device is made on the app's thread (in a frame call that requests a shader still to be
//! warmed up), never on the building thread, on an instance of its own made through the app's
//! Vulkan loader: nothing of it belongs to the app's device or instance. The building thread
//! only records, submits and waits on the warm-up device's own objects, and stops waiting when
//! the session ends. At the session's end a compile still in flight is not waited for: the
//! device is left to the driver until the compile (which no driver can stop) has finished, and
//! then destroyed with its instance on an app's thread, at the next session's warm-up or end
//! (see [`WarmUp::end`]); the process's exit waits for the compile.

use crate::algorithm::mapping::CameraMapping;
use crate::algorithm::params::Params;
use crate::gpu::core::process_exit::on_exit;
use crate::gpu::core::push_constants::PushConstants;
use crate::gpu::core::shader_ids;
use crate::gpu::core::shader_ids::ShaderId;
use crate::gpu::core::{PixelFormat, PixelLayout};
use crate::gpu::vulkan::conv::VkFormat;
use crate::gpu::vulkan::device::{
    record_first_layout, Commands, DeviceKind, GpuDevice, GpuError, StorageImage,
};
use crate::gpu::vulkan::pipelines::{BuildMode, WarmUpHook};
use crate::gpu::vulkan::record::{CameraResources, Placement, Recorder, ViewTarget};
use ash::vk;
use std::collections::HashSet;
use std::sync::{Arc, Mutex, Once, OnceLock};
use std::time::{Duration, Instant};

/// The shaders warmed up in this process, per device kind: the driver's disk cache has them,
/// so later sessions skip them (and make no device of their own at all).
fn warmed() -> std::sync::MutexGuard<'static, HashSet<(DeviceKind, ShaderId)>> {
    static WARMED: OnceLock<Mutex<HashSet<(DeviceKind, ShaderId)>>> = OnceLock::new();
    let m = WARMED.get_or_init(Default::default);
    // Only set operations happen under this lock.
    m.lock().unwrap_or_else(|p| p.into_inner())
}

/// Warm-up devices of ended sessions whose last dispatch (a compile, which no driver can
/// interrupt) was still running: destroyed on an app's thread once it has finished (at the
/// next session's warm-up or end), waited for by the process's exit.
fn left_over() -> std::sync::MutexGuard<'static, Vec<WarmUp>> {
    static LEFT: Mutex<Vec<WarmUp>> = Mutex::new(Vec::new());
    // Only pushes and takes happen under this lock.
    LEFT.lock().unwrap_or_else(|p| p.into_inner())
}

/// Side of the camera frame and view the warm-up dispatches work on.
const SIZE: (u32, u32) = (8, 8);
/// How long one warm-up dispatch may take (a compile included).
const TIMEOUT: Duration = Duration::from_secs(120);
/// The slices the building thread waits for a dispatch in, looking at the session's end.
const WAIT_SLICE_NS: u64 = 20_000_000;
/// How long dropping the device waits for work still in flight where no thread can be left
/// to wait for it (none, unless a dispatch timed out).
const DROP_WAIT_NS: u64 = 1_000_000_000;
/// What the `slow-build` fault point adds to a warm-up dispatch: a driver whose compile takes
/// longer than any wait of the session's end.
const SLOW_BUILD: Duration = Duration::from_secs(5);

pub struct WarmUp {
    engine: Recorder,
    commands: Commands,
    background: CameraResources,
    view: ViewTarget,
    /// The sampled image has been moved to GENERAL.
    image_ready: bool,
    /// Stand-ins for the app's image of the in-place shaders (GENERAL), by view format.
    storage: Vec<StorageImage>,
    /// The `slow-build` fault point: the last dispatch counts as running until then.
    slow_until: Option<Instant>,
    // Last: dropped after everything above was destroyed in Drop.
    gpu: GpuDevice,
}

/// A session's warm-up device, shared by the app's thread (which makes it when a shader that
/// still needs a warm-up is requested, and drops it after the building thread has ended) and
/// the building thread (which dispatches on it). Empty until needed.
pub type WarmUpSlot = Arc<Mutex<Device>>;

/// The warm-up device of a session, and whether making it was tried: a device that could not
/// be made is not tried again in that session (that would be a vkCreateDevice per frame).
#[derive(Default)]
pub struct Device {
    warm_up: Option<WarmUp>,
    tried: bool,
}

fn lock(slot: &WarmUpSlot) -> std::sync::MutexGuard<'_, Device> {
    // A panic while holding it leaves a usable slot.
    slot.lock().unwrap_or_else(|p| p.into_inner())
}

impl WarmUp {
    /// An empty slot and the hook that warms each shader up on the device in it (if any)
    /// before it is built for `gpu`; None where `gpu`'s driver compiles at pipeline creation.
    pub fn slot(gpu: &GpuDevice) -> Option<(WarmUpSlot, WarmUpHook)> {
        if !WarmUp::needed(gpu) {
            return None;
        }
        let slot: WarmUpSlot = Default::default();
        let kind = DeviceKind::of(gpu);
        let shared = slot.clone();
        let hook: WarmUpHook = Box::new(move |id, stopped| {
            if let Some(w) = lock(&shared).warm_up.as_mut() {
                w.once(kind, id, stopped);
            }
        });
        Some((slot, hook))
    }

    /// Makes the warm-up device in `slot`, on the caller's thread (the app's, before it asks
    /// for `ids` to be built), when one of them still needs a warm-up in this process.
    /// Failures are not fatal: the compile then happens at first dispatch on the app's queue.
    /// Returns what making the device gave, when this call made (or tried to make) one: at
    /// most once per slot.
    pub fn prepare(
        slot: &WarmUpSlot,
        app: &GpuDevice,
        ids: &[ShaderId],
    ) -> Option<Result<(), GpuError>> {
        let kind = DeviceKind::of(app);
        if ids.iter().all(|&id| warmed().contains(&(kind, id))) {
            return None;
        }
        // Held by the building thread: it is dispatching on the device, which thus exists
        // (never wait here for its compile).
        let mut slot = match slot.try_lock() {
            Ok(slot) => slot,
            Err(std::sync::TryLockError::Poisoned(p)) => p.into_inner(),
            Err(std::sync::TryLockError::WouldBlock) => return None,
        };
        if std::mem::replace(&mut slot.tried, true) {
            return None;
        }
        WarmUp::destroy_left_over();
        match WarmUp::new(app) {
            Ok(w) => {
                slot.warm_up = Some(w);
                Some(Ok(()))
            }
            Err(e) => Some(Err(e)),
        }
    }

    /// Whether a device compiles at first dispatch (a CPU driver).
    pub fn needed(gpu: &GpuDevice) -> bool {
        gpu.is_cpu()
    }

    /// A device beside `app`'s, with a camera frame and a view (the widest pixel format, so
    /// every variant stays inside the buffers) zero-filled.
    pub fn new(app: &GpuDevice) -> Result<WarmUp, GpuError> {
        crate::fault::check("warm-up-device").map_err(GpuError::Unsupported)?;
        let gpu = GpuDevice::create_beside(app)?;
        let mut engine = Recorder::new(&gpu, 1, BuildMode::Inline, None)?;
        let mut commands = match Commands::new(&gpu) {
            Ok(c) => c,
            Err(e) => {
                engine.destroy(&gpu);
                return Err(e);
            }
        };
        let format = PixelFormat {
            layout: PixelLayout::Rgba16Float,
            srgb: false,
        };
        let parts = engine
            .create_background(&gpu, SIZE, Placement::OFFLINE)
            .and_then(|mut bg| {
                match engine.create_view(&gpu, SIZE, format, &bg, Placement::OFFLINE) {
                    Ok(view) => Ok((bg, view)),
                    Err(e) => {
                        bg.destroy(&gpu);
                        Err(e)
                    }
                }
            });
        let (mut background, mut view) = match parts {
            Ok(p) => p,
            Err(e) => {
                // Nothing was submitted: the wait in destroy cannot fail.
                let _ = commands.destroy(&gpu);
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
            storage: Vec::new(),
            slow_until: None,
            gpu,
        })
    }

    /// Warms `id` up unless this process already did, waiting for it until `stopped`.
    /// Failures are not fatal: the compile then happens at first dispatch.
    pub fn once(&mut self, key: DeviceKind, id: ShaderId, stopped: &dyn Fn() -> bool) {
        if warmed().contains(&(key, id)) {
            return;
        }
        if self.run(id, stopped).is_ok() {
            warmed().insert((key, id));
        }
    }

    /// Dispatches one workgroup of the shader and waits for it (its compile) until it is
    /// done or `stopped`; a dispatch left running is waited for by [`WarmUp::end`].
    pub fn run(&mut self, id: ShaderId, stopped: &dyn Fn() -> bool) -> Result<(), GpuError> {
        let pipeline = self.engine.pipelines().get(id)?;
        self.commands.begin(&self.gpu)?;
        let cmd = self.commands.cmd;
        let (bg_set, image) = Recorder::background_parts(&self.background);
        if !self.image_ready {
            record_to_general(&self.gpu, cmd, image);
            self.image_ready = true;
        }
        if let Some(format) = shader_ids::in_place_format(id) {
            let storage = self.storage_for(cmd, format)?;
            self.engine.bind_app_image(&self.gpu, &self.view, storage);
        }
        let gpu = &self.gpu;
        let set = match shader_ids::reads_camera(id) {
            true => bg_set,
            false => Recorder::view_set(&self.view),
        };
        let push = PushConstants::new(&Params::default(), SIZE, SIZE, &CameraMapping::IDENTITY);
        // A grid of one workgroup.
        self.engine.dispatch(gpu, cmd, pipeline, set, &push, (1, 1));
        self.commands.submit(gpu)?;
        if crate::fault::hit("slow-build") {
            self.slow_until = Some(Instant::now() + SLOW_BUILD);
        }
        let deadline = Instant::now() + TIMEOUT;
        while !self.finished_within(WAIT_SLICE_NS)? {
            if stopped() || Instant::now() > deadline {
                return Err(GpuError::Unsupported("warm-up not finished".into()));
            }
        }
        Ok(())
    }

    /// Whether the last dispatch has finished, after waiting for it `timeout_ns` at most.
    fn finished_within(&mut self, timeout_ns: u64) -> Result<bool, GpuError> {
        if self.slow_until.is_some_and(|t| Instant::now() < t) {
            std::thread::sleep(Duration::from_nanos(timeout_ns));
            return Ok(false);
        }
        match self.commands.wait(&self.gpu, timeout_ns) {
            Ok(()) => Ok(true),
            Err(GpuError::Vulkan {
                result: vk::Result::TIMEOUT,
                ..
            }) => Ok(false),
            Err(e) => Err(e),
        }
    }

    /// Destroys, on the caller's thread (an app's), the left-over warm-up devices whose last
    /// dispatch has finished.
    pub fn destroy_left_over() {
        let mut finished = Vec::new();
        let mut left = left_over();
        let mut k = 0;
        while k < left.len() {
            match left[k].finished_within(0).unwrap_or(true) {
                true => finished.push(left.swap_remove(k)),
                false => k += 1,
            }
        }
        drop(left);
        drop(finished);
    }

    /// Ends a session's warm-up device, on the app's thread after the building thread has
    /// ended: dropped here when its last dispatch has finished, else left in the driver's
    /// hands until it has ([`WarmUp::destroy_left_over`]; the process's exit waits for it).
    pub fn end(slot: WarmUpSlot) {
        WarmUp::destroy_left_over();
        let Some(mut warm_up) = lock(&slot).warm_up.take() else {
            return;
        };
        if warm_up.finished_within(0).unwrap_or(true) {
            return;
        }
        static AT_EXIT: Once = Once::new();
        AT_EXIT.call_once(|| on_exit(wait_for_left_over));
        left_over().push(warm_up);
    }
}

/// At the process's exit: waits (until `deadline`) for the dispatches of left-over warm-up
/// devices, so that no compile runs under the driver's destructors, and leaves the devices to
/// the exit. Whether there were any.
fn wait_for_left_over(deadline: Instant) -> bool {
    let mut left = left_over();
    for w in left.iter_mut() {
        while !w.finished_within(WAIT_SLICE_NS).unwrap_or(true) && Instant::now() < deadline {}
    }
    let any = !left.is_empty();
    std::mem::take(&mut *left)
        .into_iter()
        .for_each(std::mem::forget);
    any
}

impl WarmUp {
    /// The view of the stand-in storage image for an in-place shader of FORMAT code `format`,
    /// made (and moved to GENERAL in `cmd`) at its first use.
    fn storage_for(
        &mut self,
        cmd: vk::CommandBuffer,
        format: u32,
    ) -> Result<vk::ImageView, GpuError> {
        let view_format = PixelFormat::from_shader_code(format)
            .and_then(PixelFormat::image_copy_format)
            .ok_or_else(|| GpuError::Unsupported("no in-place texel format".into()))?;
        if let Some(s) = self.storage.iter().find(|s| s.format == view_format) {
            return Ok(s.view);
        }
        let storage = StorageImage::new(&self.gpu, SIZE, view_format)?;
        record_to_general(&self.gpu, cmd, storage.image.raw);
        let view = storage.view;
        self.storage.push(storage);
        Ok(view)
    }
}

/// The warm-up's own images to GENERAL, where its shaders read and write them.
fn record_to_general(gpu: &GpuDevice, cmd: vk::CommandBuffer, image: vk::Image) {
    let access = vk::AccessFlags::SHADER_READ | vk::AccessFlags::SHADER_WRITE;
    let stage = vk::PipelineStageFlags::COMPUTE_SHADER;
    record_first_layout(
        gpu,
        cmd,
        &[image],
        vk::ImageLayout::GENERAL,
        (stage, access),
    );
}

impl Drop for WarmUp {
    fn drop(&mut self) {
        let slow = self.slow_until.is_some_and(|t| Instant::now() < t);
        if slow || self.commands.wait(&self.gpu, DROP_WAIT_NS).is_err() {
            // The GPU may still use every object: leave them alive rather than free them.
            self.gpu.abandon();
            return;
        }
        self.engine.destroy_view(&self.gpu, &mut self.view);
        for mut s in self.storage.drain(..) {
            s.destroy(&self.gpu);
        }
        self.background.destroy(&self.gpu);
        self.engine.destroy(&self.gpu);
        // Waited for above: this wait cannot fail.
        let _ = self.commands.destroy(&self.gpu);
    }
}
