//! The image-copy path's write-back by drawing (shaders/write_back.wgsl): a render pass and a
//! graphics pipeline per attachment format, with the descriptor-set layout of its own (the
//! view's tile list for the vertex stage, the engine's image for the fragment stage). Drawing
//! only the listed tiles into the app's image replaces the copy of the whole region back: a
//! colour attachment is the one way to write an image that may not be stored to (an sRGB
//! swapchain image), and the draw's indirect arguments come from the tile count on the GPU.
//! Pipelines are built on first use (a graphics pipeline of two small stages).

use crate::gpu::core::{kept_threads, process_exit, PixelFormat};
use crate::gpu::vulkan::device::{GpuDevice, GpuError, VkResultExt};
use ash::vk;
use std::collections::HashMap;
use std::sync::{Arc, Mutex, MutexGuard};

mod table {
    include!(concat!(env!("OUT_DIR"), "/write_back_table.rs"));
}

/// The push constants of the vertex stage (struct WriteBack in build/write_back.rs).
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct WriteBackConstants {
    pub region_size: [u32; 2],
    pub tile_columns: u32,
    pub pad: u32,
}

impl WriteBackConstants {
    pub fn bytes(&self) -> [u8; 16] {
        let words = [
            self.region_size[0],
            self.region_size[1],
            self.tile_columns,
            self.pad,
        ];
        let mut b = [0u8; 16];
        for (chunk, w) in b.as_chunks_mut::<4>().0.iter_mut().zip(words) {
            chunk.copy_from_slice(&w.to_le_bytes());
        }
        b
    }
}

/// Descriptor sets at once: one per view written back.
const MAX_SETS: u32 = 64;

/// A format's render pass and pipeline.
#[derive(Clone, Copy, Debug)]
pub struct WriteBackPass {
    render_pass: vk::RenderPass,
    pipeline: vk::Pipeline,
}

impl WriteBackPass {
    pub fn render_pass(&self) -> vk::RenderPass {
        self.render_pass
    }

    pub fn pipeline(&self) -> vk::Pipeline {
        self.pipeline
    }
}

/// Each attachment format's pass, built or failed (its message).
type Passes = HashMap<vk::Format, Result<WriteBackPass, String>>;

pub struct WriteBackPipelines {
    set_layout: vk::DescriptorSetLayout,
    layout: vk::PipelineLayout,
    pool: vk::DescriptorPool,
    passes: Arc<Mutex<Passes>>,
    /// Formats whose pass a thread of the engine's own is building or has built.
    requested: Vec<vk::Format>,
    builders: Vec<kept_threads::JobDone>,
}

/// Every SPIR-V module of the write-back, named (for spirv-val in the tests).
pub fn write_back_modules() -> Vec<(String, &'static [u8])> {
    let fragments = table::FRAGMENTS
        .iter()
        .map(|(code, spv)| (format!("write_back_fragment_f{code}"), *spv));
    std::iter::once(("write_back_vertex".to_string(), table::VERTEX))
        .chain(fragments)
        .collect()
}

/// The fragment stage's SPIR-V for a FORMAT code.
fn fragment(code: u32) -> Option<&'static [u8]> {
    table::FRAGMENTS
        .iter()
        .find(|(c, _)| *c == code)
        .map(|(_, spv)| *spv)
}

fn words(bytes: &[u8]) -> Vec<u32> {
    bytes
        .as_chunks::<4>()
        .0
        .iter()
        .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect()
}

