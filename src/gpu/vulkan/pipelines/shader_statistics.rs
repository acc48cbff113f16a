//! What the driver's compiler says of a compute shader's pipeline, through
//! VK_KHR_pipeline_executable_properties: registers, instructions, spills, occupancy, by the
//! names and in the units each driver gives them. For `contrastxr bench --shader-stats`, to see
//! where a GPU's time goes without a profiler.

use super::pipeline_set::create_compute_pipeline;
use crate::gpu::core::modules::ShaderModule;
use crate::gpu::vulkan::device::{GpuDevice, GpuError, VkResultExt};
use ash::vk;

/// One executable of a pipeline (a compute pipeline usually has one) and its statistics,
/// (name, value) as the driver reports them.
#[derive(Clone, Debug, PartialEq)]
pub struct ExecutableStatistics {
    pub executable: String,
    /// The executable's subgroup size (0 where the driver does not say).
    pub subgroup_size: u32,
    pub statistics: Vec<(String, String)>,
}

/// The statistics of `shader` compiled as a compute pipeline with `layout`, on a device made
/// with [`GpuDevice::shader_statistics`]; an error where it was not.
pub fn shader_statistics(
    gpu: &GpuDevice,
    layout: vk::PipelineLayout,
    shader: &ShaderModule,
) -> Result<Vec<ExecutableStatistics>, GpuError> {
    if !gpu.shader_statistics {
        return Err(GpuError::Unsupported(
            "the device does not report its compiler's statistics \
             (VK_KHR_pipeline_executable_properties)"
                .into(),
        ));
    }
    // No pipeline cache: a cached pipeline may come back without its statistics.
    let flags = vk::PipelineCreateFlags::CAPTURE_STATISTICS_KHR;
    let no_cache = (vk::PipelineCache::null(), layout);
    let pipeline = create_compute_pipeline(&gpu.device, no_cache, shader, flags)?;
    let result = read_statistics(gpu, pipeline);
    // SAFETY: the pipeline was never bound to a command buffer.
    unsafe { gpu.device.destroy_pipeline(pipeline, None) };
    result
}

fn read_statistics(
    gpu: &GpuDevice,
    pipeline: vk::Pipeline,
) -> Result<Vec<ExecutableStatistics>, GpuError> {
    let ext = ash::khr::pipeline_executable_properties::Device::new(&gpu.instance, &gpu.device);
    let info = vk::PipelineInfoKHR::default().pipeline(pipeline);
    // SAFETY: the pipeline was created with CAPTURE_STATISTICS on this device.
    let executables = unsafe { ext.get_pipeline_executable_properties(&info) }
        .vk("vkGetPipelineExecutablePropertiesKHR")?;
    let mut all = Vec::new();
    for (index, props) in executables.iter().enumerate() {
        let which = vk::PipelineExecutableInfoKHR::default()
            .pipeline(pipeline)
            .executable_index(index as u32);
        // SAFETY: index is one of the pipeline's executables.
        let statistics = unsafe { ext.get_pipeline_executable_statistics(&which) }
            .vk("vkGetPipelineExecutableStatisticsKHR")?;
        all.push(ExecutableStatistics {
            executable: text(props.name_as_c_str()),
            subgroup_size: props.subgroup_size,
            statistics: statistics
                .iter()
                .map(|s| (text(s.name_as_c_str()), value(s)))
                .collect(),
        });
    }
    Ok(all)
}

fn text(name: Result<&std::ffi::CStr, std::ffi::FromBytesUntilNulError>) -> String {
    name.map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default()
}

fn value(s: &vk::PipelineExecutableStatisticKHR) -> String {
    // SAFETY: the union's member is the one `format` names (the extension's contract).
    unsafe {
        match s.format {
            vk::PipelineExecutableStatisticFormatKHR::BOOL32 => (s.value.b32 != 0).to_string(),
            vk::PipelineExecutableStatisticFormatKHR::INT64 => s.value.i64.to_string(),
            vk::PipelineExecutableStatisticFormatKHR::UINT64 => s.value.u64.to_string(),
            vk::PipelineExecutableStatisticFormatKHR::FLOAT64 => s.value.f64.to_string(),
            _ => "?".into(),
        }
    }
}
