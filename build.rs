//! Compiles the WGSL compute shaders in `shaders/` to SPIR-V with naga and writes them to
//! OUT_DIR, where `src/gpu/shaders/modules.rs` embeds them. No shader compiler runs at run time.
//!
//! Each stage file is prefixed with `shaders/common.wgsl` (WGSL has no #include) and with the
//! colour constants generated here, so the shader uses exactly the numbers of docs/algorithm.md, Colour spaces:
//! the sRGB D65 matrix and its inverse computed in f64 (not a separately rounded published one).

use std::{env, fs, path::PathBuf};

include!("src/gpu/shaders/approx_constants.rs");

/// The shader interface, the one definition both sides use (see its opening comment).
#[allow(dead_code)]
mod interface {
    include!("src/gpu/shaders/interface.rs");
}
use interface::*;

// The method table (src/algorithm/method_table.rs): what build.rs needs of each entry.
include!("src/algorithm/method_table.rs");

/// A method as build.rs sees its entry.
struct BuildMethod {
    name: &'static str,
    code: u32,
    /// `Scaled` or `Linear` (the entry's reference).
    space: &'static str,
    wgsl: &'static str,
}

macro_rules! build_methods {
    ($($variant:ident {
        name: $name:literal,
        code: $code:literal,
        doc: $doc:literal,
        comparison: $comparison:literal,
        reference: $space:ident($f:ident),
        wgsl: $wgsl:literal,
        $($rest:tt)*
    }),* $(,)?) => {
        &[$(BuildMethod {
            name: $name,
            code: $code,
            space: stringify!($space),
            wgsl: $wgsl,
        }),*]
    };
}

/// Every method of the table.
const METHODS: &[BuildMethod] = with_methods!(build_methods);

/// The code of the method the single passes and the background mode are built with (their
/// METHOD is never read; `paper`'s).
fn paper_code() -> u32 {
    METHODS
        .iter()
        .find(|m| m.name == "paper")
        .expect("paper")
        .code
}

/// A method's WGSL, appended to shaders/enhance.wgsl in its variants: the entry's file, and a
/// stand-in for the function of the other space (enhance.wgsl calls both, behind the constant
/// METHOD_LINEAR).
fn method_wgsl(code: u32) -> String {
    let m = METHODS
        .iter()
        .find(|m| m.code == code)
        .expect("a method's code");
    println!("cargo:rerun-if-changed={}", m.wgsl);
    let own = fs::read_to_string(m.wgsl).unwrap_or_else(|e| panic!("{} ({}): {e}", m.wgsl, m.name));
    let linear = m.space == "Linear";
    let stand_in = if linear {
        "fn method_scaled(s: Step) -> Colours {\n    return s.d;\n}\n"
    } else {
        "fn method_linear(display: Colours, bg: Background) -> Colours {\n    return display;\n}\n"
    };
    format!(
        "\n// The method `{}` ({}).\nconst METHOD_LINEAR: bool = {linear};\n{own}{stand_in}",
        m.name, m.wgsl
    )
}

/// Stage files and their entry points.
const STAGES: &[(&str, &[&str])] = &[("enhance", &["finish_tiles"]), ("copy", &["copy_pixels"])];

/// The per-pixel `enhance` entry is built once per (method, view mode, pixel format) with all
/// three as WGSL constants, so each variant holds only its own code: a CPU driver such as
/// lavapipe runs every branch under an execution mask, so code behind a push-constant branch
/// costs time even when no pixel takes it (measured: the format as a push constant made a full
/// frame 1.8x slower). The codes are src/gpu/shaders/interface.rs's. `classify` is built once per
/// format. The beyond-the-paper extras (achromatic boost, luminance cap) are a fourth such
/// switch: a variant without them for when both are off, the default.
/// Every (pixel access, FORMAT code) a per-pixel pass is built for: both buffer accesses for
/// every format, in place for the formats that have a storage texel format.
fn pixel_accesses() -> Vec<(u32, u32)> {
    let buffers = [ACCESS_WIDE, ACCESS_NARROW]
        .into_iter()
        .flat_map(|a| FORMAT_CODES.map(|f| (a, f)));
    let in_place = FORMAT_CODES
        .into_iter()
        .filter(|&f| in_place_texel(f).is_some())
        .map(|f| (ACCESS_IN_PLACE, f));
    buffers.chain(in_place).collect()
}

