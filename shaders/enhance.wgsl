// The per-pixel enhancement (docs/algorithm.md, Per-pixel optimisation: Algorithm 1 and its
// four constraints) and the comparison methods (docs/algorithm.md, Comparison methods), on one
// display region's raw pixels, in place, four pixels at a time; each variant's method is its
// own file in shaders/methods/ (src/algorithm/method/table.rs), which build.rs appends
// (Colours in common.wgsl). Every branch is a per-pixel select: a CPU driver runs all of them
// anyway. A pixel the method leaves unchanged keeps its words, bit for bit.

// u32 words per pixel: 2 for the 16-bit formats.
const WORDS: u32 = select(1u, 2u, (FORMAT & 255u) == LAYOUT_RGBA16_UNORM || (FORMAT & 255u) == LAYOUT_RGBA16_FLOAT);

// Word 0 and (2-word formats) word 1 of four pixels.
struct Words {
    w0: vec4<u32>,
    w1: vec4<u32>,
}

// Pixels p..p+3 (one 16-byte access, two for the 2-word formats).
fn load_group(p: u32) -> Words {
    let lo = load_words4(p * WORDS);
    if (WORDS == 1u) {
        return Words(lo, lo);
    }
    let hi = load_words4((p + 2u) * WORDS);
    return Words(vec4<u32>(lo.xz, hi.xz), vec4<u32>(lo.yw, hi.yw));
}

// Stores the first n (1..=4) of pixels p..p+3.
fn store_group(p: u32, w: Words, n: u32) {
    if (WORDS == 1u) {
        store_words4(p, w.w0, n);
        return;
    }
    store_words4(p * 2u, vec4<u32>(w.w0.x, w.w1.x, w.w0.y, w.w1.y), min(n, 2u) * 2u);
    if (n > 2u) {
        store_words4((p + 2u) * 2u, vec4<u32>(w.w0.z, w.w1.z, w.w0.w, w.w1.w), (n - 2u) * 2u);
    }
}

fn lo16(w: vec4<u32>) -> vec4<f32> {
    return vec4<f32>(w & vec4<u32>(0xffffu)) * (1.0 / 65535.0);
}

fn hi16(w: vec4<u32>) -> vec4<f32> {
    return vec4<f32>(w >> vec4<u32>(16u)) * (1.0 / 65535.0);
}

fn half_lo(w: vec4<u32>) -> vec4<f32> {
    return vec4<f32>(unpack2x16float(w.x).x, unpack2x16float(w.y).x, unpack2x16float(w.z).x, unpack2x16float(w.w).x);
}

fn half_hi(w: vec4<u32>) -> vec4<f32> {
    return vec4<f32>(unpack2x16float(w.x).y, unpack2x16float(w.y).y, unpack2x16float(w.z).y, unpack2x16float(w.w).y);
}

fn byte(w: vec4<u32>, shift: u32) -> vec4<f32> {
    return vec4<f32>((w >> vec4<u32>(shift)) & vec4<u32>(255u)) * (1.0 / 255.0);
}

fn bits10(w: vec4<u32>, shift: u32) -> vec4<f32> {
    return vec4<f32>((w >> vec4<u32>(shift)) & vec4<u32>(1023u)) * (1.0 / 1023.0);
}

// Stored channel values in [0, 1] (sRGB-encoded or linear, as the format says).
fn stored_colours(w: Words) -> Colours {
    switch FORMAT & 255u {
        case LAYOUT_RGBA8: {
            return Colours(byte(w.w0, 0u), byte(w.w0, 8u), byte(w.w0, 16u));
        }
        case LAYOUT_BGRA8: {
            return Colours(byte(w.w0, 16u), byte(w.w0, 8u), byte(w.w0, 0u));
        }
        case LAYOUT_A2B10G10R10: {
            return Colours(bits10(w.w0, 0u), bits10(w.w0, 10u), bits10(w.w0, 20u));
        }
        case LAYOUT_RGBA16_UNORM: {
            return Colours(lo16(w.w0), hi16(w.w0), lo16(w.w1));
        }
        default: {
            return Colours(half_lo(w.w0), half_hi(w.w0), half_lo(w.w1));
        }
    }
}

