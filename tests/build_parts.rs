//! The parts of build.rs that need no naga (build/), compiled here as well so that `cargo test`
//! runs their tests: the variants list, the interface checks' failures, the SPIR-V 1.0
//! storage-buffer patch, the WGSL assembly's pure helpers, the colour constants and the tables.
//! The crate root mirrors build.rs's, so the parts name each other as they do there
//! (`crate::interface`, `crate::variants`, ...).

#![allow(dead_code)]

mod interface {
    include!("../src/gpu/core/interface.rs");
}
#[path = "../build/check.rs"]
mod check;
#[path = "../build/colour.rs"]
mod colour;
#[path = "../build/methods.rs"]
mod methods;
#[path = "../build/spirv_patch.rs"]
mod spirv_patch;
#[path = "../build/tables.rs"]
mod tables;
#[path = "../build/variants.rs"]
mod variants;
#[path = "../build/wgsl.rs"]
mod wgsl;

use std::collections::HashSet;
use std::panic::{catch_unwind, UnwindSafe};

use check::{Global, Member, ShaderFacts};
use interface::*;
use methods::{paper_code, perceptual_code, METHODS};
use spirv_patch::storage_buffers_to_vulkan10;
use tables::{GlTable, GlUniform, Table};
use variants::{
    ablated_variants, classify_variants, enhance_variants, pixel_accesses, Ablated, Enhance,
    PixelAccess,
};

/// The message `f` fails with.
fn failure(f: impl FnOnce() + UnwindSafe) -> String {
    let e = catch_unwind(f).expect_err("it should fail");
    e.downcast_ref::<String>()
        .cloned()
        .or_else(|| e.downcast_ref::<&str>().map(|s| s.to_string()))
        .expect("a panic message")
}

// --- The SPIR-V 1.0 storage-buffer patch ---

const HEADER: [u32; 5] = [0x0723_0203, 0x0001_0000, 0, 10, 0];

/// An instruction: its word count and opcode, then its operands.
fn inst(op: u32, operands: &[u32]) -> Vec<u32> {
    let mut v = vec![((operands.len() as u32 + 1) << 16) | op];
    v.extend_from_slice(operands);
    v
}

/// OpExtension with a NUL-terminated, word-padded string.
fn extension(name: &str) -> Vec<u32> {
    let mut bytes = name.as_bytes().to_vec();
    bytes.push(0);
    while !bytes.len().is_multiple_of(4) {
        bytes.push(0);
    }
    let words: Vec<u32> = bytes
        .chunks(4)
        .map(|c| u32::from_le_bytes(c.try_into().unwrap()))
        .collect();
    inst(10, &words)
}

const STORAGE_BUFFER: u32 = 12;
const UNIFORM: u32 = 2;
const BLOCK: u32 = 2;
const BUFFER_BLOCK: u32 = 3;

fn module(parts: &[Vec<u32>]) -> Vec<u32> {
    HEADER.iter().copied().chain(parts.concat()).collect()
}

#[test]
fn the_patch_turns_storage_buffers_into_vulkan_1_0_uniform_buffer_blocks() {
    // %1: a storage buffer's struct, %2: a uniform buffer's struct; %3, %4 pointers to them,
    // %5, %6 variables. Decorations come before the types, as in a real module.
    let before = module(&[
        inst(17, &[1]), // OpCapability Shader
        extension("SPV_KHR_storage_buffer_storage_class"),
        extension("SPV_KHR_16bit_storage"),
        inst(71, &[1, BLOCK]),             // OpDecorate %1 Block
        inst(71, &[2, BLOCK]),             // OpDecorate %2 Block
        inst(72, &[1, 0, 35, 0]),          // OpMemberDecorate %1 0 Offset 0
        inst(32, &[3, STORAGE_BUFFER, 1]), // OpTypePointer %3 StorageBuffer %1
        inst(32, &[4, UNIFORM, 2]),        // OpTypePointer %4 Uniform %2
        inst(59, &[3, 5, STORAGE_BUFFER]), // OpVariable %3 %5 StorageBuffer
        inst(59, &[4, 6, UNIFORM]),        // OpVariable %4 %6 Uniform
    ]);
    let after = module(&[
        inst(17, &[1]),
        extension("SPV_KHR_16bit_storage"),
        inst(71, &[1, BUFFER_BLOCK]),
        inst(71, &[2, BLOCK]),
        inst(72, &[1, 0, 35, 0]),
        inst(32, &[3, UNIFORM, 1]),
        inst(32, &[4, UNIFORM, 2]),
        inst(59, &[3, 5, UNIFORM]),
        inst(59, &[4, 6, UNIFORM]),
    ]);
    assert_eq!(storage_buffers_to_vulkan10(before), after);
}

