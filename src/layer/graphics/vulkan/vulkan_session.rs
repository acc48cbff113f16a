//! A Vulkan session's graphics: the frame engine on the app's device (its pipelines build on
//! the engine's own thread), the app's VkImages, and the in-place path where the runtime
//! grants storage usage.

use super::{app_vulkan, in_place};
use crate::algorithm::params::Params;
use crate::gpu::core::{BackgroundInput, CubeRoots, OverlayPixels};
use crate::gpu::vulkan::conv::VkFormat;
use crate::gpu::vulkan::frame::{copy_path, FrameOptions, FrameRunner, PipelinesReady};
use crate::gpu::vulkan::pipelines::Origin;
use crate::gpu::{FrameView, GpuDevice, GpuError, PixelFormat, Recorder, ViewPath, ViewShape};
use crate::layer::graphics::session_graphics::{
    image_handles, Bound, CapturedImage, NotDone, SessionGraphics, ViewImage,
};
use crate::layer::live_settings::Settings;
use crate::layer::log;
use ash::vk::{self, Handle};
use openxr_sys as xr;
use std::sync::atomic::{AtomicBool, Ordering};

pub struct VulkanSession {
    engine: FrameRunner,
    /// The last `ready` answer, taken by the next `enhance`.
    ready: Option<PipelinesReady>,
    /// Whether views not enhanced in place go through an image of the engine's own where
    /// their format allows it (`in_place::wanted` at the last swapchain's creation), else
    /// through a buffer.
    image_copy: AtomicBool,
    /// Whether the image-copy path draws its listed tiles back (`copy_back = "tiles"` at the
    /// last swapchain's creation) rather than copying the region back.
    tiles: AtomicBool,
    /// Whether the image-copy path reads 8-bit sRGB views through a sampled view
    /// (`copy_in = "sampled"`, or `auto` on a GPU, at the last swapchain's creation).
    sampled: AtomicBool,
}

/// The session's graphics for a Vulkan binding (None: not one).
///
/// # Safety
/// `base` starts a structure of the type it names, from a chain the runtime accepted.
pub unsafe fn bind(base: &xr::BaseInStructure, settings: &Settings) -> Option<Bound> {
    if base.ty != xr::StructureType::GRAPHICS_BINDING_VULKAN_KHR {
        return None;
    }
    // SAFETY: the type tag says this is a Vulkan binding (the caller's contract).
    let b = unsafe { &*(base as *const _ as *const xr::GraphicsBindingVulkanKHR) };
    Some(match set_up(b, settings) {
        Ok(engine) => {
            let (tiles, sampled) = in_place::ways(&engine.gpu, settings);
            Bound::Enhanced(Box::new(VulkanSession {
                image_copy: AtomicBool::new(in_place::wanted(&engine.gpu, settings)),
                tiles: AtomicBool::new(tiles),
                sampled: AtomicBool::new(sampled),
                engine,
                ready: None,
            }))
        }
        Err(e) => Bound::PassThrough(format!(
            "GPU set-up failed ({e}): passing frames through untouched"
        )),
    })
}

/// The session's frame engine on the app's device (its pipelines start building at once, on
/// its own thread).
fn set_up(b: &xr::GraphicsBindingVulkanKHR, settings: &Settings) -> Result<FrameRunner, GpuError> {
    let raw_instance = vk::Instance::from_raw(b.instance as u64);
    let entry = app_vulkan::entry_for(raw_instance).map_err(GpuError::NoLoader)?;
    // SAFETY: the handles come from a Vulkan binding the runtime accepted; the app keeps them
    // alive until after xrDestroySession, where the engine is ended first.
    let gpu = unsafe {
        GpuDevice::borrow(
            entry,
            raw_instance,
            vk::PhysicalDevice::from_raw(b.physical_device as u64),
            vk::Device::from_raw(b.device as u64),
            b.queue_family_index,
            b.queue_index,
        )
    }?;
    // The background preparation's shaders first: the views' ones need a swapchain's format.
    let roots = CubeRoots::for_device(gpu.is_cpu());
    let first = Recorder::shaders_for(&settings.params, [], roots).unwrap_or_default();
    gpu.queue_has_compute()?;
    let mut engine = FrameRunner::new(gpu, &first)?;
    log_warm_up_device(&mut engine);
    log::info(&format!(
        "session on Vulkan device {:?}, background {}: enhancing",
        engine.gpu.name, settings.background
    ));
    Ok(engine)
}

/// Says what making the process's warm-up device (CPU drivers, made inside xrCreateSession
/// when a session first needs it) gave.
fn log_warm_up_device(engine: &mut FrameRunner) {
    match engine.warm_up_made() {
        Some(Ok(took)) => log::debug(&format!(
            "warm-up device made on the app's thread in {:.3} s",
            took.as_secs_f64()
        )),
        Some(Err(e)) => log::info(&format!(
            "no warm-up device ({e}): shaders compile at their first dispatch; not tried again in this session"
        )),
        None => {}
    }
}

