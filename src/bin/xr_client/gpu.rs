//! The client's Vulkan instance and device, created through XR_KHR_vulkan_enable2 so the runtime
//! adds what it needs, plus the one command buffer and fence the frame loop uses.

use ash::vk::{self, Handle};
use openxr as xr;

use crate::error::{fail, Context, Result};
use crate::validation;

const VALIDATION_LAYER: &std::ffi::CStr = c"VK_LAYER_KHRONOS_validation";

pub struct Gpu {
    pub instance: ash::Instance,
    pub physical_device: vk::PhysicalDevice,
    pub device: ash::Device,
    pub queue_family_index: u32,
    queue: vk::Queue,
    command_pool: vk::CommandPool,
    command_buffer: vk::CommandBuffer,
    fence: vk::Fence,
    debug: Option<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>,
    /// Kept alive: the instance's function pointers come from this loader.
    _entry: ash::Entry,
}

impl Gpu {
    pub fn new(xr_instance: &xr::Instance, system: xr::SystemId, validation: bool) -> Result<Gpu> {
        let reqs = xr_instance
            .graphics_requirements::<xr::Vulkan>(system)
            .ctx("xrGetVulkanGraphicsRequirements2KHR")?;
        if reqs.min_api_version_supported > xr::Version::new(1, 1, 0) {
            return fail(format!(
                "the runtime needs Vulkan {} or newer; the client uses 1.1",
                reqs.min_api_version_supported
            ));
        }
        // SAFETY: loads the system Vulkan loader; nothing else in this process loaded another one.
        let entry = unsafe { ash::Entry::load() }.ctx("loading libvulkan")?;
        let instance = create_instance(&entry, xr_instance, system, validation)?;
        let debug = validation
            .then(|| create_messenger(&entry, &instance))
            .transpose()?;
        // SAFETY: the instance was created through the runtime for this system.
        let raw =
            unsafe { xr_instance.vulkan_graphics_device(system, instance.handle().as_raw() as _) }
                .ctx("xrGetVulkanGraphicsDevice2KHR")?;
        let physical_device = vk::PhysicalDevice::from_raw(raw as _);
        let queue_family_index = graphics_queue_family(&instance, physical_device)?;
        let device = create_device(
            &entry,
            &instance,
            xr_instance,
            system,
            physical_device,
            queue_family_index,
        )?;
        let mut gpu = Gpu {
            instance,
            physical_device,
            device,
            queue_family_index,
            queue: vk::Queue::null(),
            command_pool: vk::CommandPool::null(),
            command_buffer: vk::CommandBuffer::null(),
            fence: vk::Fence::null(),
            debug,
            _entry: entry,
        };
        gpu.create_frame_objects()?;
        Ok(gpu)
    }

    fn create_frame_objects(&mut self) -> Result<()> {
        let pool_info = vk::CommandPoolCreateInfo::default()
            .queue_family_index(self.queue_family_index)
            .flags(vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER);
        // SAFETY: the device is valid; every object made here is destroyed in Drop.
        unsafe {
            self.queue = self.device.get_device_queue(self.queue_family_index, 0);
            self.command_pool = self
                .device
                .create_command_pool(&pool_info, None)
                .ctx("vkCreateCommandPool")?;
            let alloc = vk::CommandBufferAllocateInfo::default()
                .command_pool(self.command_pool)
                .command_buffer_count(1);
            self.command_buffer = self
                .device
                .allocate_command_buffers(&alloc)
                .ctx("vkAllocateCommandBuffers")?[0];
            self.fence = self
                .device
                .create_fence(&vk::FenceCreateInfo::default(), None)
                .ctx("vkCreateFence")?;
        }
        Ok(())
    }

    pub fn session_create_info(&self) -> xr::vulkan::SessionCreateInfo {
        xr::vulkan::SessionCreateInfo {
            instance: self.instance.handle().as_raw() as _,
            physical_device: self.physical_device.as_raw() as _,
            device: self.device.handle().as_raw() as _,
            queue_family_index: self.queue_family_index,
            queue_index: 0,
        }
    }

    /// Waits until the queue has run everything submitted to it, including what a layer
    /// submitted inside xrEndFrame (for --timing).
    pub fn wait_idle(&self) -> Result<()> {
        // SAFETY: the queue is the client's; no other thread uses it during this call.
        unsafe { self.device.queue_wait_idle(self.queue) }.ctx("vkQueueWaitIdle")
    }

