//! A runtime below the layer for tests, and a session of the layer on it with fake graphics
//! ([`FakeGraphics`]): the layer's entry points run as an app would call them, with no
//! loader, runtime or GPU. The fake runtime records each call it gets, by handle, so a test
//! sees what reached the runtime and in which order. Built only for tests.

use super::dispatch::NextFns;
use super::graphics::fake_graphics::{FakeGraphics, Handle};
use super::live_settings::Settings;
use super::state::{self, SessionState, SwapchainInfo, SwapchainState};
use super::{session, swapchain};
use openxr_sys as xr;
use std::collections::{HashMap, HashSet};
use std::ffi::c_char;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex, MutexGuard, OnceLock};

/// The runtime's calls so far: (handle, call), in order; tests running at once use distinct
/// handles.
fn calls() -> MutexGuard<'static, Vec<(u64, &'static str)>> {
    static CALLS: Mutex<Vec<(u64, &'static str)>> = Mutex::new(Vec::new());
    CALLS.lock().unwrap_or_else(|p| p.into_inner())
}

fn record(handle: u64, call: &'static str) -> xr::Result {
    calls().push((handle, call));
    xr::Result::SUCCESS
}

/// Images a swapchain of the fake runtime has.
const IMAGES: u32 = 3;

/// The image each swapchain's next acquire returns, by handle.
fn next_image() -> MutexGuard<'static, HashMap<u64, u32>> {
    static NEXT: OnceLock<Mutex<HashMap<u64, u32>>> = OnceLock::new();
    let next = NEXT.get_or_init(Default::default);
    next.lock().unwrap_or_else(|p| p.into_inner())
}

unsafe extern "system" fn acquire(
    sc: xr::Swapchain,
    _: *const xr::SwapchainImageAcquireInfo,
    index: *mut u32,
) -> xr::Result {
    let mut next = next_image();
    let i = next.entry(sc.into_raw()).or_default();
    // SAFETY: the layer forwards the app's index pointer, valid in these tests.
    unsafe { *index = *i };
    *i = (*i + 1) % IMAGES;
    record(sc.into_raw(), "acquire")
}

unsafe extern "system" fn wait(
    sc: xr::Swapchain,
    _: *const xr::SwapchainImageWaitInfo,
) -> xr::Result {
    record(sc.into_raw(), "wait")
}

unsafe extern "system" fn release(
    sc: xr::Swapchain,
    _: *const xr::SwapchainImageReleaseInfo,
) -> xr::Result {
    record(sc.into_raw(), "release")
}

unsafe extern "system" fn end_frame(s: xr::Session, _: *const xr::FrameEndInfo) -> xr::Result {
    record(s.into_raw(), "end_frame")
}

/// A call that may submit on the app's queue (Monado's do), as the layer must forward it: with
/// the app-queue lock held (`app_queue`).
fn queue_call(held: &'static str, free: &'static str) -> &'static str {
    if crate::gpu::vulkan::device::app_queue::is_held() {
        held
    } else {
        free
    }
}

unsafe extern "system" fn destroy_swapchain(sc: xr::Swapchain) -> xr::Result {
    let call = queue_call("destroy_swapchain", "destroy_swapchain, queue not held");
    record(sc.into_raw(), call)
}

/// Sessions whose swapchains the fake runtime fails to make, whatever the usage (as a runtime
/// out of memory does).
fn failing_creates() -> MutexGuard<'static, HashSet<u64>> {
    static FAILING: OnceLock<Mutex<HashSet<u64>>> = OnceLock::new();
    let failing = FAILING.get_or_init(Default::default);
    failing.lock().unwrap_or_else(|p| p.into_inner())
}

unsafe extern "system" fn create_swapchain(
    s: xr::Session,
    _: *const xr::SwapchainCreateInfo,
    swapchain: *mut xr::Swapchain,
) -> xr::Result {
    if failing_creates().contains(&s.into_raw()) {
        record(s.into_raw(), "create_swapchain, failed");
        return xr::Result::ERROR_RUNTIME_FAILURE;
    }
    // SAFETY: the layer forwards the app's handle pointer, valid in these tests.
    unsafe { *swapchain = xr::Swapchain::from_raw(fresh_handle()) };
    let call = queue_call("create_swapchain", "create_swapchain, queue not held");
    record(s.into_raw(), call)
}

