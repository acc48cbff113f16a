//! The backend's compute programs: the GLSL build.rs wrote from the shaders (a program id is an
//! index into `GL_MODULES`), built without blocking a frame call and kept as binaries.
//!
//! A frame call asks for the programs its views need (`Programs::ready`); those not ready are
//! started or advanced, and the frame passes through until all are. With
//! GL_KHR_parallel_shader_compile the driver may compile and link on its own threads: the call
//! then only polls GL_COMPLETION_STATUS, and starts further builds while starting them stays
//! cheap (START_SLICE). A driver without it, or one that builds inside the calls anyway, builds
//! one program per call: the work is sliced across frames. A linked program's binary (glGetProgramBinary) goes into the
//! binary cache (binary_cache.rs), from which a later process links it without compiling.

use super::binary_cache::{BinaryCache, ProgramBinaries};
use crate::gpu::core::modules::VariantRow;
use crate::gpu::core::plan::ClassifyCover;
use crate::gpu::core::push_constants::PushConstants;
use crate::gpu::core::shader_ids;
use crate::gpu::core::VariantKey;
use crate::gpu::opengl::device::caps::Caps;
use crate::gpu::opengl::device::functions::{self as gl, Gl};
use crate::gpu::opengl::device::GlError;
use std::ffi::CString;
use std::time::{Duration, Instant};

/// How long one call may spend starting builds before it leaves the rest to the next calls:
/// a driver that compiles inside glCompileShader / glLinkProgram (llvmpipe does, although it
/// offers GL_KHR_parallel_shader_compile) then builds one program per call.
const START_SLICE: Duration = Duration::from_millis(2);

/// What one call has started so far.
struct Budget {
    since: Instant,
    started: u32,
    /// Whether builds may start at all (else only cached binaries are linked).
    build: bool,
}

impl Budget {
    /// Whether another build may start in this call: the first always; more only with
    /// parallel compilation and while starting them has stayed within START_SLICE.
    fn may_start(&self, parallel: bool) -> bool {
        self.build && (self.started == 0 || (parallel && self.since.elapsed() < START_SLICE))
    }
}

/// How a Params uniform is set (naga's GLSL type for the PARAMS field).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GlParam {
    U32,
    F32,
    UVec2,
    Vec4,
}

include!(concat!(env!("OUT_DIR"), "/gl_shader_table.rs"));

/// One id of every program source of this build: `contrastxr gl-programs --sources ID`
/// refuses to fill the caches for a layer whose sources differ.
pub fn gl_sources_id() -> u64 {
    GL_MODULE_HASHES
        .iter()
        .fold(0, |id, &hash| id.rotate_left(7) ^ hash)
}

/// A linked program and its Params uniforms' locations (GL_PARAMS order; -1 for a uniform
/// the program does not use, which glProgramUniform ignores).
pub struct Program {
    pub raw: u32,
    locations: Vec<i32>,
}

enum Slot {
    NotStarted,
    Compiling { shader: u32, program: u32 },
    Linking { program: u32 },
    Ready(Program),
    Failed(GlError),
}

pub struct Programs {
    slots: Vec<Slot>,
    parallel: bool,
    cache: BinaryCache,
    /// The binary formats the context takes (Caps::binary_formats).
    binary_formats: Vec<u32>,
}

fn info_log(g: &Gl, object: u32, program: bool) -> String {
    let mut buf = vec![0i8; 1024];
    let mut len = 0;
    // SAFETY: `object` is a live shader or program of this context; the buffer holds 1024
    // bytes and GL writes at most that many, NUL included.
    unsafe {
        if program {
            (g.get_program_info_log)(object, 1024, &mut len, buf.as_mut_ptr());
        } else {
            (g.get_shader_info_log)(object, 1024, &mut len, buf.as_mut_ptr());
        }
    }
    let bytes: Vec<u8> = buf[..len.clamp(0, 1024) as usize]
        .iter()
        .map(|&c| c as u8)
        .collect();
    let text = String::from_utf8_lossy(&bytes);
    let line = text
        .lines()
        .find(|l| !l.trim().is_empty())
        .unwrap_or("no log");
    line.trim().to_string()
}

fn status(g: &Gl, object: u32, pname: gl::Enum, program: bool) -> bool {
    let mut v = 0;
    // SAFETY: a live shader or program of this context, a valid pname, a valid output.
    unsafe {
        if program {
            (g.get_programiv)(object, pname, &mut v);
        } else {
            (g.get_shaderiv)(object, pname, &mut v);
        }
    }
    v != 0
}