#[test]
fn the_patch_leaves_a_module_without_storage_buffers_alone() {
    let words = module(&[
        inst(17, &[1]),
        extension("SPV_KHR_16bit_storage"),
        inst(71, &[2, BLOCK]),
        inst(32, &[4, UNIFORM, 2]),
        inst(59, &[4, 6, UNIFORM]),
    ]);
    assert_eq!(storage_buffers_to_vulkan10(words.clone()), words);
    assert_eq!(storage_buffers_to_vulkan10(HEADER.to_vec()), HEADER);
}

#[test]
fn every_built_spirv_module_is_in_the_vulkan_1_0_form() {
    // build.rs wrote them patched: patching again changes nothing, and no storage buffer
    // class, no extension for it, is left.
    let mut seen = 0;
    for entry in std::fs::read_dir(env!("OUT_DIR")).unwrap().flatten() {
        let path = entry.path();
        if path.extension().is_none_or(|e| e != "spv") {
            continue;
        }
        let bytes = std::fs::read(&path).unwrap();
        let words: Vec<u32> = bytes
            .chunks(4)
            .map(|c| u32::from_le_bytes(c.try_into().unwrap()))
            .collect();
        assert_eq!(
            storage_buffers_to_vulkan10(words.clone()),
            words,
            "{}",
            path.display()
        );
        let ext = b"SPV_KHR_storage_buffer_storage_class";
        assert!(
            !bytes.windows(ext.len()).any(|w| w == ext),
            "{}",
            path.display()
        );
        seen += 1;
    }
    assert!(seen > 100, "only {seen} SPIR-V files in OUT_DIR");
}

// --- The variants ---

#[test]
fn pixel_accesses_are_both_buffer_accesses_for_every_format_in_place_and_sampled_where_they_can() {
    let all = pixel_accesses();
    let set: HashSet<PixelAccess> = all.iter().copied().collect();
    assert_eq!(set.len(), all.len(), "a pixel access twice: {all:?}");
    for format in FORMAT_CODES {
        for access in [ACCESS_WIDE, ACCESS_NARROW] {
            assert!(set.contains(&PixelAccess { access, format }));
        }
        let in_place = PixelAccess {
            access: ACCESS_IN_PLACE,
            format,
        };
        assert_eq!(set.contains(&in_place), in_place_texel(format).is_some());
        let sampled = PixelAccess {
            access: ACCESS_SAMPLED,
            format,
        };
        assert_eq!(set.contains(&sampled), sampled_read(format));
    }
    assert_eq!(
        all.len(),
        2 * FORMAT_CODES.len()
            + FORMAT_CODES
                .iter()
                .filter(|&&f| in_place_texel(f).is_some())
                .count()
            + FORMAT_CODES.iter().filter(|&&f| sampled_read(f)).count()
    );
}

