//! The graphics bindings the layer knows: which API a session's create info binds, which of
//! them it enhances (one reader per API folder in [`BINDINGS`]), and the API-specific OpenXR
//! functions it intercepts.

use super::session_graphics::Bound;
use super::{opengl, vulkan};
use crate::layer::live_settings::Settings;
use openxr_sys as xr;

/// A binding reader: None when the structure is not its API's binding.
type Bind = unsafe fn(&xr::BaseInStructure, &Settings) -> Option<Bound>;

/// Every API the layer enhances: its binding's structure type, its name in words and the
/// binding's reader.
const BINDINGS: [(xr::StructureType, &str, Bind); 3] = [
    (
        xr::StructureType::GRAPHICS_BINDING_VULKAN_KHR,
        "Vulkan",
        vulkan::bind,
    ),
    (
        xr::StructureType::GRAPHICS_BINDING_OPENGL_XLIB_KHR,
        "OpenGL (Xlib)",
        opengl::bind_xlib,
    ),
    (
        xr::StructureType::GRAPHICS_BINDING_EGL_MNDX,
        "OpenGL (EGL)",
        opengl::bind_egl,
    ),
];

/// The APIs of the sessions the layer enhances, as its `graphics API of this session:` line
/// names them (what `contrastxr doctor` reads): [`BINDINGS`]' names.
pub const ENHANCED_APIS: [&str; 3] = [BINDINGS[0].1, BINDINGS[1].1, BINDINGS[2].1];

/// The graphics API a session's create-info chain binds, in words ("OpenGL (Xlib)"), for the
/// line that says why a session is passed through; None when no binding is known.
///
/// # Safety
/// `next` must be null or a valid OpenXR `next` chain (each element an XrBaseInStructure).
pub unsafe fn api_name(mut next: *const std::ffi::c_void) -> Option<&'static str> {
    use xr::StructureType as T;
    while !next.is_null() {
        // SAFETY: the caller guarantees every element starts with XrBaseInStructure.
        let base = unsafe { &*(next as *const xr::BaseInStructure) };
        let enhanced = BINDINGS.iter().find(|(ty, _, _)| *ty == base.ty);
        let api = enhanced.map(|(_, name, _)| *name).or(match base.ty {
            T::GRAPHICS_BINDING_OPENGL_XCB_KHR => Some("OpenGL (XCB)"),
            T::GRAPHICS_BINDING_OPENGL_WAYLAND_KHR => Some("OpenGL (Wayland)"),
            T::GRAPHICS_BINDING_OPENGL_ES_ANDROID_KHR => Some("OpenGL ES"),
            T::GRAPHICS_BINDING_D3D11_KHR | T::GRAPHICS_BINDING_D3D12_KHR => Some("Direct3D"),
            _ => None,
        });
        if api.is_some() {
            return api;
        }
        next = base.next as *const std::ffi::c_void;
    }
    None
}

/// The API-specific OpenXR functions the layer intercepts (the app's Vulkan instance creation).
pub fn intercepted(name: &str) -> Option<xr::pfn::VoidFunction> {
    vulkan::intercepted(name)
}

/// Tells the APIs of an instance the layer serves, with the next layer's xrGetInstanceProcAddr
/// (which the functions they intercept forward through).
pub fn instance_created(instance: xr::Instance, next: xr::pfn::GetInstanceProcAddr) {
    vulkan::app_vulkan::instance_created(instance, next);
}

/// Forgets what the APIs kept for an instance the app destroys.
pub fn forget_instance(instance: xr::Instance) {
    vulkan::app_vulkan::forget(instance);
}

/// The session's graphics from its create info's `next` chain, with the binding's API name.
///
/// # Safety
/// `next` is the next chain of a session create info the runtime accepted.
pub unsafe fn bind(next: *const std::ffi::c_void, settings: &Settings) -> (&'static str, Bound) {
    // SAFETY: the caller's contract.
    let api = unsafe { api_name(next) }.unwrap_or("no known graphics binding");
    let mut at = next;
    while !at.is_null() {
        // SAFETY: every element of an accepted chain starts with XrBaseInStructure.
        let base = unsafe { &*(at as *const xr::BaseInStructure) };
        // SAFETY: each reader casts only a structure of its own type.
        if let Some(bound) = BINDINGS.iter().find_map(|b| unsafe { b.2(base, settings) }) {
            return (api, bound);
        }
        at = base.next as *const std::ffi::c_void;
    }
    let why = format!(
        "contrastxr enhances Vulkan and OpenGL sessions, not {api}: passing its frames through untouched"
    );
    (api, Bound::PassThrough(why))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The name of the binding a chain of `types` holds (each a bare XrBaseInStructure).
    fn name_of(types: &[xr::StructureType]) -> Option<&'static str> {
        let mut chain: Vec<xr::BaseInStructure> = types
            .iter()
            .map(|&ty| xr::BaseInStructure {
                ty,
                next: std::ptr::null(),
            })
            .collect();
        for k in (1..chain.len()).rev() {
            let next: *const xr::BaseInStructure = &chain[k];
            chain[k - 1].next = next;
        }
        let head: *const xr::BaseInStructure = chain.first().map_or(std::ptr::null(), |s| s);
        // SAFETY: a chain of XrBaseInStructures that lives through the call.
        unsafe { api_name(head.cast()) }
    }

    #[test]
    fn enhanced_and_other_apis_are_named_after_other_structures() {
        use xr::StructureType as T;
        let other = T::SESSION_CREATE_INFO_OVERLAY_EXTX;
        let enhanced: Vec<_> = BINDINGS
            .iter()
            .map(|(ty, _, _)| name_of(&[other, *ty]))
            .collect();
        assert_eq!(enhanced, ENHANCED_APIS.map(Some));
        assert_eq!(
            name_of(&[T::GRAPHICS_BINDING_OPENGL_XCB_KHR]),
            Some("OpenGL (XCB)")
        );
        assert_eq!(name_of(&[T::GRAPHICS_BINDING_D3D12_KHR]), Some("Direct3D"));
        assert_eq!(name_of(&[other]), None);
        assert_eq!(name_of(&[]), None);
    }
}
