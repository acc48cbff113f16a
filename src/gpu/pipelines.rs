//! The compute pipelines built from the embedded SPIR-V, with the one descriptor-set layout and
//! push-constant block they share (see shaders/common.wgsl).
//!
//! A pipeline costs a shader compile in the driver (on lavapipe, LLVM: tenths of a second
//! each), so none is built inside a call an app makes to the layer: in [`BuildMode::Background`]
//! a thread of the engine's own builds what is requested, in order, through the device's
//! [`PipelineCache`], and a pipeline not built yet is [`GpuError::Pending`]. The offline tools
//! build on first use ([`BuildMode::Inline`]).

use super::codes::mode_code;
use super::device::DeviceKind;
use super::device::GpuDevice;
use super::error::{GpuError, VkResultExt};
use super::interface::{self, BindingKind, BINDINGS, BLUR_TAPS, PARAMS_SIZE};
use super::pipeline_cache::{self, Origin, PipelineCache};
use super::process_exit;
use super::shaders::{self, ShaderModule};
use crate::algorithm::mapping::CameraMapping;
use crate::algorithm::params::{Params, ViewMode, MAX_BLUR_SIZE, SUBTRACTION_K_B, SUBTRACTION_K_V};
use ash::vk;
use std::collections::VecDeque;
use std::sync::{Arc, Condvar, Mutex, MutexGuard};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

pub use super::interface::TILE;

// The algorithm's largest blur is the shaders' largest half-width.
const _: () = assert!(MAX_BLUR_SIZE == 2 * interface::MAX_BLUR_HALF + 1);

/// The push-constant block, laid out as the shaders' `Params` (src/gpu/interface.rs, PARAMS:
/// the same fields in the same order, checked below).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct PushConstants {
    pub camera_size: [u32; 2],
    pub region_size: [u32; 2],
    pub lambda_e: f32,
    pub lambda_jnd: f32,
    pub transmittance: f32,
    pub blur_half: u32,
    pub taps: [f32; BLUR_TAPS],
    pub k_v: f32,
    pub k_b: f32,
    pub mode: u32,
    pub tile_columns: u32,
    pub achromatic_boost: f32,
    pub luminance_cap: f32,
    /// The view's CameraMapping, row-major (PARAMS' map_00 ..= map_22).
    pub mapping: [[f32; 3]; 3],
    pub pad: u32,
}

/// Each PushConstants field's byte offset, in PARAMS order (the mapping stands for map_00 ..=
/// map_22, one f32 each).
const PUSH_OFFSETS: [usize; interface::PARAMS.len()] = {
    use std::mem::offset_of;
    let m = offset_of!(PushConstants, mapping);
    [
        offset_of!(PushConstants, camera_size),
        offset_of!(PushConstants, region_size),
        offset_of!(PushConstants, lambda_e),
        offset_of!(PushConstants, lambda_jnd),
        offset_of!(PushConstants, transmittance),
        offset_of!(PushConstants, blur_half),
        offset_of!(PushConstants, taps),
        offset_of!(PushConstants, k_v),
        offset_of!(PushConstants, k_b),
        offset_of!(PushConstants, mode),
        offset_of!(PushConstants, tile_columns),
        offset_of!(PushConstants, achromatic_boost),
        offset_of!(PushConstants, luminance_cap),
        m,
        m + 4,
        m + 8,
        m + 12,
        m + 16,
        m + 20,
        m + 24,
        m + 28,
        m + 32,
        offset_of!(PushConstants, pad),
    ]
};

const _: () = {
    let (offsets, _) = interface::params_layout();
    let mut i = 0;
    while i < offsets.len() {
        assert!(
            PUSH_OFFSETS[i] == offsets[i] as usize,
            "PushConstants differs from PARAMS"
        );
        i += 1;
    }
    assert!(std::mem::size_of::<PushConstants>() == PARAMS_SIZE as usize);
};

