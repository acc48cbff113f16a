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
use wgsl::{method_wgsl, prefix, sampling, specialise, specialise_with};

/// Stage files and their entry points.
const STAGES: &[(&str, &[&str])] = &[("enhance", &["finish_tiles"]), ("copy", &["copy_pixels"])];

fn main() {
    println!("cargo:rerun-if-changed=shaders/common.wgsl");
    println!("cargo:rerun-if-changed=build.rs");
    println!("cargo:rerun-if-changed=src/gpu/core/approx_constants.rs");
    println!("cargo:rerun-if-changed=src/gpu/core/interface.rs");
    println!("cargo:rerun-if-changed=src/algorithm/method/table.rs");
    let mut build = Build {
        out: PathBuf::from(env::var("OUT_DIR").unwrap()),
        common: fs::read_to_string("shaders/common.wgsl").expect("shaders/common.wgsl"),
        table: Table::default(),
        gl: GlTable::default(),
    };
    // The table's order: the single shaders (decode_camera, finish_tiles, copy_pixels,
    // copy_rows), the background passes, the `enhance`, the `classify` and the benchmark's ablated
    // variants.
    build
        .table
        .single("DECODE_CAMERA", "decode_camera", "decode", true);
    build.stages();
    build.copy_rows();
    build.background();
    let body = fs::read_to_string("shaders/enhance.wgsl").unwrap();
    build.enhance(&body);
    build.classify(&body);
    build.ablated(&body);
    write_back_stages(&build.out);
    fs::write(build.out.join("shader_table.rs"), build.table.source()).unwrap();
    fs::write(build.out.join("gl_shader_table.rs"), build.gl.source()).unwrap();
}

/// The build's output: the SPIR-V and GLSL files in `out`, and the tables that list them.
struct Build {
    out: PathBuf,
    /// shaders/common.wgsl, which every shader starts with.
    common: String,
    table: Table,
    gl: GlTable,
}

impl Build {
    /// A shader's opening: common.wgsl and the interface's declarations for its pixel access
    /// and format.
    fn prefix(&self, access_code: u32, format: u32) -> String {
        prefix(&self.common, access_code, format)
    }

    /// Parses, checks and writes `file`.spv; the parsed module, for the GLSL.
    fn write(&self, file: &str, stage: &str, source: &str, entry: &str) -> Parsed {
        let parsed = parse(stage, source);
        spirv::write_spirv(&self.out, file, &parsed, entry);
        parsed
    }

    /// Writes `file`.glsl from `parsed`; its id in the OpenGL table.
    fn write_glsl(&mut self, file: &str, parsed: &Parsed, entry: &str) -> usize {
        let uniforms = glsl::write_glsl(&self.out, file, parsed, entry);
        let source = fs::read(self.out.join(format!("{file}.glsl"))).unwrap();
        self.gl.add(file, tables::source_hash(&source), uniforms)
    }