impl Programs {
    pub fn new(caps: &Caps) -> Programs {
        Programs {
            slots: GL_MODULES.iter().map(|_| Slot::NotStarted).collect(),
            parallel: caps.parallel_compile,
            cache: BinaryCache::load(&caps.driver, caps.program_binaries),
            binary_formats: caps.binary_formats.clone(),
        }
    }

    /// Whether every program of `ids` is linked, advancing those that are not (see the module
    /// doc: without parallel compilation at most one is built per call). The first that
    /// failed is the error.
    pub fn ready(&mut self, g: &Gl, ids: &[usize]) -> Result<bool, GlError> {
        self.advance_all(g, ids, true)
    }

    /// Whether every program of `ids` is linked, linking those the binary cache holds and
    /// starting no build.
    pub fn ready_from_cache(&mut self, g: &Gl, ids: &[usize]) -> Result<bool, GlError> {
        self.advance_all(g, ids, false)
    }

    fn advance_all(&mut self, g: &Gl, ids: &[usize], build: bool) -> Result<bool, GlError> {
        let mut budget = Budget {
            since: Instant::now(),
            started: 0,
            build,
        };
        let mut all = true;
        for &id in ids {
            self.advance(g, id, &mut budget);
            match &self.slots[id] {
                Slot::Ready(_) => {}
                Slot::Failed(e) => return Err(e.clone()),
                _ => all = false,
            }
        }
        Ok(all)
    }

    /// A program `ready` reported linked.
    pub fn get(&self, id: usize) -> &Program {
        match &self.slots[id] {
            Slot::Ready(p) => p,
            _ => panic!("program {id} used before it was ready"),
        }
    }

    fn advance(&mut self, g: &Gl, id: usize, budget: &mut Budget) {
        let (name, source) = GL_MODULES[id];
        let fail = |log: String| {
            Slot::Failed(GlError::Program {
                name: name.to_string(),
                log,
            })
        };
        loop {
            let next = match &self.slots[id] {
                Slot::Ready(_) | Slot::Failed(_) => return,
                Slot::NotStarted => {
                    if let Some(p) = self.link_cached(g, id) {
                        self.slots[id] = Slot::Ready(p);
                        return;
                    }
                    if !budget.may_start(self.parallel) {
                        return;
                    }
                    budget.started += 1;
                    self.start(g, source)
                }
                &Slot::Compiling { shader, program } => {
                    if self.parallel && !status(g, shader, gl::COMPLETION_STATUS, false) {
                        return;
                    }
                    if !status(g, shader, gl::COMPILE_STATUS, false) {
                        let log = info_log(g, shader, false);
                        // SAFETY: both objects are ours and no longer used.
                        unsafe {
                            (g.delete_shader)(shader);
                            (g.delete_program)(program);
                        }
                        fail(log)
                    } else {
                        // The fault point links a second copy of the shader with it: two
                        // `main`s, the driver's own link failure in any profile, as a broken
                        // program would give it.
                        let twin = crate::fault::hit("gl-program-link").then(|| {
                            let Slot::Compiling { shader, program } = self.start(g, source) else {
                                unreachable!("start gives a compiling slot")
                            };
                            // SAFETY: the spare program is ours and unused.
                            unsafe { (g.delete_program)(program) };
                            shader
                        });
                        // SAFETY: shader, twin and program are ours; each is attached once.
                        unsafe {
                            (g.attach_shader)(program, shader);
                            if let Some(twin) = twin {
                                (g.attach_shader)(program, twin);
                            }
                            (g.link_program)(program);
                            (g.detach_shader)(program, shader);
                            (g.delete_shader)(shader);
                            if let Some(twin) = twin {
                                (g.detach_shader)(program, twin);
                                (g.delete_shader)(twin);
                            }
                        }
                        Slot::Linking { program }
                    }
                }
                &Slot::Linking { program } => {
                    if self.parallel && !status(g, program, gl::COMPLETION_STATUS, true) {
                        return;
                    }
                    if !status(g, program, gl::LINK_STATUS, true) {
                        let log = info_log(g, program, true);
                        // SAFETY: the program is ours and unused.
                        unsafe { (g.delete_program)(program) };
                        fail(log)
                    } else {
                        self.cache.store(g, program, GL_MODULE_HASHES[id]);
                        Slot::Ready(Program {
                            raw: program,
                            locations: locations(g, program),
                        })
                    }
                }
            };
            self.slots[id] = next;
        }
    }