impl PushConstants {
    pub fn new(
        params: &Params,
        camera: (u32, u32),
        region: (u32, u32),
        mapping: &CameraMapping,
    ) -> Self {
        let taps64 = params.blur_taps();
        let half = taps64.len() / 2;
        let mut taps = [0.0f32; BLUR_TAPS];
        for (k, t) in taps.iter_mut().enumerate().take(half + 1) {
            *t = taps64[half + k] as f32;
        }
        PushConstants {
            camera_size: [camera.0, camera.1],
            region_size: [region.0, region.1],
            lambda_e: params.lambda_e,
            lambda_jnd: params.lambda_jnd_scaled,
            transmittance: params.transmittance,
            blur_half: half as u32,
            taps,
            k_v: SUBTRACTION_K_V,
            k_b: SUBTRACTION_K_B,
            mode: mode_code(params.mode),
            tile_columns: region.0.div_ceil(TILE),
            achromatic_boost: params.achromatic_boost,
            luminance_cap: params.luminance_cap,
            mapping: mapping.to_f32_rows(),
            pad: 0,
        }
    }

    pub fn bytes(&self) -> &[u8] {
        // SAFETY: PushConstants is repr(C), Copy, made only of 4-byte scalars (no padding).
        unsafe {
            std::slice::from_raw_parts(
                (self as *const Self).cast::<u8>(),
                std::mem::size_of::<Self>(),
            )
        }
    }
}

/// Runs a shader once, on the building thread, before it is built for the engine's device: a
/// CPU driver compiles at first dispatch (see gpu/warm_up.rs).
pub type WarmUpHook = Box<dyn FnMut(ShaderId) + Send>;

/// Where pipelines are built.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BuildMode {
    /// On the thread that first needs one (the offline tools).
    Inline,
    /// On a thread of the engine's own, in the order requested (the layer).
    Background,
}

/// One shader of `shaders::all()`, by its index there.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct ShaderId(usize);

/// Indices into `shaders::all()` (its order: the fixed shaders, DECODE_BLUR, ENHANCE_VARIANTS,
/// CLASSIFY_VARIANTS).
pub const DECODE_CAMERA: ShaderId = ShaderId(0);
pub const FINISH_TILES: ShaderId = ShaderId(1);
pub const COPY_PIXELS: ShaderId = ShaderId(2);
pub const COPY_ROWS: ShaderId = ShaderId(3);
const FIXED: usize = 4;

fn unsupported() -> GpuError {
    GpuError::Unsupported("no shader for this method, mode and format".into())
}

/// Whether a shader works on the camera frame (the background's descriptor set) rather than
/// on a view.
pub fn reads_camera(ShaderId(k): ShaderId) -> bool {
    k == DECODE_CAMERA.0 || (FIXED..FIXED + shaders::DECODE_BLUR.len()).contains(&k)
}

/// The background pass for a blur half-width (0..=7).
pub fn decode_blur(half: u32) -> Result<ShaderId, GpuError> {
    let k = half as usize;
    (k < shaders::DECODE_BLUR.len())
        .then_some(ShaderId(FIXED + k))
        .ok_or_else(unsupported)
}

/// The `enhance` shader for a method, view mode and pixel format (shader codes); `wide` for
/// regions whose rows are 16-byte aligned; `extras` where the achromatic boost or the
/// luminance cap is on.
pub fn enhance(
    (method, mode, format): (u32, u32, u32),
    wide: bool,
    extras: bool,
) -> Result<ShaderId, GpuError> {
    let background = mode == mode_code(ViewMode::Background);
    let (method, extras) = if background {
        (0, false)
    } else {
        (method, extras)
    };
    let k = shaders::ENHANCE_VARIANTS
        .iter()
        .position(|&(m, v, f, w, e, _)| (m, v, f, w, e) == (method, mode, format, wide, extras))
        .ok_or_else(unsupported)?;
    Ok(ShaderId(FIXED + shaders::DECODE_BLUR.len() + k))
}

