//! The warm-up of a CPU driver's shader compiles. lavapipe (and other CPU Vulkan drivers built
//! on llvmpipe) compiles a compute shader to machine code at its first dispatch, not at
//! vkCreateComputePipelines: on the app's queue that would be seconds inside the app's
//! xrEndFrame. So the building thread first dispatches each shader once on a device of the
//! layer's own (the app's physical device, its own instance and queue): the compile happens
//! there, and the driver's shader disk cache hands the result to the app's device.
//!
//! That device is the process's, one per kind of device. It is made inside the app's
//! xrCreateSession, on the app's thread, before the session exists for any other thread of
//! the app, on an instance of its own made through the app's Vulkan loader: nothing of it
//! belongs to the app's device or instance. The sessions that follow share it, and it lives
//! until the process exits: a Vulkan instance is never created or destroyed while the app
//! may call into Vulkan from other threads (the loader's vkEnumeratePhysicalDevices for a new
//! instance unloads libraries: made inside a later swapchain call, it crashed the app's
//! thread that had the runtime make a swapchain meanwhile, inside the loader). The building
//! threads only record, submit and wait on the device's objects, one at a time, and stop
//! waiting when their session ends: a compile still in flight (which no driver can stop)
//! finishes on its own, the next session's warm-up waits for it first, and the process's exit
//! waits for it.

use crate::algorithm::mapping::CameraMapping;
use crate::algorithm::params::Params;
use crate::gpu::core::modules;
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
use std::collections::{HashMap, HashSet};
use std::sync::{Arc, Mutex, Once, OnceLock};
use std::time::{Duration, Instant};

/// The shaders warmed up in this process, per device kind: the driver's disk cache has them,
/// so later sessions skip them.
fn warmed() -> std::sync::MutexGuard<'static, HashSet<(DeviceKind, ShaderId)>> {
    static WARMED: OnceLock<Mutex<HashSet<(DeviceKind, ShaderId)>>> = OnceLock::new();
    let m = WARMED.get_or_init(Default::default);
    // Only set operations happen under this lock.
    m.lock().unwrap_or_else(|p| p.into_inner())
}

/// The process's warm-up devices, by device kind (see the module's comment).
fn devices() -> std::sync::MutexGuard<'static, HashMap<DeviceKind, Shared>> {
    static DEVICES: OnceLock<Mutex<HashMap<DeviceKind, Shared>>> = OnceLock::new();
    let m = DEVICES.get_or_init(Default::default);
    // Only look-ups and inserts happen under this lock.
    m.lock().unwrap_or_else(|p| p.into_inner())
}

/// Side of the camera frame and view the warm-up dispatches work on.
const SIZE: (u32, u32) = (8, 8);
/// How long one warm-up dispatch may take (a compile included).
const TIMEOUT: Duration = Duration::from_secs(120);
/// The slices the building thread waits for a dispatch in, looking at the session's end.
const WAIT_SLICE_NS: u64 = 20_000_000;
/// How long dropping a warm-up device waits for work in flight (the process's devices are
/// left to its exit; Drop stays sound for any other).
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

/// A warm-up device, shared by the sessions' building threads (one dispatch at a time).
type Shared = Arc<Mutex<WarmUp>>;

fn lock(device: &Shared) -> std::sync::MutexGuard<'_, WarmUp> {
    // A panic while holding it leaves a usable device (a dispatch in flight is waited for).
    device.lock().unwrap_or_else(|p| p.into_inner())
}

/// What making the process's warm-up device gave, when a session's start made (or tried to
/// make) one: the time it took, or why there is none.
pub type WarmUpMade = Result<Duration, GpuError>;

impl WarmUp {
    /// The hook that warms each shader up on the process's warm-up device of `app`'s kind
    /// before it is built for `app`; None where `app`'s driver compiles at pipeline creation,
    /// where every shader is warmed up already, or where no warm-up device can be made. The
    /// device is made here, on the caller's thread (the app's, inside xrCreateSession), the
    /// first time a session needs it; with what making it gave. Failures are not fatal: the
    /// compile then happens at first dispatch on the app's queue, and the next session tries
    /// again.
    pub fn for_session(app: &GpuDevice) -> (Option<WarmUpHook>, Option<WarmUpMade>) {
        if !WarmUp::needed(app) {
            return (None, None);
        }
        let kind = DeviceKind::of(app);
        let all_warmed = {
            let warmed = warmed();
            (0..modules::all().len()).all(|k| warmed.contains(&(kind, ShaderId(k))))
        };
        if all_warmed {
            return (None, None);
        }
        let mut devices = devices();
        let (device, made) = match devices.get(&kind) {
            Some(device) => (device.clone(), None),
            None => {
                let t = Instant::now();
                match WarmUp::new(app) {
                    Ok(w) => {
                        let device = Arc::new(Mutex::new(w));
                        devices.insert(kind, device.clone());
                        static AT_EXIT: Once = Once::new();
                        AT_EXIT.call_once(|| on_exit(wait_at_exit));
                        (device, Some(Ok(t.elapsed())))
                    }
                    Err(e) => return (None, Some(Err(e))),
                }
            }
        };
        let hook: WarmUpHook = Box::new(move |id, stopped| lock(&device).once(kind, id, stopped));
        (Some(hook), made)
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
        if shader_ids::reads_sampled(id) {
            // No app image to sample here: such a variant compiles at its first dispatch.
            warmed().insert((key, id));
            return;
        }
        if self.run(id, stopped).is_ok() {
            warmed().insert((key, id));
        }
    }

    /// Dispatches one workgroup of the shader and waits for it (its compile) until it is
    /// done or `stopped`; a dispatch left running is waited for by the next one (or the exit).
    pub fn run(&mut self, id: ShaderId, stopped: &dyn Fn() -> bool) -> Result<(), GpuError> {
        // An ended session's dispatch may still be compiling.
        self.wait_until_finished(stopped)?;
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
        self.wait_until_finished(stopped)
    }

    /// Waits for the last dispatch (none: returns at once) until it is done, `stopped` or
    /// the dispatch's time is up.
    fn wait_until_finished(&mut self, stopped: &dyn Fn() -> bool) -> Result<(), GpuError> {
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
}

/// At the process's exit: waits (until `deadline`) for the last dispatch of each warm-up
/// device, so that no compile runs under the driver's destructors; the devices are left to
/// the exit. Whether there was a dispatch to wait for. (The building threads stop waiting
/// and let go of the devices once the exit has begun.)
fn wait_at_exit(deadline: Instant) -> bool {
    let devices: Vec<Shared> = devices().values().cloned().collect();
    let mut any = false;
    for device in devices {
        let mut w = lock(&device);
        if w.finished_within(0).unwrap_or(true) {
            continue;
        }
        any = true;
        while !w.finished_within(WAIT_SLICE_NS).unwrap_or(true) && Instant::now() < deadline {}
    }
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