// Pixels the enhancement leaves alone: exactly black (transparent on an additive display) or
// alpha 0 (docs/algorithm.md, Skipped pixels).
fn see_through(w: Words) -> vec4<bool> {
    switch FORMAT & 255u {
        case LAYOUT_RGBA8, LAYOUT_BGRA8: {
            return ((w.w0 & vec4<u32>(0xffffffu)) == vec4<u32>(0u)) | ((w.w0 >> vec4<u32>(24u)) == vec4<u32>(0u));
        }
        case LAYOUT_A2B10G10R10: {
            return ((w.w0 & vec4<u32>(0x3fffffffu)) == vec4<u32>(0u)) | ((w.w0 >> vec4<u32>(30u)) == vec4<u32>(0u));
        }
        case LAYOUT_RGBA16_UNORM: {
            return ((w.w0 == vec4<u32>(0u)) & ((w.w1 & vec4<u32>(0xffffu)) == vec4<u32>(0u))) | ((w.w1 >> vec4<u32>(16u)) == vec4<u32>(0u));
        }
        default: {
            let c = stored_colours(w);
            return ((c[0] == vec4<f32>(0.0)) & (c[1] == vec4<f32>(0.0)) & (c[2] == vec4<f32>(0.0))) | (half_hi(w.w1) == vec4<f32>(0.0));
        }
    }
}

fn quantise(v: vec4<f32>, levels: f32) -> vec4<u32> {
    return vec4<u32>(floor(levels * v + 0.5));
}

fn pack_halves(lo: vec4<f32>, hi: vec4<f32>) -> vec4<u32> {
    return vec4<u32>(pack2x16float(vec2<f32>(lo.x, hi.x)), pack2x16float(vec2<f32>(lo.y, hi.y)), pack2x16float(vec2<f32>(lo.z, hi.z)), pack2x16float(vec2<f32>(lo.w, hi.w)));
}

// The words of pixels with new colour channels (stored encoding, [0, 1]); alpha bits kept.
fn encode_words(old: Words, v: Colours) -> Words {
    switch FORMAT & 255u {
        case LAYOUT_RGBA8, LAYOUT_BGRA8: {
            var c = v;
            if ((FORMAT & 255u) == LAYOUT_BGRA8) {
                c = Colours(v[2], v[1], v[0]);
            }
            let q = quantise(c[0], 255.0) | (quantise(c[1], 255.0) << vec4<u32>(8u)) | (quantise(c[2], 255.0) << vec4<u32>(16u));
            return Words((old.w0 & vec4<u32>(0xff000000u)) | q, old.w1);
        }
        case LAYOUT_A2B10G10R10: {
            let q = quantise(v[0], 1023.0) | (quantise(v[1], 1023.0) << vec4<u32>(10u)) | (quantise(v[2], 1023.0) << vec4<u32>(20u));
            return Words((old.w0 & vec4<u32>(0xc0000000u)) | q, old.w1);
        }
        case LAYOUT_RGBA16_UNORM: {
            let rg = quantise(v[0], 65535.0) | (quantise(v[1], 65535.0) << vec4<u32>(16u));
            return Words(rg, (old.w1 & vec4<u32>(0xffff0000u)) | quantise(v[2], 65535.0));
        }
        default: {
            let b = pack_halves(v[2], vec4<f32>(0.0)) & vec4<u32>(0xffffu);
            return Words(pack_halves(v[0], v[1]), (old.w1 & vec4<u32>(0xffff0000u)) | b);
        }
    }
}

// What stored values read back as after encode_words quantises them (float16 taken as exact).
fn quantised(v: Colours) -> Colours {
    var levels = 255.0;
    switch FORMAT & 255u {
        case LAYOUT_A2B10G10R10: {
            levels = 1023.0;
        }
        case LAYOUT_RGBA16_UNORM: {
            levels = 65535.0;
        }
        case LAYOUT_RGBA16_FLOAT: {
            return v;
        }
        default: {}
    }
    let q = Colours(floor(levels * v[0] + 0.5), floor(levels * v[1] + 0.5), floor(levels * v[2] + 0.5));
    return (1.0 / levels) * q;
}

// Whether the benchmark's ablation `part` (ABLATE_*; build.rs's constant ABLATE, 0 in every
// shader the layer runs) takes that part out of this variant.
fn ablated(part: u32) -> bool {
    return (ABLATE & part) != 0u;
}

fn is_srgb() -> bool {
    return (FORMAT & FORMAT_SRGB_BIT) != 0u && !ablated(ABLATE_CODEC);
}