#[test]
fn the_enhance_variants_cover_every_method_mode_extras_and_access_once() {
    let all = enhance_variants();
    let set: HashSet<Enhance> = all.iter().copied().collect();
    assert_eq!(set.len(), all.len(), "a variant twice");
    for pixels in pixel_accesses() {
        for m in METHODS {
            for mode in ENHANCE_MODES {
                for extras in [false, true] {
                    let v = Enhance {
                        method: m.code,
                        mode,
                        pixels,
                        extras,
                        shared: false,
                        pow_roots: false,
                    };
                    assert!(set.contains(&v), "{v:?} missing");
                }
            }
        }
        let paper = |mode, shared| Enhance {
            method: paper_code(),
            mode,
            pixels,
            extras: false,
            shared,
            pow_roots: false,
        };
        assert!(set.contains(&paper(MODE_BACKGROUND, false)));
        assert!(set.contains(&paper(MODE_ENHANCE, true)));
        // The cube roots by pow for the ways a GPU's views take: in place, the sampled read.
        let gpu_way = pixels.access == ACCESS_IN_PLACE || pixels.access == ACCESS_SAMPLED;
        let by_pow = |v: Enhance| Enhance {
            pow_roots: true,
            ..v
        };
        let perceptual = Enhance {
            method: perceptual_code(),
            ..paper(MODE_ENHANCE, false)
        };
        for v in [
            paper(MODE_ENHANCE, false),
            paper(MODE_ENHANCE, true),
            perceptual,
        ] {
            assert_eq!(set.contains(&by_pow(v)), gpu_way, "{v:?}");
        }
    }
    // Nothing else: shared fetches and the cube roots by pow only for the defaults (and the
    // perceptual method's), the background mode only once.
    for v in &all {
        if v.pow_roots {
            assert!(
                v.method == paper_code() || (v.method, v.shared) == (perceptual_code(), false),
                "{v:?}"
            );
            assert_eq!((v.mode, v.extras), (MODE_ENHANCE, false));
        }
        if v.shared {
            assert_eq!(
                (v.method, v.mode, v.extras),
                (paper_code(), MODE_ENHANCE, false)
            );
        } else if v.mode == MODE_BACKGROUND {
            assert_eq!((v.method, v.extras), (paper_code(), false));
        } else {
            assert!(ENHANCE_MODES.contains(&v.mode), "{v:?}");
        }
    }
    // A method adds its view modes x with and without the extras x the pixel accesses.
    let gpu_ways = pixel_accesses()
        .iter()
        .filter(|p| p.access == ACCESS_IN_PLACE || p.access == ACCESS_SAMPLED)
        .count();
    assert_eq!(
        all.len(),
        pixel_accesses().len() * (METHODS.len() * ENHANCE_MODES.len() * 2 + 2) + 3 * gpu_ways
    );
}

#[test]
fn every_variant_has_a_file_of_its_own() {
    let mut files: Vec<String> = enhance_variants().iter().map(Enhance::file).collect();
    files.extend(classify_variants().iter().map(|v| v.file()));
    files.extend(ablated_variants().iter().map(|v| v.file()));
    let unique: HashSet<&String> = files.iter().collect();
    assert_eq!(unique.len(), files.len(), "two variants share a file name");
    for single in ["decode_camera", "finish_tiles", "copy_pixels", "copy_rows"] {
        assert!(!unique.contains(&single.to_string()));
    }
    assert!(files.iter().all(|f| !f.starts_with("decode_blur_")));
    let shared = Enhance {
        method: 0,
        mode: MODE_ENHANCE,
        pixels: PixelAccess {
            access: ACCESS_WIDE,
            format: FORMAT_SRGB_BIT,
        },
        extras: false,
        shared: true,
        pow_roots: false,
    };
    assert_eq!(shared.file(), "enhance_m0_v0_f256_a1_e0_s");
    let by_pow = Enhance {
        pow_roots: true,
        ..shared
    };
    assert_eq!(by_pow.file(), "enhance_m0_v0_f256_a1_e0_s_p");
}

