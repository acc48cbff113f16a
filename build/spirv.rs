//! SPIR-V writing: a parsed shader's entry point as SPIR-V 1.0 by naga, rewritten for Vulkan
//! 1.0 storage buffers (build/spirv_patch.rs), written to OUT_DIR as `<file>.spv`.

use std::{fs, path::Path};

use crate::parse::{Parsed, BOUNDS};
use crate::spirv_patch::storage_buffers_to_vulkan10;

/// The SPIR-V words of `entry` of `stage`, as naga writes them.
pub fn spirv_stage(parsed: &Parsed, entry: &str, stage: naga::ShaderStage) -> Vec<u32> {
    let options = naga::back::spv::Options {
        // SPIR-V 1.0: apps may create Vulkan 1.0 instances (hello_xr does).
        lang_version: (1, 0),
        flags: naga::back::spv::WriterFlags::empty(),
        force_loop_bounding: false,
        bounds_check_policies: BOUNDS,
        ..Default::default()
    };
    let pipeline = naga::back::spv::PipelineOptions {
        shader_stage: stage,
        entry_point: entry.to_string(),
    };
    naga::back::spv::write_vec(&parsed.module, &parsed.info, &options, Some(&pipeline))
        .unwrap_or_else(|e| panic!("{}.wgsl entry {entry}: {e}", parsed.name))
}

/// Writes `out/<file>.spv`: the compute entry point `entry` in the Vulkan 1.0 form.
pub fn write_spirv(out: &Path, file: &str, parsed: &Parsed, entry: &str) {
    write_spirv_stage(out, file, parsed, (entry, naga::ShaderStage::Compute));
}

/// Writes `out/<file>.spv`: `entry` of `stage` in the Vulkan 1.0 form.
pub fn write_spirv_stage(
    out: &Path,
    file: &str,
    parsed: &Parsed,
    (entry, stage): (&str, naga::ShaderStage),
) {
    let words = storage_buffers_to_vulkan10(spirv_stage(parsed, entry, stage));
    let bytes: Vec<u8> = words.iter().flat_map(|w| w.to_le_bytes()).collect();
    fs::write(out.join(format!("{file}.spv")), bytes).unwrap();
}