// Linear light of stored values (only the 8-bit formats are sRGB-encoded).
fn decode_stored(v: Colours) -> Colours {
    if (is_srgb()) {
        return Colours(srgb_decode(v[0]), srgb_decode(v[1]), srgb_decode(v[2]));
    }
    return v;
}

// The stored values linear colours are written as (before quantisation).
fn encode_stored(v: Colours) -> Colours {
    if (is_srgb()) {
        return Colours(srgb_encode(v[0]), srgb_encode(v[1]), srgb_encode(v[2]));
    }
    return v;
}

fn clip(c: Colours) -> Colours {
    let lo = vec4<f32>(0.0);
    let hi = vec4<f32>(1.0);
    return Colours(clamp(c[0], lo, hi), clamp(c[1], lo, hi), clamp(c[2], lo, hi));
}

// The JND constraint: where P is strictly inside the sphere |X - B| = r and D is not, P moves
// back to the first point where the segment D->P meets the sphere. Squared lengths against
// r^2: the tests of docs/algorithm.md, JND step, up to float rounding at the boundary.
fn jnd_constraint(d: Colours, p: Colours, b: Colours) -> Colours {
    let r2 = pc.lambda_jnd * pc.lambda_jnd;
    let pb = p - b;
    let db = d - b;
    let pd = p - d;
    let a = dots(pd, pd);
    let c = dots(db, db) - r2;
    let h = dots(pd, db);
    let s = c / (-h + sqrt(max(h * h - a * c, vec4<f32>(0.0))));
    let keep = (dots(pb, pb) >= vec4<f32>(r2)) | (c < vec4<f32>(0.0)) | (a == vec4<f32>(0.0));
    return pick(d + per_pixel(s, pd), p, keep);
}

// Beyond the paper (off at 0, compiled out unless EXTRAS): on a near-grey background, move P
// further along D's own chroma direction by achromatic_boost x the room left under lambda_e
// (see src/algorithm/scaled.rs).
const ACHROMATIC_CHROMA: f32 = 0.08;

fn achromatic_boost(d: Colours, p: Colours, b: Colours) -> Colours {
    if (!EXTRAS) {
        return p;
    }
    let b_chroma = sqrt(b[1] * b[1] + b[2] * b[2]);
    let d_chroma = sqrt(d[1] * d[1] + d[2] * d[2]);
    let pd = p - d;
    let room = max(pc.lambda_e - sqrt(dots(pd, pd)), vec4<f32>(0.0));
    let k = pc.achromatic_boost * (1.0 - b_chroma / ACHROMATIC_CHROMA) * room / d_chroma;
    let skip = vec4<bool>(pc.achromatic_boost <= 0.0) | (b_chroma >= vec4<f32>(ACHROMATIC_CHROMA)) | (d_chroma <= vec4<f32>(1e-6));
    return pick(p + Colours(vec4<f32>(0.0), k * d[1], k * d[2]), p, skip);
}

// Beyond the paper (off at 0, compiled out unless EXTRAS): the output's luminance Y at most
// (1 + luminance_cap) x the input's.
fn cap_luminance(display: Colours, out: Colours) -> Colours {
    if (!EXTRAS) {
        return out;
    }
    let limit = (1.0 + pc.luminance_cap) * row_times(RGB_TO_XYZ_1, display);
    let y = row_times(RGB_TO_XYZ_1, out);
    return pick(out, per_pixel(limit / y, out), (y > limit) & vec4<bool>(pc.luminance_cap > 0.0));
}

// What a scaled-space method starts from (per pixel, four at a time): D and B, the change
// vector E (at most lambda_e long, toward I = -B/|B|), I - D and 1/|I - D| (0 where I = D),
// E'.D' and the hue part (hue_a, hue_b) of E' = (0, E.a, E.b). Chroma constraint: E'_ch is E's
// a*b* part along D's a*b* direction, E'_h the rest; an achromatic D (|D'| <= 1e-6) has no
// chroma direction, so all of E' is hue.
struct Step {
    d: Colours,
    b: Colours,
    e: Colours,
    to_i: Colours,
    inv_n: vec4<f32>,
    ed: vec4<f32>,
    hue_a: vec4<f32>,
    hue_b: vec4<f32>,
}

