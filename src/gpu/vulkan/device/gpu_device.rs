//! A Vulkan device the engine works on: either one it created itself (the offline CLI and
//! tests) or one that belongs to someone else (the app's device, inside the OpenXR layer).
//! Drop destroys only what this object created.

use super::compute_device::create_compute_device;
use super::error::{GpuError, VkResultExt};
use super::pinned_libraries::PinnedLibraries;
use ash::vk;
use gpu_allocator::vulkan::{Allocator, AllocatorCreateDesc};
use std::ffi::{c_void, CStr};
use std::mem::ManuallyDrop;
use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::{Arc, Mutex};

const VALIDATION_LAYER: &CStr = c"VK_LAYER_KHRONOS_validation";

/// Debug-messenger state: counts validation errors and keeps their text.
#[derive(Default)]
pub struct ValidationLog {
    pub errors: AtomicU32,
    pub messages: Mutex<Vec<String>>,
}

struct Messenger {
    loader: ash::ext::debug_utils::Instance,
    raw: vk::DebugUtilsMessengerEXT,
    _log: Arc<ValidationLog>,
}

/// Objects this device created and must destroy (None when borrowed).
struct Owned {
    messenger: Option<Messenger>,
    /// The instance is this object's too (false for a device made on someone else's).
    instance: bool,
    /// For a device made through the app's loader: the libraries it runs in, closed after it.
    _libraries: Option<PinnedLibraries>,
}

pub struct GpuDevice {
    pub entry: ash::Entry,
    pub instance: ash::Instance,
    pub physical: vk::PhysicalDevice,
    pub device: ash::Device,
    pub queue: vk::Queue,
    pub queue_family: u32,
    pub allocator: ManuallyDrop<Mutex<Allocator>>,
    pub name: String,
    pub validation: Option<Arc<ValidationLog>>,
    /// VK_KHR_pipeline_executable_properties is enabled: pipelines can report the compiler's
    /// statistics (gpu/vulkan/pipelines/shader_statistics.rs).
    pub shader_statistics: bool,
    owned: Option<Owned>,
    /// The GPU may still use memory or objects of this device: Drop then frees nothing.
    abandoned: bool,
}

/// Options for a device the engine creates itself.
#[derive(Clone, Debug, Default)]
pub struct DeviceOptions {
    /// Index into vkEnumeratePhysicalDevices (default the first).
    pub index: usize,
    /// Enable VK_LAYER_KHRONOS_validation (with synchronisation validation) and count errors.
    pub validation: bool,
    /// Take the physical device with this vendor, device and pipelineCacheUUID instead of
    /// `index` (a device of the same kind as someone else's).
    pub matching: Option<DeviceKind>,
    /// Enable VK_KHR_pipeline_executable_properties where the driver has it
    /// ([`GpuDevice::shader_statistics`]).
    pub shader_statistics: bool,
}

impl DeviceOptions {
    /// `CONTRASTXR_VK_VALIDATION=1` turns validation on; `CONTRASTXR_VK_DEVICE=N` picks a device.
    pub fn from_env() -> Self {
        DeviceOptions {
            index: std::env::var("CONTRASTXR_VK_DEVICE")
                .ok()
                .and_then(|v| v.parse().ok())
                .unwrap_or(0),
            validation: std::env::var("CONTRASTXR_VK_VALIDATION").is_ok_and(|v| v == "1"),
            matching: None,
            shader_statistics: false,
        }
    }
}

/// # Safety
/// Called by the Vulkan loader with a valid callback data pointer and the user data the messenger was created with.
unsafe extern "system" fn on_validation_message(
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    _types: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    user: *mut c_void,
) -> vk::Bool32 {
    if severity.contains(vk::DebugUtilsMessageSeverityFlagsEXT::ERROR) {
        // SAFETY: user is the Arc<ValidationLog> the messenger was created with, alive until
        // the messenger is destroyed; data is valid for the duration of the callback.
        let log = unsafe { &*(user as *const ValidationLog) };
        // SAFETY: data is valid for the duration of the callback (see above).
        let text = unsafe { (*data).message_as_c_str() }
            .map(|m| m.to_string_lossy().into_owned())
            .unwrap_or_default();
        eprintln!("contrastxr: Vulkan validation error: {text}");
        log.errors.fetch_add(1, Ordering::Relaxed);
        if let Ok(mut m) = log.messages.lock() {
            m.push(text);
        }
    }
    vk::FALSE
}

pub(super) fn load_entry() -> Result<ash::Entry, GpuError> {
    // SAFETY: loads libvulkan.so.1, whose initialisation has no preconditions.
    unsafe { ash::Entry::load() }.map_err(|e| GpuError::NoLoader(e.to_string()))
}

