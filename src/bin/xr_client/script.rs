//! `--script`: a scripted sequence of raw swapchain and frame calls, each one's XrResult
//! recorded as the runtime (or a layer) returned it, whatever the call order. Used to compare
//! call semantics with and without an API layer: the calls go through the raw function table,
//! so nothing in the client checks or reorders them.
//!
//! Ops (comma-separated): `acquire`, `wait`, `release` (the script's swapchain), `begin`
//! (xrWaitFrame, then xrBeginFrame: the recorded result is xrBeginFrame's), `end` (xrEndFrame
//! with one projection layer, both views on the script's swapchain, array layers 0 and 1),
//! `end-empty` (xrEndFrame with no layers), `end-opaque`/`end-additive` (`end` with that blend
//! mode), `blend-count`/`blend-short`/`blend-fill`/`blend-bad-view`
//! (xrEnumerateEnvironmentBlendModes with capacity 0, 1 and 8, and an invalid view
//! configuration; the count and modes written are recorded too), `destroy` (xrDestroySwapchain), `create` (a new
//! swapchain replaces the script's one). The script's swapchain is created before the first op.
//! After a successful `wait` the client clears the waited image to a colour, so a layer has
//! content to work on. The calls and their order are the same for every graphics API; what
//! differs (the swapchain's format and usage, its images, how to clear one) is [`ScriptApi`].

use std::ptr;

use ash::vk::{self, Handle};
use openxr as xr;
use openxr::sys;

use crate::error::{fail, Context, Result};
use crate::pattern_swapchain::{barrier, record_transfer_write};
use crate::scene::Scene;

/// What a script needs of the session's graphics API.
pub trait ScriptApi {
    type Api: xr::Graphics;
    fn session(&self) -> &xr::Session<Self::Api>;
    fn space(&self) -> &xr::Space;
    fn view_size(&self) -> (u32, u32);
    fn blend_mode(&self) -> xr::EnvironmentBlendMode;
    /// The script's swapchains' format and usage (two array layers of `view_size`).
    fn swapchain_format(&self) -> (i64, sys::SwapchainUsageFlags);
    /// The images of swapchain `raw` (VkImage handles or GL texture names).
    fn images(&self, raw: sys::Swapchain) -> Result<Vec<u64>>;
    /// Clears both layers of `image` (acquired and waited by the client) to a colour.
    fn clear(&self, image: u64) -> Result<()>;
}

/// The colour [`ScriptApi::clear`] writes.
pub const CLEAR_COLOUR: [f32; 4] = [0.8, 0.35, 0.2, 1.0];

/// The images of swapchain `raw` by the two-call idiom, as structs like `blank` (the image
/// struct of the session's graphics API).
pub fn enumerate_images<S: ScriptApi + ?Sized, T: Copy>(
    api: &S,
    raw: sys::Swapchain,
    blank: T,
) -> Result<Vec<T>> {
    let enumerate = api.session().instance().fp().enumerate_swapchain_images;
    let mut count = 0;
    // SAFETY: the two-call idiom with a null array first.
    let r = unsafe { enumerate(raw, 0, &mut count, ptr::null_mut()) };
    if r != sys::Result::SUCCESS {
        return fail(format!("xrEnumerateSwapchainImages failed: {r:?}"));
    }
    let mut images = vec![blank; count as usize];
    // SAFETY: `count` image structs of the session's graphics API (the caller's `blank`).
    let r = unsafe { enumerate(raw, count, &mut count, images.as_mut_ptr().cast()) };
    if r != sys::Result::SUCCESS {
        return fail(format!("xrEnumerateSwapchainImages failed: {r:?}"));
    }
    Ok(images)
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Op {
    Acquire,
    Wait,
    Release,
    Begin,
    End,
    EndEmpty,
    EndOpaque,
    EndAdditive,
    Blend(BlendCall),
    Destroy,
    Create,
}

/// An xrEnumerateEnvironmentBlendModes call form.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BlendCall {
    Count,
    Short,
    Fill,
    BadView,
}

pub fn parse(text: &str) -> std::result::Result<Vec<Op>, String> {
    text.split(',')
        .map(|op| match op.trim() {
            "acquire" => Ok(Op::Acquire),
            "wait" => Ok(Op::Wait),
            "release" => Ok(Op::Release),
            "begin" => Ok(Op::Begin),
            "end" => Ok(Op::End),
            "end-empty" => Ok(Op::EndEmpty),
            "end-opaque" => Ok(Op::EndOpaque),
            "end-additive" => Ok(Op::EndAdditive),
            "blend-count" => Ok(Op::Blend(BlendCall::Count)),
            "blend-short" => Ok(Op::Blend(BlendCall::Short)),
            "blend-fill" => Ok(Op::Blend(BlendCall::Fill)),
            "blend-bad-view" => Ok(Op::Blend(BlendCall::BadView)),
            "destroy" => Ok(Op::Destroy),
            "create" => Ok(Op::Create),
            other => Err(format!(
                "unknown script op {other:?}: use acquire wait release begin end end-empty end-opaque end-additive blend-count blend-short blend-fill blend-bad-view destroy create"
            )),
        })
        .collect()
}

