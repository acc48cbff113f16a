//! The layer's exported and intercepted OpenXR functions. Each body runs inside `ffi::guard`;
//! anything not intercepted goes straight to the next layer, so results, structs and error
//! codes the layer does not handle pass through unchanged.

use super::dispatch::NextFns;
use super::ffi::{c_str, guard, LayerError};
use super::graphics;
use super::live_settings::{self, Settings};
use super::state::{self, lock, InstanceState};
use super::{app_spaces, blend, elevated, log, session, swapchain, timespec};
use crate::config::{self, Live, KEYS};
use openxr_sys as xr;
use openxr_sys::loader::{ApiLayerCreateInfo, XrNegotiateApiLayerRequest, XrNegotiateLoaderInfo};
use openxr_sys::pfn;
use std::ffi::c_char;
use std::sync::{Arc, OnceLock};

pub const LAYER_NAME: &str = "XR_APILAYER_CONTRASTXR_color_contrast";

/// The next layer's xrGetInstanceProcAddr, for lookups before an instance is known.
static FIRST_NEXT_GIPA: OnceLock<pfn::GetInstanceProcAddr> = OnceLock::new();

/// # Safety
/// Called by the OpenXR loader with valid negotiation structs.
#[no_mangle]
pub unsafe extern "system" fn xrNegotiateLoaderApiLayerInterface(
    loader_info: *const XrNegotiateLoaderInfo,
    _layer_name: *const c_char,
    request: *mut XrNegotiateApiLayerRequest,
) -> xr::Result {
    guard(
        "xrNegotiateLoaderApiLayerInterface",
        xr::Result::ERROR_INITIALIZATION_FAILED,
        || {
            if loader_info.is_null() || request.is_null() {
                return Err(LayerError::Loader("bad negotiation or chain structs"));
            }
            // SAFETY: the loader passes valid structs (checked non-null above).
            let (info, req) = unsafe { (&*loader_info, &mut *request) };
            if info.ty != XrNegotiateLoaderInfo::TYPE
                || req.ty != XrNegotiateApiLayerRequest::TYPE
                || info.min_interface_version > 1
                || info.max_interface_version < 1
            {
                return Err(LayerError::Loader("bad negotiation or chain structs"));
            }
            stay_mapped();
            super::log::quiet_panics();
            req.layer_interface_version = 1;
            req.layer_api_version = xr::CURRENT_API_VERSION;
            req.get_instance_proc_addr = Some(get_instance_proc_addr);
            req.create_api_layer_instance = Some(create_api_layer_instance);
            Ok(xr::Result::SUCCESS)
        },
    )
}

/// Keeps this library mapped for the rest of the process (`RTLD_NODELETE`): the loader closes
/// it at xrDestroyInstance, while a thread of the layer may still be ending (a camera still
/// opening on the reopen helper, a capture thread closing its device) or a thread-local
/// destructor may be pending. Each such thread ends on its own within a second; none then
/// runs code of an unmapped library.
fn stay_mapped() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        let Some(file) = super::installed_files::library_file() else {
            return log::info("cannot keep the layer's library mapped (dladdr failed)");
        };
        let flags = libc::RTLD_NOW | libc::RTLD_NOLOAD | libc::RTLD_NODELETE;
        // SAFETY: RTLD_NOLOAD only promotes this already loaded library (its own name, from
        // dladdr); the handle is kept on purpose: the library is never unloaded.
        if unsafe { libc::dlopen(file.as_ptr(), flags) }.is_null() {
            log::info("cannot keep the layer's library mapped (dlopen RTLD_NODELETE failed)");
        }
    });
}

fn startup_line(settings: &Settings, app: &str) -> String {
    let state = if settings.enabled {
        "on"
    } else {
        "off (CONTRASTXR is 0/false/off/empty)"
    };
    let mut line = format!(
        "contrastxr {} {state}, app {app:?}",
        env!("CARGO_PKG_VERSION")
    );
    if settings.enabled {
        line += &format!(", {}", config::describe(settings));
    }
    line
}

