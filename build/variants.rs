//! The variants build.rs compiles, as a typed list: every (pixel access, FORMAT code) a
//! per-pixel pass is built for, and every `enhance` and `classify` variant with its file name.
//!
//! The per-pixel `enhance` entry is built once per (method, view mode, pixel format) with all
//! three as WGSL constants, so each variant holds only its own code: a CPU driver such as
//! lavapipe runs every branch under an execution mask, so code behind a push-constant branch
//! costs time even when no pixel takes it (measured: the format as a push constant made a full
//! frame 1.8x slower). The codes are src/gpu/core/interface.rs's. `classify` is built once
//! per format. The beyond-the-paper extras (achromatic boost, luminance cap) are a fourth such
//! switch: a variant without them for when both are off, the default.

use crate::interface::*;
use crate::methods::{paper_code, perceptual_code, METHODS};

/// A pixel access (ACCESS_*) and FORMAT code a per-pixel pass is built for.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
pub struct PixelAccess {
    pub access: u32,
    pub format: u32,
}

impl PixelAccess {
    /// The FORMAT code of a variant that writes `app_image` (in place, or read through a
    /// sampled view); None for the buffer accesses.
    pub fn in_place(self) -> Option<u32> {
        (self.access == ACCESS_IN_PLACE || self.access == ACCESS_SAMPLED).then_some(self.format)
    }

    /// Whether the OpenGL backend gets a GLSL variant for it: every format but the BGRA ones
    /// (OpenGL has no BGRA internal format), through a buffer object (the buffer accesses)
    /// and, for the formats with a storage texel format, in place through an image unit.
    pub fn gl(self) -> bool {
        let in_place_ok = self.access != ACCESS_IN_PLACE || in_place_texel(self.format).is_some();
        let vulkan_only = self.access == ACCESS_SAMPLED;
        in_place_ok && !vulkan_only && self.format & !FORMAT_SRGB_BIT != LAYOUT_BGRA8
    }
}

/// Every (pixel access, FORMAT code) a per-pixel pass is built for: both buffer accesses for
/// every format, in place for the formats that have a storage texel format, and read through a
/// sampled view for the 8-bit sRGB ones (Vulkan only).
pub fn pixel_accesses() -> Vec<PixelAccess> {
    let buffers = [ACCESS_WIDE, ACCESS_NARROW]
        .into_iter()
        .flat_map(|access| FORMAT_CODES.map(|format| PixelAccess { access, format }));
    let in_place = FORMAT_CODES
        .into_iter()
        .filter(|&f| in_place_texel(f).is_some())
        .map(|format| PixelAccess {
            access: ACCESS_IN_PLACE,
            format,
        });
    let sampled = FORMAT_CODES
        .into_iter()
        .filter(|&f| sampled_read(f) && in_place_texel(f).is_some())
        .map(|format| PixelAccess {
            access: ACCESS_SAMPLED,
            format,
        });
    buffers.chain(in_place).chain(sampled).collect()
}

/// One `enhance` variant.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
pub struct Enhance {
    /// The method's code.
    pub method: u32,
    /// The view mode (MODE_*).
    pub mode: u32,
    pub pixels: PixelAccess,
    /// With the beyond-the-paper extras (achromatic boost, luminance cap).
    pub extras: bool,
    /// With shared fetches (shaders/sample_shared.wgsl instead of sample_general.wgsl).
    pub shared: bool,
    /// With the CIELAB cube roots by the driver's `pow` instead of the Newton steps (WGSL
    /// CUBE_ROOTS_BY_POW): what a GPU's views take, where one is built.
    pub pow_roots: bool,
}

impl Enhance {
    /// The SPIR-V (and GLSL) file's name, without its extension.
    pub fn file(&self) -> String {
        format!(
            "enhance_m{}_v{}_f{}_a{}_e{}{}{}",
            self.method,
            self.mode,
            self.pixels.format,
            self.pixels.access,
            u8::from(self.extras),
            if self.shared { "_s" } else { "" },
            pow_suffix(self.pow_roots)
        )
    }

    /// Whether the OpenGL backend gets it: the general sampling only (the shared fetches are
    /// a Vulkan-side optimisation).
    pub fn gl(&self) -> bool {
        self.pixels.gl() && !self.shared
    }
}

/// The file name's mark of a variant with the cube roots by `pow`.
fn pow_suffix(pow_roots: bool) -> &'static str {
    if pow_roots {
        "_p"
    } else {
        ""
    }
}

/// Every (method, mode, extras, shared fetches, cube roots) an `enhance` is built for, for one
/// pixel access. The fifth switch, shared fetches (shaders/sample_shared.wgsl instead of
/// sample_general.wgsl), has a group's four pixels read their camera texels once, valid only
/// for some mappings (src/gpu/core/shared_fetch.rs): built only for the defaults (the
/// paper's method in mode enhance, extras off), each variant costing about 40 kB of library.
/// The sixth, the cube roots by `pow` (a GPU's special-function unit; the Newton steps cost
/// less on a CPU driver), is built for the paper's and the perceptual method in mode enhance,
/// extras off, in place and through the sampled read: the ways a GPU's views take.
fn enhance_of(pixels: PixelAccess) -> Vec<Enhance> {
    let mut codes: Vec<u32> = METHODS.iter().map(|m| m.code).collect();
    codes.sort();
    assert!(
        codes.windows(2).all(|w| w[0] != w[1]),
        "src/algorithm/method/table.rs: two methods share a code"
    );
    let variant = |method, mode, extras, shared| Enhance {
        method,
        mode,
        pixels,
        extras,
        shared,
        pow_roots: false,
    };
    let mut v: Vec<Enhance> = METHODS
        .iter()
        .flat_map(|m| ENHANCE_MODES.iter().map(move |&mode| (m.code, mode)))
        .flat_map(|(m, mode)| {
            [
                variant(m, mode, false, false),
                variant(m, mode, true, false),
            ]
        })
        .collect();
    v.push(variant(paper_code(), MODE_BACKGROUND, false, false));
    v.push(variant(paper_code(), MODE_ENHANCE, false, true));
    if pixels.access == ACCESS_IN_PLACE || pixels.access == ACCESS_SAMPLED {
        let by_pow = |v: Enhance| Enhance {
            pow_roots: true,
            ..v
        };
        v.extend([
            by_pow(variant(paper_code(), MODE_ENHANCE, false, false)),
            by_pow(variant(paper_code(), MODE_ENHANCE, false, true)),
            by_pow(variant(perceptual_code(), MODE_ENHANCE, false, false)),
        ]);
    }
    v
}