// The method's P in the scaled space (== D where nothing changes). The method's own
// `method_scaled(s: Step) -> Colours` (shaders/methods/, appended by build.rs) gives P; one
// reciprocal of |I - D| serves both E and cos_l, since |E| = min(|I - D|, lambda_e).
fn enhance_scaled(d: Colours, b: Colours) -> Colours {
    let nb2 = dots(b, b);
    let to_i = per_pixel(-1.0 / sqrt(nb2), b) - d;
    let n = sqrt(dots(to_i, to_i));
    let inv_n = select(vec4<f32>(0.0), 1.0 / n, n > vec4<f32>(0.0));
    let e = per_pixel(min(n, vec4<f32>(pc.lambda_e)) * inv_n, to_i);
    let d2 = d[1] * d[1] + d[2] * d[2];
    let ed = e[1] * d[1] + e[2] * d[2];
    let along = select(ed / d2, vec4<f32>(0.0), d2 <= vec4<f32>(1e-12));
    let hue_a = e[1] - along * d[1];
    let hue_b = e[2] - along * d[2];
    let p = method_scaled(Step(d, b, e, to_i, inv_n, ed, hue_a, hue_b));
    // |B| <= 1e-6: no complementary direction.
    return pick(p, d, nb2 <= vec4<f32>(1e-12));
}

struct Enhanced {
    // The enhanced colours in linear light, clipped, where `changed` (anything elsewhere: those
    // pixels keep their words).
    linear: Colours,
    // False where the method leaves the pixel unchanged.
    changed: vec4<bool>,
}

// What the perceptual method did with each pixel (PERCEIVED_*; 0 from every other method),
// which its heatmap shows.
const PERCEIVED_LEFT_ALONE: u32 = 1u;
const PERCEIVED_TO_TARGET: u32 = 2u;
const PERCEIVED_OUT_OF_REACH: u32 = 3u;

struct Perceived {
    out: Enhanced,
    kind: vec4<u32>,
}

// The display pixels' background (docs/algorithm.md, Background preparation): `linear` sampled from the blurred camera
// image (not attenuated: what subtraction uses), `scaled` the paper's B.
struct Background {
    linear: Colours,
    scaled: Colours,
}

fn enhance_linear(display: Colours, bg: Background) -> Perceived {
    let b = bg.scaled;
    if (METHOD_LINEAR) {
        // A method in linear light (shaders/methods/, `method_linear`): every pixel changes.
        let out = method_linear(display, bg);
        return Perceived(Enhanced(cap_luminance(display, clip(out)), vec4<bool>(true)), vec4<u32>(0u));
    }
    if (ablated(ABLATE_METHOD)) {
        return Perceived(Enhanced(display, vec4<bool>(true)), vec4<u32>(0u));
    }
    let d = linear_to_scaled(display);
    if (METHOD_PERCEPTUAL) {
        // The paper's change spent by perception (shaders/methods/, `method_perceptual`), which
        // runs the paper's method (`scaled_output`) only where it needs its budget.
        return method_perceptual(display, d, bg);
    }
    return Perceived(scaled_output(display, d, b), vec4<u32>(0u));
}

// The scaled method's output for display pixels whose scaled colour is `d`, over B `b`.
fn scaled_output(display: Colours, d: Colours, b: Colours) -> Enhanced {
    let s = enhance_scaled(d, b);
    let changed = (s[0] != d[0]) | (s[1] != d[1]) | (s[2] != d[2]);
    return Enhanced(cap_luminance(display, clip(scaled_to_linear(s))), changed);
}

// Unscaled CIE76 Delta E*ab between scaled-space colours.
fn delta_e(x: Colours, y: Colours) -> vec4<f32> {
    let d = x - y;
    return sqrt(2500.0 * d[0] * d[0] + 16384.0 * (d[1] * d[1] + d[2] * d[2]));
}

// The criterion of docs/algorithm.md, Evaluation metric, on the output as stored: dE(B, P) > dE(B, D), dE(P, D) >= 2.3.
fn is_enhanced(b: Colours, display: Colours, stored: Colours) -> vec4<bool> {
    let d = linear_to_scaled(display);
    let p = linear_to_scaled(decode_stored(quantised(stored)));
    return (delta_e(b, p) > delta_e(b, d)) & (delta_e(p, d) >= vec4<f32>(2.3));
}