/// # Safety
/// Called by the OpenXR loader with the arguments the app passed to xrCreateInstance and the loader's layer info.
unsafe extern "system" fn create_api_layer_instance(
    info: *const xr::InstanceCreateInfo,
    layer_info: *const ApiLayerCreateInfo,
    instance: *mut xr::Instance,
) -> xr::Result {
    guard(
        "xrCreateApiLayerInstance",
        xr::Result::ERROR_INITIALIZATION_FAILED,
        || {
            // SAFETY: the loader passes a valid ApiLayerCreateInfo whose next_info names us.
            let next_info = unsafe { layer_info.as_ref() }
                .map(|l| l.next_info)
                .unwrap_or(std::ptr::null_mut());
            // SAFETY: non-null next_info points to the loader's chain entry for this layer.
            let Some(next) = (unsafe { next_info.as_ref() }) else {
                return Err(LayerError::Loader("bad negotiation or chain structs"));
            };
            // Hand the next layer the chain without our entry.
            // SAFETY: layer_info is valid (its next_info was read above).
            let mut forwarded = unsafe { *layer_info };
            forwarded.next_info = next.next;
            let gipa = next.next_get_instance_proc_addr;
            if elevated::elevated() {
                // SAFETY: forwarding the loader's own arguments to the next layer.
                let result =
                    unsafe { (next.next_create_api_layer_instance)(info, &forwarded, instance) };
                if result.into_raw() >= 0 {
                    let _ = FIRST_NEXT_GIPA.set(gipa);
                }
                log::once("elevated", elevated::LINE);
                return Ok(result);
            }
            // SAFETY: the loader passes the app's valid create info (null left to the runtime).
            let extended = unsafe { info.as_ref() }.map(|i| unsafe { timespec::extend(i, gipa) });
            let mut result = match &extended {
                // SAFETY: the app's create info with one more extension the runtime offers.
                Some(e) if e.added => unsafe {
                    (next.next_create_api_layer_instance)(&e.info, &forwarded, instance)
                },
                _ => xr::Result::ERROR_EXTENSION_NOT_PRESENT,
            };
            let mut extended = extended.filter(|_| result.into_raw() >= 0);
            if extended.is_none() {
                // SAFETY: forwarding the loader's own arguments to the next layer.
                result =
                    unsafe { (next.next_create_api_layer_instance)(info, &forwarded, instance) };
                // SAFETY: as above.
                extended = unsafe { info.as_ref() }.map(timespec::Extended::unchanged);
            }
            if result.into_raw() < 0 {
                return Ok(result);
            }
            let _ = FIRST_NEXT_GIPA.set(gipa);
            // SAFETY: instance was just written by a successful create call.
            let handle = unsafe { *instance };
            // SAFETY: gipa is the next layer's and handle was created by it.
            let timespec =
                extended.map(|e| unsafe { timespec::Timespec::resolve(gipa, handle, &e) });
            register_instance(handle, gipa, info, timespec);
            Ok(result)
        },
    )
}

/// Logs where the settings came from: the file, every effective value with its origin, and
/// each problem (an invalid value names its file, line and key).
fn log_resolved(r: &config::Resolved) {
    let file = r.file.as_ref().map_or_else(
        || "none found (CONTRASTXR_CONFIG, $XDG_CONFIG_HOME/contrastxr/config.toml, /etc/xdg/contrastxr/config.toml)".into(),
        |p| format!("{}, watched for changes", p.display()),
    );
    log::info(&format!("config file: {file}"));
    for i in 0..KEYS.len() {
        log::info(&format!("setting {}", r.line(i)));
    }
    for p in &r.problems {
        log::info(p);
    }
}

/// The settings for `app`; when the layer is on, a watcher keeps them current from now on.
fn start_settings(handle: xr::Instance, app: &str) -> Settings {
    let env = config::Env::capture();
    let off = env.get("CONTRASTXR").is_some_and(|v| config::is_off(&v));
    if off {
        let s = config::resolve(app, None, &env).settings;
        log::info(&startup_line(&s, app));
        return s;
    }
    let (live, resolved) = Live::start(app, env, Box::new(log::info));
    log::info(&startup_line(&resolved.settings, app));
    log_resolved(&resolved);
    live_settings::register_live(handle.into_raw(), live);
    resolved.settings
}

