//! The compute pipelines built from the embedded SPIR-V, with the one descriptor-set layout and
//! push-constant block they share (src/gpu/core/interface.rs).
//!
//! A pipeline costs a shader compile in the driver (on lavapipe, LLVM: tenths of a second
//! each), so none is built inside a call an app makes to the layer: in [`BuildMode::Background`]
//! a thread of the engine's own builds what is requested, in order, through the device's
//! [`PipelineCache`], and a pipeline not built yet is [`GpuError::Pending`]. The offline tools
//! build on first use ([`BuildMode::Inline`]).

use super::pipeline_cache::{self, Origin, PipelineCache};
use crate::gpu::core::interface::{BindingKind, BINDINGS};
use crate::gpu::core::kept_threads::{self, JobDone};
use crate::gpu::core::modules::{self, ShaderModule};
use crate::gpu::core::process_exit;
use crate::gpu::core::push_constants::PushConstants;
use crate::gpu::core::shader_ids::ShaderId;
use crate::gpu::vulkan::device::{DeviceKind, GpuDevice, GpuError, VkResultExt};
use ash::vk;
use std::collections::VecDeque;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::{Arc, Condvar, Mutex, MutexGuard};

use std::time::{Duration, Instant};

/// Runs a shader once, on the building thread, before it is built for the engine's device: a
/// CPU driver compiles at first dispatch (see gpu/vulkan/frame/warm_up.rs). Its second argument says when
/// the session ended: the hook then stops waiting for its own work.
pub type WarmUpHook = Box<dyn FnMut(ShaderId, &dyn Fn() -> bool) + Send>;

/// Where pipelines are built.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BuildMode {
    /// On the thread that first needs one (the offline tools).
    Inline,
    /// On a thread of the engine's own, in the order requested (the layer).
    Background,
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
            warm_up(ShaderId(k), &|| self.lock().stop || process_exit::exiting());
        }
        // A session that ends, or a process that exits, may be about to destroy the app's
        // device: nothing more is made on it.
        if self.lock().stop || process_exit::exiting() {
            return Slot::Failed("the pipeline thread was stopped".into());
        }
        if crate::fault::hit("build-panic") {
            panic!("fault injected at build-panic (CONTRASTXR_FAULT)");
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
    set_layout: vk::DescriptorSetLayout,
    layout: vk::PipelineLayout,
    mode: BuildMode,
    shared: Option<Arc<Shared>>,
    cache: Option<PipelineCache>,
    builder: Option<JobDone>,
}

impl Pipelines {
    /// The layout of descriptor set 0, which every pipeline shares.
    pub fn set_layout(&self) -> vk::DescriptorSetLayout {
        self.set_layout
    }

    /// The pipeline layout every pipeline shares (set 0 and the push constants).
    pub fn layout(&self) -> vk::PipelineLayout {
        self.layout
    }

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
        let modules = modules::all();
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
            // A thread kept between sessions: see gpu/core/kept_threads.rs.
            let spawned = kept_threads::run("contrastxr-pipelines", move || {
                build_requests(&shared, warm_up)
            });
            self.builder = Some(spawned.map_err(|e| {
                GpuError::Unsupported(format!("cannot start the pipeline thread: {e}"))
            })?);
        }
        Ok(())
    }

    fn create_layouts(&mut self, gpu: &GpuDevice) -> Result<(), GpuError> {
        (self.set_layout, self.layout) = create_layouts(gpu)?;
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
            builder.join();
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
        // Nothing starts once the process is exiting (see gpu/core/process_exit.rs).
        let Some(_busy) = process_exit::Busy::begin() else {
            return;
        };
        match next {
            None => {
                let _ = catch_unwind(AssertUnwindSafe(|| save_if_changed(shared)));
            }
            Some(k) => {
                let slot = catch_unwind(AssertUnwindSafe(|| shared.build(k, warm_up.as_mut())))
                    .unwrap_or_else(|p| Slot::Failed(panicked(shared.modules[k].name, &*p)));
                shared.lock().slots[k] = slot;
                shared.changed.notify_all();
            }
        }
    }
}