impl VulkanSession {
    /// The path of `v`: in place where its swapchain has storage usage, else through an image
    /// of the engine's own or a buffer.
    fn path(&self, v: &ViewImage) -> ViewPath {
        self.path_of(v.format, v.in_place, (v.attachment, v.sampled))
    }

    /// The path of views of `format`, on a swapchain with storage usage (`in_place`) or with
    /// `usage` (colour-attachment, sampled).
    fn path_of(&self, format: PixelFormat, in_place: bool, usage: (bool, bool)) -> ViewPath {
        match (in_place, self.image_copy.load(Ordering::Relaxed)) {
            (true, _) => ViewPath::InPlace,
            (false, true) => self.image_copy_way(format, usage),
            (false, false) => ViewPath::BufferCopy,
        }
    }

    /// The copy path of views of `format` on a swapchain with `usage` (colour-attachment,
    /// sampled), with the image-copy path's way as the settings asked at the last swapchain's
    /// creation.
    fn image_copy_way(&self, format: PixelFormat, usage: (bool, bool)) -> ViewPath {
        let ways = (
            self.tiles.load(Ordering::Relaxed),
            self.sampled.load(Ordering::Relaxed),
        );
        let path = copy_path(&self.engine.gpu, format);
        in_place::image_copy_way(path, format, ways, usage)
    }

    fn frame_view(&self, v: &ViewImage) -> FrameView {
        FrameView::new(
            v.key,
            vk::Image::from_raw(v.image),
            v.format,
            vk::Format::from_raw(v.api_format as i32),
            self.path(v),
            v.mapping,
            v.pixels_per_degree,
        )
    }
}

fn not_done(e: GpuError) -> NotDone {
    match e {
        GpuError::Pending => NotDone::Pending,
        e => NotDone::Failed(format!("GPU work failed ({e})")),
    }
}