unsafe extern "system" fn destroy_session(s: xr::Session) -> xr::Result {
    record(s.into_raw(), "destroy_session")
}

/// Everything else the layer may call: this runtime does not have it.
macro_rules! unsupported {
    ($($name:ident($($arg:ty),*);)*) => {$(
        unsafe extern "system" fn $name($(_: $arg),*) -> xr::Result {
            xr::Result::ERROR_FUNCTION_UNSUPPORTED
        }
    )*};
}

unsupported! {
    get_instance_proc_addr(xr::Instance, *const c_char, *mut Option<xr::pfn::VoidFunction>);
    destroy_instance(xr::Instance);
    create_session(xr::Instance, *const xr::SessionCreateInfo, *mut xr::Session);
    enumerate_images(xr::Swapchain, u32, *mut u32, *mut xr::SwapchainImageBaseHeader);
    get_system_properties(xr::Instance, xr::SystemId, *mut xr::SystemProperties);
    create_reference_space(xr::Session, *const xr::ReferenceSpaceCreateInfo, *mut xr::Space);
    destroy_space(xr::Space);
    locate_space(xr::Space, xr::Space, xr::Time, *mut xr::SpaceLocation);
    enumerate_blend_modes(
        xr::Instance,
        xr::SystemId,
        xr::ViewConfigurationType,
        u32,
        *mut u32,
        *mut xr::EnvironmentBlendMode
    );
}

/// The fake runtime's functions, as the layer's dispatch holds the next layer's.
fn next_fns() -> NextFns {
    NextFns {
        get_instance_proc_addr,
        destroy_instance,
        create_session,
        destroy_session,
        create_swapchain,
        destroy_swapchain,
        enumerate_swapchain_images: enumerate_images,
        acquire_swapchain_image: acquire,
        wait_swapchain_image: wait,
        release_swapchain_image: release,
        end_frame,
        get_system_properties,
        create_reference_space,
        destroy_space,
        locate_space,
        enumerate_environment_blend_modes: enumerate_blend_modes,
    }
}

/// A handle no other test uses.
fn fresh_handle() -> u64 {
    static NEXT: AtomicU64 = AtomicU64::new(0xfa4e_0000);
    NEXT.fetch_add(1, Ordering::Relaxed)
}

/// The swapchains' size.
const SIZE: u32 = 64;

/// A session of the layer on the fake runtime, enhanced with fake graphics (forced on, a
/// colour background opened at the first frame), with one colour swapchain of 3 images.
pub struct Rig {
    pub session: xr::Session,
    pub swapchain: xr::Swapchain,
    /// The test's side of the session's graphics.
    pub fake: Handle,
}

impl Rig {
    pub fn new() -> Rig {
        let (session, swapchain) = (fresh_handle(), fresh_handle());
        let (graphics, fake) = FakeGraphics::boxed();
        let next = next_fns();
        let settings = Settings {
            force: true,
            wait_for_pipelines: true,
            background: "color:#808080".into(),
            ..Settings::default()
        };
        let state = SessionState {
            handle: xr::Session::from_raw(session),
            instance: xr::Instance::from_raw(fresh_handle()),
            next,
            settings: Arc::new(settings),
            graphics: Some(graphics),
            retired: Vec::new(),
            indicator: Default::default(),
            started: std::time::Instant::now(),
            background: None,
            background_requested: false,
            background_delivered: false,
            idle_since: None,
            frames: 0,
            processed: 0,
            last_blend_mode: None,
            regions_seen: false,
            motion: Default::default(),
            frame_in_use: None,
            retry: Default::default(),
            gpu_time: Default::default(),
        };
        let mut sc = SwapchainState::new(xr::Session::from_raw(session), next, swapchain_info());
        sc.set_images((1..=IMAGES as u64).collect());
        let mut registry = state::registry();
        registry
            .sessions
            .insert(session, Arc::new(Mutex::new(state)));
        registry
            .swapchains
            .insert(swapchain, Arc::new(Mutex::new(sc)));
        Rig {
            session: xr::Session::from_raw(session),
            swapchain: xr::Swapchain::from_raw(swapchain),
            fake,
        }
    }

