// Every per-pixel method, one entry each: the one place that holds "a method".
//
// Adding a method is adding an entry here, its WGSL (shaders/methods/), its CPU reference
// (a function of src/algorithm/scaled.rs, or of pixel.rs for one in linear light) and its test
// (docs/architecture.md, Adding a method). Everything else is derived from or checked against
// this table: the `Method` type and its names (src/algorithm/method/method_entry.rs), the values and help
// of the `method` and `mode` keys (src/config/keys.rs) and so of the CLI's --method, the shader
// code and the `enhance` variants build.rs compiles (one per method, with the entry's WGSL
// appended), and the tests that hold the entry's settings to KEYS, its push-constant fields to
// PARAMS and to its WGSL, its passes to a plan the backends run, and the example config and
// README to the names.
//
// Dependency-free: build.rs includes this file too (it uses name, code, space and wgsl).
//
// Fields of an entry:
// - the `Method` variant, then `name`: the value of `method` (and, for a comparison method, of
//   `mode`) on the command line, in config and in JSON;
// - `code`: the shader code, distinct (it names the SPIR-V files; never reuse a removed one);
// - `doc`: one line on what it does (the variant's doc comment);
// - `comparison`: whether `mode = NAME` also selects it (mode enhance with this method);
// - `reference`: `Scaled(f)`, f in src/algorithm/scaled.rs, called with D, B and the change
//   vector E in the scaled space where there is one (|B| > 1e-6), returning P; or `Linear(f)`,
//   f in src/algorithm/pixel.rs, called with the display and background in linear light,
//   returning the unclipped output; or `Perceptual(f)`, f in
//   src/algorithm/perception/perceptual_pixel.rs, called with the display, the background
//   and the paper method's output in linear light, returning the clipped output;
// - `wgsl`: its shader file, which defines `method_scaled(s: Step) -> Colours` (Scaled) or
//   `method_linear(display: Colours, bg: Background) -> Colours` (Linear) or
//   `method_perceptual(display: Colours, d: Colours, bg: Background) -> Perceived`
//   (Perceptual, which runs after the paper's `method_scaled`), see shaders/enhance.wgsl;
// - `settings`: the config keys it reads (beyond the shared background preparation);
// - `push`: the push-constant fields (src/gpu/core/interface.rs, PARAMS) its WGSL reads;
// - `passes`: its GPU passes in order (src/gpu/core/plan.rs makes them the steps both backends run).
macro_rules! with_methods {
    ($then:ident) => {
        $then! {
            Paper {
                name: "paper",
                code: 0,
                doc: "Algorithm 1 with its four constraints (the paper's method).",
                comparison: false,
                reference: Scaled(paper),
                wgsl: "shaders/methods/paper.wgsl",
                settings: ["lambda_e", "lambda_jnd_scaled", "achromatic_boost", "luminance_cap"],
                push: ["lambda_e", "lambda_jnd", "achromatic_boost"],
                passes: [Classify, FinishTiles, Enhance],
            },
            HueOnly {
                name: "hue-only",
                code: 1,
                doc: "P = D + E'_h.",
                comparison: true,
                reference: Scaled(hue_only),
                wgsl: "shaders/methods/hue_only.wgsl",
                settings: ["lambda_e", "luminance_cap"],
                push: [],
                passes: [Classify, FinishTiles, Enhance],
            },
            OtherHue {
                name: "other-hue",
                code: 2,
                doc: "P = D - E'_h.",
                comparison: true,
                reference: Scaled(other_hue),
                wgsl: "shaders/methods/other_hue.wgsl",
                settings: ["lambda_e", "luminance_cap"],
                push: [],
                passes: [Classify, FinishTiles, Enhance],
            },
            LumChroma {
                name: "lum-chroma",
                code: 3,
                doc: "P = D + |E'_h| * OD/|OD|.",
                comparison: true,
                reference: Scaled(lum_chroma),
                wgsl: "shaders/methods/lum_chroma.wgsl",
                settings: ["lambda_e", "luminance_cap"],
                push: [],
                passes: [Classify, FinishTiles, Enhance],
            },
            Subtraction {
                name: "subtraction",
                code: 4,
                doc: "Weiland et al. 2009: clip(k_v * display - k_b * background) in linear light.",
                comparison: true,
                reference: Linear(subtraction),
                wgsl: "shaders/methods/subtraction.wgsl",
                settings: ["luminance_cap"],
                push: ["k_v", "k_b"],
                passes: [Classify, FinishTiles, Enhance],
            },
            Luminance {
                name: "luminance",
                code: 5,
                doc: "Only L* moves, away from the background's, by lambda_e (hue and chroma kept).",
                comparison: true,
                reference: Scaled(luminance),
                wgsl: "shaders/methods/luminance.wgsl",
                settings: ["lambda_e", "luminance_cap"],
                push: ["lambda_e"],
                passes: [Classify, FinishTiles, Enhance],
            },
            Perceptual {
                name: "perceptual",
                code: 6,
                doc: "The paper's colour change spent where the eye gains most, down to the least that reaches target_contrast (beyond the paper).",
                comparison: false,
                reference: Perceptual(perceptual_step),
                wgsl: "shaders/methods/perceptual.wgsl",
                settings: ["lambda_e", "lambda_jnd_scaled", "achromatic_boost", "luminance_cap", "display_peak_nits", "world_nits", "target_contrast", "min_luminance", "frequency"],
                push: [],
                passes: [Classify, FinishTiles, Enhance],
            },
        }
    };
}