pub(super) fn create_instance(
    entry: &ash::Entry,
    validation: bool,
) -> Result<ash::Instance, GpuError> {
    let app = vk::ApplicationInfo::default()
        .application_name(c"contrastxr")
        .api_version(vk::API_VERSION_1_1);
    let layers = [VALIDATION_LAYER.as_ptr()];
    let extensions = [ash::ext::debug_utils::NAME.as_ptr()];
    let sync = [vk::ValidationFeatureEnableEXT::SYNCHRONIZATION_VALIDATION];
    let mut features = vk::ValidationFeaturesEXT::default().enabled_validation_features(&sync);
    let mut info = vk::InstanceCreateInfo::default().application_info(&app);
    if validation {
        info = info
            .enabled_layer_names(&layers)
            .enabled_extension_names(&extensions)
            .push_next(&mut features);
    }
    // SAFETY: info and everything it points to live until the call returns.
    unsafe { entry.create_instance(&info, None) }.map_err(|e| match e {
        vk::Result::ERROR_INCOMPATIBLE_DRIVER => GpuError::NoDevice("no Vulkan driver".into()),
        vk::Result::ERROR_LAYER_NOT_PRESENT => GpuError::NoDevice(
            "VK_LAYER_KHRONOS_validation is missing: install vulkan-validationlayers".into(),
        ),
        result => GpuError::Vulkan {
            call: "vkCreateInstance",
            result,
        },
    })
}

fn create_messenger(
    entry: &ash::Entry,
    instance: &ash::Instance,
    log: &Arc<ValidationLog>,
) -> Result<Messenger, GpuError> {
    let loader = ash::ext::debug_utils::Instance::new(entry, instance);
    let info = vk::DebugUtilsMessengerCreateInfoEXT::default()
        .message_severity(
            vk::DebugUtilsMessageSeverityFlagsEXT::ERROR
                | vk::DebugUtilsMessageSeverityFlagsEXT::WARNING,
        )
        .message_type(
            vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION
                | vk::DebugUtilsMessageTypeFlagsEXT::GENERAL,
        )
        .pfn_user_callback(Some(on_validation_message))
        .user_data(Arc::as_ptr(log) as *mut c_void);
    // SAFETY: the callback's user data (the Arc) outlives the messenger (kept in Messenger).
    let raw = unsafe { loader.create_debug_utils_messenger(&info, None) }
        .vk("vkCreateDebugUtilsMessengerEXT")?;
    Ok(Messenger {
        loader,
        raw,
        _log: log.clone(),
    })
}

fn device_name(instance: &ash::Instance, physical: vk::PhysicalDevice) -> String {
    // SAFETY: physical is a handle enumerated from this instance.
    let props = unsafe { instance.get_physical_device_properties(physical) };
    props
        .device_name_as_c_str()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|_| "unknown device".into())
}

fn create_allocator(
    instance: &ash::Instance,
    device: &ash::Device,
    physical: vk::PhysicalDevice,
) -> Result<Allocator, GpuError> {
    let mut debug_settings = gpu_allocator::AllocatorDebugSettings::default();
    debug_settings.log_leaks_on_shutdown = false;
    Ok(Allocator::new(&AllocatorCreateDesc {
        instance: instance.clone(),
        device: device.clone(),
        physical_device: physical,
        debug_settings,
        buffer_device_address: false,
        allocation_sizes: Default::default(),
    })?)
}

impl GpuDevice {
    /// Whether the device is a CPU driver (lavapipe, SwiftShader).
    pub fn is_cpu(&self) -> bool {
        // SAFETY: physical belongs to this instance.
        let props = unsafe { self.instance.get_physical_device_properties(self.physical) };
        props.device_type == vk::PhysicalDeviceType::CPU
    }

    /// Whether this is the app's device and queue (borrowed), whose submits the runtime's
    /// share (`app_queue`).
    pub fn is_the_apps(&self) -> bool {
        self.owned.is_none()
    }

    /// Creates an instance and a device of its own (Vulkan 1.1, one compute queue).
    pub fn create(options: &DeviceOptions) -> Result<GpuDevice, GpuError> {
        GpuDevice::create_with(load_entry()?, options)
    }