// Texture coordinates of display pixels (x..x+3, y) in the camera image: the view's
// CameraMapping with its projective divide (an affine mapping has a bottom row of 0, 0, 1).
// Texel centres at (i + 0.5) / W, origin top-left (docs/algorithm.md, FoV calibration).
fn camera_uv(x: u32, y: u32) -> array<vec4<f32>, 2> {
    let u = (vec4<f32>(vec4<u32>(x) + vec4<u32>(0u, 1u, 2u, 3u)) + 0.5) / f32(pc.region_size.x);
    let v = vec4<f32>((f32(y) + 0.5) / f32(pc.region_size.y));
    let z = pc.map_20 * u + pc.map_21 * v + pc.map_22;
    let cu = (pc.map_00 * u + pc.map_01 * v + pc.map_02) / z;
    let cv = (pc.map_10 * u + pc.map_11 * v + pc.map_12) / z;
    return array<vec4<f32>, 2>(cu, cv);
}

// `sampled_background(x, y) -> Background`, the background of pixels x..x+3 of row y through
// camera_uv, is in sample_general.wgsl or sample_shared.wgsl (build.rs appends one).

// The new words of pixels x..x+3 of a row given their words and background; unchanged words
// where the method or mode leaves a pixel alone.
fn enhance_group(x: u32, w: Words, bg: Background) -> Words {
    if (MODE == MODE_BACKGROUND) {
        return encode_words(w, encode_stored(pc.transmittance * bg.linear));
    }
    let b = bg.scaled;
    let display = decode_stored(stored_colours(w));
    let perceived = enhance_linear(display, bg);
    let e = perceived.out;
    let stored = encode_stored(e.linear);
    var out = encode_words(w, stored);
    var changed = e.changed & !see_through(w);
    if (MODE == MODE_HEATMAP && METHOD_PERCEPTUAL) {
        // Every content pixel by its class: left alone green, brought to the target cyan, out
        // of reach magenta.
        let k = perceived.kind;
        let one = vec4<f32>(1.0);
        let zero = vec4<f32>(0.0);
        let reach = k == vec4<u32>(PERCEIVED_OUT_OF_REACH);
        out = encode_words(w, Colours(select(zero, one, reach), select(one, zero, reach), select(zero, one, k >= vec4<u32>(PERCEIVED_TO_TARGET))));
        changed = !see_through(w);
    } else if (MODE == MODE_HEATMAP) {
        out = encode_words(w, Colours(vec4<f32>(0.0), vec4<f32>(1.0), vec4<f32>(1.0)));
        changed = changed & is_enhanced(b, display, stored);
    }
    if (MODE == MODE_SPLIT) {
        // Original left of the middle, a white divider on columns half - 1 and half.
        let half = pc.region_size.x / 2u;
        let xs = vec4<u32>(x) + vec4<u32>(0u, 1u, 2u, 3u);
        let divider = (xs + 1u == vec4<u32>(half)) | (xs == vec4<u32>(half));
        let white = encode_words(w, Colours(vec4<f32>(1.0), vec4<f32>(1.0), vec4<f32>(1.0)));
        changed = (changed & (xs > vec4<u32>(half))) | divider;
        out = Words(select(out.w0, white.w0, divider), select(out.w1, white.w1, divider));
    }
    return Words(select(w.w0, out.w0, changed), select(w.w1, out.w1, changed));
}

// One invocation per tile row: 8 tiles per workgroup (local.x, so the 8 SIMD lanes of a CPU
// driver read neighbouring tiles of one row), 8 rows per tile (local.y). The row's pixels and
// background samples are all loaded first, so that their cache misses overlap, then enhanced
// 4 at a time.
@compute @workgroup_size(TILE, TILE)
fn enhance(@builtin(workgroup_id) group: vec3<u32>, @builtin(local_invocation_id) local: vec3<u32>) {
    let k = (group.y * INDIRECT_ROW_GROUPS + group.x) * TILE + local.x;
    if (k >= tiles.total || ablated(ABLATE_ENHANCE_PASS)) {
        return;
    }
    let tile = tiles.index[k];
    let x0 = (tile % pc.tile_columns) * TILE;
    let y = (tile / pc.tile_columns) * TILE + local.y;
    let width = pc.region_size.x;
    if (y >= pc.region_size.y) {
        return;
    }
    let row = y * width + x0;
    let valid = min(TILE, width - x0);
    // The second group re-reads the first where the row ends before it (never stored).
    let second = row + select(0u, 4u, valid > 4u);
    if (METHOD_PERCEPTUAL) {
        // One group after the other: the perceptual method's search holds many values, and a
        // GPU keeps more invocations in flight when the second group's are not held through it
        // (docs/performance.md, A GPU's compiler with no GPU); a CPU driver runs it as fast.
        store_group(row, enhance_group(x0, load_group(row), background_at(x0, y)), min(valid, 4u));
        if (valid > 4u) {
            let x_second = x0 + 4u;
            store_group(second, enhance_group(x_second, load_group(second), background_at(x_second, y)), valid - 4u);
        }
        return;
    }
    let w_first = load_group(row);
    let w_second = load_group(second);
    let x_second = x0 + select(0u, 4u, valid > 4u);
    let b_first = background_at(x0, y);
    let b_second = background_at(x_second, y);
    store_group(row, enhance_group(x0, w_first, b_first), min(valid, 4u));
    if (valid > 4u) {
        store_group(second, enhance_group(x_second, w_second, b_second), valid - 4u);
    }
}