    /// Records commands with `record`, submits them and waits until the GPU has run them, so the
    /// images they write can be released to the runtime right after.
    pub fn submit_and_wait(
        &self,
        record: impl FnOnce(&ash::Device, vk::CommandBuffer),
    ) -> Result<()> {
        let cmd = self.command_buffer;
        let begin = vk::CommandBufferBeginInfo::default()
            .flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT);
        let commands = [cmd];
        let submit = vk::SubmitInfo::default().command_buffers(&commands);
        // SAFETY: the command buffer is not in use (the previous submission was waited for), and
        // the fence is unsignalled (reset after each wait).
        unsafe {
            self.device
                .begin_command_buffer(cmd, &begin)
                .ctx("vkBeginCommandBuffer")?;
            record(&self.device, cmd);
            self.device
                .end_command_buffer(cmd)
                .ctx("vkEndCommandBuffer")?;
            self.device
                .queue_submit(self.queue, &[submit], self.fence)
                .ctx("vkQueueSubmit")?;
            self.device
                .wait_for_fences(&[self.fence], true, u64::MAX)
                .ctx("vkWaitForFences")?;
            self.device
                .reset_fences(&[self.fence])
                .ctx("vkResetFences")?;
        }
        Ok(())
    }

    /// A host-visible, coherent memory type among `type_bits`.
    pub fn host_memory_type(&self, type_bits: u32) -> Result<u32> {
        let wanted = vk::MemoryPropertyFlags::HOST_VISIBLE | vk::MemoryPropertyFlags::HOST_COHERENT;
        // SAFETY: the physical device belongs to this instance.
        let props = unsafe {
            self.instance
                .get_physical_device_memory_properties(self.physical_device)
        };
        (0..props.memory_type_count)
            .find(|&i| {
                type_bits & (1 << i) != 0
                    && props.memory_types[i as usize]
                        .property_flags
                        .contains(wanted)
            })
            .map_or_else(
                || fail("no host-visible coherent memory type for the staging buffer"),
                Ok,
            )
    }

    /// Makes one call the validation layer must report (a zero-sized buffer), to prove that
    /// validation messages are seen.
    pub fn provoke_validation_error(&self) {
        let info = vk::BufferCreateInfo::default()
            .size(0)
            .usage(vk::BufferUsageFlags::TRANSFER_SRC);
        // SAFETY: invalid on purpose (VUID-VkBufferCreateInfo-size-00912); drivers accept it and
        // the buffer, if any, is destroyed at once.
        unsafe {
            if let Ok(buffer) = self.device.create_buffer(&info, None) {
                self.device.destroy_buffer(buffer, None);
            }
        }
    }
}

impl Gpu {
    /// Records two writes of one buffer with no barrier between them: synchronisation
    /// validation must report SYNC-HAZARD-WRITE-AFTER-WRITE (core validation does not).
    pub fn provoke_sync_hazard(&self) -> Result<()> {
        let info = vk::BufferCreateInfo::default()
            .size(256)
            .usage(vk::BufferUsageFlags::TRANSFER_DST);
        // SAFETY: a valid buffer bound to fresh memory; both are destroyed after the wait.
        unsafe {
            let buffer = self
                .device
                .create_buffer(&info, None)
                .ctx("vkCreateBuffer")?;
            let reqs = self.device.get_buffer_memory_requirements(buffer);
            let alloc = vk::MemoryAllocateInfo::default()
                .allocation_size(reqs.size)
                .memory_type_index(self.host_memory_type(reqs.memory_type_bits)?);
            let memory = self
                .device
                .allocate_memory(&alloc, None)
                .ctx("vkAllocateMemory")?;
            self.device
                .bind_buffer_memory(buffer, memory, 0)
                .ctx("vkBindBufferMemory")?;
            let result = self.submit_and_wait(|device, cmd| {
                device.cmd_fill_buffer(cmd, buffer, 0, 256, 1);
                device.cmd_fill_buffer(cmd, buffer, 0, 256, 2);
            });
            self.device.destroy_buffer(buffer, None);
            self.device.free_memory(memory, None);
            result
        }
    }
}

impl Gpu {
    /// Creates a buffer and never destroys it: validation must report it when the device is
    /// destroyed (what the session-cycle test relies on to see the layer's leaks).
    pub fn provoke_leak(&self) -> Result<()> {
        let info = vk::BufferCreateInfo::default()
            .size(256)
            .usage(vk::BufferUsageFlags::TRANSFER_DST);
        // SAFETY: a valid create info; leaking the buffer is the point.
        unsafe { self.device.create_buffer(&info, None) }.ctx("vkCreateBuffer")?;
        Ok(())
    }
}

impl Drop for Gpu {
    fn drop(&mut self) {
        // SAFETY: the OpenXR session using this device is gone (main drops it first) and the
        // device is idle after vkDeviceWaitIdle; all objects here were created by the client.
        unsafe {
            let _ = self.device.device_wait_idle();
            self.device.destroy_fence(self.fence, None);
            self.device.destroy_command_pool(self.command_pool, None);
            self.device.destroy_device(None);
            if let Some((debug_utils, messenger)) = &self.debug {
                debug_utils.destroy_debug_utils_messenger(*messenger, None);
            }
            self.instance.destroy_instance(None);
        }
    }
}

