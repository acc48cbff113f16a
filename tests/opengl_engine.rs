//! The OpenGL backend's own behaviour on an EGL surfaceless context (Mesa's llvmpipe on the
//! host): the background behind each pixel with GL's bottom-left origin, in place against
//! through a buffer, the app's GL state and pending error kept, a program that fails to link.
//! What every backend must do (the CPU reference per format, method and view mode) is
//! tests/engine_conformance.rs.

mod common;

use common::conformance::{
    assert_every_classify_lists_the_same, assert_the_bound_lists_every_tile_that_changes,
    nonconformant, projective,
};
use common::images::noise;
use contrastxr::algorithm::mapping::CameraMapping;
use contrastxr::algorithm::perception::frequency::DEFAULT_PIXELS_PER_DEGREE;
use contrastxr::algorithm::Params;
use contrastxr::gpu::core::{pixel_codec, ClassifyChoice};
use contrastxr::gpu::opengl::GlFormat;
use contrastxr::gpu::opengl::{GlOffline, GlTarget, GlView};
use contrastxr::gpu::OfflineBackend;
use contrastxr::image::RgbaImage;
use std::ffi::{c_void, CStr, OsStr};

const RGBA8: u32 = 0x8058;
const SRGB8_ALPHA8: u32 = 0x8C43;
const RGBA16F: u32 = 0x881A;
const RGB10_A2: u32 = 0x8059;
const RGBA16: u32 = 0x805B;

fn context() -> GlOffline {
    GlOffline::new().unwrap_or_else(|e| panic!("OpenGL context: {e}"))
}