    /// Starts compiling `source` (non-blocking with parallel compilation).
    fn start(&self, g: &Gl, source: &str) -> Slot {
        let text = CString::new(source).expect("GLSL without NUL");
        let ptr = text.as_ptr();
        // SAFETY: COMPUTE_SHADER is valid on 4.3; the source pointer is a NUL-terminated
        // string alive for the call (a null length array means NUL-terminated); the program
        // hint is a valid pname for a new program.
        unsafe {
            let shader = (g.create_shader)(gl::COMPUTE_SHADER);
            (g.shader_source)(shader, 1, &ptr, std::ptr::null());
            (g.compile_shader)(shader);
            let program = (g.create_program)();
            (g.program_parameteri)(program, gl::PROGRAM_BINARY_RETRIEVABLE_HINT, 1);
            Slot::Compiling { shader, program }
        }
    }

    /// The program linked from a cached binary, if there is one the driver takes.
    fn link_cached(&mut self, g: &Gl, id: usize) -> Option<Program> {
        let hash = GL_MODULE_HASHES[id];
        let (format, bytes) = self.cache.get(hash)?;
        if !self.binary_formats.contains(&format) {
            // glProgramBinary raises GL_INVALID_ENUM into the app's flag for a format the
            // context does not list: the program is built from source, as for a refused one.
            self.cache.forget(hash);
            return None;
        }
        // SAFETY: a new program; the binary's bytes and length are the cached entry's, in a
        // format the context lists (a binary the driver refuses leaves LINK_STATUS false, it
        // raises no error).
        let program = unsafe {
            let program = (g.create_program)();
            (g.program_binary)(program, format, bytes.as_ptr().cast(), bytes.len() as i32);
            program
        };
        if status(g, program, gl::LINK_STATUS, true) {
            return Some(Program {
                raw: program,
                locations: locations(g, program),
            });
        }
        // SAFETY: ours, unused.
        unsafe { (g.delete_program)(program) };
        self.cache.forget(hash);
        None
    }

    /// Takes in the binaries another process wrote to the cache's file since it was read.
    pub fn reload_cache(&mut self) {
        self.cache.reload();
    }

    /// The binaries the cache holds of the programs `ids`.
    pub fn binaries(&self, ids: &[usize]) -> ProgramBinaries {
        let hashes = ids.iter().map(|&id| GL_MODULE_HASHES[id]);
        self.cache.binaries(hashes)
    }

    /// Takes in binaries another engine of the driver built, where the cache has none.
    pub fn take_binaries(&mut self, binaries: ProgramBinaries) {
        self.cache.take_in(binaries);
    }

    /// Writes the binary cache's file where programs were added (see binary_cache.rs).
    pub fn save_cache(&mut self) {
        self.cache.save(GL_MODULE_HASHES.iter().copied().collect());
    }

    /// Deletes every program (the context current).
    pub fn destroy(&mut self, g: &Gl) {
        for slot in self.slots.iter_mut() {
            // SAFETY: the objects are ours; deleting a shader or program is always valid.
            unsafe {
                match *slot {
                    Slot::Compiling { shader, program } => {
                        (g.delete_shader)(shader);
                        (g.delete_program)(program);
                    }
                    Slot::Linking { program } => (g.delete_program)(program),
                    Slot::Ready(ref p) => (g.delete_program)(p.raw),
                    _ => {}
                }
            }
            *slot = Slot::NotStarted;
        }
    }
}

fn locations(g: &Gl, program: u32) -> Vec<i32> {
    GL_PARAMS
        .iter()
        .map(|(path, _, _)| {
            let name = CString::new(*path).expect("a uniform name without NUL");
            // SAFETY: a linked program and a NUL-terminated name.
            unsafe { (g.get_uniform_location)(program, name.as_ptr()) }
        })
        .collect()
}

impl Program {
    /// Sets its Params uniforms from the push-constant block (PARAMS layout).
    pub fn set_params(&self, g: &Gl, push: &PushConstants) {
        let bytes = push.bytes();
        let word = |at: u32| {
            let at = at as usize;
            u32::from_le_bytes(bytes[at..at + 4].try_into().expect("4 bytes"))
        };
        let float = |at: u32| f32::from_bits(word(at));
        for (&(_, offset, kind), &location) in GL_PARAMS.iter().zip(&self.locations) {
            if location < 0 {
                continue;
            }
            let (p, l, o) = (self.raw, location, offset);
            // SAFETY: a linked program, a location it gave, and the uniform's own type (checked
            // by build.rs against naga's reflection).
            unsafe {
                match kind {
                    GlParam::U32 => (g.program_uniform1ui)(p, l, word(o)),
                    GlParam::F32 => (g.program_uniform1f)(p, l, float(o)),
                    GlParam::UVec2 => (g.program_uniform2ui)(p, l, word(o), word(o + 4)),
                    GlParam::Vec4 => (g.program_uniform4f)(
                        p,
                        l,
                        float(o),
                        float(o + 4),
                        float(o + 8),
                        float(o + 12),
                    ),
                }
            }
        }
    }
}