impl WriteBackPipelines {
    pub fn new(gpu: &GpuDevice) -> Result<Self, GpuError> {
        use vk::{DescriptorType as T, ShaderStageFlags as S};
        let d = &gpu.device;
        let bindings = [
            vk::DescriptorSetLayoutBinding::default()
                .binding(0)
                .descriptor_type(T::STORAGE_BUFFER)
                .descriptor_count(1)
                .stage_flags(S::VERTEX),
            vk::DescriptorSetLayoutBinding::default()
                .binding(1)
                .descriptor_type(T::STORAGE_IMAGE)
                .descriptor_count(1)
                .stage_flags(S::FRAGMENT),
        ];
        let info = vk::DescriptorSetLayoutCreateInfo::default().bindings(&bindings);
        // SAFETY: valid create info on a valid device.
        let set_layout = unsafe { d.create_descriptor_set_layout(&info, None) }
            .vk("vkCreateDescriptorSetLayout")?;
        let mut made = WriteBackPipelines {
            set_layout,
            layout: vk::PipelineLayout::null(),
            pool: vk::DescriptorPool::null(),
            passes: Arc::default(),
            requested: Vec::new(),
            builders: Vec::new(),
        };
        let ranges = [vk::PushConstantRange::default()
            .stage_flags(S::VERTEX)
            .size(std::mem::size_of::<WriteBackConstants>() as u32)];
        let set_layouts = [set_layout];
        let info = vk::PipelineLayoutCreateInfo::default()
            .set_layouts(&set_layouts)
            .push_constant_ranges(&ranges);
        let sizes = [
            vk::DescriptorPoolSize::default()
                .ty(T::STORAGE_BUFFER)
                .descriptor_count(MAX_SETS),
            vk::DescriptorPoolSize::default()
                .ty(T::STORAGE_IMAGE)
                .descriptor_count(MAX_SETS),
        ];
        let pool = vk::DescriptorPoolCreateInfo::default()
            .flags(vk::DescriptorPoolCreateFlags::FREE_DESCRIPTOR_SET)
            .max_sets(MAX_SETS)
            .pool_sizes(&sizes);
        // SAFETY: valid create infos on a valid device.
        let created = unsafe { d.create_pipeline_layout(&info, None) }
            .vk("vkCreatePipelineLayout")
            .and_then(|layout| {
                made.layout = layout;
                // SAFETY: as above.
                unsafe { d.create_descriptor_pool(&pool, None) }.vk("vkCreateDescriptorPool")
            });
        match created {
            Ok(pool) => {
                made.pool = pool;
                Ok(made)
            }
            Err(e) => {
                made.destroy(gpu);
                Err(e)
            }
        }
    }

    /// The pipeline layout of every format's pipeline.
    pub fn layout(&self) -> vk::PipelineLayout {
        self.layout
    }

    /// The pool the views' sets come from (FREE_DESCRIPTOR_SET).
    pub fn pool(&self) -> vk::DescriptorPool {
        self.pool
    }

    fn passes(&self) -> MutexGuard<'_, Passes> {
        // Plain data: a panic while holding it leaves a usable map.
        self.passes.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// The render pass and pipeline that write back into images of `vk_format`, built here
    /// on first use (the offline tools).
    pub fn pass(
        &mut self,
        gpu: &GpuDevice,
        (vk_format, format): (vk::Format, PixelFormat),
    ) -> Result<WriteBackPass, GpuError> {
        if let Some(p) = self.passes().get(&vk_format) {
            return p.clone().map_err(GpuError::Unsupported);
        }
        let built = build_pass(&gpu.device, self.layout, (vk_format, format));
        let kept = built.as_ref().map(|p| *p).map_err(|e| e.to_string());
        self.passes().insert(vk_format, kept);
        built
    }

    /// Starts building the pass of `vk_format` on a thread of its own, unless it was asked
    /// for before (the layer: no pipeline is built inside a call an app makes). `ready` gives
    /// it once built.
    pub fn request(&mut self, gpu: &GpuDevice, (vk_format, format): (vk::Format, PixelFormat)) {
        if self.requested.contains(&vk_format) {
            return;
        }
        self.requested.push(vk_format);
        let (device, layout, passes) = (gpu.device.clone(), self.layout, self.passes.clone());
        // A thread kept between sessions, as the pipelines' (gpu/core/kept_threads.rs).
        let builder = kept_threads::run("contrastxr-write-back", move || {
            // Counted as a build in progress, so that the process's exit waits for it
            // before the driver's destructors run (gpu/core/process_exit.rs).
            let built = match process_exit::Busy::begin() {
                None => Err("the process is exiting".to_string()),
                Some(_busy) => std::panic::catch_unwind(|| {
                    build_pass(&device, layout, (vk_format, format)).map_err(|e| e.to_string())
                })
                .unwrap_or_else(|_| Err("the write-back's build panicked".into())),
            };
            let mut passes = passes.lock().unwrap_or_else(|p| p.into_inner());
            passes.insert(vk_format, built);
        });
        match builder {
            Ok(handle) => self.builders.push(handle),
            Err(e) => {
                let why = format!("no thread to build the write-back: {e}");
                self.passes().insert(vk_format, Err(why));
            }
        }
    }

    /// The pass of `vk_format` if it is built; None while it is being built, or when it
    /// failed (`failure` says why).
    pub fn ready(&self, vk_format: vk::Format) -> Option<WriteBackPass> {
        self.passes().get(&vk_format)?.clone().ok()
    }

    /// Waits at most `timeout` for the pass of `vk_format` (requested before) to be built or
    /// to fail.
    pub fn wait_for(&self, vk_format: vk::Format, timeout: std::time::Duration) {
        let start = std::time::Instant::now();
        while !self.passes().contains_key(&vk_format) && start.elapsed() < timeout {
            std::thread::sleep(std::time::Duration::from_millis(2));
        }
    }