/// What a build that panicked fails its slot with (the session's one line names it).
fn panicked(shader: &str, panic: &(dyn std::any::Any + Send)) -> String {
    let what = panic
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| panic.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "unknown panic".into());
    format!("internal error building the {shader} pipeline: {what}")
}

/// The descriptor type of a binding's kind.
pub fn descriptor_type(kind: BindingKind) -> vk::DescriptorType {
    match kind {
        BindingKind::StorageBuffer => vk::DescriptorType::STORAGE_BUFFER,
        BindingKind::SampledImage => vk::DescriptorType::SAMPLED_IMAGE,
        BindingKind::StorageImage => vk::DescriptorType::STORAGE_IMAGE,
    }
}

/// How many bindings of `kind` the set layout has.
pub fn binding_count(kind: BindingKind) -> u32 {
    BINDINGS.iter().filter(|b| b.kind == kind).count() as u32
}

fn compute_pipeline(shared: &Shared, shader: &ShaderModule) -> Result<vk::Pipeline, GpuError> {
    crate::fault::check("pipeline-creation").map_err(GpuError::Unsupported)?;
    let flags = vk::PipelineCreateFlags::empty();
    create_compute_pipeline(&shared.device, (shared.cache, shared.layout), shader, flags)
}

/// `shader`'s compute pipeline with `layout`, through `cache` (null: none), with `flags`.
pub(super) fn create_compute_pipeline(
    device: &ash::Device,
    (cache, layout): (vk::PipelineCache, vk::PipelineLayout),
    shader: &ShaderModule,
    flags: vk::PipelineCreateFlags,
) -> Result<vk::Pipeline, GpuError> {
    let words = shader.words();
    let info = vk::ShaderModuleCreateInfo::default().code(&words);
    // SAFETY: words is SPIR-V produced and validated by naga at build time.
    let module = unsafe { device.create_shader_module(&info, None) }.vk("vkCreateShaderModule")?;
    let entry = std::ffi::CString::new(shader.entry).expect("entry names have no NUL");
    let stage = vk::PipelineShaderStageCreateInfo::default()
        .stage(vk::ShaderStageFlags::COMPUTE)
        .module(module)
        .name(&entry);
    let info = [vk::ComputePipelineCreateInfo::default()
        .flags(flags)
        .stage(stage)
        .layout(layout)];
    // SAFETY: module, layout and cache are valid (the cache is internally synchronised); the
    // flags' features are the caller's to have enabled.
    let result = unsafe { device.create_compute_pipelines(cache, &info, None) };
    // SAFETY: a shader module may be destroyed once pipelines using it are created.
    unsafe { device.destroy_shader_module(module, None) };
    result
        .map(|p| p[0])
        .map_err(|(_, result)| GpuError::Vulkan {
            call: "vkCreateComputePipelines",
            result,
        })
}

/// Descriptor set 0's layout and the pipeline layout every pipeline shares (set 0 and the push
/// constants); the caller destroys both (on failure, nothing is left).
pub fn create_layouts(
    gpu: &GpuDevice,
) -> Result<(vk::DescriptorSetLayout, vk::PipelineLayout), GpuError> {
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
    let set_layout = unsafe { gpu.device.create_descriptor_set_layout(&info, None) }
        .vk("vkCreateDescriptorSetLayout")?;
    let ranges = [vk::PushConstantRange::default()
        .stage_flags(vk::ShaderStageFlags::COMPUTE)
        .size(std::mem::size_of::<PushConstants>() as u32)];
    let set_layouts = [set_layout];
    let info = vk::PipelineLayoutCreateInfo::default()
        .set_layouts(&set_layouts)
        .push_constant_ranges(&ranges);
    // SAFETY: valid create info on a valid device.
    match unsafe { gpu.device.create_pipeline_layout(&info, None) } {
        Ok(layout) => Ok((set_layout, layout)),
        Err(e) => {
            // SAFETY: the set layout is ours and unused.
            unsafe { gpu.device.destroy_descriptor_set_layout(set_layout, None) };
            Err(e).vk("vkCreatePipelineLayout")
        }
    }
}