/// The benchmark's ablations: the paper's ABLATIONS (with shared fetches) and the perceptual
/// method's PERCEPTUAL_ABLATIONS, each once for each access of RGBA8 sRGB but the sampled
/// read, in mode enhance.
#[test]
fn the_ablated_variants_are_each_ablation_for_each_srgb8_access() {
    let all = ablated_variants();
    let srgb8 = LAYOUT_RGBA8 | FORMAT_SRGB_BIT;
    let accesses: Vec<PixelAccess> = pixel_accesses()
        .into_iter()
        .filter(|p| p.format == srgb8 && p.access != ACCESS_SAMPLED)
        .collect();
    assert_eq!(accesses.len(), 3, "narrow, wide and in place");
    let set: HashSet<Ablated> = all.iter().copied().collect();
    assert_eq!(set.len(), all.len());
    let methods = [
        (paper_code(), &ABLATIONS[..]),
        (perceptual_code(), &PERCEPTUAL_ABLATIONS[..]),
    ];
    let count = ABLATIONS.len() + PERCEPTUAL_ABLATIONS.len();
    assert_eq!(all.len(), 2 * accesses.len() * count);
    for (method, ablations) in methods {
        for &pixels in &accesses {
            for &ablate in ablations {
                for pow_roots in [false, true] {
                    let v = Ablated {
                        method,
                        pixels,
                        ablate,
                        pow_roots,
                    };
                    assert!(set.contains(&v), "{v:?}");
                    assert_eq!(v.codes(), (method, MODE_ENHANCE, srgb8));
                    assert_eq!(v.shared(), method == paper_code());
                }
            }
        }
    }
    assert!(all.iter().all(|v| v.ablate != 0));
    let v = Ablated {
        method: perceptual_code(),
        pixels: PixelAccess {
            access: ACCESS_IN_PLACE,
            format: srgb8,
        },
        ablate: ABLATE_BISECTION,
        pow_roots: false,
    };
    assert_eq!(
        v.file(),
        format!("enhance_ablated_m{}_f256_a2_x32", perceptual_code())
    );
    let by_pow = Ablated {
        pow_roots: true,
        ..v
    };
    assert_eq!(
        by_pow.file(),
        format!("enhance_ablated_m{}_f256_a2_x32_p", perceptual_code())
    );
}

#[test]
fn opengl_gets_every_variant_but_the_bgra_ones_the_shared_fetches_and_the_sampled_reads() {
    for v in enhance_variants() {
        let bgra = v.pixels.format & !FORMAT_SRGB_BIT == LAYOUT_BGRA8;
        let sampled = v.pixels.access == ACCESS_SAMPLED;
        assert_eq!(v.gl(), !bgra && !v.shared && !sampled, "{v:?}");
    }
    for v in classify_variants() {
        let bgra = v.pixels.format & !FORMAT_SRGB_BIT == LAYOUT_BGRA8;
        let sampled = v.pixels.access == ACCESS_SAMPLED;
        assert_eq!(v.pixels.gl(), !bgra && !sampled, "{v:?}");
        let writes_app_image = v.pixels.access == ACCESS_IN_PLACE || sampled;
        assert_eq!(
            v.pixels.in_place(),
            writes_app_image.then_some(v.pixels.format)
        );
    }
    // The sampled read: the two 8-bit sRGB formats.
    let sampled: Vec<u32> = pixel_accesses()
        .into_iter()
        .filter(|p| p.access == ACCESS_SAMPLED)
        .map(|p| p.format)
        .collect();
    let srgb = [LAYOUT_RGBA8, LAYOUT_BGRA8].map(|l| l | FORMAT_SRGB_BIT);
    assert_eq!(sampled, srgb);
    // classify: two per pixel access, the paper's and the perceptual method's; and the
    // perceptual method's by tile rows for the ablations' three accesses of RGBA8 sRGB.
    assert_eq!(classify_variants().len(), 2 * pixel_accesses().len() + 3);
    let by_rows: Vec<String> = classify_variants()
        .iter()
        .filter(|v| v.rows)
        .map(|v| format!("{} {}", v.file(), v.entry()))
        .collect();
    let srgb8 = LAYOUT_RGBA8 | FORMAT_SRGB_BIT;
    let expected: Vec<String> = [ACCESS_WIDE, ACCESS_NARROW, ACCESS_IN_PLACE]
        .map(|a| format!("classify_f{srgb8}_a{a}_perceptual_rows classify_rows"))
        .into();
    assert_eq!(by_rows, expected);
}

// --- The interface checks ---