/// The `classify` shader for a pixel format (shader code) and row alignment.
pub fn classify(format: u32, wide: bool) -> Result<ShaderId, GpuError> {
    let k = shaders::CLASSIFY_VARIANTS
        .iter()
        .position(|&(f, w, _)| f == format && w == wide)
        .ok_or_else(unsupported)?;
    let offset = FIXED + shaders::DECODE_BLUR.len() + shaders::ENHANCE_VARIANTS.len();
    Ok(ShaderId(offset + k))
}

#[derive(Clone, Debug)]
enum Slot {
    Missing,
    Queued,
    /// Taken by the building thread.
    Building,
    Built(vk::Pipeline),
    Failed(String),
}

/// What the builds so far took, for the layer's start-up log line.
#[derive(Clone, Debug)]
pub struct BuildReport {
    /// Pipelines built, and the time spent building them.
    pub built: u32,
    pub build_time: Duration,
    /// Each build: the shader's name and its time (the warm-up's dispatch included).
    pub builds: Vec<(&'static str, Duration)>,
    /// What the pipeline cache started from, and its size in bytes.
    pub cache: Origin,
    pub cache_bytes: usize,
    /// The last write of the cache: bytes written, or why it failed.
    pub saved: Option<Result<usize, String>>,
}

struct BuildState {
    slots: Vec<Slot>,
    queue: VecDeque<usize>,
    stop: bool,
    /// Built since the cache was last saved.
    unsaved: bool,
    report: BuildReport,
}

/// What the building thread shares with the engine.
struct Shared {
    device: ash::Device,
    layout: vk::PipelineLayout,
    cache: vk::PipelineCache,
    cache_key: DeviceKind,
    modules: Vec<&'static ShaderModule>,
    state: Mutex<BuildState>,
    /// Signalled when a request is queued (to the builder) and when a build ends (to waiters).
    changed: Condvar,
}

impl Shared {
    fn lock(&self) -> MutexGuard<'_, BuildState> {
        // Plain data: a panic while holding it leaves a usable state.
        self.state.lock().unwrap_or_else(|p| p.into_inner())
    }

    fn build(&self, k: usize, warm_up: Option<&mut WarmUpHook>) -> Slot {
        let t = Instant::now();
        if let Some(warm_up) = warm_up {
            warm_up(ShaderId(k));
        }
        // A session that ends, or a process that exits, may be about to destroy the app's
        // device: nothing more is made on it.
        if self.lock().stop || process_exit::exiting() {
            return Slot::Failed("the pipeline thread was stopped".into());
        }
        let slot = match compute_pipeline(self, self.modules[k]) {
            Ok(p) => Slot::Built(p),
            Err(e) => Slot::Failed(e.to_string()),
        };
        let mut st = self.lock();
        st.report.built += 1;
        st.report.build_time += t.elapsed();
        st.report.builds.push((self.modules[k].name, t.elapsed()));
        st.unsaved = true;
        slot
    }
}

pub struct Pipelines {
    pub set_layout: vk::DescriptorSetLayout,
    pub layout: vk::PipelineLayout,
    mode: BuildMode,
    shared: Option<Arc<Shared>>,
    cache: Option<PipelineCache>,
    builder: Option<JoinHandle<()>>,
}

impl Pipelines {
    /// Pipelines built as `mode` says; in BuildMode::Background, `warm_up` runs before each
    /// build.
    pub fn new(
        gpu: &GpuDevice,
        mode: BuildMode,
        warm_up: Option<WarmUpHook>,
    ) -> Result<Pipelines, GpuError> {
        let mut p = Pipelines {
            set_layout: vk::DescriptorSetLayout::null(),
            layout: vk::PipelineLayout::null(),
            mode,
            shared: None,
            cache: None,
            builder: None,
        };
        // On failure, destroy what was made so far (null handles are ignored by vkDestroy*).
        if let Err(e) = p.create(gpu, warm_up) {
            p.destroy(gpu);
            return Err(e);
        }
        Ok(p)
    }