    /// From now on the fake runtime fails every xrCreateSwapchain of this session.
    pub fn fail_swapchain_creates(&self) {
        failing_creates().insert(self.session.into_raw());
    }

    /// The layer's state of the session.
    pub fn state(&self) -> Arc<Mutex<SessionState>> {
        state::session(self.session).expect("the rig's session is registered")
    }

    /// The calls the fake runtime got for this rig's session and swapchain, in order.
    pub fn runtime_calls(&self) -> Vec<&'static str> {
        let mine = [self.session.into_raw(), self.swapchain.into_raw()];
        calls()
            .iter()
            .filter(|(h, _)| mine.contains(h))
            .map(|(_, call)| *call)
            .collect()
    }

    /// The app acquires, waits for and releases an image, as a frame's rendering does: what
    /// the layer answers each.
    pub fn render(&self) -> [xr::Result; 3] {
        let mut index = u32::MAX;
        let wait_info = xr::SwapchainImageWaitInfo {
            ty: xr::SwapchainImageWaitInfo::TYPE,
            next: std::ptr::null(),
            timeout: xr::Duration::INFINITE,
        };
        // SAFETY: the layer's entry points with valid arguments, as the loader calls them.
        unsafe {
            [
                swapchain::acquire_swapchain_image(self.swapchain, std::ptr::null(), &mut index),
                swapchain::wait_swapchain_image(self.swapchain, &wait_info),
                swapchain::release_swapchain_image(self.swapchain, std::ptr::null()),
            ]
        }
    }

    /// The app ends a frame with one ADDITIVE projection view over the whole image.
    pub fn end_frame(&self) -> xr::Result {
        let view = xr::CompositionLayerProjectionView {
            ty: xr::CompositionLayerProjectionView::TYPE,
            next: std::ptr::null(),
            pose: xr::Posef::IDENTITY,
            fov: xr::Fovf {
                angle_left: -0.7,
                angle_right: 0.7,
                angle_up: 0.7,
                angle_down: -0.7,
            },
            sub_image: xr::SwapchainSubImage {
                swapchain: self.swapchain,
                image_rect: xr::Rect2Di {
                    offset: xr::Offset2Di { x: 0, y: 0 },
                    extent: xr::Extent2Di {
                        width: SIZE as i32,
                        height: SIZE as i32,
                    },
                },
                image_array_index: 0,
            },
        };
        let layer = xr::CompositionLayerProjection {
            ty: xr::CompositionLayerProjection::TYPE,
            next: std::ptr::null(),
            layer_flags: xr::CompositionLayerFlags::EMPTY,
            space: xr::Space::NULL,
            view_count: 1,
            views: &view,
        };
        let layers = [&layer as *const _ as *const xr::CompositionLayerBaseHeader];
        let info = xr::FrameEndInfo {
            ty: xr::FrameEndInfo::TYPE,
            next: std::ptr::null(),
            display_time: xr::Time::from_nanos(1),
            environment_blend_mode: xr::EnvironmentBlendMode::ADDITIVE,
            layer_count: 1,
            layers: layers.as_ptr(),
        };
        // SAFETY: as the loader calls it, with a frame end info valid for the call.
        unsafe { session::end_frame(self.session, &info) }
    }
}

impl Drop for Rig {
    fn drop(&mut self) {
        session::forget(self.session);
    }
}

/// The rig's swapchain: 64x64, one layer, enhanced through a copy.
fn swapchain_info() -> SwapchainInfo {
    SwapchainInfo::new(
        &colour_swapchain(),
        Some(super::graphics::fake_graphics::FORMAT),
        true,
        false,
    )
}

/// An app's create info of a 64x64 colour swapchain.
pub fn colour_swapchain() -> xr::SwapchainCreateInfo {
    xr::SwapchainCreateInfo {
        ty: xr::SwapchainCreateInfo::TYPE,
        next: std::ptr::null(),
        create_flags: xr::SwapchainCreateFlags::EMPTY,
        usage_flags: xr::SwapchainUsageFlags::COLOR_ATTACHMENT,
        format: 0,
        sample_count: 1,
        width: SIZE,
        height: SIZE,
        face_count: 1,
        array_size: 1,
        mip_count: 1,
    }
}