/// The facts of a shader that agrees with the interface: every binding, the push constants,
/// the tile list, every entry point.
fn agreeing() -> ShaderFacts {
    let (offsets, size) = params_layout();
    let params = PARAMS
        .iter()
        .zip(offsets)
        .map(|((name, _), offset)| Member {
            name: name.to_string(),
            offset,
        })
        .collect();
    let mut globals: Vec<Global> = BINDINGS
        .iter()
        .map(|b| Global {
            name: b.name.to_string(),
            binding: Some((0, b.number, b.kind)),
            immediate: None,
        })
        .collect();
    globals.push(Global {
        name: "pc".into(),
        binding: None,
        immediate: Some(Some((params, size))),
    });
    let member = |name: &str, offset| Member {
        name: name.into(),
        offset,
    };
    ShaderFacts {
        globals,
        tile_lists: vec![Some(vec![
            member("count", 0),
            member("groups", TILE_LIST_DISPATCH_OFFSET as u32),
            member("total", 16),
            member("pad", 20),
            member("draw", TILE_LIST_DRAW_OFFSET as u32),
            member("index", TILE_LIST_HEADER_WORDS as u32 * 4),
        ])],
        entry_points: WORKGROUPS
            .iter()
            .map(|(n, size)| (n.to_string(), *size))
            .collect(),
    }
}

/// The message the check fails with on the agreeing facts changed by `change`.
fn check_failure(change: impl FnOnce(&mut ShaderFacts)) -> String {
    let mut facts = agreeing();
    change(&mut facts);
    failure(move || check::check_interface("enhance", &facts))
}

const HERE: &str = "enhance.wgsl vs src/gpu/core/interface.rs";

fn params_members(facts: &mut ShaderFacts) -> &mut (Vec<Member>, u32) {
    let pc = facts.globals.iter_mut().find(|g| g.name == "pc").unwrap();
    pc.immediate.as_mut().unwrap().as_mut().unwrap()
}

#[test]
fn a_shader_that_agrees_with_the_interface_passes() {
    check::check_interface("enhance", &agreeing());
}

#[test]
fn a_binding_the_interface_lacks_fails_naming_both_sides() {
    let m = check_failure(|f| f.globals[0].binding = Some((0, 9, BindingKind::StorageBuffer)));
    assert_eq!(
        m,
        format!("{HERE}: `camera` at group 0 binding 9 is not in BINDINGS")
    );
    let m = check_failure(|f| f.globals[0].binding = Some((1, 0, BindingKind::StorageBuffer)));
    assert_eq!(
        m,
        format!("{HERE}: `camera` at group 1 binding 0 is not in BINDINGS")
    );
}

#[test]
fn a_binding_of_another_name_or_kind_fails_naming_both_sides() {
    let m = check_failure(|f| f.globals[1].name = "blur".into());
    assert!(
        m.contains(&format!(
            "{HERE}: binding 1 is `blur` in the shader, `blurred` in BINDINGS"
        )),
        "{m}"
    );
    let m = check_failure(|f| {
        f.globals[6].binding = Some((0, BINDING_APP_IMAGE, BindingKind::SampledImage))
    });
    assert!(
        m.contains(&format!(
            "{HERE}: binding 6 (`app_image`) is a SampledImage in the shader, a StorageImage in BINDINGS"
        )),
        "{m}"
    );
}

#[test]
fn push_constants_out_of_step_with_params_fail_naming_both_sides() {
    let m = check_failure(|f| params_members(f).0.swap(2, 3));
    assert!(
        m.contains(&format!("{HERE}: Params fields differ from PARAMS")),
        "{m}"
    );
    let m = check_failure(|f| params_members(f).0[3].offset += 4);
    assert!(
        m.contains(&format!(
            "{HERE}: Params.lambda_jnd at byte 24 in the shader, 20 in PARAMS"
        )),
        "{m}"
    );
    let size = params_layout().1;
    let m = check_failure(|f| params_members(f).1 += 16);
    assert!(
        m.contains(&format!(
            "{HERE}: Params is {} bytes in the shader, {size} in PARAMS",
            size + 16
        )),
        "{m}"
    );
    let m = check_failure(|f| {
        let pc = f.globals.iter_mut().find(|g| g.name == "pc").unwrap();
        pc.immediate = Some(None);
    });
    assert_eq!(m, format!("{HERE}: the push constants are not a struct"));
}