fn create_instance(
    entry: &ash::Entry,
    xr_instance: &xr::Instance,
    system: xr::SystemId,
    validation: bool,
) -> Result<ash::Instance> {
    if validation && !has_validation_layer(entry)? {
        return fail("--validation: VK_LAYER_KHRONOS_validation is not installed (package vulkan-validationlayers)");
    }
    let app_info = vk::ApplicationInfo::default()
        .application_name(c"contrastxr-xr-client")
        .api_version(vk::API_VERSION_1_1);
    let layers = [VALIDATION_LAYER.as_ptr()];
    let extensions = [ash::ext::debug_utils::NAME.as_ptr()];
    let mut messenger = validation::messenger_info();
    let mut info = vk::InstanceCreateInfo::default().application_info(&app_info);
    if validation {
        info = info
            .enabled_layer_names(&layers)
            .enabled_extension_names(&extensions)
            .push_next(&mut messenger);
    }
    // SAFETY: the create info and everything it points to outlive the call; the runtime calls
    // vkCreateInstance through the loader's vkGetInstanceProcAddr that we pass it.
    let raw = unsafe {
        xr_instance.create_vulkan_instance(
            system,
            std::mem::transmute::<
                vk::PFN_vkGetInstanceProcAddr,
                xr::sys::platform::VkGetInstanceProcAddr,
            >(crate::gipa::counting(entry)),
            &info as *const _ as *const _,
        )
    }
    .ctx("xrCreateVulkanInstanceKHR")?
    .map_err(vk::Result::from_raw)
    .ctx("vkCreateInstance (through the runtime)")?;
    // SAFETY: `raw` is a live VkInstance created with this entry's loader.
    Ok(unsafe { ash::Instance::load(entry.static_fn(), vk::Instance::from_raw(raw as _)) })
}

fn has_validation_layer(entry: &ash::Entry) -> Result<bool> {
    // SAFETY: a plain query of the loader.
    let layers = unsafe { entry.enumerate_instance_layer_properties() }
        .ctx("vkEnumerateInstanceLayerProperties")?;
    Ok(layers
        .iter()
        .any(|l| l.layer_name_as_c_str() == Ok(VALIDATION_LAYER)))
}

fn create_messenger(
    entry: &ash::Entry,
    instance: &ash::Instance,
) -> Result<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)> {
    let debug_utils = ash::ext::debug_utils::Instance::new(entry, instance);
    // SAFETY: VK_EXT_debug_utils was enabled on this instance (validation mode only).
    let messenger =
        unsafe { debug_utils.create_debug_utils_messenger(&validation::messenger_info(), None) }
            .ctx("vkCreateDebugUtilsMessengerEXT")?;
    Ok((debug_utils, messenger))
}

fn graphics_queue_family(
    instance: &ash::Instance,
    physical_device: vk::PhysicalDevice,
) -> Result<u32> {
    // SAFETY: the physical device belongs to this instance.
    let families = unsafe { instance.get_physical_device_queue_family_properties(physical_device) };
    families
        .iter()
        .position(|f| f.queue_flags.contains(vk::QueueFlags::GRAPHICS))
        .map_or_else(
            || fail("the Vulkan device has no graphics queue"),
            |i| Ok(i as u32),
        )
}

fn create_device(
    entry: &ash::Entry,
    instance: &ash::Instance,
    xr_instance: &xr::Instance,
    system: xr::SystemId,
    physical_device: vk::PhysicalDevice,
    queue_family_index: u32,
) -> Result<ash::Device> {
    let priorities = [1.0];
    let queues = [vk::DeviceQueueCreateInfo::default()
        .queue_family_index(queue_family_index)
        .queue_priorities(&priorities)];
    let info = vk::DeviceCreateInfo::default().queue_create_infos(&queues);
    // SAFETY: as for the instance: the create info outlives the call.
    let raw = unsafe {
        xr_instance.create_vulkan_device(
            system,
            std::mem::transmute::<
                vk::PFN_vkGetInstanceProcAddr,
                xr::sys::platform::VkGetInstanceProcAddr,
            >(crate::gipa::counting(entry)),
            physical_device.as_raw() as _,
            &info as *const _ as *const _,
        )
    }
    .ctx("xrCreateVulkanDeviceKHR")?
    .map_err(vk::Result::from_raw)
    .ctx("vkCreateDevice (through the runtime)")?;
    // SAFETY: `raw` is a live VkDevice of this instance.
    Ok(unsafe { ash::Device::load(instance.fp_v1_0(), vk::Device::from_raw(raw as _)) })
}