fn op_name(op: Op) -> &'static str {
    match op {
        Op::Acquire => "acquire",
        Op::Wait => "wait",
        Op::Release => "release",
        Op::Begin => "begin",
        Op::End => "end",
        Op::EndEmpty => "end-empty",
        Op::EndOpaque => "end-opaque",
        Op::EndAdditive => "end-additive",
        Op::Blend(BlendCall::Count) => "blend-count",
        Op::Blend(BlendCall::Short) => "blend-short",
        Op::Blend(BlendCall::Fill) => "blend-fill",
        Op::Blend(BlendCall::BadView) => "blend-bad-view",
        Op::Destroy => "destroy",
        Op::Create => "create",
    }
}

/// A swapchain driven only through raw calls (the `openxr` crate's wrapper checks call order
/// itself and would destroy the handle a second time).
struct RawSwapchain {
    raw: sys::Swapchain,
    images: Vec<u64>,
    /// Acquired and not yet waited, oldest first; then the waited one (the client's own view).
    acquired: std::collections::VecDeque<u32>,
    destroyed: bool,
}

/// What a script runs against.
struct Runner<'s, S: ScriptApi + ?Sized> {
    scene: &'s S,
    swapchain: RawSwapchain,
    display_time: sys::Time,
    results: Vec<String>,
}

fn fp<S: ScriptApi + ?Sized>(scene: &S) -> &xr::raw::Instance {
    scene.session().instance().fp()
}

fn create<S: ScriptApi + ?Sized>(scene: &S) -> Result<RawSwapchain> {
    let (width, height) = scene.view_size();
    let (format, usage_flags) = scene.swapchain_format();
    let info = sys::SwapchainCreateInfo {
        ty: sys::SwapchainCreateInfo::TYPE,
        next: ptr::null(),
        create_flags: sys::SwapchainCreateFlags::EMPTY,
        usage_flags,
        format,
        sample_count: 1,
        width,
        height,
        face_count: 1,
        array_size: 2,
        mip_count: 1,
    };
    let mut raw = sys::Swapchain::NULL;
    let session = scene.session().as_raw();
    // SAFETY: a valid create info and out pointer for this session.
    let r = unsafe { (fp(scene).create_swapchain)(session, &info, &mut raw) };
    if r != sys::Result::SUCCESS {
        return fail(format!("xrCreateSwapchain (script) failed: {r:?}"));
    }
    Ok(RawSwapchain {
        raw,
        images: scene.images(raw)?,
        acquired: Default::default(),
        destroyed: false,
    })
}