    /// Why the pass of `vk_format` could not be built, if it could not.
    pub fn failure(&self, vk_format: vk::Format) -> Option<String> {
        self.passes().get(&vk_format)?.clone().err()
    }

    /// A descriptor set of a view: its tile list and the engine's image it is enhanced in.
    pub fn view_set(
        &self,
        gpu: &GpuDevice,
        tiles: vk::Buffer,
        own: vk::ImageView,
    ) -> Result<vk::DescriptorSet, GpuError> {
        let layouts = [self.set_layout];
        let info = vk::DescriptorSetAllocateInfo::default()
            .descriptor_pool(self.pool)
            .set_layouts(&layouts);
        // SAFETY: pool and layout are ours and valid.
        let set = unsafe { gpu.device.allocate_descriptor_sets(&info) }
            .vk("vkAllocateDescriptorSets")?[0];
        let buffer = [vk::DescriptorBufferInfo::default()
            .buffer(tiles)
            .range(vk::WHOLE_SIZE)];
        let image = [vk::DescriptorImageInfo::default()
            .image_view(own)
            .image_layout(vk::ImageLayout::GENERAL)];
        let writes = [
            vk::WriteDescriptorSet::default()
                .dst_set(set)
                .dst_binding(0)
                .descriptor_type(vk::DescriptorType::STORAGE_BUFFER)
                .buffer_info(&buffer),
            vk::WriteDescriptorSet::default()
                .dst_set(set)
                .dst_binding(1)
                .descriptor_type(vk::DescriptorType::STORAGE_IMAGE)
                .image_info(&image),
        ];
        // SAFETY: the set is ours and not in use; buffer and view are valid.
        unsafe { gpu.device.update_descriptor_sets(&writes, &[]) };
        Ok(set)
    }

    /// Frees a view's set. The GPU must be done with it.
    pub fn free_set(&self, gpu: &GpuDevice, set: vk::DescriptorSet) {
        // SAFETY: the set came from our pool (FREE_DESCRIPTOR_SET) and is no longer in use.
        let _ = unsafe { gpu.device.free_descriptor_sets(self.pool, &[set]) };
    }

    /// Destroys everything. The GPU must be done with it.
    pub fn destroy(&mut self, gpu: &GpuDevice) {
        // The builders use the device: they end before anything is destroyed.
        for b in self.builders.drain(..) {
            b.join();
        }
        let d = &gpu.device;
        let passes: Vec<WriteBackPass> =
            self.passes().drain().filter_map(|(_, p)| p.ok()).collect();
        // SAFETY: our own objects; the GPU no longer uses them (the caller's contract); null
        // handles are ignored.
        unsafe {
            for p in passes {
                d.destroy_pipeline(p.pipeline, None);
                d.destroy_render_pass(p.render_pass, None);
            }
            d.destroy_descriptor_pool(self.pool, None);
            d.destroy_pipeline_layout(self.layout, None);
            d.destroy_descriptor_set_layout(self.set_layout, None);
        }
        self.pool = vk::DescriptorPool::null();
        self.layout = vk::PipelineLayout::null();
        self.set_layout = vk::DescriptorSetLayout::null();
    }
}

/// The render pass and pipeline of `vk_format` (read as `format`).
fn build_pass(
    d: &ash::Device,
    layout: vk::PipelineLayout,
    (vk_format, format): (vk::Format, PixelFormat),
) -> Result<WriteBackPass, GpuError> {
    crate::fault::check("write-back-build").map_err(GpuError::Unsupported)?;
    let spv = fragment(format.shader_code())
        .ok_or_else(|| GpuError::Unsupported(format!("no write-back for {vk_format:?}")))?;
    let render_pass = render_pass(d, vk_format)?;
    match pipeline(d, layout, render_pass, spv) {
        Ok(pipeline) => Ok(WriteBackPass {
            render_pass,
            pipeline,
        }),
        Err(e) => {
            // SAFETY: our own render pass, used by nothing.
            unsafe { d.destroy_render_pass(render_pass, None) };
            Err(e)
        }
    }
}

