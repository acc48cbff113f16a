//! Whether the library a manifest names loads as the OpenXR loader would load it, and exports
//! the negotiation function the loader calls first.

use super::finding::{tool, Finding};
use std::ffi::{CStr, CString, OsStr};
use std::os::unix::ffi::OsStrExt;
use std::path::{Path, PathBuf};

const NEGOTIATE: &CStr = c"xrNegotiateLoaderApiLayerInterface";

/// Where a manifest's library is: a path (absolute, or relative to the manifest's real folder,
/// as the loader resolves it), or a bare file name the dynamic linker looks up.
pub enum Library {
    Path(PathBuf),
    Name(String),
}

pub fn resolve(manifest: &Path, library: &str) -> Library {
    if !library.contains('/') {
        return Library::Name(library.to_string());
    }
    let path = Path::new(library);
    if path.is_absolute() {
        return Library::Path(path.to_path_buf());
    }
    let real = manifest
        .canonicalize()
        .unwrap_or_else(|_| manifest.to_path_buf());
    let dir = real.parent().unwrap_or(Path::new("/"));
    Library::Path(dir.join(path))
}

fn dlerror() -> String {
    // SAFETY: dlerror returns null or a NUL-terminated string valid until the next dl call.
    let e = unsafe { libc::dlerror() };
    if e.is_null() {
        "unknown error".into()
    } else {
        // SAFETY: non-null, NUL-terminated (above).
        unsafe { CStr::from_ptr(e) }.to_string_lossy().into_owned()
    }
}

/// Why a library did not pass.
enum LoadError {
    /// dlopen failed; dlerror's message.
    Open(String),
    /// It loaded but has no `xrNegotiateLoaderApiLayerInterface`.
    NoNegotiate,
}

/// Loads `target` (a path or a bare name) as the loader would and looks up the negotiation
/// function. The library stays loaded: this process ends soon, and unloading a library that
/// carries its own Rust runtime is not worth the risk.
fn load(target: &OsStr) -> Result<(), LoadError> {
    let c = CString::new(target.as_bytes())
        .map_err(|_| LoadError::Open("the path has a NUL byte".into()))?;
    // SAFETY: a NUL-terminated path; the library has no constructors that need more than
    // the loader would give them.
    let handle = unsafe { libc::dlopen(c.as_ptr(), libc::RTLD_NOW | libc::RTLD_LOCAL) };
    if handle.is_null() {
        return Err(LoadError::Open(dlerror()));
    }
    // SAFETY: a handle from dlopen and a NUL-terminated symbol name.
    let symbol = unsafe { libc::dlsym(handle, NEGOTIATE.as_ptr()) };
    if symbol.is_null() {
        return Err(LoadError::NoNegotiate);
    }
    Ok(())
}

fn is_elf(path: &Path) -> bool {
    use std::io::Read;
    let mut magic = [0u8; 4];
    contrastxr::user_file::open(path, u64::MAX)
        .ok()
        .and_then(|mut f| f.read_exact(&mut magic).ok())
        .is_some_and(|()| magic == *b"\x7fELF")
}

/// A source build reinstalls its own library; the package's tool has none beside it.
fn reinstall() -> String {
    format!(
        "reinstall the layer: in the source checkout `cargo build --release` and `{} install \
         --user --library target/release/libcontrastxr.so`, or reinstall the Debian package \
         (`sudo apt install --reinstall contrastxr`)",
        tool()
    )
}

/// The finding for `library`, as written in the manifest at `manifest`.
pub fn library_finding(manifest: &Path, library: &str) -> Finding {
    const NAME: &str = "library";
    let (target, shown) = match resolve(manifest, library) {
        Library::Path(p) if !p.exists() => {
            return Finding::problem(
                NAME,
                format!(
                    "{} (named by {}) does not exist",
                    p.display(),
                    manifest.display()
                ),
                reinstall(),
            )
        }
        Library::Path(p) if !is_elf(&p) => {
            return Finding::problem(
                NAME,
                format!("{} is not an ELF shared library", p.display()),
                reinstall(),
            )
        }
        Library::Path(p) => (p.clone().into_os_string(), p.display().to_string()),
        Library::Name(n) => (
            n.clone().into(),
            format!("{n} (looked up by the dynamic linker)"),
        ),
    };
    match load(&target) {
        Ok(()) => Finding::ok(
            NAME,
            format!("{shown} loads and exports xrNegotiateLoaderApiLayerInterface"),
        ),
        Err(LoadError::Open(why)) => Finding::problem(
            NAME,
            format!("{shown} cannot be loaded: {why}"),
            format!(
                "{}; `ldd {}` shows a missing dependency",
                reinstall(),
                Path::new(&target).display()
            ),
        ),
        Err(LoadError::NoNegotiate) => Finding::problem(
            NAME,
            format!("{shown} loads but does not export xrNegotiateLoaderApiLayerInterface"),
            reinstall(),
        ),
    }
}