impl<S: ScriptApi + ?Sized> Runner<'_, S> {
    fn record(&mut self, op: Op, result: sys::Result, extra: Option<u32>) {
        let extra = extra.map(|i| format!(" {i}")).unwrap_or_default();
        self.results
            .push(format!("{} {result:?}{extra}", op_name(op)));
    }

    fn run(&mut self, op: Op) -> Result<()> {
        let sc = self.swapchain.raw;
        let f = fp(self.scene);
        match op {
            Op::Acquire => {
                let mut index = u32::MAX;
                // SAFETY: raw call with a valid out pointer (the handle may be destroyed: that
                // is what some scripts test, and the answer is recorded).
                let r = unsafe { (f.acquire_swapchain_image)(sc, ptr::null(), &mut index) };
                if r.into_raw() >= 0 {
                    self.swapchain.acquired.push_back(index);
                }
                self.record(op, r, (r.into_raw() >= 0).then_some(index));
            }
            Op::Wait => {
                let info = sys::SwapchainImageWaitInfo {
                    ty: sys::SwapchainImageWaitInfo::TYPE,
                    next: ptr::null(),
                    timeout: sys::Duration::INFINITE,
                };
                // SAFETY: raw call with a valid wait info.
                let r = unsafe { (f.wait_swapchain_image)(sc, &info) };
                if r == sys::Result::SUCCESS {
                    if let Some(&index) = self.swapchain.acquired.front() {
                        if let Some(&image) = self.swapchain.images.get(index as usize) {
                            self.scene.clear(image)?;
                        }
                    }
                }
                self.record(op, r, None);
            }
            Op::Release => {
                // SAFETY: raw call; a null release info is allowed.
                let r = unsafe { (f.release_swapchain_image)(sc, ptr::null()) };
                if r.into_raw() >= 0 {
                    self.swapchain.acquired.pop_front();
                }
                self.record(op, r, None);
            }
            Op::Begin => self.begin()?,
            Op::End => {
                let r = self.end(true)?;
                self.record(op, r, None);
            }
            Op::EndEmpty => {
                let r = self.end(false)?;
                self.record(op, r, None);
            }
            Op::EndOpaque | Op::EndAdditive => {
                let r = self.end_in(true, blend_of(op))?;
                self.record(op, r, None);
            }
            Op::Blend(call) => {
                let text = blend_modes(self.scene, call)?;
                self.results.push(format!("{} {text}", op_name(op)));
            }
            Op::Destroy => {
                // SAFETY: raw destroy; the handle is not used by the client afterwards except
                // by later ops of the script, whose answers are recorded.
                let r = unsafe { (f.destroy_swapchain)(sc) };
                self.swapchain.destroyed = r == sys::Result::SUCCESS;
                self.record(op, r, None);
            }
            Op::Create => {
                self.drop_swapchain();
                self.swapchain = create(self.scene)?;
                self.record(op, sys::Result::SUCCESS, None);
            }
        }
        Ok(())
    }

    fn begin(&mut self) -> Result<()> {
        let f = fp(self.scene);
        let session = self.scene.session().as_raw();
        let mut state = sys::FrameState {
            ty: sys::FrameState::TYPE,
            next: ptr::null_mut(),
            predicted_display_time: sys::Time::from_nanos(0),
            predicted_display_period: sys::Duration::from_nanos(0),
            should_render: false.into(),
        };
        // SAFETY: raw xrWaitFrame with a null wait info (allowed) and a valid out struct.
        let r = unsafe { (f.wait_frame)(session, ptr::null(), &mut state) };
        if r != sys::Result::SUCCESS {
            return fail(format!("xrWaitFrame (script) failed: {r:?}"));
        }
        self.display_time = state.predicted_display_time;
        // SAFETY: raw xrBeginFrame with a null begin info (allowed).
        let r = unsafe { (f.begin_frame)(session, ptr::null()) };
        self.record(Op::Begin, r, None);
        Ok(())
    }

    /// xrEndFrame with the projection layer on the script's swapchain, or with no layers.
    fn end(&mut self, with_layer: bool) -> Result<sys::Result> {
        self.end_in(with_layer, self.scene.blend_mode())
    }

    /// [`Runner::end`] in blend mode `mode`.
    fn end_in(&mut self, with_layer: bool, mode: sys::EnvironmentBlendMode) -> Result<sys::Result> {
        let scene = self.scene;
        let (_, views) = scene
            .session()
            .locate_views(
                xr::ViewConfigurationType::PRIMARY_STEREO,
                self.display_time,
                scene.space(),
            )
            .ctx("xrLocateViews")?;
        let (w, h) = (scene.view_size().0 as i32, scene.view_size().1 as i32);
        let projection_views: Vec<sys::CompositionLayerProjectionView> = (0..2)
            .map(|i| sys::CompositionLayerProjectionView {
                ty: sys::CompositionLayerProjectionView::TYPE,
                next: ptr::null(),
                pose: views[i].pose,
                fov: views[i].fov,
                sub_image: sys::SwapchainSubImage {
                    swapchain: self.swapchain.raw,
                    image_rect: sys::Rect2Di {
                        offset: sys::Offset2Di { x: 0, y: 0 },
                        extent: sys::Extent2Di {
                            width: w,
                            height: h,
                        },
                    },
                    image_array_index: i as u32,
                },
            })
            .collect();
        let projection = sys::CompositionLayerProjection {
            ty: sys::CompositionLayerProjection::TYPE,
            next: ptr::null(),
            layer_flags: sys::CompositionLayerFlags::EMPTY,
            space: scene.space().as_raw(),
            view_count: 2,
            views: projection_views.as_ptr(),
        };
        let layers = [&projection as *const _ as *const sys::CompositionLayerBaseHeader];
        let info = sys::FrameEndInfo {
            ty: sys::FrameEndInfo::TYPE,
            next: ptr::null(),
            display_time: self.display_time,
            environment_blend_mode: mode,
            layer_count: u32::from(with_layer),
            layers: if with_layer {
                layers.as_ptr()
            } else {
                ptr::null()
            },
        };
        // SAFETY: every struct above lives until the call returns.
        Ok(unsafe { (fp(scene).end_frame)(scene.session().as_raw(), &info) })
    }

    fn drop_swapchain(&mut self) {
        if !self.swapchain.destroyed {
            // SAFETY: the script's own live swapchain.
            unsafe { (fp(self.scene).destroy_swapchain)(self.swapchain.raw) };
            self.swapchain.destroyed = true;
        }
    }
}