    /// The stage files' single shaders (finish_tiles, copy_pixels), in the narrow access.
    fn stages(&mut self) {
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
                self.prefix(ACCESS_NARROW, FORMAT_CODES[0]),
                specialise((0, 0, FORMAT_CODES[0]), false)
            );
            for entry in *entries {
                let parsed = self.write(entry, stage, &source, entry);
                self.table
                    .single(&entry.to_uppercase(), entry, entry, false);
                if *entry == "finish_tiles" {
                    self.gl.finish_tiles = Some(self.write_glsl(entry, &parsed, entry));
                }
            }
        }
    }

    /// The benchmark's 16-byte copy (shaders/copy_wide.wgsl).
    fn copy_rows(&mut self) {
        println!("cargo:rerun-if-changed=shaders/copy_wide.wgsl");
        let body = fs::read_to_string("shaders/copy_wide.wgsl").unwrap();
        let source = format!(
            "{}\n{}{body}",
            self.prefix(ACCESS_WIDE, 0),
            specialise((0, 0, 0), false)
        );
        let _ = self.write("copy_rows", "copy_wide", &source, "copy_rows");
        self.table
            .single("COPY_ROWS", "copy_rows", "copy_rows", false);
    }

    /// The background pass once per blur half-width (Params::blur_taps: at most 7), so that its
    /// loops have constant trip counts (see shaders/background.wgsl); its half-width 0 source
    /// also holds `decode`, the camera texels' decode.
    fn background(&mut self) {
        println!("cargo:rerun-if-changed=shaders/background.wgsl");
        let body = fs::read_to_string("shaders/background.wgsl").unwrap();
        for half in 0..=MAX_BLUR_HALF {
            let source = format!(
                "{}\n{}const BLUR_HALF: u32 = {half}u;\n{body}",
                self.prefix(ACCESS_NARROW, FORMAT_CODES[0]),
                specialise((0, 0, FORMAT_CODES[0]), false)
            );
            let file = format!("decode_blur_{half}");
            let _ = self.write(&file, "background", &source, "decode_blur");
            if half == 0 {
                let _ = self.write("decode_camera", "background", &source, "decode");
            }
            let id = self.table.add(&file, "decode_blur", true, None);
            self.table.decode_blur.push(id);
        }
    }

    /// The `enhance` variants (method, mode, pixels, extras, shared fetches) of `body`
    /// (shaders/enhance.wgsl).
    fn enhance(&mut self, body: &str) {
        let [general, shared_fetch] = [false, true].map(sampling);
        for v in variants::enhance_variants() {
            let file = v.file();
            let source = format!(
                "{}\n{}{body}{}{}",
                self.prefix(v.pixels.access, v.pixels.format),
                specialise_with(
                    (v.method, v.mode, v.pixels.format),
                    v.extras,
                    0,
                    v.pow_roots
                ),
                if v.shared { &shared_fetch } else { &general },
                method_wgsl(v.method)
            );
            let parsed = self.write(&file, "enhance", &source, "enhance");
            let id = self.table.add(&file, "enhance", false, Some(v.pixels));
            self.table.enhance.push((v, id));
            if v.gl() {
                let id = self.write_glsl(&file, &parsed, "enhance");
                self.gl.enhance.push((v, id));
            }
        }
    }

    /// The `classify` variants (method, pixels) of `body`.
    fn classify(&mut self, body: &str) {
        let general = sampling(false);
        for v in variants::classify_variants() {
            let file = v.file();
            let format = v.pixels.format;
            let source = format!(
                "{}\n{}{body}{general}{}",
                self.prefix(v.pixels.access, format),
                specialise((v.method, 0, format), false),
                method_wgsl(v.method)
            );
            let entry = v.entry();
            let parsed = self.write(&file, "enhance", &source, entry);
            let id = self.table.add(&file, entry, false, Some(v.pixels));
            self.table.classify.push((v, id));
            if v.pixels.gl() {
                let id = self.write_glsl(&file, &parsed, entry);
                self.gl.classify.push((v, id));
            }
        }
    }

    /// The benchmark's ablations of `body`, after the variants the layer runs.
    fn ablated(&mut self, body: &str) {
        let [general, shared_fetch] = [false, true].map(sampling);
        for v in variants::ablated_variants() {
            let file = v.file();
            let source = |sampling: &str| {
                format!(
                    "{}\n{}{body}{sampling}{}",
                    self.prefix(v.pixels.access, v.pixels.format),
                    specialise_with(v.codes(), false, v.ablate, v.pow_roots),
                    method_wgsl(v.method)
                )
            };
            // The general sampling for every view; the paper's also with shared fetches, which
            // the views whose mapping allows them take (as without an ablation).
            let shared_source = v.shared().then(|| source(&shared_fetch));
            let parsed = self.write(&file, "enhance", &source(&general), "enhance");
            let id = self.table.add(&file, "enhance", false, Some(v.pixels));
            self.table.ablated.push((v, false, id));
            if let Some(shared_source) = shared_source {
                let shared_file = format!("{file}_s");
                self.write(&shared_file, "enhance", &shared_source, "enhance");
                let id = self
                    .table
                    .add(&shared_file, "enhance", false, Some(v.pixels));
                self.table.ablated.push((v, true, id));
            }
            if v.pixels.gl() {
                // OpenGL has no shared fetches: its variants sample as its own `enhance` does.
                let id = self.write_glsl(&file, &parsed, "enhance");
                self.gl.ablated.push((v, id));
            }
        }
    }
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