    /// Creates an instance and a device of its own through `entry`'s Vulkan loader.
    fn create_with(entry: ash::Entry, options: &DeviceOptions) -> Result<GpuDevice, GpuError> {
        let instance = create_instance(&entry, options.validation)?;
        let log = options
            .validation
            .then(|| Arc::new(ValidationLog::default()));
        let messenger = match &log {
            Some(log) => Some(create_messenger(&entry, &instance, log)?),
            None => None,
        };
        // From here on, a failure must destroy the instance: build the device in a helper.
        match Self::create_device(&entry, &instance, options) {
            Ok((physical, device, family, statistics)) => {
                let allocator = match create_allocator(&instance, &device, physical) {
                    Ok(a) => a,
                    Err(e) => {
                        // SAFETY: the device was just created and has no children.
                        unsafe { device.destroy_device(None) };
                        Self::destroy_instance(&instance, messenger);
                        return Err(e);
                    }
                };
                let handles = (entry, instance, physical, device, allocator);
                // SAFETY: the device was created with one queue of `family`.
                let mut gpu = unsafe { Self::assemble(handles, family, 0) };
                gpu.validation = log;
                gpu.shader_statistics = statistics;
                gpu.owned = Some(Owned {
                    messenger,
                    instance: true,
                    _libraries: None,
                });
                Ok(gpu)
            }
            Err(e) => {
                Self::destroy_instance(&instance, messenger);
                Err(e)
            }
        }
    }

    /// A device of its own beside `app`'s: an instance of its own, made through the app's
    /// Vulkan loader (never another copy), on a physical device of the same kind, with one
    /// compute queue. Nothing of it belongs to the app's instance, so it may outlive the app's
    /// device and instance: a CPU driver's compile in flight on it is left to finish on its own
    /// at the session's end (gpu/vulkan/frame/warm_up.rs). Drop destroys the device and the instance.
    pub fn create_beside(app: &GpuDevice) -> Result<GpuDevice, GpuError> {
        let options = DeviceOptions {
            matching: Some(DeviceKind::of(app)),
            ..DeviceOptions::default()
        };
        let mut gpu = GpuDevice::create_with(app.entry.clone(), &options)?;
        let functions = [
            gpu.entry.static_fn().get_instance_proc_addr as *const c_void,
            gpu.instance.fp_v1_0().destroy_instance as *const c_void,
            gpu.device.fp_v1_0().destroy_device as *const c_void,
        ];
        if let Some(owned) = gpu.owned.as_mut() {
            owned._libraries = Some(PinnedLibraries::of(&functions));
        }
        Ok(gpu)
    }

    /// The GPU may still be using this device's memory or objects (a wait for it timed out):
    /// Drop then leaves everything alive rather than free what is in use.
    pub fn abandon(&mut self) {
        self.abandoned = true;
    }

    /// Destroys an instance this object created (and its messenger) after a failed set-up.
    fn destroy_instance(instance: &ash::Instance, messenger: Option<Messenger>) {
        if let Some(m) = messenger {
            // SAFETY: the messenger was created from this instance and is unused.
            unsafe { m.loader.destroy_debug_utils_messenger(m.raw, None) };
        }
        // SAFETY: the instance has no children left.
        unsafe { instance.destroy_instance(None) };
    }

    fn create_device(
        entry: &ash::Entry,
        instance: &ash::Instance,
        options: &DeviceOptions,
    ) -> Result<(vk::PhysicalDevice, ash::Device, u32, bool), GpuError> {
        let _ = entry;
        // SAFETY: instance is a valid instance.
        let physicals =
            unsafe { instance.enumerate_physical_devices() }.vk("vkEnumeratePhysicalDevices")?;
        let index = match &options.matching {
            Some(key) => physicals
                .iter()
                .position(|&p| DeviceKind::of_physical(instance, p) == *key)
                .ok_or_else(|| GpuError::NoDevice("no device of the wanted kind".into()))?,
            None => options.index,
        };
        let physical = *physicals.get(index).ok_or_else(|| {
            GpuError::NoDevice(format!(
                "{} Vulkan devices, asked for #{index}",
                physicals.len()
            ))
        })?;
        // SAFETY: physical was enumerated from this instance.
        let props = unsafe { instance.get_physical_device_properties(physical) };
        if props.api_version < vk::API_VERSION_1_1 {
            return Err(GpuError::NoDevice(
                "the device supports only Vulkan 1.0".into(),
            ));
        }
        let (device, family, statistics) =
            create_compute_device(instance, physical, options.shader_statistics)?;
        Ok((physical, device, family, statistics))
    }