// The background of pixels x..x+3 of row y: sampled, or a constant mid grey where the
// benchmark ablates the sampling.
fn background_at(x: u32, y: u32) -> Background {
    if (ablated(ABLATE_BACKGROUND)) {
        let grey = Colours(vec4<f32>(0.5), vec4<f32>(0.5), vec4<f32>(0.5));
        return Background(grey, linear_to_scaled(pc.transmittance * grey));
    }
    return sampled_background(x, y);
}

// Of pixels x..x+3 of row y (words w), those the method may change: all, but in the perceptual
// method's own `classify` variants (built for its enhance and split modes) only those below
// its target, so that the tiles it leaves alone are not listed at all.
fn may_change(x: u32, y: u32, w: Words) -> vec4<bool> {
    if (!METHOD_PERCEPTUAL) {
        return vec4<bool>(true);
    }
    return perceptual_may_change(decode_stored(stored_colours(w)), sampled_background(x, y));
}

// `content_from` of a tile the current mode wants whatever it holds.
const WHOLE_TILE: u32 = 0xffffffffu;

// The first column of the tile at x0 whose pixels count as content in the current mode (right
// of the split divider), or WHOLE_TILE (the background view, the divider's columns).
fn content_from(x0: u32) -> u32 {
    if (pc.mode == MODE_BACKGROUND) {
        return WHOLE_TILE;
    }
    if (pc.mode == MODE_SPLIT) {
        // The divider columns half - 1 and half are drawn on every row.
        let half = pc.region_size.x / 2u;
        if (x0 <= half && half < x0 + TILE + 1u) {
            return WHOLE_TILE;
        }
        return max(x0, half + 1u);
    }
    return x0;
}

// Whether a tile needs the enhancement pass in the current mode: it holds a foreground pixel
// (in the perceptual method's own variant, one it may change).
fn tile_wanted(tx: u32, ty: u32) -> bool {
    let x0 = tx * TILE;
    let y0 = ty * TILE;
    let first_x = content_from(x0);
    if (first_x == WHOLE_TILE) {
        return true;
    }
    // Row by row, stopping at the first row with a foreground pixel (a full frame reads one
    // row per tile). Pixels outside the region or left of the split divider are masked.
    var first_row = TILE;
    for (var dy = 0u; dy < TILE && first_row == TILE; dy++) {
        if (y0 + dy >= pc.region_size.y) {
            break;
        }
        for (var c = 0u; c < TILE; c += 4u) {
            if (any(foreground(x0 + c, y0 + dy, first_x, false))) {
                first_row = dy;
            }
        }
    }
    if (!METHOD_PERCEPTUAL) {
        return first_row < TILE;
    }
    // The perceptual method's own variant: from that row on, four pixels at a time, until one
    // it may change. A tile without foreground runs no group of it (a CPU driver, whose SIMD
    // lanes are neighbouring tiles, may still run one under an empty mask).
    var found = false;
    for (var g = first_row * (TILE / 4u); g < TILE * (TILE / 4u) && !found; g++) {
        let y = y0 + g / (TILE / 4u);
        if (y >= pc.region_size.y) {
            break;
        }
        found = any(foreground(x0 + (g % (TILE / 4u)) * 4u, y, first_x, true));
    }
    return found;
}

