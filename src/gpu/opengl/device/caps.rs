//! What the current context offers the backend, read with GL 1.x/3.x queries only (no call
//! that could raise an error on an older context), before anything else runs.

use super::error::GlError;
use super::functions::{self as gl, Gl};
use std::ffi::CStr;

/// The context's version and the extensions the backend looks for.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Caps {
    pub version: (i32, i32),
    /// GL_KHR_parallel_shader_compile (or the ARB one): compile and link without blocking.
    pub parallel_compile: bool,
    /// glGetProgramBinary gives something (at least one binary format).
    pub program_binaries: bool,
    /// The binary formats glProgramBinary takes (GL_PROGRAM_BINARY_FORMATS): a cached binary
    /// of another format is not handed to it.
    pub binary_formats: Vec<u32>,
    /// GL_VENDOR, GL_RENDERER and GL_VERSION without its profile ("(Core Profile)"), which
    /// name the program binaries' cache file: a core context's binaries serve a
    /// compatibility-profile context of the same driver.
    pub driver: String,
    /// A driver that renders on the CPU (llvmpipe, softpipe): there a buffer copy is a memcpy
    /// and image load/store costs more than it saves, so views go through a buffer by default.
    pub software: bool,
    /// A compatibility-profile context: its pixel-transfer state (glPixelTransfer) applies to
    /// the backend's transfers of non-integer texels, so the state guard neutralises it.
    pub compatibility: bool,
    /// GL_ARB_imaging in a compatibility-profile context: colour tables, convolution,
    /// histogram, minmax and the colour matrix apply to those transfers too.
    pub imaging: bool,
}

/// GL_VERSION without the context's profile.
fn without_profile(version: &str) -> String {
    version
        .replace(" (Core Profile)", "")
        .replace(" (Compatibility Profile)", "")
}

/// Whether two "vendor | renderer | version" strings name the same driver: a context's
/// profile (core or compatibility) is no part of it.
pub fn same_driver(a: &str, b: &str) -> bool {
    without_profile(a) == without_profile(b)
}

/// Whether GL_RENDERER names a driver that renders on the CPU.
fn is_software(renderer: &str) -> bool {
    ["llvmpipe", "softpipe", "swrast", "Software Rasterizer"]
        .iter()
        .any(|name| renderer.contains(name))
}

fn text(gl: &Gl, name: gl::Enum) -> String {
    // SAFETY: glGetString is GL 1.0, valid with any current context; a non-null result is a
    // static NUL-terminated string.
    let p = unsafe { (gl.get_string)(name) };
    if p.is_null() {
        return String::new();
    }
    // SAFETY: see above.
    unsafe { CStr::from_ptr(p.cast()) }
        .to_string_lossy()
        .into_owned()
}

/// "4.5 (Core Profile) Mesa ..." -> (4, 5); also "OpenGL ES 3.2 ...".
fn parse_version(v: &str) -> Option<(i32, i32)> {
    let digits = v.trim_start_matches(|c: char| !c.is_ascii_digit());
    let mut parts = digits.split(|c: char| !c.is_ascii_digit());
    Some((parts.next()?.parse().ok()?, parts.next()?.parse().ok()?))
}

/// The context's program binary formats (GL 4.1 queries; the context is 4.5 by then).
fn binary_formats(gl: &Gl) -> Vec<u32> {
    let mut count = 0;
    // SAFETY: a query of one value into a valid i32.
    unsafe { (gl.get_integerv)(gl::NUM_PROGRAM_BINARY_FORMATS, &mut count) };
    let mut formats = vec![0; count.max(0) as usize];
    if !formats.is_empty() {
        // SAFETY: GL writes GL_NUM_PROGRAM_BINARY_FORMATS values, the vector's length.
        unsafe { (gl.get_integerv)(gl::PROGRAM_BINARY_FORMATS, formats.as_mut_ptr()) };
    }
    formats.into_iter().map(|f| f as u32).collect()
}