/// Every (method, mode, extras, shared fetches) an `enhance` is built for. The fifth switch,
/// shared fetches (shaders/sample_shared.wgsl instead of sample_general.wgsl), has a group's
/// four pixels read their camera texels once, valid only for some mappings
/// (src/gpu/recipe/shared_fetch.rs): built only for the defaults (the paper's method in mode enhance,
/// extras off), each variant costing about 40 kB of library.
fn enhance_variants() -> Vec<(u32, u32, bool, bool)> {
    let mut codes: Vec<u32> = METHODS.iter().map(|m| m.code).collect();
    codes.sort();
    assert!(
        codes.windows(2).all(|w| w[0] != w[1]),
        "src/algorithm/method_table.rs: two methods share a code"
    );
    let mut v: Vec<(u32, u32, bool, bool)> = METHODS
        .iter()
        .flat_map(|m| ENHANCE_MODES.iter().map(move |&mode| (m.code, mode)))
        .flat_map(|(m, mode)| [(m, mode, false, false), (m, mode, true, false)])
        .collect();
    v.push((paper_code(), MODE_BACKGROUND, false, false));
    v.push((paper_code(), MODE_ENHANCE, false, true));
    v
}

/// linear sRGB -> XYZ (docs/algorithm.md, XYZ matrices).
const RGB_TO_XYZ: [[f64; 3]; 3] = [
    [0.4124564, 0.3575761, 0.1804375],
    [0.2126729, 0.7151522, 0.0721750],
    [0.0193339, 0.1191920, 0.9503041],
];

fn invert(m: [[f64; 3]; 3]) -> [[f64; 3]; 3] {
    let c = |r: usize, k: usize| {
        let (r1, r2, k1, k2) = ((r + 1) % 3, (r + 2) % 3, (k + 1) % 3, (k + 2) % 3);
        m[r1][k1] * m[r2][k2] - m[r1][k2] * m[r2][k1]
    };
    let det = m[0][0] * c(0, 0) + m[0][1] * c(0, 1) + m[0][2] * c(0, 2);
    let mut inv = [[0.0; 3]; 3];
    for (i, row) in inv.iter_mut().enumerate() {
        for (j, v) in row.iter_mut().enumerate() {
            *v = c(j, i) / det;
        }
    }
    inv
}

fn wgsl_rows(name: &str, m: [[f64; 3]; 3]) -> String {
    let mut s = String::new();
    for (i, r) in m.iter().enumerate() {
        s += &format!(
            "const {name}_{i}: vec3<f32> = vec3<f32>({:.9e}, {:.9e}, {:.9e});\n",
            r[0], r[1], r[2]
        );
    }
    s
}

/// A WGSL function evaluating a polynomial (coefficients lowest power first) per component
/// with Horner's rule, `scale * p(x) + offset` folded into the coefficients.
fn wgsl_polynomial(name: &str, coefficients: &[f64], scale: f64, offset: f64) -> String {
    let c: Vec<f64> = coefficients.iter().map(|c| c * scale).collect();
    let mut s = format!(
        "fn {name}(x: vec4<f32>) -> vec4<f32> {{\n    var r = vec4<f32>({:.9e});\n",
        c[c.len() - 1]
    );
    for (k, ck) in c.iter().enumerate().rev().skip(1) {
        let ck = if k == 0 { ck + offset } else { *ck };
        s += &format!("    r = r * x + {ck:.9e};\n");
    }
    s + "    return r;\n}\n"
}

fn colour_constants() -> String {
    let white: Vec<f64> = RGB_TO_XYZ.iter().map(|r| r.iter().sum()).collect();
    let inverse = invert(RGB_TO_XYZ);
    // XYZ / white straight from linear RGB, and back: the white point folded into the matrices.
    let to_t: [[f64; 3]; 3] = std::array::from_fn(|i| RGB_TO_XYZ[i].map(|v| v / white[i]));
    let from_t: [[f64; 3]; 3] =
        std::array::from_fn(|i| std::array::from_fn(|j| inverse[i][j] * white[j]));
    // The shader's unit_row_times relies on it: white maps to t = (1, 1, 1) and back.
    for row in to_t.iter().chain(&from_t) {
        assert!((row.iter().sum::<f64>() - 1.0).abs() < 1e-12, "row {row:?}");
    }
    format!(
        "// Generated by build.rs from docs/algorithm.md (Colour spaces) and src/gpu/shaders/approx_constants.rs.\n{}{}{}const CBRT_SEED_MAGIC: u32 = {CBRT_SEED_MAGIC}u;\nconst CBRT_NEWTON_STEPS: i32 = {CBRT_NEWTON_STEPS};\n{}{}",
        wgsl_rows("RGB_TO_XYZ", RGB_TO_XYZ),
        wgsl_rows("RGB_TO_T", to_t),
        wgsl_rows("T_TO_RGB", from_t),
        wgsl_polynomial("srgb_decode_poly", &SRGB_DECODE_POLY, 1.0, 0.0),
        wgsl_polynomial("srgb_encode_poly", &SRGB_ENCODE_POLY, 1.055, -0.055),
    )
}