// Whether row dy of a tile holds a pixel the method may change (in the perceptual method's
// own `classify_rows`: a foreground pixel below its target).
fn tile_row_wanted(tx: u32, ty: u32, dy: u32) -> bool {
    let x0 = tx * TILE;
    let y = ty * TILE + dy;
    let first_x = content_from(x0);
    if (first_x == WHOLE_TILE) {
        return true;
    }
    if (y >= pc.region_size.y) {
        return false;
    }
    // Only a row with content evaluates the model (a GPU skips the others' branch).
    let content = foreground(x0, y, first_x, false) | foreground(x0 + 4u, y, first_x, false);
    if (!any(content)) {
        return false;
    }
    return any(foreground(x0, y, first_x, true)) || any(foreground(x0 + 4u, y, first_x, true));
}

// Of pixels x..x+3 of row y: those in the region, at or right of first_x and foreground, and,
// where `changing`, of those the ones the method may change.
fn foreground(x: u32, y: u32, first_x: u32, changing: bool) -> vec4<bool> {
    let width = pc.region_size.x;
    let xs = vec4<u32>(x) + vec4<u32>(0u, 1u, 2u, 3u);
    let w = load_group(select(0u, y * width + x, x < width));
    let inside = (xs < vec4<u32>(width)) & (xs >= vec4<u32>(first_x));
    var wanted = inside & !see_through(w);
    if (changing) {
        wanted = wanted & may_change(x, y, w);
    }
    return wanted;
}

// Appends tile (tx, ty) to the list.
fn list_tile(tx: u32, ty: u32) {
    let k = atomicAdd(&tiles.count, 1u);
    tiles.index[k] = ty * pc.tile_columns + tx;
}

// One invocation per tile: lists the tiles with any foreground pixel (in the perceptual method's
// own variant, any it may change), a row of tiles per workgroup (CLASSIFY_WORKGROUP in
// src/gpu/core/interface.rs) so that the list runs in row order.
@compute @workgroup_size(CLASSIFY_WORKGROUP_X, CLASSIFY_WORKGROUP_Y)
fn classify(@builtin(global_invocation_id) id: vec3<u32>) {
    let rows = (pc.region_size.y + TILE - 1u) / TILE;
    if (id.x >= pc.tile_columns || id.y >= rows || !tile_wanted(id.x, id.y)) {
        return;
    }
    list_tile(id.x, id.y);
}

// Which of a workgroup's tiles `classify_rows` lists.
var<workgroup> wanted_tiles: array<atomic<u32>, TILE>;

// The perceptual method's own classify with an invocation per tile row, as `enhance` runs:
// TILE tiles of a row per workgroup (local.x), TILE rows each (local.y). It lists the tiles
// `classify` lists, with TILE times as many invocations checking their pixels side by side,
// but no tile stops at its first pixel below the target (`contrastxr bench --ablate
// classify-rows` compares them).
@compute @workgroup_size(TILE, TILE)
fn classify_rows(@builtin(workgroup_id) group: vec3<u32>, @builtin(local_invocation_id) local: vec3<u32>) {
    let tx = group.x * TILE + local.x;
    let ty = group.y;
    let rows = (pc.region_size.y + TILE - 1u) / TILE;
    let tile = tx < pc.tile_columns && ty < rows;
    if (local.y == 0u) {
        atomicStore(&wanted_tiles[local.x], 0u);
    }
    workgroupBarrier();
    if (tile && tile_row_wanted(tx, ty, local.y)) {
        atomicStore(&wanted_tiles[local.x], 1u);
    }
    workgroupBarrier();
    if (tile && local.y == 0u && atomicLoad(&wanted_tiles[local.x]) != 0u) {
        list_tile(tx, ty);
    }
}

// Turns the tile count into the enhancement's indirect dispatch: TILE tiles per workgroup, at
// most 32768 workgroups per row (maxComputeWorkGroupCount is only guaranteed to be 65535); and
// into the write-back's indirect draw (shaders/write_back.wgsl): six vertices per tile. Zeroes
// the count for the next frame.
@compute @workgroup_size(1)
fn finish_tiles() {
    let n = atomicExchange(&tiles.count, 0u);
    let groups = (n + TILE - 1u) / TILE;
    tiles.total = n;
    tiles.groups[0] = min(groups, INDIRECT_ROW_GROUPS);
    tiles.groups[1] = (groups + (INDIRECT_ROW_GROUPS - 1u)) / INDIRECT_ROW_GROUPS;
    tiles.groups[2] = 1u;
    tiles.draw = array<u32, 4>(6u, n, 0u, 0u);
}
