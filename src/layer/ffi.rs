//! The boundary with the OpenXR loader: panics never cross it, and `next` chains are walked
//! in one place.

use super::log;
use openxr_sys as xr;
use std::panic::{catch_unwind, AssertUnwindSafe};

/// Why the layer answers an app's call itself, without the runtime.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum LayerError {
    /// A handle the layer never saw created (or already saw destroyed).
    UnknownHandle(&'static str),
    /// The loader's negotiation or layer chain is not what the loader interface specifies.
    Loader(&'static str),
}

impl LayerError {
    /// The result the app gets.
    pub fn result(&self) -> xr::Result {
        match self {
            LayerError::UnknownHandle(_) => xr::Result::ERROR_HANDLE_INVALID,
            LayerError::Loader(_) => xr::Result::ERROR_INITIALIZATION_FAILED,
        }
    }
}

impl std::fmt::Display for LayerError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            LayerError::UnknownHandle(kind) => write!(f, "unknown {kind} handle"),
            LayerError::Loader(what) => write!(f, "loader interface: {what}"),
        }
    }
}

/// An entry point's outcome: the runtime's (or the layer's own) result, or why the layer
/// answers the call itself.
pub type LayerResult = Result<xr::Result, LayerError>;

/// A panic the layer caught in its own code, by what the layer was doing (the panic's own
/// words are already in the log, through the panic hook).
#[derive(Debug)]
pub struct Contained<'a> {
    /// What the layer was doing ("in xrEndFrame", "while enhancing"), as the log says it.
    pub during: &'a str,
}

impl std::fmt::Display for Contained<'_> {
    /// The log's words for it: "internal error in xrEndFrame".
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "internal error {}", self.during)
    }
}

/// Runs part of the layer's work with a panic in it contained: an error comes back instead of
/// an unwind. The panic hook has already written the panic as one line of the log;
/// the caller decides what the failure costs (usually the session's enhancement, through
/// `SessionState::pass_through`).
pub fn contain<R>(during: &str, body: impl FnOnce() -> R) -> Result<R, Contained<'_>> {
    caught(body).map_err(|_| Contained { during })
}

/// The one place the layer catches panics ([`contain`] and [`guard`] run their bodies here).
fn caught<R>(body: impl FnOnce() -> R) -> Result<R, String> {
    catch_unwind(AssertUnwindSafe(body)).map_err(|panic| {
        panic
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| panic.downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "unknown panic".into())
    })
}

/// Runs an entry point's body. A layer error becomes its XrResult; a panic is logged once and
/// answered with `on_panic` (the layer then behaves as pass-through where the caller arranges
/// it), never unwound into the app.
pub fn guard(name: &str, on_panic: xr::Result, body: impl FnOnce() -> LayerResult) -> xr::Result {
    match caught(body) {
        Ok(Ok(result)) => result,
        Ok(Err(e)) => {
            log::debug(&format!("{name}: {e}"));
            e.result()
        }
        Err(what) => {
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

#[cfg(test)]
mod tests {
    use super::*;

    /// A panic comes back as what the layer was doing, in the log's words; a body that ends
    /// normally gives its value.
    #[test]
    fn contain_turns_a_panic_into_the_logs_words() {
        let caught = contain("in xrEndFrame", || -> u32 { panic!("fault injected") });
        assert_eq!(
            caught.map_err(|e| e.to_string()),
            Err("internal error in xrEndFrame".to_string())
        );
        assert_eq!(contain("while enhancing", || 7).ok(), Some(7));
    }

    /// An entry point that panics answers `on_panic`; a layer error, its own result.
    #[test]
    fn guard_answers_a_panic_and_a_layer_error() {
        let on_panic = xr::Result::ERROR_RUNTIME_FAILURE;
        let panicked = guard("xrTestCall", on_panic, || panic!("fault injected"));
        assert_eq!(panicked, on_panic);
        let unknown = guard("xrTestCall", on_panic, || {
            Err(LayerError::UnknownHandle("XrSession"))
        });
        assert_eq!(unknown, xr::Result::ERROR_HANDLE_INVALID);
    }
}