/// The interface's WGSL declarations (src/gpu/shaders/interface.rs) for a pixel access (ACCESS_*) and
/// FORMAT code: the codes and sizes, the push-constant block, the tile list and the bindings.
fn interface_wgsl(access: u32, format: u32) -> String {
    let mut s = String::from("// Generated by build.rs from src/gpu/shaders/interface.rs.\n");
    for (name, value) in CODES {
        s += &format!("const {name}: u32 = {value}u;\n");
    }
    s += "struct Params {\n";
    for (name, ty) in PARAMS {
        s += &format!("    {name}: {},\n", ty.wgsl());
    }
    s += "}\nvar<immediate> pc: Params;\n";
    s += TILE_LIST_WGSL;
    for b in BINDINGS {
        if let Some(decl) = (b.wgsl)(access, format) {
            s += &format!("@group(0) @binding({}) var{decl};\n", b.number);
        }
    }
    s
}

/// Fails the build where a parsed shader disagrees with src/gpu/shaders/interface.rs: its bindings,
/// its push-constant block's layout, its tile list's header, or its entry points' workgroup
/// sizes (each message names both sides).
fn check_interface(name: &str, module: &naga::Module) {
    let here = format!("{name}.wgsl vs src/gpu/shaders/interface.rs");
    for (_, var) in module.global_variables.iter() {
        let var_name = var.name.as_deref().unwrap_or("?");
        if let Some(rb) = &var.binding {
            let b = BINDINGS
                .iter()
                .find(|b| rb.group == 0 && b.number == rb.binding)
                .unwrap_or_else(|| {
                    panic!(
                        "{here}: `{var_name}` at group {} binding {} is not in BINDINGS",
                        rb.group, rb.binding
                    )
                });
            assert_eq!(
                var_name, b.name,
                "{here}: binding {} is `{var_name}` in the shader, `{}` in BINDINGS",
                b.number, b.name
            );
            let kind = match module.types[var.ty].inner {
                naga::TypeInner::Image {
                    class: naga::ImageClass::Storage { .. },
                    ..
                } => BindingKind::StorageImage,
                naga::TypeInner::Image { .. } => BindingKind::SampledImage,
                _ => BindingKind::StorageBuffer,
            };
            assert_eq!(
                kind, b.kind,
                "{here}: binding {} (`{var_name}`) is a {kind:?} in the shader, a {:?} in BINDINGS",
                b.number, b.kind
            );
        }
        if var.space == naga::AddressSpace::Immediate {
            check_params(&here, module, var.ty);
        }
    }
    for (_, ty) in module.types.iter() {
        if ty.name.as_deref() == Some("TileList") {
            check_tile_list(&here, &ty.inner);
        }
    }
    for ep in &module.entry_points {
        let (_, size) = WORKGROUPS
            .iter()
            .find(|(n, _)| *n == ep.name)
            .unwrap_or_else(|| panic!("{here}: entry point `{}` is not in WORKGROUPS", ep.name));
        assert_eq!(
            &ep.workgroup_size, size,
            "{here}: `{}` has workgroup size {:?} in the shader, {size:?} in WORKGROUPS",
            ep.name, ep.workgroup_size
        );
    }
}

fn check_params(here: &str, module: &naga::Module, ty: naga::Handle<naga::Type>) {
    let naga::TypeInner::Struct { members, span } = &module.types[ty].inner else {
        panic!("{here}: the push constants are not a struct");
    };
    let (offsets, size) = params_layout();
    let names: Vec<_> = members
        .iter()
        .map(|m| m.name.as_deref().unwrap_or("?"))
        .collect();
    let wanted: Vec<_> = PARAMS.iter().map(|(n, _)| *n).collect();
    assert_eq!(names, wanted, "{here}: Params fields differ from PARAMS");
    for (m, (&offset, (field, _))) in members.iter().zip(offsets.iter().zip(PARAMS)) {
        assert_eq!(
            m.offset, offset,
            "{here}: Params.{field} at byte {} in the shader, {offset} in PARAMS",
            m.offset
        );
    }
    assert_eq!(
        *span, size,
        "{here}: Params is {span} bytes in the shader, {size} in PARAMS"
    );
}

