//! The boundary with the OpenXR loader: panics never cross it, and `next` chains are walked
//! in one place.

use super::log;
use openxr_sys as xr;
use std::panic::{catch_unwind, AssertUnwindSafe};

/// Runs an entry point's body. A panic is logged once and answered with `on_panic` (the layer
/// then behaves as pass-through where the caller arranges it), never unwound into the app.
pub fn guard(name: &str, on_panic: xr::Result, body: impl FnOnce() -> xr::Result) -> xr::Result {
    match catch_unwind(AssertUnwindSafe(body)) {
        Ok(result) => result,
        Err(panic) => {
            let what = panic
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| panic.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "unknown panic".into());
            log::once(
                &format!("panic-{name}"),
                &format!("internal error in {name}: {what}"),
            );
            on_panic
        }
    }
}

/// Finds the first struct of type `ty` in a `next` chain.
///
/// # Safety
/// `next` must be null or point to a valid chain of OpenXR structs (each starting with
/// `XrBaseInStructure`), and `T` must be the struct that `ty` identifies.
pub unsafe fn find_in_chain<T>(
    mut next: *const std::ffi::c_void,
    ty: xr::StructureType,
) -> Option<*const T> {
    while !next.is_null() {
        // SAFETY: the caller guarantees every element starts with XrBaseInStructure.
        let base = unsafe { &*(next as *const xr::BaseInStructure) };
        if base.ty == ty {
            return Some(next as *const T);
        }
        next = base.next as *const std::ffi::c_void;
    }
    None
}

/// A C string pointer as &str (None if null or not UTF-8).
///
/// # Safety
/// `p` must be null or point to a NUL-terminated string valid for the returned lifetime.
pub unsafe fn c_str<'a>(p: *const std::ffi::c_char) -> Option<&'a str> {
    if p.is_null() {
        return None;
    }
    // SAFETY: guaranteed by the caller.
    unsafe { std::ffi::CStr::from_ptr(p) }.to_str().ok()
}
