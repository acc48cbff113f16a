//! Tests of gl_session.rs: sessions of an offline context standing for the app's.

use super::*;
use crate::algorithm::perception::frequency::DEFAULT_PIXELS_PER_DEGREE;
use crate::gpu::opengl::{Gl, GlError, GlOffline};
use crate::gpu::ViewKey;
use crate::image::RgbaImage;
use crate::layer::graphics::opengl::app_context::{Previous, NOT_CURRENT};
use std::rc::Rc;

/// The test's offline context standing for the app's: current on this thread, or, once
/// `elsewhere` says so, current on another thread (it cannot be entered).
struct TestContext {
    elsewhere: Rc<Cell<bool>>,
}

impl AppContext for TestContext {
    fn enter(&self) -> Result<Option<Previous>, String> {
        match self.elsewhere.get() {
            true => Err(NOT_CURRENT.into()),
            false => Ok(None),
        }
    }
    fn leave(&self, _: Option<Previous>) {}
    fn gl(&self) -> Result<Gl, GlError> {
        Gl::from_process()
    }
    fn key(&self) -> (usize, usize) {
        (1, 2)
    }
}

/// Sessions on one context, each ended (xrDestroySession) while the context is current on
/// another thread: each leaves its engine's objects (view buffers, background texture,
/// mapped upload buffers) in the context, and the next session on it deletes them, so the
/// context's live buffers and textures stay as many as one session's (without that they
/// grow by 6 a session).
#[test]
fn sessions_ended_with_their_context_elsewhere_leave_a_bounded_number_of_objects() {
    type Is = unsafe extern "system" fn(u32) -> u8;
    let mut offline = GlOffline::new().expect("an OpenGL context");
    let is = |name: &std::ffi::CStr| {
        let p = offline.proc_address(name);
        assert!(!p.is_null());
        // SAFETY: glIsBuffer and glIsTexture have this C type.
        unsafe { std::mem::transmute::<*const std::ffi::c_void, Is>(p) }
    };
    let (is_buffer, is_texture) = (is(c"glIsBuffer"), is(c"glIsTexture"));
    // Buffers and textures have names of their own: each kind counted.
    let live = || {
        [is_buffer, is_texture]
            .into_iter()
            // SAFETY: the offline context is current on this thread; glIs* take any name.
            .map(|is| (1..4096u32).filter(|&n| unsafe { is(n) } != 0).count())
            .sum::<usize>()
    };
    let (w, h) = (64u32, 32u32);
    let pixels: Vec<[u8; 4]> = (0..w * h)
        .map(|i| [(i * 7) as u8, (i * 13) as u8, (i * 29) as u8, 255])
        .collect();
    let display: Vec<u8> = pixels.iter().flatten().copied().collect();
    let texture = offline
        .create_texture(
            crate::gpu::opengl::device::functions::RGBA8,
            (w, h),
            &display,
        )
        .unwrap();
    let camera = RgbaImage {
        width: 40,
        height: 30,
        pixels: pixels[..1200].to_vec(),
        has_alpha: false,
    };
    let params = Params::default();
    let format = GlFormat::of(crate::gpu::opengl::device::functions::RGBA8).unwrap();
    let view = ViewImage {
        key: ViewKey {
            swapchain: 1,
            offset: (0, 0),
            extent: (w, h),
            array_index: 0,
        },
        image: u64::from(texture),
        api_format: i64::from(crate::gpu::opengl::device::functions::RGBA8),
        format: format.pixel,
        layered: false,
        in_place: false,
        mapping: params.camera_mapping(),
        pixels_per_degree: DEFAULT_PIXELS_PER_DEGREE,
    };
    let mut counts = Vec::new();
    for sequence in 1..=6 {
        let elsewhere = Rc::new(Cell::new(false));
        let context = TestContext {
            elsewhere: elsewhere.clone(),
        };
        let mut session = Box::new(GlSession::new("OpenGL (test)", Box::new(context)));
        let views = [view.clone()];
        session.ready(&views, &params, true).expect("programs");
        let background = BackgroundInput {
            image: &camera,
            prepared: None,
            sequence,
        };
        session
            .enhance(&views, background, &params, None, false)
            .expect("enhanced");
        elsewhere.set(true);
        assert!(session.finish().is_err(), "the context could be entered");
        counts.push(live());
    }
    assert!(
        counts.iter().all(|&c| c <= counts[0]),
        "live buffers and textures after each session: {counts:?}"
    );
    assert!(left_engines::waiting() <= 1, "{}", left_engines::waiting());
    offline.delete_texture(texture);
}
