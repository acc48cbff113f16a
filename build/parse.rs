//! A shader's WGSL parsed and validated by naga, and checked against the interface
//! (build/check.rs) from the facts read here of naga's module: both back ends (SPIR-V for
//! Vulkan, GLSL for OpenGL) write from the same module.

use crate::check::{check_interface, Global, Member, ShaderFacts};
use crate::interface::BindingKind;

/// A shader parsed, validated and checked against src/gpu/core/interface.rs.
pub struct Parsed {
    pub name: String,
    pub module: naga::Module,
    pub info: naga::valid::ModuleInfo,
}

/// Out-of-bounds reads give zero, out-of-bounds writes are skipped (the narrow access reads
/// up to three words past a region's last pixel).
pub const BOUNDS: naga::proc::BoundsCheckPolicies = naga::proc::BoundsCheckPolicies {
    index: naga::proc::BoundsCheckPolicy::ReadZeroSkipWrite,
    buffer: naga::proc::BoundsCheckPolicy::ReadZeroSkipWrite,
    image_load: naga::proc::BoundsCheckPolicy::ReadZeroSkipWrite,
    binding_array: naga::proc::BoundsCheckPolicy::ReadZeroSkipWrite,
};

/// Parses and validates `source` (`name`.wgsl in messages) and checks it against the interface.
pub fn parse(name: &str, source: &str) -> Parsed {
    let parsed = parse_own(name, source);
    check_interface(name, &facts(&parsed.module));
    parsed
}

/// Parses and validates a shader with bindings of its own (not the compute passes' interface).
pub fn parse_own(name: &str, source: &str) -> Parsed {
    let module = naga::front::wgsl::parse_str(source)
        .unwrap_or_else(|e| panic!("{name}.wgsl: {}", e.emit_to_string(source)));
    let info = naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::IMMEDIATES
            | naga::valid::Capabilities::SHADER_FLOAT16_IN_FLOAT32,
    )
    .validate(&module)
    .unwrap_or_else(|e| panic!("{name}.wgsl: {}\n{e:?}", e.emit_to_string(source)));
    Parsed {
        name: name.to_string(),
        module,
        info,
    }
}

/// What the interface checks read of a module.
fn facts(module: &naga::Module) -> ShaderFacts {
    let members = |inner: &naga::TypeInner| match inner {
        naga::TypeInner::Struct { members, span } => Some((
            members
                .iter()
                .map(|m| Member {
                    name: m.name.as_deref().unwrap_or("?").to_string(),
                    offset: m.offset,
                })
                .collect::<Vec<_>>(),
            *span,
        )),
        _ => None,
    };
    let globals = module
        .global_variables
        .iter()
        .map(|(_, var)| Global {
            name: var.name.as_deref().unwrap_or("?").to_string(),
            binding: var.binding.as_ref().map(|rb| {
                let kind = match module.types[var.ty].inner {
                    naga::TypeInner::Image {
                        class: naga::ImageClass::Storage { .. },
                        ..
                    } => BindingKind::StorageImage,
                    naga::TypeInner::Image { .. } => BindingKind::SampledImage,
                    _ => BindingKind::StorageBuffer,
                };
                (rb.group, rb.binding, kind)
            }),
            immediate: (var.space == naga::AddressSpace::Immediate)
                .then(|| members(&module.types[var.ty].inner)),
        })
        .collect();
    let tile_lists = module
        .types
        .iter()
        .filter(|(_, ty)| ty.name.as_deref() == Some("TileList"))
        .map(|(_, ty)| members(&ty.inner).map(|(m, _)| m))
        .collect();
    let entry_points = module
        .entry_points
        .iter()
        .map(|ep| (ep.name.clone(), ep.workgroup_size))
        .collect();
    ShaderFacts {
        globals,
        tile_lists,
        entry_points,
    }
}