#[test]
fn a_tile_list_out_of_step_fails_naming_both_sides() {
    let m = check_failure(|f| f.tile_lists[0].as_mut().unwrap()[1].offset = 8);
    assert!(
        m.contains(&format!(
            "{HERE}: TileList.groups at byte 8 in the shader, TILE_LIST_DISPATCH_OFFSET 4"
        )),
        "{m}"
    );
    let m = check_failure(|f| {
        f.tile_lists[0].as_mut().unwrap().pop();
    });
    assert_eq!(m, format!("{HERE}: TileList has no `index`"));
    let m = check_failure(|f| f.tile_lists[0].as_mut().unwrap()[4].offset = 28);
    assert!(
        m.contains(&format!(
            "{HERE}: TileList.draw at byte 28 in the shader, TILE_LIST_DRAW_OFFSET 32"
        )),
        "{m}"
    );
    let m = check_failure(|f| f.tile_lists[0].as_mut().unwrap()[5].offset = 36);
    assert!(
        m.contains(&format!(
            "{HERE}: TileList.index at byte 36 in the shader, TILE_LIST_HEADER_WORDS 12 words"
        )),
        "{m}"
    );
    let m = check_failure(|f| f.tile_lists[0] = None);
    assert_eq!(m, format!("{HERE}: TileList is not a struct"));
}

#[test]
fn an_entry_point_out_of_step_with_workgroups_fails_naming_both_sides() {
    let m = check_failure(|f| f.entry_points.push(("blend".into(), [8, 8, 1])));
    assert_eq!(
        m,
        format!("{HERE}: entry point `blend` is not in WORKGROUPS")
    );
    let m = check_failure(|f| {
        let classify = f.entry_points.iter_mut().find(|(n, _)| n == "classify");
        classify.unwrap().1 = [32, 1, 1];
    });
    assert!(
        m.contains(&format!(
            "{HERE}: `classify` has workgroup size [32, 1, 1] in the shader, {CLASSIFY_WORKGROUP:?} in WORKGROUPS"
        )),
        "{m}"
    );
}

#[test]
fn a_glsl_uniform_is_found_in_params_by_name_and_element() {
    let here = "enhance.wgsl entry enhance (GLSL) vs src/gpu/core/interface.rs";
    let (offsets, _) = params_layout();
    let k = |name: &str| PARAMS.iter().position(|(n, _)| *n == name).unwrap();
    // naga appends `_` to a name ending in a digit.
    let path = "_immediates_binding_cs.map_01_";
    assert_eq!(
        check::gl_uniform_param(here, path, offsets[k("map_01")]),
        (k("map_01"), offsets[k("map_01")])
    );
    // An array element is 16 bytes after the one before.
    let path = "_immediates_binding_cs.taps[1]";
    let taps = offsets[k("taps")] + 16;
    assert_eq!(check::gl_uniform_param(here, path, taps), (k("taps"), taps));
    let m = failure(|| {
        check::gl_uniform_param(here, "_immediates_binding_cs.lambda", 16);
    });
    assert_eq!(
        m,
        format!("{here}: uniform `_immediates_binding_cs.lambda` is not in PARAMS")
    );
    let m = failure(|| {
        check::gl_uniform_param(here, "lambda_e", 16);
    });
    assert_eq!(
        m,
        format!("{here}: uniform `lambda_e` is not a field of Params")
    );
    let m = failure(|| {
        check::gl_uniform_param(here, "_immediates_binding_cs.lambda_e", 20);
    });
    assert!(
        m.contains(&format!(
            "{here}: `_immediates_binding_cs.lambda_e` at byte 20 in the GLSL, 16 in PARAMS"
        )),
        "{m}"
    );
}

