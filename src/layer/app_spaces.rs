//! The app's reference spaces: the type of each space the app creates with
//! xrCreateReferenceSpace (what captures record as a projection layer's `space_type`), and
//! their destruction.

use super::ffi::guard;
use super::state;
use openxr_sys as xr;
use openxr_sys::pfn;
use std::collections::HashMap;
use std::sync::{Mutex, MutexGuard, OnceLock};

/// The reference space type of each space the app created with xrCreateReferenceSpace, with
/// the next layer's xrDestroySpace of its session.
type Types = HashMap<u64, (xr::ReferenceSpaceType, pfn::DestroySpace)>;

fn types() -> MutexGuard<'static, Types> {
    static TYPES: OnceLock<Mutex<Types>> = OnceLock::new();
    let m = TYPES.get_or_init(Default::default);
    // Only map operations happen under this lock.
    m.lock().unwrap_or_else(|p| p.into_inner())
}

/// The app's name for a reference space's type, if `space` is one.
pub fn type_name(space: xr::Space) -> Option<String> {
    let ty = types().get(&space.into_raw())?.0;
    Some(
        match ty {
            xr::ReferenceSpaceType::VIEW => "VIEW",
            xr::ReferenceSpaceType::LOCAL => "LOCAL",
            xr::ReferenceSpaceType::STAGE => "STAGE",
            xr::ReferenceSpaceType::LOCAL_FLOOR => "LOCAL_FLOOR",
            _ => return Some(format!("{}", ty.into_raw())),
        }
        .into(),
    )
}

/// # Safety
/// Called by the OpenXR loader with the arguments the app passed to xrCreateReferenceSpace.
pub unsafe extern "system" fn create_reference_space(
    session: xr::Session,
    info: *const xr::ReferenceSpaceCreateInfo,
    space: *mut xr::Space,
) -> xr::Result {
    guard(
        "xrCreateReferenceSpace",
        xr::Result::ERROR_RUNTIME_FAILURE,
        || {
            let s = state::session(session)
                .ok_or(super::ffi::LayerError::UnknownHandle("XrSession"))?;
            let next = state::lock(&s).next;
            // SAFETY: forwarding the app's call.
            let r = unsafe { (next.create_reference_space)(session, info, space) };
            if r == xr::Result::SUCCESS {
                // SAFETY: the runtime accepted info and wrote space.
                if let (Some(info), Some(space)) = unsafe { (info.as_ref(), space.as_ref()) } {
                    types().insert(
                        space.into_raw(),
                        (info.reference_space_type, next.destroy_space),
                    );
                }
            }
            Ok(r)
        },
    )
}

/// # Safety
/// Called by the OpenXR loader with the argument the app passed to xrDestroySpace.
pub unsafe extern "system" fn destroy_space(space: xr::Space) -> xr::Result {
    guard("xrDestroySpace", xr::Result::ERROR_RUNTIME_FAILURE, || {
        let known = types().remove(&space.into_raw()).map(|(_, f)| f);
        let next = known.map_or_else(any_destroy_space, Ok)?;
        // SAFETY: forwarding the app's call.
        Ok(unsafe { next(space) })
    })
}

/// The next xrDestroySpace for a space the app made otherwise (action spaces): an instance's
/// (the loader runs one runtime per process).
fn any_destroy_space() -> Result<pfn::DestroySpace, super::ffi::LayerError> {
    state::registry()
        .instances
        .values()
        .next()
        .map(|i| i.next.destroy_space)
        .ok_or(super::ffi::LayerError::UnknownHandle("XrInstance"))
}