fn check_tile_list(here: &str, inner: &naga::TypeInner) {
    let naga::TypeInner::Struct { members, .. } = inner else {
        panic!("{here}: TileList is not a struct");
    };
    let offset = |field: &str| {
        let m = members.iter().find(|m| m.name.as_deref() == Some(field));
        m.unwrap_or_else(|| panic!("{here}: TileList has no `{field}`"))
            .offset
    };
    let groups = u64::from(offset("groups"));
    assert_eq!(groups, TILE_LIST_DISPATCH_OFFSET, "{here}: TileList.groups at byte {groups} in the shader, TILE_LIST_DISPATCH_OFFSET {TILE_LIST_DISPATCH_OFFSET}");
    let index = u64::from(offset("index"));
    assert_eq!(index, TILE_LIST_HEADER_WORDS * 4, "{here}: TileList.index at byte {index} in the shader, TILE_LIST_HEADER_WORDS {TILE_LIST_HEADER_WORDS} words");
}

/// A shader parsed, validated and checked against src/gpu/interface.rs: both back ends (SPIR-V
/// for Vulkan, GLSL for OpenGL) write from the same module.
struct Parsed {
    name: String,
    module: naga::Module,
    info: naga::valid::ModuleInfo,
}

fn parse(name: &str, source: &str) -> Parsed {
    let module = naga::front::wgsl::parse_str(source)
        .unwrap_or_else(|e| panic!("{name}.wgsl: {}", e.emit_to_string(source)));
    let info = naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::IMMEDIATES
            | naga::valid::Capabilities::SHADER_FLOAT16_IN_FLOAT32,
    )
    .validate(&module)
    .unwrap_or_else(|e| panic!("{name}.wgsl: {}\n{e:?}", e.emit_to_string(source)));
    check_interface(name, &module);
    Parsed {
        name: name.to_string(),
        module,
        info,
    }
}

/// Out-of-bounds reads give zero, out-of-bounds writes are skipped (the narrow access reads
/// up to three words past a region's last pixel).
const BOUNDS: naga::proc::BoundsCheckPolicies = naga::proc::BoundsCheckPolicies {
    index: naga::proc::BoundsCheckPolicy::ReadZeroSkipWrite,
    buffer: naga::proc::BoundsCheckPolicy::ReadZeroSkipWrite,
    image_load: naga::proc::BoundsCheckPolicy::ReadZeroSkipWrite,
    binding_array: naga::proc::BoundsCheckPolicy::ReadZeroSkipWrite,
};

fn spirv(parsed: &Parsed, entry: &str) -> Vec<u32> {
    let options = naga::back::spv::Options {
        // SPIR-V 1.0: apps may create Vulkan 1.0 instances (hello_xr does).
        lang_version: (1, 0),
        flags: naga::back::spv::WriterFlags::empty(),
        force_loop_bounding: false,
        bounds_check_policies: BOUNDS,
        ..Default::default()
    };
    let pipeline = naga::back::spv::PipelineOptions {
        shader_stage: naga::ShaderStage::Compute,
        entry_point: entry.to_string(),
    };
    naga::back::spv::write_vec(&parsed.module, &parsed.info, &options, Some(&pipeline))
        .unwrap_or_else(|e| panic!("{}.wgsl entry {entry}: {e}", parsed.name))
}

/// The GLSL version the OpenGL backend's programs are written in (core profile): 4.50, the
/// first with `mix` of integer vectors by a boolean vector, which naga writes for WGSL's
/// `select` on them.
const GLSL_VERSION: u16 = 450;

/// One item of `Params` as naga's GLSL declares it (a uniform, since GLSL outside Vulkan has
/// no push constants): its uniform name, byte offset in PARAMS and type (a `GlParam` variant
/// of src/gpu/opengl/programs.rs).
#[derive(Clone, PartialEq, Debug)]
struct GlUniform {
    path: String,
    offset: u32,
    kind: &'static str,
}

