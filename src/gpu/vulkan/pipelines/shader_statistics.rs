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
    pub statistics: Vec<(String, StatisticValue)>,
}

/// A statistic's value, in the type the driver gives it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum StatisticValue {
    Bool(bool),
    Int(i64),
    Uint(u64),
    Float(f64),
    /// A format the extension did not define when this was written.
    Unknown,
}

impl std::fmt::Display for StatisticValue {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            StatisticValue::Bool(b) => write!(f, "{b}"),
            StatisticValue::Int(i) => write!(f, "{i}"),
            StatisticValue::Uint(u) => write!(f, "{u}"),
            StatisticValue::Float(x) => write!(f, "{x}"),
            StatisticValue::Unknown => f.write_str("?"),
        }
    }
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

fn value(s: &vk::PipelineExecutableStatisticKHR) -> StatisticValue {
    use vk::PipelineExecutableStatisticFormatKHR as Format;
    // SAFETY: the union's member is the one `format` names (the extension's contract).
    unsafe {
        match s.format {
            Format::BOOL32 => StatisticValue::Bool(s.value.b32 != 0),
            Format::INT64 => StatisticValue::Int(s.value.i64),
            Format::UINT64 => StatisticValue::Uint(s.value.u64),
            Format::FLOAT64 => StatisticValue::Float(s.value.f64),
            _ => StatisticValue::Unknown,
        }
    }
}