    fn create(&mut self, gpu: &GpuDevice, warm_up: Option<WarmUpHook>) -> Result<(), GpuError> {
        self.create_layouts(gpu)?;
        let cache = PipelineCache::new(gpu)?;
        let modules = shaders::all();
        let report = BuildReport {
            built: 0,
            build_time: Duration::ZERO,
            builds: Vec::new(),
            cache: cache.origin.clone(),
            cache_bytes: cache.loaded_bytes,
            saved: None,
        };
        let shared = Arc::new(Shared {
            device: gpu.device.clone(),
            layout: self.layout,
            cache: cache.raw,
            cache_key: cache.key,
            state: Mutex::new(BuildState {
                slots: vec![Slot::Missing; modules.len()],
                queue: VecDeque::new(),
                stop: false,
                unsaved: false,
                report,
            }),
            modules,
            changed: Condvar::new(),
        });
        self.cache = Some(cache);
        self.shared = Some(shared.clone());
        if self.mode == BuildMode::Background {
            process_exit::watch();
            let spawned = std::thread::Builder::new()
                .name("contrastxr-pipelines".into())
                .spawn(move || build_requests(&shared, warm_up));
            self.builder = Some(spawned.map_err(|e| {
                GpuError::Unsupported(format!("cannot start the pipeline thread: {e}"))
            })?);
        }
        Ok(())
    }

    fn create_layouts(&mut self, gpu: &GpuDevice) -> Result<(), GpuError> {
        let bindings: Vec<_> = BINDINGS
            .iter()
            .map(|b| {
                let ty = descriptor_type(b.kind);
                vk::DescriptorSetLayoutBinding::default()
                    .binding(b.number)
                    .descriptor_type(ty)
                    .descriptor_count(1)
                    .stage_flags(vk::ShaderStageFlags::COMPUTE)
            })
            .collect();
        let info = vk::DescriptorSetLayoutCreateInfo::default().bindings(&bindings);
        // SAFETY: valid create info on a valid device.
        self.set_layout = unsafe { gpu.device.create_descriptor_set_layout(&info, None) }
            .vk("vkCreateDescriptorSetLayout")?;
        let ranges = [vk::PushConstantRange::default()
            .stage_flags(vk::ShaderStageFlags::COMPUTE)
            .size(std::mem::size_of::<PushConstants>() as u32)];
        let set_layouts = [self.set_layout];
        let info = vk::PipelineLayoutCreateInfo::default()
            .set_layouts(&set_layouts)
            .push_constant_ranges(&ranges);
        // SAFETY: valid create info on a valid device.
        self.layout = unsafe { gpu.device.create_pipeline_layout(&info, None) }
            .vk("vkCreatePipelineLayout")?;
        Ok(())
    }

    fn shared(&self) -> Result<&Arc<Shared>, GpuError> {
        self.shared
            .as_ref()
            .ok_or_else(|| GpuError::Unsupported("the pipelines were destroyed".into()))
    }

    /// Queues the shaders not built yet ahead of earlier requests, in the given order (the
    /// first is built first). Nothing in [`BuildMode::Inline`].
    pub fn request(&self, ids: &[ShaderId]) {
        let Ok(shared) = self.shared() else { return };
        if self.mode == BuildMode::Inline {
            return;
        }
        let mut st = shared.lock();
        for &ShaderId(k) in ids.iter().rev() {
            match st.slots[k] {
                Slot::Missing => st.slots[k] = Slot::Queued,
                Slot::Queued => st.queue.retain(|&q| q != k),
                _ => continue,
            }
            st.queue.push_front(k);
        }
        shared.changed.notify_all();
    }

    /// Whether every one of `ids` is built; requests the missing ones. An error if one failed.
    pub fn ready(&self, ids: &[ShaderId]) -> Result<bool, GpuError> {
        if self.mode == BuildMode::Inline {
            return ids
                .iter()
                .try_for_each(|&id| self.get(id).map(drop))
                .map(|_| true);
        }
        let missing = {
            let st = self.shared()?.lock();
            let mut missing = Vec::new();
            for &id in ids {
                match &st.slots[id.0] {
                    Slot::Built(_) => {}
                    Slot::Failed(e) => return Err(GpuError::Unsupported(e.clone())),
                    _ => missing.push(id),
                }
            }
            missing
        };
        self.request(&missing);
        Ok(missing.is_empty())
    }