/// The GLSL of `entry`, with every resource at the binding point BINDINGS gives it, checked
/// against src/gpu/interface.rs: every uniform naga made of the push constants is a PARAMS
/// field (by name, at its PARAMS offset, of its type), and every resource the entry uses is declared at
/// its binding.
fn glsl(parsed: &Parsed, entry: &str) -> (String, Vec<GlUniform>) {
    let here = format!(
        "{}.wgsl entry {entry} (GLSL) vs src/gpu/interface.rs",
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
    let (offsets, _) = params_layout();
    let mut uniforms = Vec::new();
    for item in &reflection.immediates_items {
        let path = &item.access_path;
        let field = path
            .split_once('.')
            .map(|(_, f)| f.split('[').next().unwrap_or(f))
            .unwrap_or_else(|| panic!("{here}: uniform `{path}` is not a field of Params"));
        // naga's GLSL namer appends `_` to a name ending in a digit (map_00 -> map_00_).
        let field = match field.strip_suffix('_') {
            Some(f) if f.ends_with(|c: char| c.is_ascii_digit()) => f,
            _ => field,
        };
        let (k, (_, ty)) = PARAMS
            .iter()
            .enumerate()
            .find(|(_, (n, _))| *n == field)
            .unwrap_or_else(|| panic!("{here}: uniform `{path}` is not in PARAMS"));
        let element = path
            .rsplit_once('[')
            .and_then(|(_, i)| i.trim_end_matches(']').parse::<u32>().ok())
            .unwrap_or(0);
        let offset = offsets[k] + 16 * element;
        assert_eq!(
            item.offset, offset,
            "{here}: `{path}` at byte {} in the GLSL, {offset} in PARAMS",
            item.offset
        );
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
        let decl = format!("binding = {}", rb.binding);
        assert!(
            text.contains(&decl),
            "{here}: `{}` is used but the GLSL declares nothing at `{decl}`",
            var.name.as_deref().unwrap_or("?")
        );
    }
    (text, uniforms)
}

/// Rewrites naga's storage buffers into the SPIR-V 1.0 / Vulkan 1.0 form: `StorageBuffer`
/// storage class -> `Uniform`, their structs' `Block` -> `BufferBlock`, and the
/// SPV_KHR_storage_buffer_storage_class extension removed. Apps may create Vulkan 1.0 devices
/// without that extension (hello_xr does), and the layer must run on their device.
fn storage_buffers_to_vulkan10(words: Vec<u32>) -> Vec<u32> {
    const OP_EXTENSION: u32 = 10;
    const OP_DECORATE: u32 = 71;
    const OP_TYPE_POINTER: u32 = 32;
    const OP_VARIABLE: u32 = 59;
    const STORAGE_BUFFER: u32 = 12;
    const UNIFORM: u32 = 2;
    const BLOCK: u32 = 2;
    const BUFFER_BLOCK: u32 = 3;
    let (header, body) = words.split_at(5);
    let mut insts: Vec<Vec<u32>> = Vec::new();
    let mut i = 0;
    while i < body.len() {
        let len = (body[i] >> 16) as usize;
        insts.push(body[i..i + len].to_vec());
        i += len;
    }
    let mut buffer_structs = std::collections::HashSet::new();
    for inst in insts.iter_mut() {
        let op = inst[0] & 0xffff;
        if op == OP_TYPE_POINTER && inst[2] == STORAGE_BUFFER {
            inst[2] = UNIFORM;
            buffer_structs.insert(inst[3]);
        } else if op == OP_VARIABLE && inst[3] == STORAGE_BUFFER {
            inst[3] = UNIFORM;
        }
    }
    let is_extension = |inst: &Vec<u32>| {
        inst[0] & 0xffff == OP_EXTENSION
            && inst[1..]
                .iter()
                .flat_map(|w| w.to_le_bytes())
                .take_while(|&b| b != 0)
                .collect::<Vec<u8>>()
                == b"SPV_KHR_storage_buffer_storage_class"
    };
    insts.retain(|inst| !is_extension(inst));
    for inst in insts.iter_mut() {
        if inst[0] & 0xffff == OP_DECORATE && inst[2] == BLOCK && buffer_structs.contains(&inst[1])
        {
            inst[2] = BUFFER_BLOCK;
        }
    }
    header
        .iter()
        .copied()
        .chain(insts.into_iter().flatten())
        .collect()
}

/// Pixel access (shaders/access_*.wgsl, ACCESS_*): wide for regions whose rows are 16-byte
/// aligned, narrow otherwise and for the passes outside the per-pixel hot path, in place in the
/// app's image.
fn access(access: u32, format: u32) -> String {
    let name = match access {
        ACCESS_WIDE => "wide",
        ACCESS_NARROW => "narrow",
        _ => "in_place",
    };
    let path = format!("shaders/access_{name}.wgsl");
    println!("cargo:rerun-if-changed={path}");
    let source = fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path}: {e}"));
    match (access, in_place_texel(format)) {
        (ACCESS_IN_PLACE, Some(texel)) => texel_codec(texel) + &source,
        _ => source,
    }
}