/// Every `enhance` variant, in the table's order: by pixel access, then by method, mode,
/// extras, with the background mode and the shared fetches last.
pub fn enhance_variants() -> Vec<Enhance> {
    pixel_accesses().into_iter().flat_map(enhance_of).collect()
}

/// One ablated `enhance` variant of the benchmark (`contrastxr bench --ablate`): the paper's or
/// the perceptual method in mode enhance, extras off, RGBA8 sRGB, with the sampling the bench's
/// views take otherwise (the paper's: shared fetches; the perceptual method has no such
/// variant), some parts taken out (interface.rs ABLATE_*).
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
pub struct Ablated {
    /// paper_code() or perceptual_code().
    pub method: u32,
    pub pixels: PixelAccess,
    /// The ABLATE_* bits.
    pub ablate: u32,
    /// With the cube roots by `pow` (`Enhance::pow_roots`), as a GPU's views take them.
    pub pow_roots: bool,
}

impl Ablated {
    /// The method, mode and FORMAT codes it is specialised on.
    pub fn codes(&self) -> (u32, u32, u32) {
        (self.method, MODE_ENHANCE, self.pixels.format)
    }

    /// With shared fetches (shaders/sample_shared.wgsl): the paper's.
    pub fn shared(&self) -> bool {
        self.method == paper_code()
    }

    /// The SPIR-V file's name, without its extension.
    pub fn file(&self) -> String {
        format!(
            "enhance_ablated_m{}_f{}_a{}_x{}{}",
            self.method,
            self.pixels.format,
            self.pixels.access,
            self.ablate,
            pow_suffix(self.pow_roots)
        )
    }
}

/// Every ablated variant: the paper's ABLATIONS and the perceptual method's
/// PERCEPTUAL_ABLATIONS, for each pixel access of RGBA8 sRGB but the sampled read, with each
/// way of taking the cube roots (each in GLSL too, with the general sampling).
pub fn ablated_variants() -> Vec<Ablated> {
    let methods = [
        (paper_code(), &ABLATIONS[..]),
        (perceptual_code(), &PERCEPTUAL_ABLATIONS[..]),
    ];
    let accesses = ablation_accesses();
    methods
        .into_iter()
        .flat_map(|(method, ablations)| {
            let accesses = &accesses;
            ablations.iter().flat_map(move |&ablate| {
                accesses.iter().map(move |&pixels| Ablated {
                    method,
                    pixels,
                    ablate,
                    pow_roots: false,
                })
            })
        })
        .flat_map(|v| {
            [
                v,
                Ablated {
                    pow_roots: true,
                    ..v
                },
            ]
        })
        .collect()
}

/// The pixel accesses the benchmark's ablations run: those of RGBA8 sRGB but the sampled read.
fn ablation_accesses() -> Vec<PixelAccess> {
    let srgb8 = LAYOUT_RGBA8 | FORMAT_SRGB_BIT;
    pixel_accesses()
        .into_iter()
        .filter(|p| p.format == srgb8 && p.access != ACCESS_SAMPLED)
        .collect()
}

/// One `classify` variant (mode 0, extras off): built with the paper's method, which lists
/// every tile with content, or the perceptual method's, which lists only tiles with a pixel
/// below its target (it leaves the others as they are); an invocation per tile, or (the
/// benchmark's `classify-rows`, the perceptual method's only) per tile row.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
pub struct Classify {
    pub pixels: PixelAccess,
    /// The method's code: paper_code() or perceptual_code().
    pub method: u32,
    /// An invocation per tile row (`classify_rows`; src/gpu/core/plan.rs ClassifyCover).
    pub rows: bool,
}

impl Classify {
    /// Its entry point in shaders/enhance.wgsl.
    pub fn entry(&self) -> &'static str {
        match self.rows {
            false => "classify",
            true => "classify_rows",
        }
    }

    /// The SPIR-V (and GLSL) file's name, without its extension.
    pub fn file(&self) -> String {
        let own = if self.method == paper_code() {
            ""
        } else {
            "_perceptual"
        };
        let rows = if self.rows { "_rows" } else { "" };
        format!(
            "classify_f{}_a{}{own}{rows}",
            self.pixels.format, self.pixels.access
        )
    }
}

/// Every `classify` variant, in the table's order: two per pixel access (the paper's, the
/// perceptual method's), then the perceptual method's by tile rows for the benchmark's
/// ablation, on RGBA8 sRGB through the accesses the ablations run (as `ablated_variants`).
pub fn classify_variants() -> Vec<Classify> {
    let per_tile = pixel_accesses().into_iter().flat_map(|pixels| {
        [paper_code(), perceptual_code()].map(|method| Classify {
            pixels,
            method,
            rows: false,
        })
    });
    let rows = ablation_accesses().into_iter().map(|pixels| Classify {
        pixels,
        method: perceptual_code(),
        rows: true,
    });
    per_tile.chain(rows).collect()
}