/// Runs `ops` on a fresh swapchain; returns each op's name and XrResult.
pub fn run<S: ScriptApi + ?Sized>(scene: &S, ops: &[Op]) -> Result<Vec<String>> {
    let mut runner = Runner {
        scene,
        swapchain: create(scene)?,
        display_time: sys::Time::from_nanos(0),
        results: Vec::new(),
    };
    let outcome = ops.iter().try_for_each(|&op| runner.run(op));
    // The swapchain goes with the script; the frame loop goes on with empty frames.
    runner.drop_swapchain();
    outcome.map(|_| runner.results)
}

fn blend_of(op: Op) -> sys::EnvironmentBlendMode {
    match op {
        Op::EndAdditive => sys::EnvironmentBlendMode::ADDITIVE,
        _ => sys::EnvironmentBlendMode::OPAQUE,
    }
}

/// One raw xrEnumerateEnvironmentBlendModes call: its result, the count written and the modes
/// written (`RESULT n=COUNT [MODE ...]`).
fn blend_modes<S: ScriptApi + ?Sized>(scene: &S, call: BlendCall) -> Result<String> {
    let instance = scene.session().instance();
    let system = instance
        .system(xr::FormFactor::HEAD_MOUNTED_DISPLAY)
        .ctx("xrGetSystem")?;
    let (capacity, view) = match call {
        BlendCall::Count => (0, sys::ViewConfigurationType::PRIMARY_STEREO),
        BlendCall::Short => (1, sys::ViewConfigurationType::PRIMARY_STEREO),
        BlendCall::Fill => (8, sys::ViewConfigurationType::PRIMARY_STEREO),
        BlendCall::BadView => (8, sys::ViewConfigurationType::from_raw(0x7fff_0000)),
    };
    let mut modes = [sys::EnvironmentBlendMode::from_raw(0); 8];
    let mut count = u32::MAX;
    let array = if capacity == 0 {
        ptr::null_mut()
    } else {
        modes.as_mut_ptr()
    };
    // SAFETY: the array holds `capacity` modes (or is null for the count query).
    let r = unsafe {
        (instance.fp().enumerate_environment_blend_modes)(
            instance.as_raw(),
            system,
            view,
            capacity,
            &mut count,
            array,
        )
    };
    let written: Vec<String> = modes
        .iter()
        .take_while(|m| m.into_raw() != 0)
        .map(|m| format!("{m:?}"))
        .collect();
    Ok(format!("{r:?} n={count} [{}]", written.join(" ")))
}

/// A Vulkan session's script: swapchains in the session's format, cleared by the client's GPU.
impl ScriptApi for Scene<'_> {
    type Api = xr::Vulkan;

    fn session(&self) -> &xr::Session<xr::Vulkan> {
        self.session
    }

    fn space(&self) -> &xr::Space {
        self.space
    }

    fn view_size(&self) -> (u32, u32) {
        self.view_size
    }

    fn blend_mode(&self) -> xr::EnvironmentBlendMode {
        self.blend_mode
    }

    fn swapchain_format(&self) -> (i64, sys::SwapchainUsageFlags) {
        let usage =
            sys::SwapchainUsageFlags::COLOR_ATTACHMENT | sys::SwapchainUsageFlags::TRANSFER_DST;
        (self.format.vk.as_raw() as i64, usage)
    }

    fn images(&self, raw: sys::Swapchain) -> Result<Vec<u64>> {
        let blank = sys::SwapchainImageVulkanKHR {
            ty: sys::SwapchainImageVulkanKHR::TYPE,
            next: ptr::null_mut(),
            image: 0,
        };
        let images = enumerate_images(self, raw, blank)?;
        Ok(images.iter().map(|i| i.image).collect())
    }

    /// Clears both layers, leaving COLOR_ATTACHMENT_OPTIMAL.
    fn clear(&self, image: u64) -> Result<()> {
        let image = vk::Image::from_raw(image);
        let range = vk::ImageSubresourceRange::default()
            .aspect_mask(vk::ImageAspectFlags::COLOR)
            .level_count(1)
            .layer_count(2);
        let colour = vk::ClearColorValue {
            float32: CLEAR_COLOUR,
        };
        self.gpu.submit_and_wait(|device, cmd| {
            let to_transfer = barrier(
                image,
                range,
                vk::ImageLayout::UNDEFINED,
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
            )
            .dst_access_mask(vk::AccessFlags::TRANSFER_WRITE);
            record_transfer_write(device, cmd, image, range, to_transfer, || {
                // SAFETY: `cmd` is recording; the image is acquired and waited by the client.
                unsafe {
                    device.cmd_clear_color_image(
                        cmd,
                        image,
                        vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                        &colour,
                        &[range],
                    )
                };
            });
        })
    }
}