/// The conversions between an in-place variant's storage texel (interface.rs `in_place_texel`)
/// and the format's raw words (the buffer layout), exact both ways, for
/// shaders/access_in_place.wgsl: `texel_words` (the second word only for 2-word formats) and
/// `words_texel`.
fn texel_codec(texel: &str) -> String {
    let (ty, load, store) = match texel {
        "rgba8unorm" => (
            "vec4<f32>",
            "vec2<u32>(pack4x8unorm(t), 0u)",
            "unpack4x8unorm(w.x)",
        ),
        "rgba16float" => (
            "vec4<f32>",
            "vec2<u32>(pack2x16float(t.xy), pack2x16float(t.zw))",
            "vec4<f32>(unpack2x16float(w.x), unpack2x16float(w.y))",
        ),
        "r32uint" => (
            "vec4<u32>",
            "vec2<u32>(t.x, 0u)",
            "vec4<u32>(w.x, 0u, 0u, 1u)",
        ),
        "rgba16uint" => (
            "vec4<u32>",
            "vec2<u32>(t.x | (t.y << 16u), t.z | (t.w << 16u))",
            "vec4<u32>(w.x & 0xffffu, w.x >> 16u, w.y & 0xffffu, w.y >> 16u)",
        ),
        other => panic!("src/gpu/shaders/interface.rs: no texel codec for {other} in build.rs"),
    };
    format!(
        "// Generated by build.rs: the {texel} texel's words.\n\
         fn texel_words(t: {ty}) -> vec2<u32> {{\n    return {load};\n}}\n\
         fn words_texel(w: vec2<u32>) -> {ty} {{\n    return {store};\n}}\n"
    )
}

/// The background sampling appended to shaders/enhance.wgsl: for every mapping, or with the
/// texel reads shared by a group's four pixels (naga writes every function of a module into
/// its SPIR-V, also one behind a constant `if`, so each variant holds only its own).
fn sampling(shared: bool) -> String {
    let path = match shared {
        false => "shaders/sample_general.wgsl",
        true => "shaders/sample_shared.wgsl",
    };
    println!("cargo:rerun-if-changed={path}");
    fs::read_to_string(path).unwrap_or_else(|e| panic!("{path}: {e}"))
}

/// One embedded shader as build.rs writes it into the generated table (src/gpu/shaders/modules.rs).
struct Module {
    /// The SPIR-V file's name (without `.spv`).
    file: String,
    entry: &'static str,
    /// Works on the camera frame (the background's descriptor set) rather than on a view.
    camera: bool,
    /// The FORMAT code of an in-place variant (it reads and writes `app_image`).
    in_place: Option<u32>,
}

/// The generated table: every module once in MODULES (a ShaderId is an index there, written
/// here with the list, never counted by hand), the single shaders' ids by name, and each
/// family's variants with their ids.
#[derive(Default)]
struct Table {
    modules: Vec<Module>,
    /// Rust items naming ids (`pub const NAME: usize = id;`, the families' tables).
    items: String,
}

impl Table {
    fn add(
        &mut self,
        file: &str,
        entry: &'static str,
        camera: bool,
        in_place: Option<u32>,
    ) -> usize {
        self.modules.push(Module {
            file: file.to_string(),
            entry,
            camera,
            in_place,
        });
        self.modules.len() - 1
    }

    fn single(&mut self, name: &str, file: &str, entry: &'static str, camera: bool) {
        let id = self.add(file, entry, camera, None);
        self.items += &format!("/// The id of `{file}`.\npub const ID_{name}: usize = {id};\n");
    }

    fn source(&self) -> String {
        let mut s = String::from("// Generated by build.rs.\n");
        s += "/// Every embedded shader; a ShaderId is an index into this list.\n";
        s += "pub static MODULES: &[ShaderModule] = &[\n";
        for m in &self.modules {
            s += &format!(
                "    spirv!(\"{}\", \"{}\", {}, {:?}),\n",
                m.file, m.entry, m.camera, m.in_place
            );
        }
        s + "];\n" + &self.items
    }
}

/// Whether the OpenGL backend gets a GLSL variant for this (pixel access, FORMAT code): every
/// format but the BGRA ones (OpenGL has no BGRA internal format), through a buffer object
/// (the buffer accesses) and, for the formats with a storage texel format, in place through
/// an image unit.
fn gl_variant(access: u32, format: u32) -> bool {
    let in_place_ok = access != ACCESS_IN_PLACE || in_place_texel(format).is_some();
    in_place_ok && format & !FORMAT_SRGB_BIT != LAYOUT_BGRA8
}

/// The OpenGL backend's generated table (src/gpu/opengl/programs.rs includes it): every GLSL
/// module once (a program id is an index there), the Params uniforms every module shares,
/// the single programs' ids and the families' variants.
#[derive(Default)]
struct GlTable {
    files: Vec<String>,
    uniforms: Option<Vec<GlUniform>>,
    items: String,
}

