//! Camera times to XrTime. The layer enables XR_KHR_convert_timespec_time on the instance when
//! the runtime offers it and the app did not ask for it, invisibly: the app's enumerations and
//! its own enabled list are unchanged, and its xrGetInstanceProcAddr for the extension's
//! functions stays XR_ERROR_FUNCTION_UNSUPPORTED. Without the extension, the offset between
//! the clocks is measured from the frames' displayTime (late by the runtime's prediction lead).

use super::dispatch::lookup;
use super::ffi::c_str;
use openxr_sys as xr;
use openxr_sys::pfn;
use std::ffi::{c_char, CStr};

const EXTENSION: &CStr = c"XR_KHR_convert_timespec_time";
/// The extension's functions, hidden from an app that did not enable it.
pub const FUNCTIONS: [&str; 2] = [
    "xrConvertTimespecTimeToTimeKHR",
    "xrConvertTimeToTimespecTimeKHR",
];

/// The instance's conversion from CLOCK_MONOTONIC to XrTime.
#[derive(Clone, Copy)]
pub struct Timespec {
    convert: Option<pfn::ConvertTimespecTimeToTimeKHR>,
    /// The layer enabled the extension, not the app: its functions are hidden from the app.
    pub hidden: bool,
}

/// The app's create info with the extension added (when the runtime offers it, the app did not
/// enable it and the layer is on), and the names it points to.
pub struct Extended {
    pub info: xr::InstanceCreateInfo,
    _names: Vec<*const c_char>,
    pub added: bool,
    pub app_enabled: bool,
}

impl Extended {
    /// The app's create info as it is.
    pub fn unchanged(info: &xr::InstanceCreateInfo) -> Extended {
        let wanted = EXTENSION.to_str().unwrap_or_default();
        let app_enabled = (0..info.enabled_extension_count as usize).any(|i| {
            // SAFETY: the app's array of enabled_extension_count NUL-terminated names.
            (unsafe { c_str(*info.enabled_extension_names.add(i)) }) == Some(wanted)
        });
        Extended {
            info: *info,
            _names: Vec::new(),
            added: false,
            app_enabled,
        }
    }
}

/// # Safety
/// `info` must be the app's valid create info; `gipa` the next layer's xrGetInstanceProcAddr.
pub unsafe fn extend(info: &xr::InstanceCreateInfo, gipa: pfn::GetInstanceProcAddr) -> Extended {
    let app: Vec<*const c_char> = if info.enabled_extension_names.is_null() {
        Vec::new()
    } else {
        // SAFETY: the app's array of enabled_extension_count names.
        unsafe {
            std::slice::from_raw_parts(
                info.enabled_extension_names,
                info.enabled_extension_count as usize,
            )
        }
        .to_vec()
    };
    let wanted = EXTENSION.to_str().unwrap_or_default();
    // SAFETY: each name is a NUL-terminated string of the app's.
    let app_enabled = app.iter().any(|n| unsafe { c_str(*n) } == Some(wanted));
    let layer_on = std::env::var("CONTRASTXR").map_or(true, |v| !crate::config::is_off(&v));
    // SAFETY: gipa is the next layer's.
    let added = !app_enabled && layer_on && unsafe { runtime_offers(gipa) };
    let mut names = app;
    if added {
        names.push(EXTENSION.as_ptr());
    }
    let mut extended = *info;
    extended.enabled_extension_count = names.len() as u32;
    extended.enabled_extension_names = names.as_ptr();
    Extended {
        info: extended,
        _names: names,
        added,
        app_enabled,
    }
}

/// Whether the runtime (below the layers) lists the extension.
unsafe fn runtime_offers(gipa: pfn::GetInstanceProcAddr) -> bool {
    // SAFETY: a null instance is allowed for this global function.
    let Some(f) = (unsafe {
        lookup(
            gipa,
            xr::Instance::NULL,
            c"xrEnumerateInstanceExtensionProperties",
        )
    }) else {
        return false;
    };
    // SAFETY: the function registered under this name has this signature.
    let enumerate = unsafe {
        std::mem::transmute::<pfn::VoidFunction, pfn::EnumerateInstanceExtensionProperties>(f)
    };
    let mut count = 0;
    // SAFETY: a count query with a valid out pointer.
    if unsafe { enumerate(std::ptr::null(), 0, &mut count, std::ptr::null_mut()) }.into_raw() < 0 {
        return false;
    }
    let blank = xr::ExtensionProperties {
        ty: xr::StructureType::EXTENSION_PROPERTIES,
        next: std::ptr::null_mut(),
        extension_name: [0; xr::MAX_EXTENSION_NAME_SIZE],
        extension_version: 0,
    };
    let mut props = vec![blank; count as usize];
    // SAFETY: props holds `count` initialised structs.
    let r = unsafe { enumerate(std::ptr::null(), count, &mut count, props.as_mut_ptr()) };
    r.into_raw() >= 0
        && props.iter().take(count as usize).any(|p| {
            // SAFETY: the runtime writes NUL-terminated names.
            (unsafe { CStr::from_ptr(p.extension_name.as_ptr()) }) == EXTENSION
        })
}

impl Timespec {
    /// The conversion of an instance created with `extended`.
    ///
    /// # Safety
    /// `gipa` must be the next layer's and `instance` created by it.
    pub unsafe fn resolve(
        gipa: pfn::GetInstanceProcAddr,
        instance: xr::Instance,
        extended: &Extended,
    ) -> Timespec {
        let enabled = extended.added || extended.app_enabled;
        // SAFETY: as the caller guarantees.
        let f = enabled
            .then(|| unsafe { lookup(gipa, instance, c"xrConvertTimespecTimeToTimeKHR") })
            .flatten();
        Timespec {
            // SAFETY: the function registered under this name has this signature.
            convert: f.map(|f| unsafe {
                std::mem::transmute::<pfn::VoidFunction, pfn::ConvertTimespecTimeToTimeKHR>(f)
            }),
            hidden: extended.added,
        }
    }

    /// CLOCK_MONOTONIC `ns` as XrTime, when the runtime converts it.
    pub fn xr_time(&self, instance: xr::Instance, ns: i64) -> Option<xr::Time> {
        let convert = self.convert?;
        let ts = libc::timespec {
            tv_sec: ns.div_euclid(1_000_000_000) as libc::time_t,
            tv_nsec: ns.rem_euclid(1_000_000_000) as libc::c_long,
        };
        let mut time = xr::Time::from_nanos(0);
        // SAFETY: valid in and out pointers; libc's timespec is the C struct the runtime takes.
        let r = unsafe { convert(instance, (&ts as *const libc::timespec).cast(), &mut time) };
        (r == xr::Result::SUCCESS).then_some(time)
    }

    pub fn available(&self) -> bool {
        self.convert.is_some()
    }
}