impl Caps {
    /// The current context's caps, or why the backend cannot run on it: OpenGL ES, a version
    /// before 4.3 (no compute shaders) or before 4.5 (GLSL 4.50, direct state access,
    /// glGetTextureSubImage).
    pub fn check(gl: &Gl) -> Result<Caps, GlError> {
        let version_text = text(gl, gl::VERSION);
        if version_text.is_empty() {
            return Err(GlError::Unsupported("no OpenGL context is current".into()));
        }
        if version_text.starts_with("OpenGL ES") {
            return Err(GlError::Unsupported(format!(
                "the context is OpenGL ES ({version_text}), not desktop OpenGL"
            )));
        }
        let mut version = parse_version(&version_text).unwrap_or((0, 0));
        if crate::fault::hit("gl-old-context") {
            version = (3, 3);
        }
        if version < (4, 3) {
            return Err(GlError::Unsupported(format!(
                "the context is OpenGL {}.{}, older than 4.3 (no compute shaders)",
                version.0, version.1
            )));
        }
        // The programs are GLSL 4.50 (build.rs), and the recipe uses 4.5's direct state access
        // and glGetTextureSubImage.
        if version < (4, 5) {
            return Err(GlError::Unsupported(format!(
                "the context is OpenGL {}.{}, older than 4.5 (the layer's programs are GLSL 4.50)",
                version.0, version.1
            )));
        }
        let mut count = 0;
        // SAFETY: GL 3.0 query into a valid i32 (the context is 4.5 or later).
        unsafe { (gl.get_integerv)(gl::NUM_EXTENSIONS, &mut count) };
        let extensions: Vec<String> = (0..count.max(0) as u32)
            .filter_map(|i| {
                // SAFETY: i < GL_NUM_EXTENSIONS; a non-null result is a static string.
                let p = unsafe { (gl.get_stringi)(gl::EXTENSIONS, i) };
                (!p.is_null()).then(|| {
                    // SAFETY: non-null: a static NUL-terminated string (see above).
                    unsafe { CStr::from_ptr(p.cast()) }
                        .to_string_lossy()
                        .into_owned()
                })
            })
            .collect();
        let has = |name: &str| extensions.iter().any(|e| e == name);
        let binary_formats = binary_formats(gl);
        let renderer = text(gl, gl::RENDERER);
        let mut profile = 0;
        // SAFETY: GL 3.2 query into a valid i32.
        unsafe { (gl.get_integerv)(gl::CONTEXT_PROFILE_MASK, &mut profile) };
        let compatibility = profile & gl::CONTEXT_COMPATIBILITY_PROFILE_BIT != 0;
        if compatibility && gl.pixel_transferf.is_none() {
            return Err(GlError::Unsupported(
                "a compatibility-profile context without glPixelTransferf".into(),
            ));
        }
        let imaging = compatibility && has("GL_ARB_imaging");
        if imaging && (gl.matrix_mode.is_none() || gl.load_matrixf.is_none()) {
            return Err(GlError::Unsupported(
                "GL_ARB_imaging without glMatrixMode or glLoadMatrixf".into(),
            ));
        }
        Ok(Caps {
            compatibility,
            imaging,
            version,
            software: is_software(&renderer),
            parallel_compile: has("GL_KHR_parallel_shader_compile")
                || has("GL_ARB_parallel_shader_compile"),
            program_binaries: !binary_formats.is_empty(),
            binary_formats,
            driver: format!(
                "{} | {renderer} | {}",
                text(gl, gl::VENDOR),
                without_profile(&version_text)
            ),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::{is_software, parse_version, same_driver};

    #[test]
    fn a_profile_is_no_part_of_the_driver() {
        let core = "Mesa | llvmpipe (LLVM 19.1.7, 256 bits) | 4.5 (Core Profile) Mesa 25.0.7";
        let compat = core.replace("Core", "Compatibility");
        assert!(same_driver(core, &compat));
        assert!(!same_driver(core, &core.replace("25.0.7", "25.0.8")));
        assert!(!same_driver(
            core,
            "NVIDIA Corporation | NVIDIA H200 | 4.6.0 NVIDIA 580"
        ));
    }

    #[test]
    fn cpu_drivers_are_told_from_gpus() {
        assert!(is_software("llvmpipe (LLVM 19.1.7, 256 bits)"));
        assert!(is_software("softpipe"));
        assert!(!is_software("NVIDIA H200/PCIe/SSE2"));
        assert!(!is_software(
            "AMD Radeon RX 7900 XTX (radeonsi, navi31, LLVM 19.1.7)"
        ));
    }

    #[test]
    fn versions_are_read_from_the_version_string() {
        assert_eq!(
            parse_version("4.5 (Core Profile) Mesa 22.3.6"),
            Some((4, 5))
        );
        assert_eq!(parse_version("4.6.0 NVIDIA 550.54"), Some((4, 6)));
        assert_eq!(parse_version("OpenGL ES 3.2 Mesa"), Some((3, 2)));
        assert_eq!(parse_version("garbage"), None);
    }
}
