//! The shared libraries a device of the layer's own runs in (the Vulkan loader, the driver),
//! held loaded while it lives. Such a device is made through the app's Vulkan loader, which the
//! app and the runtime may unload (their last `dlclose`) while it still exists: its function
//! pointers would then point at unmapped code. Each library is opened again with
//! `RTLD_NOLOAD` (only a reference to the copy already loaded, never another) and closed after
//! the device and its instance are destroyed.

use std::ffi::c_void;

/// References to the loaded libraries, dropped (closed) last.
pub struct PinnedLibraries(Vec<*mut c_void>);

// SAFETY: dlopen handles may be closed from any thread.
unsafe impl Send for PinnedLibraries {}
// SAFETY: the handles are only read (closed once, in Drop, through &mut).
unsafe impl Sync for PinnedLibraries {}

impl PinnedLibraries {
    /// Takes a reference on each library that one of `functions` lies in (once per library).
    pub fn of(functions: &[*const c_void]) -> PinnedLibraries {
        let mut handles: Vec<*mut c_void> = Vec::new();
        for &f in functions {
            let Some(handle) = reference_to_library_of(f) else {
                continue;
            };
            if handles.contains(&handle) {
                // SAFETY: a handle dlopen just returned, closed once here.
                unsafe { libc::dlclose(handle) };
            } else {
                handles.push(handle);
            }
        }
        PinnedLibraries(handles)
    }
}

/// A new reference (dlopen with RTLD_NOLOAD) to the library `function` lies in.
fn reference_to_library_of(function: *const c_void) -> Option<*mut c_void> {
    // SAFETY: Dl_info is plain data that dladdr fills in.
    let mut info: libc::Dl_info = unsafe { std::mem::zeroed() };
    // SAFETY: dladdr only reads the address; info is a valid out pointer.
    if unsafe { libc::dladdr(function, &mut info) } == 0 || info.dli_fname.is_null() {
        return None;
    }
    // SAFETY: dli_fname is a NUL-terminated path owned by the dynamic linker; RTLD_NOLOAD
    // never loads anything, it only references a library already in the process.
    let handle = unsafe { libc::dlopen(info.dli_fname, libc::RTLD_NOW | libc::RTLD_NOLOAD) };
    (!handle.is_null()).then_some(handle)
}

impl Drop for PinnedLibraries {
    fn drop(&mut self) {
        for &handle in &self.0 {
            // SAFETY: each handle came from dlopen in `of` and is closed once.
            unsafe { libc::dlclose(handle) };
        }
    }
}