    /// Wraps a device that belongs to someone else (the app's, in the layer). Nothing of it is
    /// destroyed on drop; only the allocator's memory is freed.
    ///
    /// `entry` is the app's own Vulkan loader (the layer never loads another).
    ///
    /// # Safety
    /// The handles must be valid, belong together, come from `entry`'s loader and outlive this
    /// object; `queue_family` and `queue_index` must name a queue the device was created with.
    pub unsafe fn borrow(
        entry: ash::Entry,
        raw_instance: vk::Instance,
        physical: vk::PhysicalDevice,
        raw_device: vk::Device,
        queue_family: u32,
        queue_index: u32,
    ) -> Result<GpuDevice, GpuError> {
        crate::fault::check("device-setup").map_err(GpuError::Unsupported)?;
        // SAFETY: the caller guarantees the instance handle is valid.
        let instance = unsafe { ash::Instance::load(entry.static_fn(), raw_instance) };
        // SAFETY: the caller guarantees the device handle is valid and from this instance.
        let device = unsafe { ash::Device::load(instance.fp_v1_0(), raw_device) };
        let allocator = create_allocator(&instance, &device, physical)?;
        let handles = (entry, instance, physical, device, allocator);
        // SAFETY: the caller guarantees the family and index exist on this device.
        Ok(unsafe { Self::assemble(handles, queue_family, queue_index) })
    }

    /// The object around handles (borrowed: no validation log, nothing owned).
    ///
    /// # Safety
    /// `queue_family` and `queue_index` must name a queue the device was created with.
    unsafe fn assemble(
        (entry, instance, physical, device, allocator): (
            ash::Entry,
            ash::Instance,
            vk::PhysicalDevice,
            ash::Device,
            Allocator,
        ),
        queue_family: u32,
        queue_index: u32,
    ) -> GpuDevice {
        // SAFETY: guaranteed by the caller.
        let queue = unsafe { device.get_device_queue(queue_family, queue_index) };
        GpuDevice {
            name: device_name(&instance, physical),
            entry,
            instance,
            physical,
            device,
            queue,
            queue_family,
            allocator: ManuallyDrop::new(Mutex::new(allocator)),
            validation: None,
            shader_statistics: false,
            owned: None,
            abandoned: false,
        }
    }

    /// Validation errors seen so far (0 when validation is off).
    pub fn validation_errors(&self) -> u32 {
        self.validation
            .as_ref()
            .map_or(0, |v| v.errors.load(Ordering::Relaxed))
    }

    /// Whether the queue the engine records for supports compute work (an app may hand the
    /// layer a graphics-only or transfer-only queue family).
    pub fn queue_has_compute(&self) -> Result<(), GpuError> {
        // The fault point makes the real failure, message included.
        let injected = crate::fault::check("queue-without-compute").is_err();
        // SAFETY: physical belongs to this instance.
        let families = unsafe {
            self.instance
                .get_physical_device_queue_family_properties(self.physical)
        };
        let flags = families
            .get(self.queue_family as usize)
            .map_or(vk::QueueFlags::empty(), |f| f.queue_flags);
        if flags.contains(vk::QueueFlags::COMPUTE) && !injected {
            return Ok(());
        }
        Err(GpuError::Unsupported(format!(
            "the app's queue family {} has no compute support",
            self.queue_family
        )))
    }

    /// Nanoseconds per timestamp tick.
    pub fn timestamp_period(&self) -> f32 {
        // SAFETY: physical belongs to this instance.
        unsafe { self.instance.get_physical_device_properties(self.physical) }
            .limits
            .timestamp_period
    }
}

impl Drop for GpuDevice {
    fn drop(&mut self) {
        if self.abandoned {
            return;
        }
        // SAFETY: the allocator is dropped exactly once, here, before the device it uses.
        unsafe { ManuallyDrop::drop(&mut self.allocator) };
        let Some(owned) = self.owned.take() else {
            return;
        };
        // SAFETY: this object created the device (and the instance and messenger where
        // `owned` says so); the engine objects built on them were destroyed by their owners
        // before (they borrow this device).
        unsafe {
            self.device.destroy_device(None);
            if let Some(m) = owned.messenger {
                m.loader.destroy_debug_utils_messenger(m.raw, None);
            }
            if owned.instance {
                self.instance.destroy_instance(None);
            }
        }
    }
}

/// A kind of device: its vendor, device and pipelineCacheUUID (which changes with the driver).
/// What a pipeline cache's data belongs to, and how a device of the same kind is found.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct DeviceKind {
    pub vendor: u32,
    pub device: u32,
    pub uuid: [u8; vk::UUID_SIZE],
}

impl DeviceKind {
    pub fn of(gpu: &GpuDevice) -> DeviceKind {
        DeviceKind::of_physical(&gpu.instance, gpu.physical)
    }

    pub fn of_physical(instance: &ash::Instance, physical: vk::PhysicalDevice) -> DeviceKind {
        // SAFETY: the caller passes a physical device of this instance.
        let p = unsafe { instance.get_physical_device_properties(physical) };
        DeviceKind {
            vendor: p.vendor_id,
            device: p.device_id,
            uuid: p.pipeline_cache_uuid,
        }
    }
}
