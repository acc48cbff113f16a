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
        attachment: true,
        sampled: true,
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

/// A build off the app's threads that ended is linked in a frame call from the binaries the
/// build thread handed back, never by reading the program binary cache's file in that call:
/// with every file operation stalled 2 s (`stalled-file-system`, a cache folder on a slow
/// network or FUSE mount, so the build's own write fails too), no frame call takes 500 ms, from
/// the first after the build's thread ended (and every read it started has returned) to the
/// one after which the programs are ready. Run in a child process of this test binary, where
/// the fault is armed, with an empty cache folder.
#[test]
fn a_finished_build_is_linked_without_reading_the_cache_in_a_frame_call() {
    const NAME: &str = "layer::graphics::opengl::gl_session::tests::a_finished_build_is_linked_without_reading_the_cache_in_a_frame_call";
    if std::env::var_os("CONTRASTXR_FAULT").is_none() {
        let cache =
            std::env::temp_dir().join(format!("contrastxr-gl-frame-read-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&cache);
        let out = std::process::Command::new(std::env::current_exe().unwrap())
            .args(["--exact", NAME, "--nocapture", "--test-threads=1"])
            .env("CONTRASTXR_FAULT", "stalled-file-system")
            .env("XDG_CACHE_HOME", &cache)
            .output()
            .expect("run the child");
        let _ = std::fs::remove_dir_all(&cache);
        let text = String::from_utf8_lossy(&out.stderr).into_owned()
            + &String::from_utf8_lossy(&out.stdout);
        assert!(out.status.success() && text.contains("1 passed"), "{text}");
        return;
    }
    let mut offline = GlOffline::new().expect("an OpenGL context");
    let rgba8 = crate::gpu::opengl::device::functions::RGBA8;
    let (w, h) = (48u32, 32u32);
    let texture = offline
        .create_texture(rgba8, (w, h), &vec![128; (w * h * 4) as usize])
        .unwrap();
    let params = Params::default();
    let format = GlFormat::of(rgba8).unwrap();
    let view = ViewImage {
        key: ViewKey {
            swapchain: 1,
            offset: (0, 0),
            extent: (w, h),
            array_index: 0,
        },
        image: u64::from(texture),
        api_format: i64::from(rgba8),
        format: format.pixel,
        layered: false,
        in_place: false,
        attachment: true,
        sampled: true,
        mapping: params.camera_mapping(),
        pixels_per_degree: DEFAULT_PIXELS_PER_DEGREE,
    };
    let context = TestContext {
        elsewhere: Rc::new(Cell::new(false)),
    };
    let mut session = Box::new(GlSession::new("OpenGL (test)", Box::new(context)));
    // Swapchain creation: the caches are read (bounded), the build starts on its thread.
    session.request_shaders(&params, format.pixel, w, false, false);
    assert!(!session.builders.is_empty(), "no build started");
    let views = [view];
    let since = Instant::now();
    let building = || {
        std::fs::read_dir("/proc/self/task")
            .unwrap()
            .flatten()
            .filter_map(|t| std::fs::read_to_string(t.path().join("comm")).ok())
            .any(|n| n.trim() == "contrastxr-gl-b")
    };
    while building() {
        assert!(since.elapsed() < Duration::from_secs(300), "never built");
        std::thread::sleep(Duration::from_millis(10));
    }
    // Every read of the cache's file the build started has returned (each stalls 2 s).
    std::thread::sleep(Duration::from_millis(2500));
    let mut calls = Vec::new();
    loop {
        let t = Instant::now();
        let ready = session.ready(&views, &params, false);
        calls.push(t.elapsed());
        match ready {
            Ok(()) => break,
            Err(NotDone::Pending) => {}
            Err(e) => panic!("{e:?}"),
        }
        assert!(since.elapsed() < Duration::from_secs(300), "never ready");
        std::thread::sleep(Duration::from_millis(10));
    }
    let longest = calls.iter().max().copied().unwrap_or_default();
    eprintln!("{} frame calls, the longest {longest:?}", calls.len());
    assert!(
        longest < Duration::from_millis(500),
        "a frame call took {longest:?}"
    );
    assert!(session.finish().is_ok());
    offline.delete_texture(texture);
}
