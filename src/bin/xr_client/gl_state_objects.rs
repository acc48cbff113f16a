//! The objects of `--check-gl-state`'s own ([`super::gl_state`]) whose names it binds: a
//! program, textures, samplers, buffers, framebuffers, pbuffers. Created once per run.

use crate::error::{fail, Result};
use crate::gl_binding::GlBinding;
use crate::gl_state_enums::*;
use crate::gl_state_fns::{Create, Fns};
use crate::glx::GlContext;

/// The objects whose names the check binds; created once, never deleted (the run is short).
pub struct Objects {
    pub program: u32,
    pub pipeline: u32,
    pub textures_2d: [u32; UNITS],
    pub textures_array: [u32; UNITS],
    pub samplers: [u32; UNITS],
    pub storage: [u32; UNITS],
    pub uniform: [u32; UNITS],
    pub generic: [u32; GENERIC_BUFFERS.len()],
    pub storage_alignment: i64,
    pub uniform_alignment: i64,
    /// Draw and read.
    pub framebuffers: [u32; 2],
    pub renderbuffer: u32,
    pub vertex_array: u32,
    /// Two pbuffers of the check's own: the draw and read drawables it makes current.
    pub draw: u64,
    pub read: u64,
}

/// Bytes of each buffer; the indexed ranges lie inside it at every offset alignment up to 256.
const BUFFER_BYTES: isize = 4096;

impl Objects {
    pub fn create(f: &Fns, gl: &GlContext) -> Result<Objects> {
        let program = program(f)?;
        let (textures_2d, textures_array) = textures(f);
        let buffers = buffers(f);
        let framebuffers = names(f.create_framebuffers, 2);
        let array = |v: &[u32]| -> [u32; UNITS] { v.try_into().expect("UNITS names") };
        let objects = Objects {
            program,
            pipeline: names(f.create_program_pipelines, 1)[0],
            textures_2d,
            textures_array,
            samplers: array(&names(f.create_samplers, UNITS)),
            storage: array(&buffers[..UNITS]),
            uniform: array(&buffers[UNITS..2 * UNITS]),
            generic: buffers[2 * UNITS..].try_into().expect("one per target"),
            storage_alignment: alignment(f, SHADER_STORAGE_BUFFER_OFFSET_ALIGNMENT),
            uniform_alignment: alignment(f, UNIFORM_BUFFER_OFFSET_ALIGNMENT),
            framebuffers: [framebuffers[0], framebuffers[1]],
            renderbuffer: names(f.create_renderbuffers, 1)[0],
            vertex_array: names(f.create_vertex_arrays, 1)[0],
            draw: pbuffer(gl)?,
            read: pbuffer(gl)?,
        };
        // The indexed ranges must lie inside BUFFER_BYTES.
        if objects.storage_alignment > 256 || objects.uniform_alignment > 256 {
            return fail("--check-gl-state: buffer offset alignments above 256");
        }
        Ok(objects)
    }

    /// Indexed range `i` of a buffer target: (offset, size).
    pub fn range(alignment: i64, i: usize) -> (i64, i64) {
        (alignment * (i as i64 + 1), 16 * (i as i64 + 1))
    }
}

/// Another 16x16 pbuffer on the context's configuration: a GLX pbuffer, or with EGL an
/// EGLSurface (as u64).
fn pbuffer(gl: &GlContext) -> Result<u64> {
    match gl.binding {
        GlBinding::Xlib => gl.glx_pbuffer(),
        GlBinding::Egl => crate::egl::pbuffer(gl),
    }
}

/// `n` new object names from a glCreate* function.
fn names(create: Create, n: usize) -> Vec<u32> {
    let mut v = vec![0u32; n];
    // SAFETY: room for n names.
    unsafe { create(n as i32, v.as_mut_ptr()) };
    v
}

/// An empty compute program, linked: a program name to bind.
fn program(f: &Fns) -> Result<u32> {
    let source = c"#version 430 core\nlayout(local_size_x = 1) in;\nvoid main() {}\n";
    let mut linked = 0;
    // SAFETY: one NUL-terminated source; the program is a name of this context.
    let program = unsafe {
        let program = (f.create_shader_program_v)(COMPUTE_SHADER, 1, &source.as_ptr());
        (f.get_program_iv)(program, LINK_STATUS, &mut linked);
        program
    };
    if program == 0 || linked == 0 {
        return fail("--check-gl-state: the compute program does not link");
    }
    Ok(program)
}

/// A 2D and a 2D array texture per unit, with storage: two levels of 4x4 (x2 layers) RGBA8,
/// so that an image unit can bind level 1, layer 1.
fn textures(f: &Fns) -> ([u32; UNITS], [u32; UNITS]) {
    let mut textures_2d = [0; UNITS];
    let mut textures_array = [0; UNITS];
    // SAFETY: room for UNITS names; storage on textures just created.
    unsafe {
        (f.create_textures)(TEXTURE_2D, UNITS as i32, textures_2d.as_mut_ptr());
        (f.create_textures)(TEXTURE_2D_ARRAY, UNITS as i32, textures_array.as_mut_ptr());
        for t in textures_2d {
            (f.texture_storage_2d)(t, 2, RGBA8, 4, 4);
        }
        for t in textures_array {
            (f.texture_storage_3d)(t, 2, RGBA8, 4, 4, 2);
        }
    }
    (textures_2d, textures_array)
}

/// The buffers: UNITS storage, UNITS uniform, then one per generic target, each with
/// BUFFER_BYTES of immutable storage.
fn buffers(f: &Fns) -> Vec<u32> {
    let buffers = names(f.create_buffers, 2 * UNITS + GENERIC_BUFFERS.len());
    for &b in &buffers {
        // SAFETY: a buffer just created, immutable storage with no data and no flags.
        unsafe { (f.named_buffer_storage)(b, BUFFER_BYTES, std::ptr::null(), 0) };
    }
    buffers
}

/// A buffer offset alignment (at least 1).
fn alignment(f: &Fns, pname: Enum) -> i64 {
    let mut v = 0;
    // SAFETY: a single-valued query.
    unsafe { (f.get_integer64v)(pname, &mut v) };
    v.max(1)
}
