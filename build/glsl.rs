//! GLSL writing for the OpenGL backend: a parsed shader's entry point as GLSL 4.50 (core) by
//! naga, every resource at the binding point BINDINGS gives it, checked against
//! src/gpu/core/interface.rs (build/check.rs), written to OUT_DIR as `<file>.glsl`.

use std::{fs, path::Path};

use crate::check::{check_gl_binding, gl_uniform_param};
use crate::interface::*;
use crate::parse::{Parsed, BOUNDS};
use crate::tables::GlUniform;

/// The GLSL version the OpenGL backend's programs are written in (core profile): 4.50, the
/// first with `mix` of integer vectors by a boolean vector, which naga writes for WGSL's
/// `select` on them.
const GLSL_VERSION: u16 = 450;

/// The GLSL of `entry`, with every resource at the binding point BINDINGS gives it, checked
/// against src/gpu/core/interface.rs: every uniform naga made of the push constants is a
/// PARAMS field (by name, at its PARAMS offset, of its type), and every resource the entry
/// uses is declared at its binding.
pub fn glsl(parsed: &Parsed, entry: &str) -> (String, Vec<GlUniform>) {
    let here = format!(
        "{}.wgsl entry {entry} (GLSL) vs src/gpu/core/interface.rs",
        parsed.name
    );
    let binding_map = BINDINGS
        .iter()
        .map(|b| {
            let rb = naga::ResourceBinding {
                group: 0,
                binding: b.number,
            };
            (
                rb,
                u8::try_from(b.number).expect("a GL binding point below 256"),
            )
        })
        .collect();
    let options = naga::back::glsl::Options {
        version: naga::back::glsl::Version::Desktop(GLSL_VERSION),
        writer_flags: naga::back::glsl::WriterFlags::empty(),
        binding_map,
        zero_initialize_workgroup_memory: true,
    };
    let pipeline = naga::back::glsl::PipelineOptions {
        shader_stage: naga::ShaderStage::Compute,
        entry_point: entry.to_string(),
        multiview: None,
    };
    let mut text = String::new();
    let mut writer = naga::back::glsl::Writer::new(
        &mut text,
        &parsed.module,
        &parsed.info,
        &options,
        &pipeline,
        BOUNDS,
    )
    .unwrap_or_else(|e| panic!("{here}: {e}"));
    let reflection = writer.write().unwrap_or_else(|e| panic!("{here}: {e}"));
    let mut uniforms = Vec::new();
    for item in &reflection.immediates_items {
        let path = &item.access_path;
        let (k, offset) = gl_uniform_param(&here, path, item.offset);
        let (_, ty) = PARAMS[k];
        use naga::back::glsl::{GlslScalarKind as S, GlslUniformType as U};
        let kind = match (ty, item.ty) {
            (ParamType::U32, U::Scalar(s)) if s.kind == S::Uint => "U32",
            (ParamType::F32, U::Scalar(s)) if s.kind == S::Float => "F32",
            (ParamType::Vec2U32, U::Vector { scalar, .. }) if scalar.kind == S::Uint => "UVec2",
            (ParamType::Vec4F32Array(_), U::Vector { scalar, .. }) if scalar.kind == S::Float => {
                "Vec4"
            }
            (ty, glsl) => panic!("{here}: `{path}` is {glsl:?} in the GLSL, {ty:?} in PARAMS"),
        };
        uniforms.push(GlUniform {
            path: path.clone(),
            offset,
            kind,
        });
    }
    let ep = parsed
        .module
        .entry_points
        .iter()
        .position(|e| e.name == entry)
        .expect("the entry point");
    let used = parsed.info.get_entry_point(ep);
    for (handle, var) in parsed.module.global_variables.iter() {
        let (Some(rb), false) = (&var.binding, used[handle].is_empty()) else {
            continue;
        };
        let name = var.name.as_deref().unwrap_or("?");
        check_gl_binding(&here, &text, name, rb.binding);
    }
    (text, uniforms)
}

/// Writes `out/<file>.glsl`, `entry` of the parsed shader; the Params uniforms it declares.
pub fn write_glsl(out: &Path, file: &str, parsed: &Parsed, entry: &str) -> Vec<GlUniform> {
    let (text, uniforms) = glsl(parsed, entry);
    fs::write(out.join(format!("{file}.glsl")), text).unwrap();
    uniforms
}