#[test]
fn a_used_resource_the_glsl_does_not_declare_fails() {
    let here = "enhance.wgsl entry enhance (GLSL) vs src/gpu/core/interface.rs";
    check::check_gl_binding(here, "layout(std430, binding = 2) buffer", "pixels", 2);
    let m = failure(|| check::check_gl_binding(here, "layout(binding = 3)", "pixels", 2));
    assert_eq!(
        m,
        format!("{here}: `pixels` is used but the GLSL declares nothing at `binding = 2`")
    );
}

// --- WGSL assembly and colour constants ---

#[test]
fn every_in_place_texel_has_a_codec() {
    for format in FORMAT_CODES {
        if let Some(texel) = in_place_texel(format) {
            let codec = wgsl::texel_codec(texel);
            assert!(codec.contains("fn texel_words(") && codec.contains("fn words_texel("));
        }
    }
    let m = failure(|| {
        wgsl::texel_codec("rgba32float");
    });
    assert!(m.contains("no texel codec for rgba32float"), "{m}");
}

#[test]
fn the_interface_declarations_name_every_params_field_and_the_access_bindings() {
    for p in pixel_accesses() {
        let s = wgsl::interface_wgsl(p.access, p.format);
        for (name, _) in PARAMS {
            assert!(s.contains(&format!("    {name}: ")), "{name}");
        }
        for (name, value) in CODES {
            assert!(s.contains(&format!("const {name}: u32 = {value}u;\n")));
        }
        let app_image = s.contains("var app_image: texture_storage_2d<");
        assert_eq!(app_image, p.in_place().is_some(), "{p:?}");
        let app_texels = s.contains("var app_texels: texture_2d<f32>");
        assert_eq!(app_texels, p.access == ACCESS_SAMPLED, "{p:?}");
        assert_eq!(
            s.contains("var<storage, read_write> pixels"),
            p.in_place().is_none()
        );
    }
}

#[test]
fn a_variant_is_specialised_by_constants() {
    assert_eq!(
        wgsl::specialise((1, 2, 256), true),
        "const METHOD: u32 = 1u;\nconst MODE: u32 = 2u;\nconst FORMAT: u32 = 256u;\nconst EXTRAS: bool = true;\nconst ABLATE: u32 = 0u;\nconst CUBE_ROOTS_BY_POW: bool = false;\n"
    );
    let ablated = wgsl::specialise_with((0, 0, 256), false, 7, true);
    assert!(ablated.ends_with("const ABLATE: u32 = 7u;\nconst CUBE_ROOTS_BY_POW: bool = true;\n"));
}

#[test]
fn every_method_gets_both_functions_one_of_them_a_stand_in() {
    for m in METHODS {
        let s = wgsl::method_wgsl(m.code);
        let linear = m.space == "Linear";
        assert!(s.contains(&format!("const METHOD_LINEAR: bool = {linear};")));
        assert_eq!(s.matches("fn method_scaled(").count(), 1, "{}", m.name);
        assert_eq!(s.matches("fn method_linear(").count(), 1, "{}", m.name);
    }
}

#[test]
fn the_colour_matrices_invert_and_the_polynomials_fold_scale_and_offset() {
    let inv = colour::invert(colour::RGB_TO_XYZ);
    for n in 0..9 {
        let (i, j) = (n / 3, n % 3);
        let p: f64 = (0..3).map(|k| colour::RGB_TO_XYZ[i][k] * inv[k][j]).sum();
        assert!((p - f64::from(u8::from(i == j))).abs() < 1e-12);
    }
    assert_eq!(
        colour::wgsl_polynomial("p", &[1.0, 2.0, 3.0], 2.0, 0.5),
        "fn p(x: vec4<f32>) -> vec4<f32> {\n    var r = vec4<f32>(6.000000000e0);\n    r = r * x + 4.000000000e0;\n    r = r * x + 2.500000000e0;\n    return r;\n}\n"
    );
    let s = colour::colour_constants();
    for name in [
        "RGB_TO_XYZ_2",
        "RGB_TO_T_0",
        "T_TO_RGB_1",
        "fn srgb_decode_poly(",
        "fn srgb_encode_poly(",
    ] {
        assert!(s.contains(name), "{name}");
    }
}