fn register_instance(
    handle: xr::Instance,
    gipa: pfn::GetInstanceProcAddr,
    info: *const xr::InstanceCreateInfo,
    timespec: Option<timespec::Timespec>,
) {
    // SAFETY: info is the app's valid create info; the name is a NUL-terminated array.
    let app = unsafe { info.as_ref() }
        .and_then(|i| unsafe { c_str(i.application_info.application_name.as_ptr()) })
        .unwrap_or("")
        .to_string();
    crate::camera::set_log_sink(Box::new(log::info));
    let settings = start_settings(handle, &app);
    // SAFETY: gipa is the next layer's and handle was created by it.
    match unsafe { NextFns::load(gipa, handle) } {
        Ok(next) => {
            graphics::instance_created(handle, next.get_instance_proc_addr);
            let state = InstanceState {
                next,
                settings: Arc::new(settings),
                timespec,
            };
            state::registry()
                .instances
                .insert(handle.into_raw(), Arc::new(state));
        }
        Err(e) => {
            live_settings::forget_live(handle.into_raw());
            log::info(&format!("{e}: passing everything through"));
        }
    }
}

/// Our replacement for `name`, if the layer intercepts it.
fn intercepted(name: &str) -> Option<pfn::VoidFunction> {
    // SAFETY: (all arms) the loader calls each pointer through the signature its name has
    // in the OpenXR specification, which is the one each function below is declared with.
    unsafe {
        Some(match name {
            "xrGetInstanceProcAddr" => std::mem::transmute::<
                pfn::GetInstanceProcAddr,
                pfn::VoidFunction,
            >(get_instance_proc_addr),
            "xrDestroyInstance" => {
                std::mem::transmute::<pfn::DestroyInstance, pfn::VoidFunction>(destroy_instance)
            }
            "xrCreateSession" => std::mem::transmute::<pfn::CreateSession, pfn::VoidFunction>(
                session::create_session,
            ),
            "xrDestroySession" => std::mem::transmute::<pfn::DestroySession, pfn::VoidFunction>(
                session::destroy_session,
            ),
            "xrEnumerateEnvironmentBlendModes" => {
                std::mem::transmute::<pfn::EnumerateEnvironmentBlendModes, pfn::VoidFunction>(
                    blend::enumerate_environment_blend_modes,
                )
            }
            "xrEndFrame" => {
                std::mem::transmute::<pfn::EndFrame, pfn::VoidFunction>(session::end_frame)
            }
            "xrCreateReferenceSpace" => std::mem::transmute::<
                pfn::CreateReferenceSpace,
                pfn::VoidFunction,
            >(app_spaces::create_reference_space),
            "xrDestroySpace" => std::mem::transmute::<pfn::DestroySpace, pfn::VoidFunction>(
                app_spaces::destroy_space,
            ),
            "xrCreateSwapchain" => std::mem::transmute::<pfn::CreateSwapchain, pfn::VoidFunction>(
                swapchain::create_swapchain,
            ),
            "xrDestroySwapchain" => {
                std::mem::transmute::<pfn::DestroySwapchain, pfn::VoidFunction>(
                    swapchain::destroy_swapchain,
                )
            }
            "xrEnumerateSwapchainImages" => std::mem::transmute::<
                pfn::EnumerateSwapchainImages,
                pfn::VoidFunction,
            >(swapchain::enumerate_swapchain_images),
            "xrAcquireSwapchainImage" => std::mem::transmute::<
                pfn::AcquireSwapchainImage,
                pfn::VoidFunction,
            >(swapchain::acquire_swapchain_image),
            "xrWaitSwapchainImage" => std::mem::transmute::<
                pfn::WaitSwapchainImage,
                pfn::VoidFunction,
            >(swapchain::wait_swapchain_image),
            "xrReleaseSwapchainImage" => std::mem::transmute::<
                pfn::ReleaseSwapchainImage,
                pfn::VoidFunction,
            >(swapchain::release_swapchain_image),
            _ => return graphics::intercepted(name),
        })
    }
}