impl GlTable {
    /// Writes `file`.glsl from a parsed module and lists it; its id.
    fn add(&mut self, out: &std::path::Path, file: &str, parsed: &Parsed, entry: &str) -> usize {
        let (text, uniforms) = glsl(parsed, entry);
        fs::write(out.join(format!("{file}.glsl")), text).unwrap();
        // The engine sets them by one list: naga declares the whole block in every module
        // whose entry reads it (finish_tiles reads none).
        match &self.uniforms {
            _ if uniforms.is_empty() => {}
            None => self.uniforms = Some(uniforms),
            Some(u) => assert_eq!(*u, uniforms, "{file}.glsl: its Params uniforms differ"),
        }
        self.files.push(file.to_string());
        self.files.len() - 1
    }

    fn source(&self) -> String {
        let mut s = String::from("// Generated by build.rs.\n");
        s += "/// Every embedded GLSL module (file name, source); a program id is an index here.\n";
        s += "pub static GL_MODULES: &[(&str, &str)] = &[\n";
        for f in &self.files {
            s += &format!(
                "    (\"{f}\", include_str!(concat!(env!(\"OUT_DIR\"), \"/{f}.glsl\"))),\n"
            );
        }
        s += "];\n/// The uniforms naga's GLSL declares for `Params` (name, PARAMS byte offset, type).\n";
        s += "pub static GL_PARAMS: &[(&str, u32, GlParam)] = &[\n";
        for u in self.uniforms.iter().flatten() {
            s += &format!("    (\"{}\", {}, GlParam::{}),\n", u.path, u.offset, u.kind);
        }
        s + "];\n" + &self.items
    }
}