// --- The tables ---

#[test]
fn the_table_lists_modules_singles_and_variants_with_their_ids() {
    let mut t = Table::default();
    t.single("DECODE_CAMERA", "decode_camera", "decode", true);
    let blur = t.add("decode_blur_0", "decode_blur", true, None);
    t.decode_blur.push(blur);
    let pixels = PixelAccess {
        access: ACCESS_IN_PLACE,
        format: 0,
    };
    let v = Enhance {
        method: 0,
        mode: MODE_SPLIT,
        pixels,
        extras: true,
        shared: false,
        pow_roots: true,
    };
    let id = t.add(&v.file(), "enhance", false, Some(pixels));
    t.enhance.push((v, id));
    let c = variants::Classify {
        pixels,
        method: 0,
        rows: false,
    };
    let id = t.add(&c.file(), "classify", false, Some(pixels));
    t.classify.push((c, id));
    let a = variants::Ablated {
        method: 0,
        pixels,
        ablate: 5,
        pow_roots: false,
    };
    let id = t.add(&a.file(), "enhance", false, Some(pixels));
    t.ablated.push((a, true, id));
    assert_eq!(
        t.source(),
        "// Generated by build.rs.
/// Every embedded shader; a ShaderId is an index into this list.
pub static MODULES: &[ShaderModule] = &[
    spirv!(\"decode_camera\", \"decode\", true, None, false),
    spirv!(\"decode_blur_0\", \"decode_blur\", true, None, false),
    spirv!(\"enhance_m0_v2_f0_a2_e1_p\", \"enhance\", false, Some(0), false),
    spirv!(\"classify_f0_a2\", \"classify\", false, Some(0), false),
    spirv!(\"enhance_ablated_m0_f0_a2_x5\", \"enhance\", false, Some(0), false),
];
/// The id of `decode_camera`.
pub const ID_DECODE_CAMERA: usize = 0;
/// The background pass's id for each blur half-width (index = half-width).
pub static DECODE_BLUR: &[usize] = &[1];
/// (method, mode, format, access, extras, shared fetches, cube roots by pow, id) of each
/// `enhance` variant.
pub static ENHANCE_VARIANTS: &[VariantRow] = &[
    (0, 2, 0, 2, true, false, true, 2),
];
/// (format, access, method, by tile rows, id) of each `classify` variant.
pub static CLASSIFY_VARIANTS: &[(u32, u32, u32, bool, usize)] = &[
    (0, 2, 0, false, 3),
];
/// (method, access, ablations, shared fetches, cube roots by pow, id) of each ablated
/// `enhance` variant of the benchmark.
pub static ENHANCE_ABLATED: &[(u32, u32, u32, bool, bool, usize)] = &[
    (0, 2, 5, true, false, 4),
];
"
    );
}

#[test]
fn every_glsl_module_must_declare_the_same_uniforms() {
    let u = |path: &str, offset| GlUniform {
        path: path.into(),
        offset,
        kind: "F32",
    };
    let mut gl = GlTable::default();
    assert_eq!(gl.add("finish_tiles", 1, vec![]), 0);
    assert_eq!(gl.add("a", 1, vec![u("pc.lambda_e", 16)]), 1);
    assert_eq!(gl.add("b", 1, vec![u("pc.lambda_e", 16)]), 2);
    let m = failure(move || {
        gl.add("c", 1, vec![u("pc.lambda_jnd", 20)]);
    });
    assert!(m.contains("c.glsl: its Params uniforms differ"), "{m}");
}

/// The build's module hash is FNV-1a 64 (its published test values), the hash the program
/// binary cache keys its file by.
#[test]
fn module_hashes_are_fnv_1a_64() {
    assert_eq!(tables::source_hash(b""), 0xcbf2_9ce4_8422_2325);
    assert_eq!(tables::source_hash(b"a"), 0xaf63_dc4c_8601_ec8c);
    assert_eq!(tables::source_hash(b"foobar"), 0x8594_4171_f739_67e8);
}