/// # Safety
/// Called by the OpenXR loader (or the app) with a valid name and a valid output pointer.
unsafe extern "system" fn get_instance_proc_addr(
    instance: xr::Instance,
    name: *const c_char,
    function: *mut Option<pfn::VoidFunction>,
) -> xr::Result {
    guard(
        "xrGetInstanceProcAddr",
        xr::Result::ERROR_RUNTIME_FAILURE,
        || {
            let state = state::instance(instance);
            let next_gipa = state
                .as_ref()
                .map(|s| s.next.get_instance_proc_addr)
                .or(FIRST_NEXT_GIPA.get().copied());
            let Some(next_gipa) = next_gipa else {
                return Err(LayerError::UnknownHandle("XrInstance"));
            };
            // SAFETY: the app passes a NUL-terminated name.
            let wanted = unsafe { c_str(name) }.unwrap_or("");
            // Ask the next layer first: an extension function the app did not enable must stay
            // XR_ERROR_FUNCTION_UNSUPPORTED, and its error codes pass through unchanged.
            let hidden = state
                .as_ref()
                .is_some_and(|s| s.timespec.is_some_and(|t| t.hidden));
            if hidden && timespec::FUNCTIONS.contains(&wanted) {
                // The layer enabled this extension for itself: to the app it is not enabled.
                // SAFETY: function is the app's out pointer.
                if let Some(f) = unsafe { function.as_mut() } {
                    *f = None;
                }
                return Ok(xr::Result::ERROR_FUNCTION_UNSUPPORTED);
            }
            // SAFETY: forwarding the app's own arguments.
            let result = unsafe { next_gipa(instance, name, function) };
            let enabled = state.as_ref().is_some_and(|s| s.settings.enabled);
            if result == xr::Result::SUCCESS && enabled {
                if let Some(ours) = intercepted(wanted) {
                    // SAFETY: function is the app's valid out pointer (the call above wrote it).
                    unsafe { *function = Some(ours) };
                }
            }
            if wanted == "xrGetInstanceProcAddr" && result == xr::Result::SUCCESS {
                // SAFETY: as above; our gipa must stay in the chain even when disabled.
                unsafe { *function = intercepted(wanted) };
            }
            Ok(result)
        },
    )
}

/// # Safety
/// Called by the OpenXR loader with the argument the app passed to xrDestroyInstance.
unsafe extern "system" fn destroy_instance(instance: xr::Instance) -> xr::Result {
    guard(
        "xrDestroyInstance",
        xr::Result::ERROR_RUNTIME_FAILURE,
        || {
            let state = state::instance(instance).ok_or(LayerError::UnknownHandle("XrInstance"))?;
            // A panic in the layer's own part is logged; the runtime gets the call regardless.
            guard("xrDestroyInstance", xr::Result::SUCCESS, || {
                forget_instance(instance);
                Ok(xr::Result::SUCCESS)
            });
            // The captures of its frames, written on the capture thread: waited for boundedly.
            super::capture_writer::finish(super::capture_writer::INSTANCE_WAIT);
            if let Some((name, n)) = crate::fault::reached().filter(|(_, n)| *n > 0) {
                log::info(&format!("fault point {name} reached {n} times"));
            }
            // The log file's writer ends once it has written what was queued (never waited
            // for); a later line starts another.
            super::log_file::end_writer();
            // SAFETY: forwarding the app's call.
            Ok(unsafe { (state.next.destroy_instance)(instance) })
        },
    )
}

/// Drops the layer's state of an instance, and of the sessions the app left alive with it
/// (their GPU state first).
fn forget_instance(instance: xr::Instance) {
    // Lock order: sessions are locked only after the registry lock is dropped.
    let all: Vec<(u64, Arc<std::sync::Mutex<state::SessionState>>)> = state::registry()
        .sessions
        .iter()
        .map(|(k, s)| (*k, s.clone()))
        .collect();
    let sessions: Vec<u64> = all
        .into_iter()
        .filter(|(_, s)| lock(s).instance == instance)
        .map(|(k, _)| k)
        .collect();
    for s in sessions {
        session::forget(xr::Session::from_raw(s));
    }
    if crate::fault::hit("destroy-bookkeeping") {
        panic!("fault injected at destroy-bookkeeping (CONTRASTXR_FAULT)");
    }
    state::registry().instances.remove(&instance.into_raw());
    live_settings::forget_live(instance.into_raw());
    graphics::forget_instance(instance);
}