fn main() {
    let out = PathBuf::from(env::var("OUT_DIR").unwrap());
    let common = fs::read_to_string("shaders/common.wgsl").expect("shaders/common.wgsl");
    println!("cargo:rerun-if-changed=shaders/common.wgsl");
    println!("cargo:rerun-if-changed=build.rs");
    println!("cargo:rerun-if-changed=src/gpu/shaders/approx_constants.rs");
    println!("cargo:rerun-if-changed=src/gpu/shaders/interface.rs");
    println!("cargo:rerun-if-changed=src/algorithm/method_table.rs");
    let prefix = |access_code: u32, format: u32| {
        colour_constants()
            + &interface_wgsl(access_code, format)
            + &common
            + &access(access_code, format)
    };
    let write = |file: &str, stage: &str, source: &str, entry: &str| -> Parsed {
        let parsed = parse(stage, source);
        let words = storage_buffers_to_vulkan10(spirv(&parsed, entry));
        let bytes: Vec<u8> = words.iter().flat_map(|w| w.to_le_bytes()).collect();
        fs::write(out.join(format!("{file}.spv")), bytes).unwrap();
        parsed
    };
    let mut gl = GlTable::default();
    let specialise = |(method, mode, format): (u32, u32, u32), extras: bool| {
        format!(
            "const METHOD: u32 = {method}u;\nconst MODE: u32 = {mode}u;\nconst FORMAT: u32 = {format}u;\nconst EXTRAS: bool = {extras};\n"
        )
    };
    let mut table = Table::default();
    // The table's order: the single shaders (decode_camera, finish_tiles, copy_pixels,
    // copy_rows), the background passes, the `enhance` and then the `classify` variants.
    table.single("DECODE_CAMERA", "decode_camera", "decode", true);
    for (stage, entries) in STAGES {
        let path = format!("shaders/{stage}.wgsl");
        println!("cargo:rerun-if-changed={path}");
        let mut body = fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path}: {e}"));
        if *stage == "enhance" {
            body += &sampling(false);
            body += &method_wgsl(paper_code());
        }
        let source = format!(
            "{}\n{}{body}",
            prefix(ACCESS_NARROW, FORMAT_CODES[0]),
            specialise((0, 0, FORMAT_CODES[0]), false)
        );
        for entry in *entries {
            let parsed = write(entry, stage, &source, entry);
            table.single(&entry.to_uppercase(), entry, entry, false);
            if *entry == "finish_tiles" {
                let id = gl.add(&out, entry, &parsed, entry);
                gl.items += &format!(
                    "/// The id of `{entry}.glsl`.\npub const GL_FINISH_TILES: usize = {id};\n"
                );
            }
        }
    }
    println!("cargo:rerun-if-changed=shaders/copy_wide.wgsl");
    let body = fs::read_to_string("shaders/copy_wide.wgsl").unwrap();
    let source = format!(
        "{}\n{}{body}",
        prefix(ACCESS_WIDE, 0),
        specialise((0, 0, 0), false)
    );
    let _ = write("copy_rows", "copy_wide", &source, "copy_rows");
    table.single("COPY_ROWS", "copy_rows", "copy_rows", false);
    // The background pass once per blur half-width (Params::blur_taps: at most 7), so that its
    // loops have constant trip counts (see shaders/background.wgsl); its half-width 0 source
    // also holds `decode`, the camera texels' decode.
    println!("cargo:rerun-if-changed=shaders/background.wgsl");
    let body = fs::read_to_string("shaders/background.wgsl").unwrap();
    let mut blur_ids = Vec::new();
    for half in 0..=MAX_BLUR_HALF {
        let source = format!(
            "{}\n{}const BLUR_HALF: u32 = {half}u;\n{body}",
            prefix(ACCESS_NARROW, FORMAT_CODES[0]),
            specialise((0, 0, FORMAT_CODES[0]), false)
        );
        let file = format!("decode_blur_{half}");
        let _ = write(&file, "background", &source, "decode_blur");
        if half == 0 {
            let _ = write("decode_camera", "background", &source, "decode");
        }
        blur_ids.push(table.add(&file, "decode_blur", true, None));
    }
    table.items += &format!(
        "/// The background pass's id for each blur half-width (index = half-width).\npub static DECODE_BLUR: &[usize] = &{blur_ids:?};\n"
    );
    let body = fs::read_to_string("shaders/enhance.wgsl").unwrap();
    let [general, shared_fetch] = [false, true].map(sampling);
    let (mut gl_enhance, mut gl_classify) = (String::new(), String::new());
    let mut variants = String::from("/// (method, mode, format, access, extras, shared fetches, id) of each `enhance`\n/// variant.\n");
    variants += "pub static ENHANCE_VARIANTS: &[(u32, u32, u32, u32, bool, bool, usize)] = &[\n";
    for (access_code, format) in pixel_accesses() {
        for (method, mode, extras, shared) in enhance_variants() {
            let file = format!(
                "enhance_m{method}_v{mode}_f{format}_a{access_code}_e{}{}",
                u8::from(extras),
                if shared { "_s" } else { "" }
            );
            let source = format!(
                "{}\n{}{body}{}{}",
                prefix(access_code, format),
                specialise((method, mode, format), extras),
                if shared { &shared_fetch } else { &general },
                method_wgsl(method)
            );
            let parsed = write(&file, "enhance", &source, "enhance");
            let in_place = (access_code == ACCESS_IN_PLACE).then_some(format);
            let id = table.add(&file, "enhance", false, in_place);
            variants += &format!(
                "    ({method}, {mode}, {format}, {access_code}, {extras}, {shared}, {id}),\n"
            );
            // The general sampling only: the shared fetches are a Vulkan-side optimisation.
            if gl_variant(access_code, format) && !shared {
                let id = gl.add(&out, &file, &parsed, "enhance");
                gl_enhance += &format!(
                    "    ({method}, {mode}, {format}, {access_code}, {extras}, {shared}, {id}),\n"
                );
            }
        }
    }
    variants += "];\n/// (format, access, id) of each `classify` variant.\n";
    variants += "pub static CLASSIFY_VARIANTS: &[(u32, u32, usize)] = &[\n";
    for (access_code, format) in pixel_accesses() {
        let file = format!("classify_f{format}_a{access_code}");
        let source = format!(
            "{}\n{}{body}{general}{}",
            prefix(access_code, format),
            specialise((paper_code(), 0, format), false),
            method_wgsl(paper_code())
        );
        let parsed = write(&file, "enhance", &source, "classify");
        let in_place = (access_code == ACCESS_IN_PLACE).then_some(format);
        let id = table.add(&file, "classify", false, in_place);
        variants += &format!("    ({format}, {access_code}, {id}),\n");
        if gl_variant(access_code, format) {
            let id = gl.add(&out, &file, &parsed, "classify");
            gl_classify += &format!("    ({format}, {access_code}, {id}),\n");
        }
    }
    variants += "];\n";
    table.items += &variants;
    fs::write(out.join("shader_table.rs"), table.source()).unwrap();
    gl.items += "/// (method, mode, format, access, extras, shared fetches, id) of each `enhance` GLSL\n/// variant.\n";
    gl.items += &format!("pub static GL_ENHANCE_VARIANTS: &[(u32, u32, u32, u32, bool, bool, usize)] = &[\n{gl_enhance}];\n");
    gl.items += &format!("/// (format, access, id) of each `classify` GLSL variant.\npub static GL_CLASSIFY_VARIANTS: &[(u32, u32, usize)] = &[\n{gl_classify}];\n");
    fs::write(out.join("gl_shader_table.rs"), gl.source()).unwrap();
}