/// The `classify` program of a FORMAT code, access, the method code it lists tiles for and its
/// cover (`VariantKey::classify_taken`); None where none is built.
pub fn classify(format: u32, access: u32, (method, cover): (u32, ClassifyCover)) -> Option<usize> {
    let rows = cover == ClassifyCover::TileRows;
    GL_CLASSIFY_VARIANTS
        .iter()
        .find(|&&(f, a, m, r, _)| (f, a, m, r) == (format, access, method, rows))
        .map(|&(.., id)| id)
}

/// The benchmark's ablated `enhance` program of a method (its code), access, ablations
/// (interface.rs ABLATE_*) and cube roots (by pow or not): the paper's or the perceptual method
/// in mode enhance on RGBA8 sRGB; None for the others.
pub fn enhance_ablated(method: u32, access: u32, ablate: u32, pow: bool) -> Option<usize> {
    GL_ENHANCE_ABLATED
        .iter()
        .find(|&&(m, a, x, p, _)| (m, a, x, p) == (method, access, ablate, pow))
        .map(|&(.., id)| id)
}

/// The `enhance` program of a view's variant (`key`; the general sampling: OpenGL has no
/// shared fetches), with the cube roots the key asks for where built.
pub fn enhance(key: VariantKey) -> Option<usize> {
    shader_ids::variant_of(GL_ENHANCE_VARIANTS, key, false)
}

#[cfg(test)]
mod tests {
    use super::super::binary_cache::source_hash;
    use super::*;
    use crate::gpu::opengl::GlOffline;

    /// The hashes build.rs wrote are each module's `source_hash`, as the cache's file keys
    /// them (a program's binary is found under its source's hash, in any build).
    #[test]
    fn the_built_hashes_are_the_sources_hashes() {
        assert_eq!(GL_MODULE_HASHES.len(), GL_MODULES.len());
        for (&(name, source), &hash) in GL_MODULES.iter().zip(GL_MODULE_HASHES) {
            assert_eq!(source_hash(source), hash, "{name}");
        }
    }

    /// glGetError of the offline context (EGL's loader; the engine itself never calls it).
    fn get_error() -> unsafe extern "C" fn() -> u32 {
        type GetProc = unsafe extern "C" fn(*const std::ffi::c_char) -> *mut std::ffi::c_void;
        // SAFETY: libEGL is loaded (the offline context's); dlsym and eglGetProcAddress only
        // look names up, and the addresses found have these C types.
        unsafe {
            let egl = libc::dlopen(c"libEGL.so.1".as_ptr(), libc::RTLD_NOW | libc::RTLD_NOLOAD);
            let get: GetProc = std::mem::transmute(libc::dlsym(egl, c"eglGetProcAddress".as_ptr()));
            std::mem::transmute(get(c"glGetError".as_ptr()))
        }
    }

    /// A cached binary in a format the context does not list is never handed to
    /// glProgramBinary (which would raise GL_INVALID_ENUM into the app's flag): it is
    /// forgotten and the program built from source.
    #[test]
    fn a_binary_of_a_format_the_context_lacks_is_not_loaded() {
        let _offline = GlOffline::new().expect("an OpenGL context");
        let g = Gl::from_process().unwrap();
        let caps = Caps::check(&g).unwrap();
        if !caps.program_binaries {
            println!("the driver gives no program binaries: nothing to test");
            return;
        }
        let mut programs = Programs::new(&caps);
        let format = (1..).find(|f| !caps.binary_formats.contains(f)).unwrap();
        let hash = GL_MODULE_HASHES[0];
        programs.cache.keep(hash, format, vec![1, 2, 3, 4]);
        assert!(programs.cache.get(hash).is_some());
        let error = get_error();
        // SAFETY: the offline context is current on this thread.
        assert_eq!(unsafe { error() }, 0, "an error before the test");
        assert!(programs.link_cached(&g, 0).is_none());
        // SAFETY: as above.
        assert_eq!(unsafe { error() }, 0, "loading the binary raised an error");
        assert!(programs.cache.get(hash).is_none(), "the binary was kept");
    }
}
