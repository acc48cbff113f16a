//! Compiles the WGSL compute shaders in `shaders/` with naga: SPIR-V for Vulkan and GLSL for
//! OpenGL, written to OUT_DIR with the tables that list them (`src/gpu/core/modules.rs` and
//! `src/gpu/opengl/pipelines/programs.rs` embed them). No shader compiler runs at run time.
//!
//! Each shader is the stage file prefixed with `shaders/common.wgsl` (WGSL has no #include),
//! the colour constants generated here, so the shader uses exactly the numbers of
//! docs/algorithm.md, Colour spaces, and the interface's declarations
//! (src/gpu/core/interface.rs). One module of `build/` per job:
//!
//! - `methods`: the method table (src/algorithm/method/table.rs) as build.rs sees it;
//! - `colour`: the colour constants;
//! - `variants`: the variants built, as a typed list;
//! - `wgsl`: a shader's WGSL source assembled;
//! - `parse` and `check`: the source parsed and validated by naga, and checked against the
//!   interface;
//! - `spirv` and `spirv_patch`: the SPIR-V written, in the Vulkan 1.0 storage-buffer form;
//! - `glsl`: the GLSL written, its uniforms checked against the interface;
//! - `tables`: the tables emitted.
//!
//! The modules without naga (all but `parse`, `spirv` and `glsl`) are also compiled into
//! tests/build_parts.rs, which tests them.

use std::{env, fs, path::PathBuf};

/// The shader interface, the one definition both sides use (see its opening comment).
#[allow(dead_code)]
mod interface {
    include!("src/gpu/core/interface.rs");
}
#[path = "build/check.rs"]
mod check;
#[path = "build/colour.rs"]
mod colour;
#[path = "build/glsl.rs"]
mod glsl;
#[path = "build/methods.rs"]
mod methods;
#[path = "build/parse.rs"]
mod parse;
#[path = "build/spirv.rs"]
mod spirv;
#[path = "build/spirv_patch.rs"]
mod spirv_patch;
#[path = "build/tables.rs"]
mod tables;
#[path = "build/variants.rs"]
mod variants;
#[path = "build/wgsl.rs"]
mod wgsl;
#[path = "build/write_back.rs"]
mod write_back;

use interface::*;
use methods::paper_code;
use parse::{parse, Parsed};
use tables::{GlTable, Table};
use wgsl::{method_wgsl, prefix, sampling, specialise};

/// Stage files and their entry points.
const STAGES: &[(&str, &[&str])] = &[("enhance", &["finish_tiles"]), ("copy", &["copy_pixels"])];

fn main() {
    let out = PathBuf::from(env::var("OUT_DIR").unwrap());
    let common = fs::read_to_string("shaders/common.wgsl").expect("shaders/common.wgsl");
    println!("cargo:rerun-if-changed=shaders/common.wgsl");
    println!("cargo:rerun-if-changed=build.rs");
    println!("cargo:rerun-if-changed=src/gpu/core/approx_constants.rs");
    println!("cargo:rerun-if-changed=src/gpu/core/interface.rs");
    println!("cargo:rerun-if-changed=src/algorithm/method/table.rs");
    let prefix = |access_code: u32, format: u32| prefix(&common, access_code, format);
    // Parses, checks and writes `file`.spv; the parsed module, for the GLSL.
    let write = |file: &str, stage: &str, source: &str, entry: &str| -> Parsed {
        let parsed = parse(stage, source);
        spirv::write_spirv(&out, file, &parsed, entry);
        parsed
    };
    let mut table = Table::default();
    let mut gl = GlTable::default();
    // The table's order: the single shaders (decode_camera, finish_tiles, copy_pixels,
    // copy_rows), the background passes, the `enhance`, the `classify` and the benchmark's ablated
    // variants.
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
                let uniforms = glsl::write_glsl(&out, entry, &parsed, entry);
                gl.finish_tiles = Some(gl.add(entry, uniforms));
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
        let id = table.add(&file, "decode_blur", true, None);
        table.decode_blur.push(id);
    }
    let body = fs::read_to_string("shaders/enhance.wgsl").unwrap();
    let [general, shared_fetch] = [false, true].map(sampling);
    for v in variants::enhance_variants() {
        let file = v.file();
        let source = format!(
            "{}\n{}{body}{}{}",
            prefix(v.pixels.access, v.pixels.format),
            specialise((v.method, v.mode, v.pixels.format), v.extras),
            if v.shared { &shared_fetch } else { &general },
            method_wgsl(v.method)
        );
        let parsed = write(&file, "enhance", &source, "enhance");
        let id = table.add(&file, "enhance", false, Some(v.pixels));
        table.enhance.push((v, id));
        if v.gl() {
            let uniforms = glsl::write_glsl(&out, &file, &parsed, "enhance");
            let id = gl.add(&file, uniforms);
            gl.enhance.push((v, id));
        }
    }
    for v in variants::classify_variants() {
        let file = v.file();
        let format = v.pixels.format;
        let source = format!(
            "{}\n{}{body}{general}{}",
            prefix(v.pixels.access, format),
            specialise((v.method, 0, format), false),
            method_wgsl(v.method)
        );
        let parsed = write(&file, "enhance", &source, "classify");
        let id = table.add(&file, "classify", false, Some(v.pixels));
        table.classify.push((v, id));
        if v.pixels.gl() {
            let uniforms = glsl::write_glsl(&out, &file, &parsed, "classify");
            let id = gl.add(&file, uniforms);
            gl.classify.push((v, id));
        }
    }
    // The benchmark's ablations, after the variants the layer runs.
    for v in variants::ablated_variants() {
        let file = v.file();
        let source = |sampling: &str| {
            format!(
                "{}\n{}{body}{sampling}{}",
                prefix(v.pixels.access, v.pixels.format),
                wgsl::specialise_ablated(v.codes(), false, v.ablate),
                method_wgsl(v.method)
            )
        };
        let sampling = if v.shared() { &shared_fetch } else { &general };
        let parsed = write(&file, "enhance", &source(sampling), "enhance");
        let id = table.add(&file, "enhance", false, Some(v.pixels));
        table.ablated.push((v, id));
        if v.pixels.gl() {
            // OpenGL has no shared fetches: its variants sample as its own `enhance` does.
            let parsed = match v.shared() {
                true => parse("enhance", &source(&general)),
                false => parsed,
            };
            let uniforms = glsl::write_glsl(&out, &file, &parsed, "enhance");
            let id = gl.add(&file, uniforms);
            gl.ablated.push((v, id));
        }
    }
    write_back_stages(&out);
    fs::write(out.join("shader_table.rs"), table.source()).unwrap();
    fs::write(out.join("gl_shader_table.rs"), gl.source()).unwrap();
}

/// The image-copy path's write-back (shaders/write_back.wgsl): its vertex stage once, its
/// fragment stage per format, and their table.
fn write_back_stages(out: &std::path::Path) {
    use naga::ShaderStage::{Fragment, Vertex};
    let body = wgsl::read("shaders/write_back.wgsl");
    for (i, format) in write_back::formats().into_iter().enumerate() {
        let source = write_back::declarations(format) + &body;
        let parsed = parse::parse_own("write_back", &source);
        if i == 0 {
            let entry = ("write_back_vertex", Vertex);
            spirv::write_spirv_stage(out, write_back::VERTEX_FILE, &parsed, entry);
        }
        let file = write_back::fragment_file(format);
        spirv::write_spirv_stage(out, &file, &parsed, ("write_back_fragment", Fragment));
    }
    fs::write(out.join("write_back_table.rs"), write_back::table_source()).unwrap();
}