/// One colour attachment of `format`, loaded and stored, in GENERAL throughout: the app's
/// image stays in the layout of the copies around it, and the barriers around the pass are the
/// caller's.
fn render_pass(d: &ash::Device, format: vk::Format) -> Result<vk::RenderPass, GpuError> {
    let general = vk::ImageLayout::GENERAL;
    let attachments = [vk::AttachmentDescription::default()
        .format(format)
        .samples(vk::SampleCountFlags::TYPE_1)
        .load_op(vk::AttachmentLoadOp::LOAD)
        .store_op(vk::AttachmentStoreOp::STORE)
        .stencil_load_op(vk::AttachmentLoadOp::DONT_CARE)
        .stencil_store_op(vk::AttachmentStoreOp::DONT_CARE)
        .initial_layout(general)
        .final_layout(general)];
    let colour = [vk::AttachmentReference::default()
        .attachment(0)
        .layout(general)];
    let subpasses = [vk::SubpassDescription::default()
        .pipeline_bind_point(vk::PipelineBindPoint::GRAPHICS)
        .color_attachments(&colour)];
    let info = vk::RenderPassCreateInfo::default()
        .attachments(&attachments)
        .subpasses(&subpasses);
    // SAFETY: valid create info on a valid device.
    unsafe { d.create_render_pass(&info, None) }.vk("vkCreateRenderPass")
}

fn pipeline(
    d: &ash::Device,
    layout: vk::PipelineLayout,
    render_pass: vk::RenderPass,
    fragment_spv: &[u8],
) -> Result<vk::Pipeline, GpuError> {
    let mut modules = Vec::new();
    for spv in [table::VERTEX, fragment_spv] {
        let code = words(spv);
        let info = vk::ShaderModuleCreateInfo::default().code(&code);
        // SAFETY: SPIR-V produced and validated by naga at build time.
        match unsafe { d.create_shader_module(&info, None) }.vk("vkCreateShaderModule") {
            Ok(m) => modules.push(m),
            Err(e) => {
                // SAFETY: modules we made, used by nothing.
                modules
                    .iter()
                    .for_each(|&m| unsafe { d.destroy_shader_module(m, None) });
                return Err(e);
            }
        }
    }
    let result = graphics_pipeline(d, layout, render_pass, (modules[0], modules[1]));
    // SAFETY: a shader module may be destroyed once pipelines using it are created.
    modules
        .iter()
        .for_each(|&m| unsafe { d.destroy_shader_module(m, None) });
    result
}

fn graphics_pipeline(
    d: &ash::Device,
    layout: vk::PipelineLayout,
    render_pass: vk::RenderPass,
    (vertex, fragment): (vk::ShaderModule, vk::ShaderModule),
) -> Result<vk::Pipeline, GpuError> {
    let stages = [
        vk::PipelineShaderStageCreateInfo::default()
            .stage(vk::ShaderStageFlags::VERTEX)
            .module(vertex)
            .name(c"write_back_vertex"),
        vk::PipelineShaderStageCreateInfo::default()
            .stage(vk::ShaderStageFlags::FRAGMENT)
            .module(fragment)
            .name(c"write_back_fragment"),
    ];
    let vertex_input = vk::PipelineVertexInputStateCreateInfo::default();
    let assembly = vk::PipelineInputAssemblyStateCreateInfo::default()
        .topology(vk::PrimitiveTopology::TRIANGLE_LIST);
    let viewport = vk::PipelineViewportStateCreateInfo::default()
        .viewport_count(1)
        .scissor_count(1);
    let raster = vk::PipelineRasterizationStateCreateInfo::default()
        .polygon_mode(vk::PolygonMode::FILL)
        .cull_mode(vk::CullModeFlags::NONE)
        .front_face(vk::FrontFace::COUNTER_CLOCKWISE)
        .line_width(1.0);
    let multisample = vk::PipelineMultisampleStateCreateInfo::default()
        .rasterization_samples(vk::SampleCountFlags::TYPE_1);
    let blend_attachments = [vk::PipelineColorBlendAttachmentState::default()
        .color_write_mask(vk::ColorComponentFlags::RGBA)];
    let blend = vk::PipelineColorBlendStateCreateInfo::default().attachments(&blend_attachments);
    let dynamic_states = [vk::DynamicState::VIEWPORT, vk::DynamicState::SCISSOR];
    let dynamic = vk::PipelineDynamicStateCreateInfo::default().dynamic_states(&dynamic_states);
    let info = [vk::GraphicsPipelineCreateInfo::default()
        .stages(&stages)
        .vertex_input_state(&vertex_input)
        .input_assembly_state(&assembly)
        .viewport_state(&viewport)
        .rasterization_state(&raster)
        .multisample_state(&multisample)
        .color_blend_state(&blend)
        .dynamic_state(&dynamic)
        .layout(layout)
        .render_pass(render_pass)
        .subpass(0)];
    // SAFETY: the stages, layout and render pass are valid and agree with the shaders.
    let result = unsafe { d.create_graphics_pipelines(vk::PipelineCache::null(), &info, None) };
    result
        .map(|p| p[0])
        .map_err(|(_, result)| GpuError::Vulkan {
            call: "vkCreateGraphicsPipelines",
            result,
        })
}