/// A projective mapping (a registered view's homography) over a camera whose top and bottom
/// halves differ: a pixel sampling the background of the row mirrored from it (GL's rows
/// counted from the bottom, not turned) takes the other half's colour and fails the check.
/// Runs the ignored test `name` of this binary in a child process with `env` set (a fault
/// point, a cache folder, a GL version), and holds that it passed.
fn run_child(name: &str, env: &[(&str, &OsStr)]) {
    let mut child = std::process::Command::new(std::env::current_exe().unwrap());
    child.args(["--exact", name, "--ignored", "--nocapture"]);
    for (key, value) in env {
        child.env(key, value);
    }
    let out = child.output().unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success() && text.contains("1 passed"),
        "{text}{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

#[test]
fn the_background_behind_each_pixel_is_the_one_above_or_below_it_as_displayed() {
    let mut gl = context();
    let mut camera = RgbaImage::new(90, 60, [230, 40, 30, 255]);
    for (i, p) in camera.pixels.iter_mut().enumerate() {
        if i / 90 >= 30 {
            *p = [30, 60, 230, 255];
        }
    }
    let display = RgbaImage::new(64, 48, [150, 120, 110, 255]);
    let mapping = CameraMapping {
        rows: [[0.8, 0.06, 0.05], [-0.04, 0.7, 0.12], [0.12, -0.09, 0.98]],
    };
    let params = Params::default();
    let bad = nonconformant(&mut gl, &display, &camera, &mapping, &params);
    assert!(
        bad.is_empty(),
        "{} pixels differ, e.g. {:?}",
        bad.len(),
        &bad[..bad.len().min(3)]
    );
    // The two halves' backgrounds give the same content different colours.
    let out = gl
        .enhance_mapped(&display, &camera, &mapping, &params)
        .unwrap();
    let (top, bottom) = (out.pixels[64 * 2 + 32], out.pixels[64 * 45 + 32]);
    assert_ne!(top, bottom);
}

fn linear(c: u8) -> f64 {
    contrastxr::colour::code_to_linear(c)
}

/// An 8-bit sRGB colour as a format's raw words, the way an app would store it.
fn encode(format: GlFormat, p: [u8; 4]) -> Vec<u32> {
    let a = f64::from(p[3]) / 255.0;
    let bytes = if format.pixel.srgb {
        p.to_vec()
    } else {
        pixel_codec::encode(format.pixel, [linear(p[0]), linear(p[1]), linear(p[2]), a])
    };
    bytes
        .as_chunks::<4>()
        .0
        .iter()
        .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect()
}

#[test]
fn a_format_it_does_not_handle_is_named_and_left_untouched() {
    let mut gl = context();
    let camera = noise(16, 16, 3);
    let err = gl
        .enhance_raw(
            &[0x1234_5678; 64],
            (8, 8),
            0x8814,
            &camera,
            &Params::default(),
        )
        .unwrap_err()
        .to_string();
    assert!(err.contains("0x8814") && err.lines().count() == 1, "{err}");
}

fn load(gl: &GlOffline, name: &CStr) -> *const c_void {
    let p = gl.proc_address(name);
    assert!(!p.is_null(), "{name:?}");
    p
}

macro_rules! app_gl {
    ($($field:ident = $name:literal: fn($($arg:ty),*) $(-> $ret:ty)?;)*) => {
        /// The GL calls the state test makes as the app, through the offline context's loader.
        struct AppGl {
            $($field: unsafe extern "system" fn($($arg),*) $(-> $ret)?,)*
        }

        fn app_gl(gl: &GlOffline) -> AppGl {
            AppGl {
                $($field: {
                    let p = load(gl, $name);
                    // SAFETY: the address of the GL function of that name, whose C signature
                    // is the one declared.
                    unsafe {
                        std::mem::transmute::<*const c_void, unsafe extern "system" fn($($arg),*) $(-> $ret)?>(p)
                    }
                },)*
            }
        }
    };
}

app_gl! {
    get_integerv = c"glGetIntegerv": fn(u32, *mut i32);
    get_integeri_v = c"glGetIntegeri_v": fn(u32, u32, *mut i32);
    get_integer64i_v = c"glGetInteger64i_v": fn(u32, u32, *mut i64);
    is_enabled = c"glIsEnabled": fn(u32) -> u8;
    enable = c"glEnable": fn(u32);
    get_error = c"glGetError": fn() -> u32;
    gen = c"glCreateBuffers": fn(i32, *mut u32);
    bind_buffer = c"glBindBuffer": fn(u32, u32);
    bind_buffer_range = c"glBindBufferRange": fn(u32, u32, u32, isize, isize);
    named_buffer_data = c"glNamedBufferData": fn(u32, isize, *const c_void, u32);
    create_textures = c"glCreateTextures": fn(u32, i32, *mut u32);
    texture_storage_2d = c"glTextureStorage2D": fn(u32, i32, u32, i32, i32);
    active_texture = c"glActiveTexture": fn(u32);
    bind_texture = c"glBindTexture": fn(u32, u32);
    create_samplers = c"glCreateSamplers": fn(i32, *mut u32);
    bind_sampler = c"glBindSampler": fn(u32, u32);
    bind_image_texture = c"glBindImageTexture": fn(u32, u32, i32, u8, i32, u32, u32);
    create_shader_programv = c"glCreateShaderProgramv": fn(u32, i32, *const *const i8) -> u32;
    use_program = c"glUseProgram": fn(u32);
    delete_program = c"glDeleteProgram": fn(u32);
    delete_textures = c"glDeleteTextures": fn(i32, *const u32);
    delete_buffers = c"glDeleteBuffers": fn(i32, *const u32);
    delete_samplers = c"glDeleteSamplers": fn(i32, *const u32);
    bind_buffer_base = c"glBindBufferBase": fn(u32, u32, u32);
    begin_transform_feedback = c"glBeginTransformFeedback": fn(u32);
    pause_transform_feedback = c"glPauseTransformFeedback": fn();
    resume_transform_feedback = c"glResumeTransformFeedback": fn();
    end_transform_feedback = c"glEndTransformFeedback": fn();
    create_program_pipelines = c"glCreateProgramPipelines": fn(i32, *mut u32);
    bind_program_pipeline = c"glBindProgramPipeline": fn(u32);
    create_framebuffers = c"glCreateFramebuffers": fn(i32, *mut u32);
    bind_framebuffer = c"glBindFramebuffer": fn(u32, u32);
    pixel_storei = c"glPixelStorei": fn(u32, i32);
    pixel_transferf = c"glPixelTransferf": fn(u32, f32);
    get_floatv = c"glGetFloatv": fn(u32, *mut f32);
}

/// Every value of the state the recipe may touch, as the app reads it.
#[derive(Debug, PartialEq)]
struct AppState {
    ints: Vec<(u32, i32)>,
    indexed: Vec<(u32, u32, i64)>,
    srgb: bool,
}

fn read_state(a: &AppGl) -> AppState {
    let single = [
        0x8B8D, // CURRENT_PROGRAM
        0x825A, // PROGRAM_PIPELINE_BINDING
        0x84E0, // ACTIVE_TEXTURE
        0x8069, // TEXTURE_BINDING_2D (of the active unit)
        0x8919, // SAMPLER_BINDING (of the active unit)
        0x90D3, // SHADER_STORAGE_BUFFER_BINDING
        0x8A28, // UNIFORM_BUFFER_BINDING
        0x88ED, // PIXEL_PACK_BUFFER_BINDING
        0x88EF, // PIXEL_UNPACK_BUFFER_BINDING
        0x90EF, // DISPATCH_INDIRECT_BUFFER_BINDING
        0x8CA6, // DRAW_FRAMEBUFFER_BINDING
        0x8CAA, // READ_FRAMEBUFFER_BINDING
        0x0D05, 0x0D02, 0x0D03, 0x0D04, 0x806B, 0x806C, 0x0D00, 0x0D01, // PACK_*
        0x0CF5, 0x0CF2, 0x0CF3, 0x0CF4, 0x806D, 0x806E, 0x0CF0, 0x0CF1, // UNPACK_*
    ];
    let mut ints = Vec::new();
    for unit in [0x84C0 + 5, 0x84C0 + 3] {
        // SAFETY: a valid texture unit; the app's active unit is put back by the loop's end.
        unsafe { (a.active_texture)(unit) };
        for q in [0x8069, 0x8919] {
            let mut v = 0;
            // SAFETY: a valid single-valued query.
            unsafe { (a.get_integerv)(q, &mut v) };
            ints.push((unit * 0x10000 + q, v));
        }
    }
    for q in single {
        let mut v = 0;
        // SAFETY: a valid single-valued query.
        unsafe { (a.get_integerv)(q, &mut v) };
        ints.push((q, v));
    }
    let mut indexed = Vec::new();
    for slot in 0..8 {
        for (binding, start, size) in [(0x90D3, 0x90D4, 0x90D5), (0x8A28, 0x8A29, 0x8A2A)] {
            let (mut b, mut st, mut sz) = (0, 0i64, 0i64);
            // SAFETY: indexed queries of bindings below the 4.5 minimums.
            unsafe {
                (a.get_integeri_v)(binding, slot, &mut b);
                (a.get_integer64i_v)(start, slot, &mut st);
                (a.get_integer64i_v)(size, slot, &mut sz);
            }
            indexed.extend([
                (binding, slot, i64::from(b)),
                (start, slot, st),
                (size, slot, sz),
            ]);
        }
        // IMAGE_BINDING_NAME, _LEVEL, _LAYERED, _LAYER, _ACCESS, _FORMAT: the in-place
        // programs store through unit 6.
        for q in [0x8F3A, 0x8F3B, 0x8F3C, 0x8F3D, 0x8F3E, 0x906E] {
            let mut v = 0;
            // SAFETY: an indexed query of an image unit below the minimum of 8.
            unsafe { (a.get_integeri_v)(q, slot, &mut v) };
            indexed.push((q, slot, i64::from(v)));
        }
    }
    AppState {
        ints,
        indexed,
        // SAFETY: FRAMEBUFFER_SRGB is a capability of core contexts.
        srgb: unsafe { (a.is_enabled)(0x8DB9) } != 0,
    }
}

/// A 40x24 GL_SRGB8_ALPHA8 view of noise (seed `seeds.1`) against a 64x40 camera of noise (seed
/// `seeds.0`), enhanced once so that its programs are built; the view and its texels as made.
fn built_srgb_view(gl: &mut GlOffline, seeds: (u32, u32), params: &Params) -> (GlView, Vec<u8>) {
    gl.set_camera(&noise(64, 40, seeds.0), params).unwrap();
    let display = noise(40, 24, seeds.1);
    let bytes: Vec<u8> = display.pixels.iter().flatten().copied().collect();
    let texture = gl.create_texture(SRGB8_ALPHA8, (40, 24), &bytes).unwrap();
    let view = GlView {
        texture,
        target: GlTarget::Texture2D,
        internal_format: SRGB8_ALPHA8,
        rect: (0, 0, 40, 24),
        mapping: params.camera_mapping(),
        pixels_per_degree: DEFAULT_PIXELS_PER_DEGREE,
    };
    gl.enhance_views(&[view], params).unwrap();
    (view, bytes)
}

/// Non-default values of every piece of state the recipe touches (and of the image units and
/// uniform buffers it must not), and a pending GL_INVALID_ENUM: after the call the app reads
/// every value back unchanged, and the same pending error, and then none.
#[test]
fn the_apps_gl_state_and_pending_error_survive_the_call() {
    let mut gl = context();
    let a = app_gl(&gl);
    let params = Params::default();
    // The programs built first, so the call below runs the whole recipe.
    let (view, bytes) = built_srgb_view(&mut gl, (7, 8), &params);
    let texture = view.texture;
    let source = c"#version 450\nlayout(local_size_x = 1) in;\nvoid main() {}\n";
    // SAFETY: the context is current on this thread; every name passed is made here, every
    // enum valid for its call (but the glEnable, which raises GL_INVALID_ENUM on purpose).
    unsafe {
        let mut buffers = [0u32; 8];
        (a.gen)(8, buffers.as_mut_ptr());
        for &b in &buffers {
            (a.named_buffer_data)(b, 4096, std::ptr::null(), 0x88EA);
        }
        (a.bind_buffer_range)(0x90D2, 2, buffers[0], 256, 512);
        (a.bind_buffer_range)(0x90D2, 3, buffers[1], 0, 1024);
        (a.bind_buffer_range)(0x8A11, 0, buffers[2], 0, 256);
        (a.bind_buffer)(0x90D2, buffers[3]);
        (a.bind_buffer)(0x8A11, buffers[4]);
        (a.bind_buffer)(0x88EB, buffers[5]);
        (a.bind_buffer)(0x88EC, buffers[6]);
        (a.bind_buffer)(0x90EE, buffers[7]);
        let mut textures = [0u32; 2];
        (a.create_textures)(0x0DE1, 2, textures.as_mut_ptr());
        for &t in &textures {
            (a.texture_storage_2d)(t, 1, 0x8058, 4, 4);
        }
        let mut sampler = 0;
        (a.create_samplers)(1, &mut sampler);
        (a.active_texture)(0x84C0 + 5);
        (a.bind_texture)(0x0DE1, textures[0]);
        (a.bind_sampler)(5, sampler);
        (a.active_texture)(0x84C0 + 3);
        (a.bind_texture)(0x0DE1, textures[1]);
        (a.bind_image_texture)(2, textures[1], 0, 0, 0, 0x88B8, 0x8058);
        // The unit the in-place programs use: write-only, as R32UI.
        (a.bind_image_texture)(6, textures[0], 0, 0, 0, 0x88B9, 0x8236);
        let program = (a.create_shader_programv)(0x91B9, 1, &source.as_ptr());
        (a.use_program)(program);
        let mut pipeline = 0;
        (a.create_program_pipelines)(1, &mut pipeline);
        (a.bind_program_pipeline)(pipeline);
        let mut framebuffers = [0u32; 2];
        (a.create_framebuffers)(2, framebuffers.as_mut_ptr());
        (a.bind_framebuffer)(0x8CA9, framebuffers[0]);
        (a.bind_framebuffer)(0x8CA8, framebuffers[1]);
        (a.enable)(0x8DB9);
        for (p, v) in [
            (0x0D05, 8),
            (0x0D02, 7),
            (0x0D03, 2),
            (0x0D04, 3),
            (0x0CF5, 2),
            (0x0CF2, 9),
            (0x0CF3, 1),
            (0x0CF4, 5),
            (0x806B, 1),
            (0x806D, 2),
            (0x806C, 3),
            (0x806E, 4),
        ] {
            (a.pixel_storei)(p, v);
        }
        assert_eq!((a.get_error)(), 0, "the test's own set-up raised an error");
        (a.enable)(0xFFFF);
    }
    let before = read_state(&a);
    let mut other = params.clone();
    other.lambda_e = 0.7;
    gl.set_camera(&noise(64, 40, 99), &other).unwrap();
    gl.enhance_views(&[view], &other).unwrap();
    let after = read_state(&a);
    assert_eq!(after, before, "the app's GL state changed");
    // SAFETY: glGetError takes no arguments.
    let (first, second) = unsafe { ((a.get_error)(), (a.get_error)()) };
    assert_eq!(
        first, 0x0500,
        "the app's pending GL_INVALID_ENUM was not kept"
    );
    assert_eq!(second, 0, "an error was left behind");
    // With no error pending, the call raises none.
    gl.enhance_views(&[view], &params).unwrap();
    // SAFETY: glGetError takes no arguments.
    let error = unsafe { (a.get_error)() };
    assert_eq!(error, 0, "the recipe raised a GL error");
    let out = gl.read_texture(texture, SRGB8_ALPHA8, (40, 24)).unwrap();
    assert_ne!(out, bytes, "the view was not enhanced");
}

/// Run by `a_program_that_fails_to_link_leaves_the_texture_untouched` in a process of its own
/// with the fault point armed (it is read once per process) and an empty program cache.
#[test]
#[ignore = "run by a_program_that_fails_to_link_leaves_the_texture_untouched"]
fn link_failure_child() {
    assert_eq!(
        std::env::var("CONTRASTXR_FAULT").as_deref(),
        Ok("gl-program-link")
    );
    let mut gl = context();
    let camera = noise(32, 32, 4);
    let display = noise(24, 16, 5);
    let params = Params::default();
    gl.set_camera(&camera, &params).unwrap();
    let bytes: Vec<u8> = display.pixels.iter().flatten().copied().collect();
    let texture = gl.create_texture(SRGB8_ALPHA8, (24, 16), &bytes).unwrap();
    let view = GlView {
        texture,
        target: GlTarget::Texture2D,
        internal_format: SRGB8_ALPHA8,
        rect: (0, 0, 24, 16),
        mapping: params.camera_mapping(),
        pixels_per_degree: DEFAULT_PIXELS_PER_DEGREE,
    };
    let err = gl.enhance_views(&[view], &params).unwrap_err().to_string();
    assert!(
        err.contains("did not build") && err.lines().count() == 1,
        "{err}"
    );
    println!("error: {err}");
    let out = gl.read_texture(texture, SRGB8_ALPHA8, (24, 16)).unwrap();
    assert_eq!(out, bytes, "the texture changed");
}

#[test]
fn a_program_that_fails_to_link_leaves_the_texture_untouched() {
    let cache = std::env::temp_dir().join(format!("contrastxr-gl-link-{}", std::process::id()));
    let env = [
        ("CONTRASTXR_FAULT", OsStr::new("gl-program-link")),
        ("XDG_CACHE_HOME", cache.as_os_str()),
    ];
    run_child("link_failure_child", &env);
    let _ = std::fs::remove_dir_all(&cache);
}

/// `contrastxr enhance --engine opengl` runs the OpenGL backend on its offline context and
/// agrees with the CPU reference within one code value on a sample scene.
#[test]
fn cli_opengl_and_cpu_engines_agree_on_a_sample_scene() {
    let dir = common::scratch_dir("opengl-engine-cli");
    let samples = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("samples");
    let display = samples.join("display-text-swatches.png");
    let background = samples.join("background-blue-sky.png");
    let mut outs = Vec::new();
    for engine in ["opengl", "cpu"] {
        let out = dir.join(format!("{engine}.png"));
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_contrastxr"))
            .args(["enhance", "--engine", engine, "--display"])
            .arg(&display)
            .arg("--background")
            .arg(&background)
            .arg("-o")
            .arg(&out)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert!(o.status.success(), "{engine}: {stderr}");
        outs.push(RgbaImage::load_png(&out).unwrap());
    }
    let _ = std::fs::remove_dir_all(&dir);
    let input = RgbaImage::load_png(&display).unwrap();
    let (gl, cpu) = (&outs[0], &outs[1]);
    assert_ne!(gl, &input, "the OpenGL engine changed nothing");
    let worst = gl
        .pixels
        .iter()
        .zip(&cpu.pixels)
        .flat_map(|(g, c)| (0..4).map(move |k| g[k].abs_diff(c[k])))
        .max();
    assert!(worst <= Some(1), "engines differ by {worst:?} code values");
}

/// Run by `frames_pass_through_while_programs_build_and_binaries_are_kept` in a process of its
/// own with an empty cache folder (the program binaries' and Mesa's).
#[test]
#[ignore = "run by frames_pass_through_while_programs_build_and_binaries_are_kept"]
fn compile_child() {
    use contrastxr::gpu::opengl::Outcome;
    let camera = noise(32, 32, 4);
    let display = noise(24, 16, 5);
    let params = Params::default();
    let bytes: Vec<u8> = display.pixels.iter().flatten().copied().collect();
    let first_call = |gl: &mut GlOffline| {
        gl.set_camera(&camera, &params).unwrap();
        let texture = gl.create_texture(SRGB8_ALPHA8, (24, 16), &bytes).unwrap();
        let view = GlView {
            texture,
            target: GlTarget::Texture2D,
            internal_format: SRGB8_ALPHA8,
            rect: (0, 0, 24, 16),
            mapping: params.camera_mapping(),
            pixels_per_degree: DEFAULT_PIXELS_PER_DEGREE,
        };
        // SAFETY: the offline context is current on this thread; the texture is its own.
        let outcome = unsafe { gl.engine().enhance(&[view], &params) }.unwrap();
        let out = gl.read_texture(texture, SRGB8_ALPHA8, (24, 16)).unwrap();
        (outcome, out, view)
    };
    let mut gl = context();
    let (outcome, out, view) = first_call(&mut gl);
    assert_eq!(
        outcome,
        Outcome::Compiling,
        "the first call waited for the programs"
    );
    assert_eq!(
        out, bytes,
        "a frame changed while its programs were building"
    );
    gl.enhance_views(&[view], &params).unwrap();
    drop(gl);
    let mut gl = context();
    let (outcome, out, _) = first_call(&mut gl);
    assert_eq!(outcome, Outcome::Enhanced, "the binaries were not kept");
    assert_ne!(out, bytes);
    println!("both calls as expected");
}

#[test]
fn frames_pass_through_while_programs_build_and_binaries_are_kept() {
    let cache = std::env::temp_dir().join(format!("contrastxr-gl-build-{}", std::process::id()));
    run_child("compile_child", &[("XDG_CACHE_HOME", cache.as_os_str())]);
    let files: Vec<_> = std::fs::read_dir(cache.join("contrastxr"))
        .map(|d| d.filter_map(|e| e.ok()).map(|e| e.file_name()).collect())
        .unwrap_or_default();
    let _ = std::fs::remove_dir_all(&cache);
    assert!(
        files
            .iter()
            .any(|f| f.to_string_lossy().starts_with("pipelines-gl-")),
        "no program binary file: {files:?}"
    );
}

/// Bottom-first rows of an image (as GL stores it).
fn bottom_first(img: &RgbaImage) -> Vec<u8> {
    let bytes: Vec<u8> = img.pixels.iter().flatten().copied().collect();
    bytes
        .chunks(img.width as usize * 4)
        .rev()
        .flatten()
        .copied()
        .collect()
}

/// A view that is a part of its texture (an OpenXR imageRect away from the corner, as the
/// right eye of a side-by-side swapchain) and a layer of an array texture: the region is
/// enhanced exactly as the same pixels alone, and nothing outside it changes.
#[test]
fn a_region_of_a_texture_and_a_layer_of_an_array_are_enhanced_in_place() {
    let mut gl = context();
    let camera = noise(70, 50, 12);
    let view_img = noise(32, 20, 13);
    let params = Params::default();
    let mapping = CameraMapping {
        rows: [[0.8, 0.06, 0.05], [-0.04, 0.7, 0.12], [0.12, -0.09, 0.98]],
    };
    let alone = gl
        .enhance_mapped(&view_img, &camera, &mapping, &params)
        .unwrap();
    let want = bottom_first(&alone);
    let (w, h) = (32usize, 20usize);
    // A 67x27 texture with the view at (35, 5) in GL's coordinates.
    let (tw, th, x0, y0) = (67usize, 27usize, 35usize, 5usize);
    let filler = noise(tw as u32, th as u32, 14);
    let mut texels = bottom_first(&filler);
    let view_rows = bottom_first(&view_img);
    for r in 0..h {
        let dst = ((y0 + r) * tw + x0) * 4;
        texels[dst..dst + w * 4].copy_from_slice(&view_rows[r * w * 4..(r + 1) * w * 4]);
    }
    gl.set_camera(&camera, &params).unwrap();
    let texture = gl
        .create_texture(SRGB8_ALPHA8, (tw as u32, th as u32), &texels)
        .unwrap();
    let view = GlView {
        texture,
        target: GlTarget::Texture2D,
        internal_format: SRGB8_ALPHA8,
        rect: (x0 as u32, y0 as u32, w as u32, h as u32),
        mapping,
        pixels_per_degree: DEFAULT_PIXELS_PER_DEGREE,
    };
    gl.enhance_views(&[view], &params).unwrap();
    let out = gl
        .read_texture(texture, SRGB8_ALPHA8, (tw as u32, th as u32))
        .unwrap();
    for y in 0..th {
        for x in 0..tw {
            let at = (y * tw + x) * 4;
            let inside = (x0..x0 + w).contains(&x) && (y0..y0 + h).contains(&y);
            let expected = if inside {
                let k = ((y - y0) * w + (x - x0)) * 4;
                &want[k..k + 4]
            } else {
                &texels[at..at + 4]
            };
            assert_eq!(
                &out[at..at + 4],
                expected,
                "texel ({x}, {y}), inside {inside}"
            );
        }
    }
    // Layer 1 of two.
    let other = bottom_first(&noise(32, 20, 15));
    let layers = [other.clone(), view_rows].concat();
    let array = gl
        .create_array_texture(SRGB8_ALPHA8, (32, 20), 2, &layers)
        .unwrap();
    let view = GlView {
        texture: array,
        target: GlTarget::Texture2DArray { layer: 1 },
        internal_format: SRGB8_ALPHA8,
        rect: (0, 0, 32, 20),
        mapping,
        pixels_per_degree: DEFAULT_PIXELS_PER_DEGREE,
    };
    gl.enhance_views(&[view], &params).unwrap();
    let out = gl
        .read_texture_layers(array, SRGB8_ALPHA8, (32, 20), 2)
        .unwrap();
    assert_eq!(&out[..other.len()], &other[..], "layer 0 changed");
    assert_eq!(&out[other.len()..], &want[..], "layer 1");
}

/// Run by `a_context_older_than_4_5_is_refused_with_the_reason` with Mesa told to make 4.3
/// contexts.
#[test]
#[ignore = "run by a_context_older_than_4_5_is_refused_with_the_reason"]
fn old_context_child() {
    let err = match GlOffline::with_version((4, 3)) {
        Ok(_) => panic!("an OpenGL 4.3 context was taken"),
        Err(e) => e.to_string(),
    };
    assert!(
        err.contains("OpenGL 4.3, older than 4.5") && err.lines().count() == 1,
        "{err}"
    );
}

/// An OpenGL 4.3 context (compute shaders, but not the 4.5 the programs are written for) is
/// refused with one line saying why, before the engine makes any GL call past the queries.
#[test]
fn a_context_older_than_4_5_is_refused_with_the_reason() {
    run_child(
        "old_context_child",
        &[("MESA_GL_VERSION_OVERRIDE", OsStr::new("4.3"))],
    );
}

/// The layer finds the entry points through the GL the app loaded (here the offline
/// context's libEGL, opened privately as SDL opens an app's GL), and the engine runs with them
/// on the current context.
#[test]
fn the_entry_points_are_found_through_the_gl_in_the_process() {
    let mut gl = context();
    let functions = contrastxr::gpu::opengl::Gl::from_process().unwrap();
    // SAFETY: the offline context is current on this thread; the functions are its driver's.
    let mut engine = unsafe { contrastxr::gpu::opengl::GlFrameRunner::new(functions) }.unwrap();
    let camera = noise(32, 24, 6);
    let display = noise(16, 8, 7);
    let params = Params::default();
    let texels = contrastxr::gpu::core::blurred_texels::BlurredTexels::prepare(
        &camera,
        contrastxr::gpu::core::blurred_texels::BlurTaps::of(&params),
    );
    let bytes = bottom_first(&display);
    let texture = gl.create_texture(SRGB8_ALPHA8, (16, 8), &bytes).unwrap();
    let view = GlView {
        texture,
        target: GlTarget::Texture2D,
        internal_format: SRGB8_ALPHA8,
        rect: (0, 0, 16, 8),
        mapping: params.camera_mapping(),
        pixels_per_degree: DEFAULT_PIXELS_PER_DEGREE,
    };
    // SAFETY: as above, and the texture is this context's.
    unsafe {
        engine.set_background(&texels).unwrap();
        while engine.enhance(&[view], &params).unwrap()
            == contrastxr::gpu::opengl::Outcome::Compiling
        {}
        engine.destroy();
    }
    let out = gl.read_texture(texture, SRGB8_ALPHA8, (16, 8)).unwrap();
    let alone = bottom_first(&gl.enhance(&display, &camera, &params).unwrap());
    assert_eq!(out, alone);
}

/// A view the texture cannot hold (a layer of a texture that has none, a region past its
/// edge) is refused before any transfer: the texture is untouched and no GL error is raised.
#[test]
fn a_view_its_texture_cannot_hold_is_refused_without_a_gl_error() {
    let mut gl = context();
    // SAFETY: glGetError's address in this context, of its C signature.
    let get_error = unsafe {
        std::mem::transmute::<*const c_void, unsafe extern "system" fn() -> u32>(load(
            &gl,
            c"glGetError",
        ))
    };
    let params = Params::default();
    gl.set_camera(&noise(32, 24, 2), &params).unwrap();
    let bytes = bottom_first(&noise(16, 8, 3));
    let texture = gl.create_texture(SRGB8_ALPHA8, (16, 8), &bytes).unwrap();
    let view = GlView {
        texture,
        target: GlTarget::Texture2D,
        internal_format: SRGB8_ALPHA8,
        rect: (0, 0, 16, 8),
        mapping: params.camera_mapping(),
        pixels_per_degree: DEFAULT_PIXELS_PER_DEGREE,
    };
    let wrong = [
        GlView {
            target: GlTarget::Texture2DArray { layer: 0 },
            ..view
        },
        GlView {
            rect: (1, 0, 16, 8),
            ..view
        },
        GlView {
            internal_format: RGBA8,
            ..view
        },
    ];
    for v in wrong {
        let err = gl.enhance_views(&[v], &params).unwrap_err().to_string();
        assert_eq!(err.lines().count(), 1, "{err}");
        // SAFETY: glGetError takes no arguments.
        assert_eq!(unsafe { get_error() }, 0, "{v:?} raised a GL error");
    }
    let out = gl.read_texture(texture, SRGB8_ALPHA8, (16, 8)).unwrap();
    assert_eq!(out, bytes);
}

/// In place (image load/store on the app's texture, through a GL_RGBA8 view for sRGB) and
/// through a buffer object give the same texels, bit for bit, for every format, a region of a
/// 2D texture and a layer of an array, under a projective mapping; texels outside the region
/// and the other layer are untouched. Every format has an in-place path (GL_RGBA16 and
/// GL_RGB10_A2 through an image unit format of their size).
#[test]
fn in_place_and_through_a_buffer_give_the_same_texels() {
    use contrastxr::gpu::opengl::StoreThrough;
    let mut gl = context();
    let camera = noise(70, 50, 21);
    let params = Params::default();
    gl.set_camera(&camera, &params).unwrap();
    let mapping = CameraMapping {
        rows: [[0.8, 0.06, 0.05], [-0.04, 0.7, 0.12], [0.12, -0.09, 0.98]],
    };
    let (tw, th) = (45u32, 23u32);
    for internal in [SRGB8_ALPHA8, RGBA8, RGBA16F, RGBA16, RGB10_A2] {
        let format = GlFormat::of(internal).unwrap();
        for layers in [None, Some(2u32)] {
            let texels: Vec<u8> = (0..layers.unwrap_or(1))
                .flat_map(|l| noise(tw, th, 31 + l).pixels)
                .flat_map(|p| encode(format, p))
                .flat_map(u32::to_le_bytes)
                .collect();
            let mut outputs = Vec::new();
            let mut paths = Vec::new();
            for in_place in [false, true] {
                gl.engine().set_in_place(in_place);
                let texture = match layers {
                    None => gl.create_texture(internal, (tw, th), &texels),
                    Some(n) => gl.create_array_texture(internal, (tw, th), n, &texels),
                }
                .unwrap();
                let view = GlView {
                    texture,
                    target: match layers {
                        None => GlTarget::Texture2D,
                        Some(_) => GlTarget::Texture2DArray { layer: 1 },
                    },
                    internal_format: internal,
                    rect: (7, 3, 29, 17),
                    mapping,
                    pixels_per_degree: DEFAULT_PIXELS_PER_DEGREE,
                };
                paths.push(gl.engine().store_through(&view));
                gl.enhance_views(&[view], &params).unwrap();
                let n = layers.unwrap_or(1);
                outputs.push(
                    gl.read_texture_layers(texture, internal, (tw, th), n)
                        .unwrap(),
                );
                gl.delete_texture(texture);
            }
            let what = format!("{internal:#x}, layers {layers:?}");
            assert_eq!(paths[0], None, "{what}: in_place off stores in place");
            let expected = match internal {
                SRGB8_ALPHA8 => StoreThrough::View(RGBA8),
                RGBA16 => StoreThrough::Texture(0x8D76), // GL_RGBA16UI
                RGB10_A2 => StoreThrough::Texture(0x8236), // GL_R32UI
                other => StoreThrough::Texture(other),
            };
            let expected = Some(expected);
            assert_eq!(paths[1], expected, "{what}: the in-place path");
            assert_ne!(outputs[0], texels, "{what}: nothing changed");
            let bpp = format.pixel.bytes_per_pixel() as usize;
            let differing = outputs[0]
                .chunks_exact(bpp)
                .zip(outputs[1].chunks_exact(bpp))
                .filter(|(a, b)| a != b)
                .count();
            assert_eq!(differing, 0, "{what}: texels differ between the paths");
            // Outside the region (and on layer 0 of the array) the texels are the app's.
            let layer_bytes = (tw * th) as usize * bpp;
            let base = if layers.is_some() { layer_bytes } else { 0 };
            assert_eq!(
                outputs[1][..base],
                texels[..base],
                "{what}: layer 0 changed"
            );
            for y in 0..th as usize {
                for x in 0..tw as usize {
                    let inside = (7..36).contains(&x) && (3..20).contains(&y);
                    let at = base + (y * tw as usize + x) * bpp;
                    if !inside {
                        assert_eq!(
                            outputs[1][at..at + bpp],
                            texels[at..at + bpp],
                            "{what}: texel ({x}, {y}) outside the region changed"
                        );
                    }
                }
            }
        }
    }
}

/// The programs with the cube roots by `pow`, which a GPU's views take (forced here: a CPU
/// driver takes the Newton steps), hold the ±1 contract against the CPU reference in place on
/// 8-bit sRGB for both methods that have them, at two lambda_e; and in every format they give
/// the Newton steps' output within one step in every channel (and not bit for bit: the pow
/// programs ran).
#[test]
fn opengl_cube_roots_by_pow_conform_in_place() {
    use contrastxr::algorithm::Method;
    use contrastxr::gpu::core::{CubeRoots, PixelLayout};
    let mut gl = context();
    let cpu = gl.on_cpu();
    assert_eq!(gl.engine().cube_roots(), CubeRoots::for_device(cpu));
    gl.engine().set_in_place(true);
    gl.engine().set_cube_roots(CubeRoots::Pow);
    let camera = noise(70, 50, 23);
    let display = noise(45, 23, 7);
    for method in [Method::Paper, Method::Perceptual] {
        for lambda_e in [0.1, 1.0] {
            let params = Params {
                method,
                lambda_e,
                ..Params::default()
            };
            let bad = nonconformant(&mut gl, &display, &camera, &projective(), &params);
            let (n, some) = (bad.len(), &bad[..bad.len().min(5)]);
            assert!(
                n == 0,
                "{method:?} lambda_e {lambda_e}: {n} pixels differ, e.g. {some:?}"
            );
        }
    }
    let region = (37, 21);
    let mut moved = 0;
    for internal in [SRGB8_ALPHA8, RGBA8, RGBA16F, RGBA16, RGB10_A2] {
        let format = GlFormat::of(internal).unwrap();
        let raw: Vec<u32> = noise(region.0, region.1, 9)
            .pixels
            .into_iter()
            .flat_map(|p| encode(format, p))
            .collect();
        let channels = |words: &[u32]| -> Vec<u32> {
            match format.pixel.layout {
                PixelLayout::A2b10g10r10 => words
                    .iter()
                    .flat_map(|w| [w & 0x3ff, w >> 10 & 0x3ff, w >> 20 & 0x3ff, w >> 30])
                    .collect(),
                PixelLayout::Rgba16Unorm | PixelLayout::Rgba16Float => {
                    words.iter().flat_map(|w| [w & 0xffff, w >> 16]).collect()
                }
                _ => words
                    .iter()
                    .flat_map(|w| w.to_le_bytes())
                    .map(u32::from)
                    .collect(),
            }
        };
        for method in [Method::Paper, Method::Perceptual] {
            let params = Params {
                method,
                ..Params::default()
            };
            let mut run = |roots| {
                gl.engine().set_cube_roots(roots);
                gl.enhance_raw(&raw, region, internal, &camera, &params)
                    .unwrap_or_else(|e| panic!("{internal:#x}: {e}"))
            };
            let (by_pow, newton) = (run(CubeRoots::Pow), run(CubeRoots::Newton));
            let what = format!("{internal:#x} {method:?}");
            // (The perceptual method may find every random pixel of a format at its target.)
            assert!(
                method != Method::Paper || newton != raw,
                "{what}: nothing changed"
            );
            let (a, b) = (channels(&by_pow), channels(&newton));
            let worst = a.iter().zip(&b).map(|(x, y)| x.abs_diff(*y)).max();
            assert!(
                worst <= Some(1),
                "{what}: channels differ by up to {worst:?}"
            );
            moved += a.iter().zip(&b).filter(|(x, y)| x != y).count();
        }
    }
    assert!(
        moved > 0,
        "the pow programs gave the Newton steps' output bit for bit"
    );
    gl.engine().set_cube_roots(CubeRoots::for_device(cpu));
}

/// `contrastxr bench --engine opengl` reports the OpenGL engine's figures in the Vulkan bench's
/// JSON: the device names the GL driver, every time is positive, the ratios are the times'
/// quotients, the frame in place is there (it is the enhancement's figure) and the image-copy
/// path, which OpenGL has not, is null; a bad engine name is refused.
#[test]
fn bench_times_the_opengl_engine() {
    let bench = |extra: &[&str]| {
        std::process::Command::new(env!("CARGO_BIN_EXE_contrastxr"))
            .args([
                "bench", "--sizes", "48x32", "--views", "2", "--runs", "3", "--json",
            ])
            .args(extra)
            .output()
            .unwrap()
    };
    let o = bench(&["--engine", "opengl", "--content", "typical"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("one JSON object");
    assert!(
        v["device"]
            .as_str()
            .is_some_and(|d| d.starts_with("OpenGL: ")),
        "{v}"
    );
    let cpu = v["device"].as_str().is_some_and(|d| d.contains("llvmpipe"));
    assert_eq!(v["cube_roots"], if cpu { "newton" } else { "pow" }, "{v}");
    let results = v["results"].as_array().unwrap();
    assert_eq!(results.len(), 1, "{v}");
    let r = &results[0];
    assert_eq!(
        (r["width"].as_u64(), r["views"].as_u64()),
        (Some(48), Some(2))
    );
    assert_eq!(r["content"], "typical");
    let fg = r["foreground_fraction"].as_f64().unwrap();
    assert!(fg > 0.05 && fg < 0.5, "{fg}");
    let ms = |k: &str| r[k].as_f64().unwrap_or_else(|| panic!("{k} missing: {r}"));
    for k in [
        "copy_ms",
        "enhance_ms",
        "frame_ms",
        "image_copy_ms",
        "frame_in_place_ms",
        "background_ms",
    ] {
        assert!(ms(k) > 0.0, "{k} {}", ms(k));
    }
    assert_eq!(ms("enhance_ms"), ms("frame_in_place_ms"));
    let ratio = ms("frame_in_place_ms") / ms("frame_ms");
    assert!((ms("in_place_ratio") - ratio).abs() < 1e-9 * ratio);
    assert!((ms("frame_ratio") - ms("frame_ms") / ms("copy_ms")).abs() < 1e-9 * ms("frame_ratio"));
    for k in [
        "copy_wide_ms",
        "frame_image_copy_ms",
        "image_copy_copies_ms",
    ] {
        assert!(r[k].is_null(), "{k}: {r}");
    }
    let o = bench(&["--engine", "metal"]);
    assert_eq!(
        o.status.code(),
        Some(2),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(String::from_utf8_lossy(&o.stderr).contains("--engine must be vulkan or opengl"));
    // Ablations: a row each after the baseline; no shared fetches to ablate in OpenGL.
    let o = bench(&["--engine", "opengl", "--ablate", "enhance-pass"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("one JSON object");
    let names: Vec<&str> = v["results"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r["ablation"].as_str().unwrap())
        .collect();
    assert_eq!(names, ["none", "enhance-pass", "none", "enhance-pass"]);
    let o = bench(&["--engine", "opengl", "--ablate", "shared-fetch"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("on the OpenGL engine"));
}

/// Two outputs' 8-bit channels: the same on a CPU driver, which compiles both programs'
/// arithmetic alike; elsewhere within one step (a GPU compiler may contract one program's
/// multiply-adds and not the other's).
fn assert_same_arithmetic(gl: &GlOffline, a: &[u32], b: &[u32], what: &str) {
    let channels = |w: &[u32]| -> Vec<u8> { w.iter().flat_map(|x| x.to_le_bytes()).collect() };
    let (a, b) = (channels(a), channels(b));
    assert_eq!(a.len(), b.len(), "{what}");
    let worst = a
        .iter()
        .zip(&b)
        .map(|(x, y)| x.abs_diff(*y))
        .max()
        .unwrap_or(0);
    let bound = if gl.on_cpu() { 0 } else { 1 };
    assert!(worst <= bound, "{what}: channels differ by up to {worst}");
}

/// The benchmark's ablations in the OpenGL engine take out what they name, through a buffer
/// and in place: without the method (alone or with the background and the codec) or the
/// enhance pass every word comes back unchanged; without the codec the sRGB words come out as
/// RGBA8 words do; with the constant background the camera no longer matters; the perceptual
/// method without its directions, every pixel below the target, gives the paper's output, and
/// through the paper's classify or its own by tile rows its own.
#[test]
fn opengl_ablations_take_out_what_they_name() {
    let channels = |words: &[u32]| -> std::vec::IntoIter<u8> {
        let bytes: Vec<u8> = words.iter().flat_map(|w| w.to_le_bytes()).collect();
        bytes.into_iter()
    };
    use contrastxr::algorithm::Method;
    use contrastxr::gpu::core::interface::{
        ABLATE_BACKGROUND, ABLATE_CODEC, ABLATE_CUBE_ROOT, ABLATE_DIRECTIONS, ABLATE_ENHANCE_PASS,
        ABLATE_METHOD,
    };
    let mut gl = context();
    let (camera, other_camera) = (noise(64, 40, 23), noise(64, 40, 29));
    let raw: Vec<u32> = noise(96, 9, 43)
        .pixels
        .iter()
        .map(|p| u32::from_le_bytes(*p))
        .collect();
    let run = |gl: &mut GlOffline, ablate, format, camera: &RgbaImage, params: &Params| {
        gl.engine().set_ablation(ablate);
        let out = gl.enhance_raw(&raw, (96, 9), format, camera, params);
        gl.engine().set_ablation(0);
        out.unwrap_or_else(|err| panic!("ablation {ablate}: {err}"))
    };
    let paper = Params::default();
    for in_place in [false, true] {
        gl.engine().set_in_place(in_place);
        let enhanced = run(&mut gl, 0, SRGB8_ALPHA8, &camera, &paper);
        assert_ne!(enhanced, raw, "in place {in_place}: nothing changed");
        let all_three = ABLATE_METHOD | ABLATE_BACKGROUND | ABLATE_CODEC;
        for ablate in [ABLATE_METHOD, all_three, ABLATE_ENHANCE_PASS] {
            let out = run(&mut gl, ablate, SRGB8_ALPHA8, &camera, &paper);
            assert_eq!(out, raw, "in place {in_place}: ablation {ablate}");
        }
        let without_codec = run(&mut gl, ABLATE_CODEC, SRGB8_ALPHA8, &camera, &paper);
        let as_unorm = run(&mut gl, 0, RGBA8, &camera, &paper);
        assert_ne!(
            without_codec, enhanced,
            "in place {in_place}: the codec ran"
        );
        let what = format!("in place {in_place}: no codec against RGBA8");
        assert_same_arithmetic(&gl, &without_codec, &as_unorm, &what);
        // The cube roots by pow: replaced, not taken out, so still the enhancement.
        let by_pow = run(&mut gl, ABLATE_CUBE_ROOT, SRGB8_ALPHA8, &camera, &paper);
        let worst = channels(&by_pow)
            .zip(channels(&enhanced))
            .map(|(a, b)| a.abs_diff(b))
            .max();
        assert!(
            worst <= Some(1),
            "in place {in_place}: cube roots by pow: {worst:?}"
        );
        let grey = run(&mut gl, ABLATE_BACKGROUND, SRGB8_ALPHA8, &camera, &paper);
        let grey_too = run(
            &mut gl,
            ABLATE_BACKGROUND,
            SRGB8_ALPHA8,
            &other_camera,
            &paper,
        );
        assert_ne!(
            grey, raw,
            "in place {in_place}: no enhancement over the grey"
        );
        assert_eq!(grey, grey_too, "in place {in_place}: the camera still read");
        assert_ne!(
            run(&mut gl, 0, SRGB8_ALPHA8, &other_camera, &paper),
            enhanced,
            "in place {in_place}: the camera made no difference"
        );
    }
    gl.engine().set_in_place(false);
    let mut never = Params {
        method: Method::Perceptual,
        ..Params::default()
    };
    never.perceptual.target_contrast = 1.0;
    let paper_out = run(&mut gl, 0, SRGB8_ALPHA8, &camera, &paper);
    let paper_only = run(&mut gl, ABLATE_DIRECTIONS, SRGB8_ALPHA8, &camera, &never);
    assert_ne!(run(&mut gl, 0, SRGB8_ALPHA8, &camera, &never), paper_out);
    assert_same_arithmetic(
        &gl,
        &paper_only,
        &paper_out,
        "no directions against the paper",
    );
    let default = Params {
        method: Method::Perceptual,
        ..Params::default()
    };
    let own = run(&mut gl, 0, SRGB8_ALPHA8, &camera, &default);
    assert_ne!(own, raw);
    for (choice, what) in [
        (ClassifyChoice::Paper, "the paper's classify"),
        (ClassifyChoice::OwnByRows, "by tile rows"),
    ] {
        gl.engine().set_classify(choice);
        let out = run(&mut gl, 0, SRGB8_ALPHA8, &camera, &default);
        gl.engine().set_classify(ClassifyChoice::Own);
        assert_same_arithmetic(&gl, &out, &own, what);
    }
    // Other methods and formats have none.
    gl.engine().set_ablation(ABLATE_METHOD);
    let luminance = Params {
        method: Method::Luminance,
        ..Params::default()
    };
    let refused = gl.enhance_raw(&raw, (96, 9), SRGB8_ALPHA8, &camera, &luminance);
    let refused_rgba8 = gl.enhance_raw(&raw, (96, 9), RGBA8, &camera, &paper);
    gl.engine().set_ablation(0);
    for r in [refused, refused_rgba8] {
        let err = r.expect_err("no ablated variant").to_string();
        assert!(err.contains("paper's and the perceptual method"), "{err}");
    }
}

/// The perceptual method's classify by tile rows lists every tile its own classify lists, in
/// the OpenGL engine too: one content pixel per tile, in each row and column of the tiles in
/// turn, every pixel below the target (target_contrast 1): the same words through a buffer and
/// in place, and the same as with every tile with content listed.
#[test]
fn opengl_classify_by_tile_rows_lists_the_tiles_its_own_does() {
    use contrastxr::algorithm::Method;
    let mut gl = context();
    let camera = noise(64, 40, 53);
    let raw: Vec<u32> = common::images::one_pixel_per_tile(96, 17, 59)
        .pixels
        .iter()
        .map(|p| u32::from_le_bytes(*p))
        .collect();
    let mut params = Params {
        method: Method::Perceptual,
        ..Params::default()
    };
    params.perceptual.target_contrast = 1.0;
    for in_place in [false, true] {
        gl.engine().set_in_place(in_place);
        let run = |choice| {
            gl.engine().set_classify(choice);
            let out = gl.enhance_raw(&raw, (96, 17), SRGB8_ALPHA8, &camera, &params);
            gl.engine().set_classify(ClassifyChoice::Own);
            out.unwrap_or_else(|err| panic!("in place {in_place}, {choice:?}: {err}"))
        };
        assert_every_classify_lists_the_same(&raw, run, &format!("in place {in_place}"));
    }
    gl.engine().set_in_place(false);
}

/// The perceptual method's own classify, with its lower bound of c', lists every tile whose
/// pixel the enhancement changes (common::conformance::assert_the_bound_lists_every_tile_that_changes).
#[test]
fn opengl_the_bound_of_the_own_classify_lists_every_tile_that_changes() {
    let mut gl = context();
    let camera = noise(64, 40, 61);
    let mut image = common::images::one_pixel_per_tile(256, 64, 67);
    common::images::darken_every_other(&mut image);
    let raw: Vec<u32> = image
        .pixels
        .iter()
        .map(|p| u32::from_le_bytes(*p))
        .collect();
    let run = |choice, params: &Params| {
        gl.engine().set_classify(choice);
        let out = gl.enhance_raw(&raw, (256, 64), SRGB8_ALPHA8, &camera, params);
        gl.engine().set_classify(ClassifyChoice::Own);
        out.unwrap_or_else(|err| panic!("{choice:?}: {err}"))
    };
    assert_the_bound_lists_every_tile_that_changes(&raw, run, "OpenGL");
}

/// The app's reset status is the app's: a robust context reports a reset once, so the engine
/// never resolves (let alone calls) glGetGraphicsResetStatus or its ARB/KHR/EXT forms.
#[test]
fn the_engine_never_asks_for_the_reset_status() {
    use contrastxr::gpu::opengl::Gl;
    let gl = context();
    let mut asked = Vec::new();
    let loaded = Gl::load(&mut |name: &CStr| {
        asked.push(name.to_string_lossy().into_owned());
        gl.proc_address(name)
    });
    assert!(loaded.is_ok(), "the entry points load");
    assert!(asked.len() > 50, "{asked:?}");
    let reset: Vec<&String> = asked.iter().filter(|n| n.contains("ResetStatus")).collect();
    assert!(reset.is_empty(), "the engine resolves {reset:?}");
}

/// `glUseProgram(p); glDeleteProgram(p)` before the call (a common pattern: the program lives
/// on while current): the layer could not make `p` current again once its own programs ran, so
/// it passes the frame through untouched, changing nothing (the program still current, no
/// error raised, the texture as it was), and enhances again once the app lets go of it.
#[test]
fn a_program_kept_only_by_its_binding_passes_the_frame_through() {
    use contrastxr::gpu::opengl::GlError;
    let mut gl = context();
    let a = app_gl(&gl);
    let params = Params::default();
    // The programs built, and a copy of the texture as the app left it.
    let (view, _) = built_srgb_view(&mut gl, (3, 4), &params);
    let texture = view.texture;
    let before = gl.read_texture(texture, SRGB8_ALPHA8, (40, 24)).unwrap();
    let source = c"#version 450\nlayout(local_size_x = 1) in;\nvoid main() {}\n";
    // SAFETY: the context is current on this thread; a program made here.
    let program = unsafe {
        let p = (a.create_shader_programv)(0x91B9, 1, &source.as_ptr());
        (a.use_program)(p);
        (a.delete_program)(p);
        assert_eq!((a.get_error)(), 0, "the test's own set-up raised an error");
        p
    };
    let r = gl.enhance_views(&[view], &params);
    assert!(matches!(r, Err(GlError::Unrestorable(_))), "{r:?}");
    let mut current = 0;
    // SAFETY: single-valued queries; glGetError takes no arguments.
    let error = unsafe {
        (a.get_integerv)(0x8B8D, &mut current);
        (a.get_error)()
    };
    assert_eq!(
        current as u32, program,
        "the app's program is no longer current"
    );
    assert_eq!(error, 0, "an error was left in the app's flag");
    let after = gl.read_texture(texture, SRGB8_ALPHA8, (40, 24)).unwrap();
    assert_eq!(after, before, "the frame was not passed through untouched");
    // SAFETY: as above: the app lets go of its program (GL frees it now).
    unsafe { (a.use_program)(0) };
    gl.enhance_views(&[view], &params).unwrap();
    let again = gl.read_texture(texture, SRGB8_ALPHA8, (40, 24)).unwrap();
    assert_ne!(again, before, "frames are not enhanced again");
}

/// A second context sharing the current one's objects (as the context of an app's loading
/// thread does) is current while `f` runs; the first one is current again after it.
fn in_shared_context(f: impl FnOnce()) {
    use std::ptr::null_mut;
    type GetCurrent = unsafe extern "C" fn() -> *mut c_void;
    type Create =
        unsafe extern "C" fn(*mut c_void, *mut c_void, *mut c_void, *const i32) -> *mut c_void;
    type MakeCurrent =
        unsafe extern "C" fn(*mut c_void, *mut c_void, *mut c_void, *mut c_void) -> u32;
    type Destroy = unsafe extern "C" fn(*mut c_void, *mut c_void) -> u32;
    // SAFETY: the libEGL the offline context opened (RTLD_NOLOAD: its handle, never another).
    let lib = unsafe { libc::dlopen(c"libEGL.so.1".as_ptr(), libc::RTLD_NOW | libc::RTLD_NOLOAD) };
    assert!(!lib.is_null(), "libEGL.so.1 is not loaded");
    let symbol = |name: &CStr| {
        // SAFETY: a handle dlopen returned; a NUL-terminated name.
        let p = unsafe { libc::dlsym(lib, name.as_ptr()) };
        assert!(!p.is_null(), "{name:?}");
        p
    };
    // SAFETY: libEGL's functions of these names have these C types.
    let (display, context, create, make_current, destroy) = unsafe {
        use std::mem::transmute;
        (
            transmute::<*mut c_void, GetCurrent>(symbol(c"eglGetCurrentDisplay")),
            transmute::<*mut c_void, GetCurrent>(symbol(c"eglGetCurrentContext")),
            transmute::<*mut c_void, Create>(symbol(c"eglCreateContext")),
            transmute::<*mut c_void, MakeCurrent>(symbol(c"eglMakeCurrent")),
            transmute::<*mut c_void, Destroy>(symbol(c"eglDestroyContext")),
        )
    };
    // An OpenGL 4.5 core context (major, minor, profile mask: core), EGL_NONE-terminated.
    let attributes = [0x3098, 4, 0x30FB, 5, 0x30FD, 1, 0x3038];
    // SAFETY: the offline context is current on this thread (OpenGL bound as its API); the new
    // context has no config (EGL_KHR_no_config_context, as the offline one) and no surfaces.
    unsafe {
        let (display, first) = (display(), context());
        assert!(!first.is_null(), "no context is current");
        let second = create(display, null_mut(), first, attributes.as_ptr());
        assert!(!second.is_null(), "EGL made no shared context");
        assert_eq!(make_current(display, null_mut(), null_mut(), second), 1);
        f();
        assert_eq!(make_current(display, null_mut(), null_mut(), first), 1);
        destroy(display, second);
    }
}

/// Enhances `view`, whose texels were `texels`, with a binding of the app's that could not be
/// put back (made after they were read: reading them binds no pack buffer): the call is refused
/// before anything changes, with one line naming `what`, and the app finds every binding
/// (`read_state`), its error flag (none) and the texture as it left them.
fn refused_untouched(
    gl: &mut GlOffline,
    a: &AppGl,
    (view, texels): (GlView, &[u8]),
    (what, binding): (&str, &str),
) {
    use contrastxr::gpu::opengl::GlError;
    let before = read_state(a);
    let r = gl.enhance_views(&[view], &Params::default());
    let after = read_state(a);
    // SAFETY: glGetError takes no arguments.
    let error = unsafe { (a.get_error)() };
    let kept = after == before;
    let said = format!("{r:?}; then the app's error {error:#x}, its state kept: {kept}");
    let line = match r {
        Err(e @ GlError::Unrestorable(_)) => e.to_string(),
        _ => panic!("{binding}: the call was not refused: {said}"),
    };
    assert!(line.contains(what) && line.lines().count() == 1, "{line}");
    assert!(kept, "{binding}: the app's GL state changed: {said}");
    assert_eq!(error, 0, "{binding}: an error was left in the app's flag");
    let out = gl
        .read_texture(view.texture, SRGB8_ALPHA8, (40, 24))
        .unwrap();
    assert_eq!(
        out, texels,
        "{binding}: the frame was not passed through untouched"
    );
}

/// Enhances `view` and holds that it changed and left no error: the app let go of what held the
/// frames back.
fn enhanced_again(gl: &mut GlOffline, a: &AppGl, view: GlView, after: &str) {
    let texels = gl
        .read_texture(view.texture, SRGB8_ALPHA8, (40, 24))
        .unwrap();
    let before = read_state(a);
    gl.enhance_views(&[view], &Params::default())
        .unwrap_or_else(|e| panic!("{after}: {e}"));
    assert_eq!(read_state(a), before, "{after}: the app's GL state changed");
    // SAFETY: glGetError takes no arguments.
    let error = unsafe { (a.get_error)() };
    assert_eq!(error, 0, "{after}: an error was raised");
    let out = gl
        .read_texture(view.texture, SRGB8_ALPHA8, (40, 24))
        .unwrap();
    assert_ne!(out, texels, "{after}: frames are not enhanced again");
}

/// Binds an object (a name) to one binding point, or lets go of it (0).
type Bind = fn(&AppGl, u32);

/// An object the app bound, deleted through another context sharing its objects (its loading
/// thread's) before the call: the binding alone keeps it alive, the recipe's own binding would
/// free it and binding its name again would be an error. Each of `bindings` binds an object
/// made by `make` (deleted by `delete`), and lets go of it when given 0.
struct DeletedElsewhere {
    what: &'static str,
    make: fn(&AppGl) -> u32,
    delete: fn(&AppGl, u32),
    bindings: &'static [(&'static str, Bind)],
}

fn deleted_elsewhere_passes_frames_through(case: DeletedElsewhere) {
    let mut gl = context();
    let a = app_gl(&gl);
    let params = Params::default();
    let (view, _) = built_srgb_view(&mut gl, (11, 12), &params);
    for (binding, bind) in case.bindings {
        let texels = gl
            .read_texture(view.texture, SRGB8_ALPHA8, (40, 24))
            .unwrap();
        let name = (case.make)(&a);
        bind(&a, name);
        in_shared_context(|| (case.delete)(&a, name));
        // SAFETY: glGetError takes no arguments.
        let error = unsafe { (a.get_error)() };
        assert_eq!(error, 0, "{binding}: the set-up raised an error");
        refused_untouched(&mut gl, &a, (view, &texels), (case.what, binding));
        bind(&a, 0);
        enhanced_again(&mut gl, &a, view, binding);
    }
}

/// A texture bound on the unit the recipe samples its background on, or to the image unit it
/// stores through, deleted through a shared context.
#[test]
fn a_texture_deleted_through_a_shared_context_passes_the_frame_through() {
    deleted_elsewhere_passes_frames_through(DeletedElsewhere {
        what: "a texture the app has bound is deleted",
        make: |a| {
            let mut t = 0;
            // SAFETY: the context is current on this thread; a 4x4 GL_RGBA8 2D texture.
            unsafe {
                (a.create_textures)(0x0DE1, 1, &mut t);
                (a.texture_storage_2d)(t, 1, RGBA8, 4, 4);
            }
            t
        },
        // SAFETY: deleting a name is always valid.
        delete: |a, t| unsafe { (a.delete_textures)(1, &t) },
        bindings: &[
            ("GL_TEXTURE_2D of unit 5", |a, t| {
                // SAFETY: unit 5, then the app's active unit (0) again; a texture or 0.
                unsafe {
                    (a.active_texture)(0x84C0 + 5);
                    (a.bind_texture)(0x0DE1, t);
                    (a.active_texture)(0x84C0);
                }
            }),
            ("image unit 6", |a, t| {
                // SAFETY: image unit 6 (< 8), read-write GL_RGBA8, or unbound with GL's
                // defaults (read-only, GL_R8).
                unsafe {
                    match t {
                        0 => (a.bind_image_texture)(6, 0, 0, 0, 0, 0x88B8, 0x8229),
                        t => (a.bind_image_texture)(6, t, 0, 0, 0, 0x88BA, RGBA8),
                    }
                }
            }),
        ],
    });
}

/// A buffer bound to each buffer binding the recipe uses (storage slots 2 and 3 with a range,
/// the generic storage binding, pixel pack and unpack, dispatch indirect), deleted through a
/// shared context.
#[test]
fn a_buffer_deleted_through_a_shared_context_passes_the_frame_through() {
    deleted_elsewhere_passes_frames_through(DeletedElsewhere {
        what: "a buffer the app has bound is deleted",
        make: |a| {
            let mut b = 0;
            // SAFETY: the context is current on this thread; 1 KiB of GL_DYNAMIC_DRAW data.
            unsafe {
                (a.gen)(1, &mut b);
                (a.named_buffer_data)(b, 1024, std::ptr::null(), 0x88E8);
            }
            b
        },
        // SAFETY: deleting a name is always valid.
        delete: |a, b| unsafe { (a.delete_buffers)(1, &b) },
        bindings: &[
            // SAFETY: a buffer (256 bytes from 256) or 0 bound to storage slot 2.
            ("storage slot 2", |a, b| unsafe {
                match b {
                    0 => (a.bind_buffer_base)(0x90D2, 2, 0),
                    b => (a.bind_buffer_range)(0x90D2, 2, b, 256, 256),
                }
            }),
            // SAFETY: a buffer or 0 bound to storage slot 3.
            ("storage slot 3", |a, b| unsafe {
                (a.bind_buffer_base)(0x90D2, 3, b)
            }),
            // SAFETY: a buffer or 0 bound to GL_SHADER_STORAGE_BUFFER.
            ("the generic storage binding", |a, b| unsafe {
                (a.bind_buffer)(0x90D2, b)
            }),
            // SAFETY: a buffer or 0 bound to GL_PIXEL_PACK_BUFFER.
            ("pixel pack", |a, b| unsafe { (a.bind_buffer)(0x88EB, b) }),
            // SAFETY: a buffer or 0 bound to GL_PIXEL_UNPACK_BUFFER.
            ("pixel unpack", |a, b| unsafe { (a.bind_buffer)(0x88EC, b) }),
            // SAFETY: a buffer or 0 bound to GL_DISPATCH_INDIRECT_BUFFER.
            ("dispatch indirect", |a, b| unsafe {
                (a.bind_buffer)(0x90EE, b)
            }),
        ],
    });
}

/// A sampler bound on the unit the recipe samples its background on, deleted through a shared
/// context.
#[test]
fn a_sampler_deleted_through_a_shared_context_passes_the_frame_through() {
    deleted_elsewhere_passes_frames_through(DeletedElsewhere {
        what: "a sampler the app has bound is deleted",
        make: |a| {
            let mut s = 0;
            // SAFETY: the context is current on this thread.
            unsafe { (a.create_samplers)(1, &mut s) };
            s
        },
        // SAFETY: deleting a name is always valid.
        delete: |a, s| unsafe { (a.delete_samplers)(1, &s) },
        // SAFETY: a sampler or 0 bound to unit 5.
        bindings: &[("unit 5", |a, s| unsafe { (a.bind_sampler)(5, s) })],
    });
}

/// Transform feedback active (begun and not paused) at the call: glUseProgram is an error then,
/// so the recipe could neither make its programs current nor the app's again. The frame passes
/// through untouched with transform feedback still active; paused, the frame is enhanced and
/// the app finds it paused, its program current.
#[test]
fn active_transform_feedback_passes_the_frame_through() {
    const TRANSFORM_FEEDBACK_ACTIVE: u32 = 0x8E24;
    const TRANSFORM_FEEDBACK_PAUSED: u32 = 0x8E23;
    let mut gl = context();
    let a = app_gl(&gl);
    let params = Params::default();
    let (view, _) = built_srgb_view(&mut gl, (13, 14), &params);
    let texels = gl
        .read_texture(view.texture, SRGB8_ALPHA8, (40, 24))
        .unwrap();
    let source = c"#version 450
layout(xfb_buffer = 0, xfb_offset = 0) out float written;
void main() { written = 1.0; }
";
    // SAFETY: the context is current on this thread; a vertex program capturing one float into
    // a buffer bound at transform feedback index 0, current when transform feedback begins
    // (GL_POINTS).
    unsafe {
        let program = (a.create_shader_programv)(0x8B31, 1, &source.as_ptr());
        let mut buffer = 0;
        (a.gen)(1, &mut buffer);
        (a.named_buffer_data)(buffer, 1024, std::ptr::null(), 0x88E8);
        (a.bind_buffer_base)(0x8C8E, 0, buffer);
        (a.use_program)(program);
        (a.begin_transform_feedback)(0);
        assert_eq!((a.get_error)(), 0, "the test's own set-up raised an error");
    }
    let state = |q| {
        let mut v = 0;
        // SAFETY: a single-valued query into a valid i32.
        unsafe { (a.get_integerv)(q, &mut v) };
        v
    };
    let what = ("transform feedback is active", "transform feedback");
    refused_untouched(&mut gl, &a, (view, &texels), what);
    assert_eq!(state(TRANSFORM_FEEDBACK_ACTIVE), 1, "no longer active");
    // SAFETY: transform feedback is active and not paused.
    unsafe { (a.pause_transform_feedback)() };
    enhanced_again(&mut gl, &a, view, "transform feedback paused");
    assert_eq!(
        (
            state(TRANSFORM_FEEDBACK_ACTIVE),
            state(TRANSFORM_FEEDBACK_PAUSED)
        ),
        (1, 1),
        "transform feedback is no longer active and paused"
    );
    // SAFETY: transform feedback is paused; then active again, and ended.
    unsafe {
        (a.resume_transform_feedback)();
        (a.end_transform_feedback)();
        assert_eq!(
            (a.get_error)(),
            0,
            "the app's transform feedback was disturbed"
        );
    }
}

/// In a compatibility-profile context the app's pixel-transfer state (a red scale, a green bias
/// and the colour maps on, whose default maps send every component to 0) would apply to the
/// texels the buffer path writes back with glTextureSubImage: the call sets it neutral and puts
/// it back, so every format's enhanced texels are those of a context with none, and the app
/// finds its own values after the call, with no error raised; in place too (where the texture
/// is checked without GL_TEXTURE_TARGET, which Mesa refuses in such a context).
#[test]
fn a_compatibility_contexts_pixel_transfer_does_not_alter_the_written_texels() {
    const RED_SCALE: u32 = 0x0D14;
    const GREEN_BIAS: u32 = 0x0D19;
    const MAP_COLOR: u32 = 0x0D10;
    let apps = [(RED_SCALE, 0.5f32), (GREEN_BIAS, 0.25), (MAP_COLOR, 1.0)];
    let neutral = [(RED_SCALE, 1.0f32), (GREEN_BIAS, 0.0), (MAP_COLOR, 0.0)];
    let mut gl = GlOffline::compatibility().unwrap_or_else(|e| panic!("OpenGL context: {e}"));
    assert!(gl.engine().caps().compatibility, "{:?}", gl.engine().caps());
    let a = app_gl(&gl);
    let params = Params::default();
    gl.set_camera(&noise(40, 30, 5), &params).unwrap();
    let (w, h) = (33u32, 19u32);
    let set = |values: &[(u32, f32)]| {
        for &(p, v) in values {
            // SAFETY: the context is current on this thread; a pixel-transfer parameter.
            unsafe { (a.pixel_transferf)(p, v) };
        }
    };
    let formats = [RGBA8, SRGB8_ALPHA8, RGBA16F, RGBA16, RGB10_A2];
    for (internal, in_place) in formats.into_iter().flat_map(|f| [(f, false), (f, true)]) {
        gl.engine().set_in_place(in_place);
        let format = GlFormat::of(internal).unwrap();
        let texels: Vec<u8> = noise(w, h, 9)
            .pixels
            .into_iter()
            .flat_map(|p| encode(format, p))
            .flat_map(u32::to_le_bytes)
            .collect();
        let mut outputs = Vec::new();
        for with_state in [false, true] {
            let texture = gl.create_texture(internal, (w, h), &texels).unwrap();
            if with_state {
                set(&apps);
            }
            let view = GlView {
                texture,
                target: GlTarget::Texture2D,
                internal_format: internal,
                rect: (0, 0, w, h),
                mapping: params.camera_mapping(),
                pixels_per_degree: DEFAULT_PIXELS_PER_DEGREE,
            };
            gl.enhance_views(&[view], &params).unwrap();
            if with_state {
                for (p, v) in apps {
                    let mut got = 0.0f32;
                    // SAFETY: a single-valued query into a valid f32.
                    unsafe { (a.get_floatv)(p, &mut got) };
                    assert_eq!(got, v, "{internal:#x}: the app's {p:#x} was not put back");
                }
                // SAFETY: glGetError takes no arguments.
                assert_eq!(unsafe { (a.get_error)() }, 0, "{internal:#x}: an error");
                set(&neutral);
            }
            outputs.push(gl.read_texture(texture, internal, (w, h)).unwrap());
            gl.delete_texture(texture);
        }
        assert_ne!(outputs[0], texels, "{internal:#x}: nothing changed");
        assert!(
            outputs[1] == outputs[0],
            "{internal:#x}: the app's pixel transfer altered the written texels"
        );
    }
}

/// An engine tells its own context from another current in its place, even where the other's
/// objects have the same names (each context's first framebuffer is 1): only then may the layer
/// delete the objects of a session that ended while the context was current elsewhere.
#[test]
fn an_engine_knows_its_own_context() {
    let mut first = context();
    // SAFETY: the first context is current on this thread.
    assert!(unsafe { first.engine().made_in_current_context() });
    let mut second = context();
    // SAFETY: a context of the same driver (the second) is current on this thread.
    unsafe {
        assert!(!first.engine().made_in_current_context());
        assert!(second.engine().made_in_current_context());
    }
}

/// The driver's debug messages about the engine's own work (building and linking its programs,
/// making its buffers and textures, uploading the background, the passes) do not reach the
/// app's debug callback: with the app's debug output on and a callback set, a first frame with
/// new programs, a background and a view sends it none, also with a message the driver sends
/// while the recipe runs (fault point `gl-driver-message`; Mesa's llvmpipe sends none of its
/// own here), and the app's debug output is still on after the call; the app's own message
/// still reaches it.
#[test]
fn the_engines_work_sends_the_apps_debug_callback_nothing() {
    // A cache folder of its own (the program binaries' and Mesa's), so that the programs are
    // compiled, and their logs made, in the call.
    let cache = std::env::temp_dir().join(format!("contrastxr-debug-{}", std::process::id()));
    let env = [
        ("XDG_CACHE_HOME", cache.as_os_str()),
        ("CONTRASTXR_FAULT", OsStr::new("gl-driver-message")),
    ];
    run_child("debug_output_child", &env);
    let _ = std::fs::remove_dir_all(&cache);
}

/// Run by `the_engines_work_sends_the_apps_debug_callback_nothing` with an empty cache folder.
#[test]
#[ignore = "run by the_engines_work_sends_the_apps_debug_callback_nothing"]
fn debug_output_child() {
    use std::sync::atomic::{AtomicUsize, Ordering};
    use std::sync::Mutex;
    static COUNT: AtomicUsize = AtomicUsize::new(0);
    static TEXTS: Mutex<Vec<String>> = Mutex::new(Vec::new());
    extern "system" fn callback(
        _: u32,
        _: u32,
        _: u32,
        _: u32,
        length: i32,
        message: *const std::ffi::c_char,
        _: *const c_void,
    ) {
        COUNT.fetch_add(1, Ordering::Relaxed);
        // SAFETY: GL passes the message's text and its length.
        let text = unsafe { std::slice::from_raw_parts(message.cast::<u8>(), length as usize) };
        TEXTS
            .lock()
            .unwrap()
            .push(String::from_utf8_lossy(text).into_owned());
    }
    type Callback =
        extern "system" fn(u32, u32, u32, u32, i32, *const std::ffi::c_char, *const c_void);
    type SetCallback = unsafe extern "system" fn(Callback, *const c_void);
    type Insert = unsafe extern "system" fn(u32, u32, u32, u32, i32, *const std::ffi::c_char);
    const DEBUG_OUTPUT: u32 = 0x92E0;
    const DEBUG_OUTPUT_SYNCHRONOUS: u32 = 0x8242;
    let mut gl = context();
    let a = app_gl(&gl);
    // SAFETY: the functions of these names have these C types.
    let (set_callback, insert) = unsafe {
        (
            std::mem::transmute::<*const c_void, SetCallback>(load(&gl, c"glDebugMessageCallback")),
            std::mem::transmute::<*const c_void, Insert>(load(&gl, c"glDebugMessageInsert")),
        )
    };
    let params = Params::default();
    let (w, h) = (40u32, 24u32);
    let texels: Vec<u8> = noise(w, h, 3).pixels.into_iter().flatten().collect();
    let texture = gl.create_texture(SRGB8_ALPHA8, (w, h), &texels).unwrap();
    // SAFETY: the context is current on this thread; a callback of GL's type.
    unsafe {
        set_callback(callback, std::ptr::null());
        (a.enable)(DEBUG_OUTPUT);
        (a.enable)(DEBUG_OUTPUT_SYNCHRONOUS);
    }
    gl.set_camera(&noise(30, 20, 4), &params).unwrap();
    let view = GlView {
        texture,
        target: GlTarget::Texture2D,
        internal_format: SRGB8_ALPHA8,
        rect: (0, 0, w, h),
        mapping: params.camera_mapping(),
        pixels_per_degree: DEFAULT_PIXELS_PER_DEGREE,
    };
    gl.enhance_views(&[view], &params).unwrap();
    let during = COUNT.load(Ordering::Relaxed);
    let texts = TEXTS.lock().unwrap().clone();
    // SAFETY: as above: the app's own message (GL_DEBUG_SOURCE_APPLICATION, TYPE_MARKER,
    // SEVERITY_NOTIFICATION), which must still arrive.
    unsafe {
        assert_ne!(
            (a.is_enabled)(DEBUG_OUTPUT),
            0,
            "the app's debug output was left off"
        );
        insert(0x824A, 0x8268, 1, 0x826B, -1, c"the app's".as_ptr());
    }
    let after = COUNT.load(Ordering::Relaxed);
    gl.delete_texture(texture);
    assert_eq!(
        during, 0,
        "the engine's work sent the app's callback: {texts:?}"
    );
    assert_eq!(after, 1, "the app's own message did not arrive");
}

/// The perceptual method's model, uploaded into a view's buffer only when it changes, follows
/// every change of the settings: frames alternating between two world luminances (and one
/// repeated) on one engine each give what a new engine gives.
#[test]
fn the_perceptual_model_follows_each_change_of_the_settings() {
    let at = |world: f64| {
        let mut p = Params {
            method: contrastxr::algorithm::Method::Perceptual,
            ..Params::default()
        };
        p.perceptual.world_nits = world;
        p
    };
    let (office, outdoors) = (at(500.0), at(5000.0));
    // The same view and camera each time (built_srgb_view's seeds), enhanced by `gl`.
    let frame = |gl: &mut GlOffline, params: &Params| {
        let (view, _) = built_srgb_view(gl, (41, 42), params);
        gl.read_texture(view.texture, SRGB8_ALPHA8, (40, 24))
            .unwrap()
    };
    let want_office = frame(&mut context(), &office);
    let want_outdoors = frame(&mut context(), &outdoors);
    assert_ne!(
        want_office, want_outdoors,
        "the two settings give one output"
    );
    let mut gl = context();
    for (n, params) in [&office, &outdoors, &outdoors, &office, &outdoors]
        .into_iter()
        .enumerate()
    {
        let want = match params.perceptual.world_nits == 500.0 {
            true => &want_office,
            false => &want_outdoors,
        };
        assert!(
            frame(&mut gl, params) == *want,
            "frame {n}: {} cd/m²",
            params.perceptual.world_nits
        );
    }
}