impl SessionGraphics for VulkanSession {
    fn api(&self) -> &'static str {
        "Vulkan"
    }

    fn graphics(&self) -> &'static str {
        "vulkan"
    }

    fn pixel_format(&self, api_format: i64) -> Option<PixelFormat> {
        PixelFormat::from_vk(vk::Format::from_raw(api_format as i32))
    }

    fn format_name(&self, api_format: i64) -> String {
        format!("{:?}", vk::Format::from_raw(api_format as i32))
    }

    fn needed_usage(&self) -> xr::SwapchainUsageFlags {
        xr::SwapchainUsageFlags::TRANSFER_SRC | xr::SwapchainUsageFlags::TRANSFER_DST
    }

    fn in_place_usage(
        &self,
        format: PixelFormat,
        info: &xr::SwapchainCreateInfo,
        settings: &Settings,
    ) -> Option<xr::SwapchainUsageFlags> {
        let wanted = in_place::wanted(&self.engine.gpu, settings);
        self.image_copy.store(wanted, Ordering::Relaxed);
        let (tiles, sampled) = in_place::ways(&self.engine.gpu, settings);
        self.tiles.store(tiles, Ordering::Relaxed);
        self.sampled.store(sampled, Ordering::Relaxed);
        in_place::added_usage(&self.engine.gpu, settings, format, info)
    }

    fn sampled_usage(
        &self,
        format: PixelFormat,
        settings: &Settings,
    ) -> Option<xr::SwapchainUsageFlags> {
        let path = in_place::copy_path(&self.engine.gpu, settings, format);
        (path == ViewPath::SampledTiles).then_some(xr::SwapchainUsageFlags::SAMPLED)
    }

    fn copy_path(&self, format: PixelFormat, settings: &Settings) -> &'static str {
        in_place::copy_path(&self.engine.gpu, settings, format).name()
    }

    unsafe fn images(
        &self,
        images: *const xr::SwapchainImageBaseHeader,
        count: usize,
    ) -> Option<Vec<u64>> {
        let ty = xr::StructureType::SWAPCHAIN_IMAGE_VULKAN_KHR;
        // SAFETY: the caller's contract, passed on.
        unsafe { image_handles(images, count, ty, |i: &xr::SwapchainImageVulkanKHR| i.image) }
    }

    fn request_shaders(
        &mut self,
        params: &Params,
        format: PixelFormat,
        width: u32,
        in_place: bool,
        _: bool,
    ) {
        // The engine's pipeline thread runs at the app's priority whatever `pipelines` says.
        // The path of its views where the swapchain has every usage the layer may add.
        let path = self.path_of(format, in_place, (true, true));
        let shape = ViewShape {
            format,
            width,
            pixels_in: path.pixels_in(),
        };
        let roots = CubeRoots::for_device(self.engine.gpu.is_cpu());
        if let Ok(ids) = Recorder::shaders_for(params, [shape], roots) {
            self.engine.request(&ids);
        }
    }

    fn forget_swapchain(&mut self, swapchain: u64) -> Result<(), String> {
        self.engine
            .forget_swapchain(swapchain)
            .map_err(|e| e.to_string())
    }

    fn take_live_texels(&self, background: &crate::camera::Background) {
        // The engine's sink is one for its life: after the first frame this delivers nothing new.
        background.deliver_texels_to(Some(self.engine.texel_sink()));
    }

    fn ready(&mut self, views: &[ViewImage], params: &Params, wait: bool) -> Result<(), NotDone> {
        let views: Vec<FrameView> = views.iter().map(|v| self.frame_view(v)).collect();
        let ready = self.engine.pipelines_ready(&views, params, wait);
        self.ready = Some(ready.map_err(not_done)?);
        Ok(())
    }

    fn enhance(
        &mut self,
        views: &[ViewImage],
        background: BackgroundInput,
        params: &Params,
        overlay: Option<&OverlayPixels>,
        capture: bool,
    ) -> Result<Vec<CapturedImage>, NotDone> {
        let ready = self.ready.take().ok_or(NotDone::Pending)?;
        let frame_views: Vec<FrameView> = views.iter().map(|v| self.frame_view(v)).collect();
        let options = FrameOptions {
            capture,
            wait_for_pipelines: false,
        };
        let captured = self
            .engine
            .process(ready, &frame_views, background, params, overlay, options)
            .map_err(not_done)?;
        Ok(captured
            .into_iter()
            .zip(views)
            .map(|(c, v)| CapturedImage {
                path: c.view.path.name(),
                view: v.clone(),
                display: c.display,
                output: c.output,
            })
            .collect())
    }

    fn take_gpu_times(&mut self) -> Vec<std::time::Duration> {
        self.engine.take_gpu_times()
    }

    fn pending_line(&self) -> &'static str {
        "building the shader pipelines on the layer's own thread: frames go through untouched until they are ready"
    }

    fn build_summary(&self) -> Option<String> {
        let r = self.engine.build_report()?;
        let cache = match &r.cache {
            Origin::Process => format!(
                "{} bytes from this process's earlier session",
                r.cache_bytes
            ),
            Origin::File(path) => format!("{} bytes from {}", r.cache_bytes, path.display()),
            Origin::Empty(None) => "empty".into(),
            Origin::Empty(Some(why)) => format!("empty ({why})"),
        };
        let each: Vec<String> = r
            .builds
            .iter()
            .map(|(name, t)| format!("{name} {:.0} ms", t.as_secs_f64() * 1e3))
            .collect();
        log::debug(&format!("pipeline builds: {}", each.join(", ")));
        Some(format!(
            "{} pipelines built in {:.3} s on the layer's thread; pipeline cache: {cache}",
            r.built,
            r.build_time.as_secs_f64()
        ))
    }

    fn frame_lines(&self, views: &[ViewImage], prepared: bool) -> Vec<(&'static str, String)> {
        let mut lines = Vec::new();
        if prepared {
            let path = match self.engine.direct_texels() {
                true => {
                    "live frames' texels are written straight into mapped images the views sample"
                }
                false => {
                    "live frames' texels reach the views through a staging buffer and an image copy"
                }
            };
            lines.push(("prepared-texels-path", path.to_string()));
        }
        if self.engine.texels_from_source().0 > 0 {
            lines.push(("source-texels", "live frames' texels are written into mapped memory on the camera's thread, before the frame call".to_string()));
        }
        if let Some(why) = self.engine.write_back_failure() {
            let line = format!(
                "the listed tiles cannot be drawn back ({why}): those views copy the region back"
            );
            lines.push(("write-back-failed", line));
        }
        let paths: Vec<ViewPath> = views.iter().map(|v| self.path(v)).collect();
        let count = |p: ViewPath| paths.iter().filter(|&&q| q == p).count();
        let tiles = count(ViewPath::ImageCopyTiles) + count(ViewPath::SampledTiles);
        lines.push((
            "first-frame-path",
            format!(
                "views enhanced in place: {} of {} (the others through a copy: {} through an image of the layer's own, {} of them with the listed tiles drawn back, {} of those read through a sampled view instead of copied in; {} through a buffer)",
                count(ViewPath::InPlace),
                views.len(),
                count(ViewPath::ImageCopy) + tiles,
                tiles,
                count(ViewPath::SampledTiles),
                count(ViewPath::BufferCopy),
            ),
        ));
        lines
    }

    fn stop_building(&self) {
        self.engine.stop_building();
    }

    fn finish(self: Box<Self>) -> Result<(), String> {
        self.engine.finish().map_err(|e| {
            format!(
                "the GPU did not finish the layer's last work ({e}): its objects are left alive, not destroyed"
            )
        })
    }
}