    /// Waits (at most `timeout`) until every one of `ids` is built; requests the missing ones.
    pub fn wait_for(&self, ids: &[ShaderId], timeout: Duration) -> Result<(), GpuError> {
        let deadline = Instant::now() + timeout;
        while !self.ready(ids)? {
            let shared = self.shared()?;
            let st = shared.lock();
            let left = deadline.saturating_duration_since(Instant::now());
            if left.is_zero() {
                return Err(GpuError::Unsupported(
                    "the shader pipelines took too long to build".into(),
                ));
            }
            // Woken when a build ends; ready() then looks again.
            let _ = shared
                .changed
                .wait_timeout(st, left.min(Duration::from_millis(50)));
        }
        Ok(())
    }

    /// A pipeline: built, or built now in [`BuildMode::Inline`], else [`GpuError::Pending`].
    pub fn get(&self, ShaderId(k): ShaderId) -> Result<vk::Pipeline, GpuError> {
        let shared = self.shared()?;
        let mut st = shared.lock();
        match &st.slots[k] {
            Slot::Built(p) => return Ok(*p),
            Slot::Failed(e) => return Err(GpuError::Unsupported(e.clone())),
            _ if self.mode == BuildMode::Background => return Err(GpuError::Pending),
            _ => {}
        }
        drop(st);
        let slot = shared.build(k, None);
        st = shared.lock();
        st.slots[k] = slot;
        match &st.slots[k] {
            Slot::Built(p) => Ok(*p),
            Slot::Failed(e) => Err(GpuError::Unsupported(e.clone())),
            _ => unreachable!("just built"),
        }
    }

    /// What the builds took so far.
    pub fn report(&self) -> Option<BuildReport> {
        Some(self.shared.as_ref()?.lock().report.clone())
    }

    /// Tells the building thread to stop after the pipeline it is building, without waiting
    /// for it: the session passes its frames through from now on.
    pub fn stop(&self) {
        if let Some(shared) = &self.shared {
            shared.lock().stop = true;
            shared.changed.notify_all();
        }
    }

    /// Stops the building thread and waits for it to end: afterwards nothing of this object
    /// touches the device on another thread.
    pub fn join(&mut self) {
        self.stop();
        if let Some(builder) = self.builder.take() {
            let _ = builder.join();
        }
    }

    /// Stops the building thread (after the pipeline it is building), saves the cache and
    /// destroys every object.
    pub fn destroy(&mut self, gpu: &GpuDevice) {
        self.join();
        let slots = self.shared.take().map(|s| {
            save_if_changed(&s);
            std::mem::take(&mut s.lock().slots)
        });
        // SAFETY: the caller guarantees the GPU no longer uses these objects; the building
        // thread has ended.
        unsafe {
            for slot in slots.into_iter().flatten() {
                if let Slot::Built(p) = slot {
                    gpu.device.destroy_pipeline(p, None);
                }
            }
            gpu.device.destroy_pipeline_layout(self.layout, None);
            gpu.device
                .destroy_descriptor_set_layout(self.set_layout, None);
        }
        if let Some(mut cache) = self.cache.take() {
            cache.destroy(&gpu.device);
        }
        self.layout = vk::PipelineLayout::null();
        self.set_layout = vk::DescriptorSetLayout::null();
    }
}

/// Writes the cache when pipelines were built since the last write (without holding the
/// state's lock: the render thread may be asking what is ready).
fn save_if_changed(shared: &Shared) {
    if !std::mem::take(&mut shared.lock().unsaved) {
        return;
    }
    let saved = pipeline_cache::save(&shared.device, shared.cache, &shared.cache_key);
    shared.lock().report.saved = Some(saved);
}

/// The building thread: builds queued shaders until stopped; saves the cache whenever the
/// queue runs empty after builds.
fn build_requests(shared: &Shared, mut warm_up: Option<WarmUpHook>) {
    loop {
        let next = {
            let mut st = shared.lock();
            loop {
                if st.stop {
                    return;
                }
                if let Some(k) = st.queue.pop_front() {
                    st.slots[k] = Slot::Building;
                    break Some(k);
                }
                if st.unsaved {
                    break None;
                }
                st = shared.changed.wait(st).unwrap_or_else(|p| p.into_inner());
            }
        };
        // Nothing starts once the process is exiting (see gpu/process_exit.rs).
        if !process_exit::begin() {
            return;
        }
        match next {
            None => save_if_changed(shared),
            Some(k) => {
                let slot = shared.build(k, warm_up.as_mut());
                shared.lock().slots[k] = slot;
                shared.changed.notify_all();
            }
        }
        process_exit::end();
    }
}

/// The descriptor type of a binding's kind.
pub fn descriptor_type(kind: BindingKind) -> vk::DescriptorType {
    match kind {
        BindingKind::StorageBuffer => vk::DescriptorType::STORAGE_BUFFER,
        BindingKind::SampledImage => vk::DescriptorType::SAMPLED_IMAGE,
    }
}

/// How many bindings of `kind` the set layout has.
pub fn binding_count(kind: BindingKind) -> u32 {
    BINDINGS.iter().filter(|b| b.kind == kind).count() as u32
}

fn compute_pipeline(shared: &Shared, shader: &ShaderModule) -> Result<vk::Pipeline, GpuError> {
    crate::fault::check("pipeline-creation").map_err(GpuError::Unsupported)?;
    let words = shader.words();
    let info = vk::ShaderModuleCreateInfo::default().code(&words);
    let device = &shared.device;
    // SAFETY: words is SPIR-V produced and validated by naga at build time.
    let module = unsafe { device.create_shader_module(&info, None) }.vk("vkCreateShaderModule")?;
    let entry = std::ffi::CString::new(shader.entry).expect("entry names have no NUL");
    let stage = vk::PipelineShaderStageCreateInfo::default()
        .stage(vk::ShaderStageFlags::COMPUTE)
        .module(module)
        .name(&entry);
    let info = [vk::ComputePipelineCreateInfo::default()
        .stage(stage)
        .layout(shared.layout)];
    // SAFETY: module, layout and cache are valid (the cache is internally synchronised).
    let result = unsafe { device.create_compute_pipelines(shared.cache, &info, None) };
    // SAFETY: a shader module may be destroyed once pipelines using it are created.
    unsafe { device.destroy_shader_module(module, None) };
    result
        .map(|p| p[0])
        .map_err(|(_, result)| GpuError::Vulkan {
            call: "vkCreateComputePipelines",
            result,
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The ids name the shaders they stand for in `shaders::all()`.
    #[test]
    fn ids_index_the_shader_list() {
        let all = shaders::all();
        let name = |id: ShaderId| all[id.0].name;
        assert_eq!(name(DECODE_CAMERA), "decode_camera");
        assert_eq!(name(FINISH_TILES), "finish_tiles");
        assert_eq!(name(COPY_PIXELS), "copy_pixels");
        assert_eq!(name(COPY_ROWS), "copy_rows");
        assert_eq!(name(decode_blur(3).unwrap()), "decode_blur_3");
        assert!(decode_blur(8).is_err());
        for &(m, v, f, w, e, ref module) in shaders::ENHANCE_VARIANTS {
            assert_eq!(name(enhance((m, v, f), w, e).unwrap()), module.name);
        }
        for &(f, w, ref module) in shaders::CLASSIFY_VARIANTS {
            assert_eq!(name(classify(f, w).unwrap()), module.name);
        }
        assert!(reads_camera(decode_blur(7).unwrap()) && reads_camera(DECODE_CAMERA));
        assert!(!reads_camera(FINISH_TILES));
    }
}
