// The per-pixel enhancement of spec section 3 (Algorithm 1 and its four constraints) and the
// comparison methods of section 5, on one display region's raw pixels, in place.
// A pixel the method leaves unchanged is not written, so its bits stay exactly as they were.

struct Pixel {
    // Stored channel values in [0, 1] (sRGB-encoded or linear, as the format says).
    rgb: vec3<f32>,
    alpha: f32,
    // True when the stored colour is exactly zero (black is transparent on an additive display).
    black: bool,
}

// u32 words per pixel: 2 for the 16-bit formats.
const WORDS: u32 = select(1u, 2u, (FORMAT & 255u) == LAYOUT_RGBA16_UNORM || (FORMAT & 255u) == LAYOUT_RGBA16_FLOAT);
// Pixels per group of 4 words (one 16-byte access).
const CHUNK_PIXELS: u32 = 4u / WORDS;

// A pixel's channels from its words (w.y is used by the 2-word formats only).
fn decode_words(w: vec2<u32>) -> Pixel {
    let pixel_layout = FORMAT & 255u;
    let w0 = w.x;
    if (pixel_layout == LAYOUT_RGBA8 || pixel_layout == LAYOUT_BGRA8) {
        var v = unpack4x8unorm(w0);
        if (pixel_layout == LAYOUT_BGRA8) {
            v = v.bgra;
        }
        return Pixel(v.rgb, v.a, (w0 & 0xffffffu) == 0u);
    }
    if (pixel_layout == LAYOUT_A2B10G10R10) {
        let rgb = vec3<u32>(w0 & 1023u, (w0 >> 10u) & 1023u, (w0 >> 20u) & 1023u);
        return Pixel(vec3<f32>(rgb) / 1023.0, f32(w0 >> 30u) / 3.0, (w0 & 0x3fffffffu) == 0u);
    }
    let w1 = w.y;
    if (pixel_layout == LAYOUT_RGBA16_UNORM) {
        let rg = unpack2x16unorm(w0);
        let ba = unpack2x16unorm(w1);
        return Pixel(vec3<f32>(rg, ba.x), ba.y, w0 == 0u && (w1 & 0xffffu) == 0u);
    }
    let rg = unpack2x16float(w0);
    let ba = unpack2x16float(w1);
    let rgb = vec3<f32>(rg, ba.x);
    return Pixel(rgb, ba.y, all(rgb == vec3<f32>(0.0)));
}

// The words of pixel j of a 4-word group (w.y is used by the 2-word formats only).
fn group_pixel(v: vec4<u32>, j: u32) -> vec2<u32> {
    return vec2<u32>(v[j * WORDS], v[j * WORDS + WORDS - 1u]);
}

// True for pixels the enhancement leaves alone: black (transparent on an additive display) or
// alpha 0 (spec section 3, "Skip").
fn is_see_through(w: vec2<u32>) -> bool {
    let px = decode_words(w);
    return px.black || px.alpha == 0.0;
}

// The words of a pixel with new colour channels (stored encoding, [0, 1]); alpha bits kept.
fn encode_words(old: vec2<u32>, v: vec3<f32>) -> vec2<u32> {
    let pixel_layout = FORMAT & 255u;
    if (pixel_layout == LAYOUT_RGBA8 || pixel_layout == LAYOUT_BGRA8) {
        let q = vec3<u32>(floor(255.0 * v + 0.5));
        let c = select(q, q.bgr, pixel_layout == LAYOUT_BGRA8);
        return vec2<u32>((old.x & 0xff000000u) | c.x | (c.y << 8u) | (c.z << 16u), old.y);
    }
    if (pixel_layout == LAYOUT_A2B10G10R10) {
        let q = vec3<u32>(floor(1023.0 * v + 0.5));
        return vec2<u32>((old.x & 0xc0000000u) | q.x | (q.y << 10u) | (q.z << 20u), old.y);
    }
    if (pixel_layout == LAYOUT_RGBA16_UNORM) {
        let q = vec3<u32>(floor(65535.0 * v + 0.5));
        return vec2<u32>(q.x | (q.y << 16u), (old.y & 0xffff0000u) | q.z);
    }
    let b = pack2x16float(vec2<f32>(v.b, 0.0)) & 0xffffu;
    return vec2<u32>(pack2x16float(v.rg), (old.y & 0xffff0000u) | b);
}

// The JND constraint: if P is strictly inside the sphere |X - B| = r and D is not, move P back
// to the first point where the segment D->P meets the sphere. Squared lengths against r^2:
// the same tests as the spec's lengths up to float rounding at the boundary.
fn jnd_constraint(d: vec3<f32>, p: vec3<f32>, b: vec3<f32>) -> vec3<f32> {
    let r2 = pc.lambda_jnd * pc.lambda_jnd;
    let pb = p - b;
    let db = d - b;
    let pd = p - d;
    let a = dot(pd, pd);
    let c = dot(db, db) - r2;
    if (dot(pb, pb) >= r2 || c < 0.0 || a == 0.0) {
        return p;
    }
    let h = dot(pd, db);
    let s = c / (-h + sqrt(max(h * h - a * c, 0.0)));
    return d + s * pd;
}

// Beyond the paper (off at 0): on a near-grey background, move P further along D's own chroma
// direction by achromatic_boost x the room left under lambda_e (see src/algorithm/scaled.rs).
const ACHROMATIC_CHROMA: f32 = 0.08;

fn achromatic_boost(d: vec3<f32>, p: vec3<f32>, b: vec3<f32>) -> vec3<f32> {
    let b_chroma = length(b.yz);
    let d_chroma = length(d.yz);
    if (!EXTRAS || pc.achromatic_boost <= 0.0 || b_chroma >= ACHROMATIC_CHROMA || d_chroma <= 1e-6) {
        return p;
    }
    let room = max(pc.lambda_e - length(p - d), 0.0);
    let k = pc.achromatic_boost * (1.0 - b_chroma / ACHROMATIC_CHROMA) * room / d_chroma;
    return p + vec3<f32>(0.0, k * d.yz);
}

// Beyond the paper (off at 0): the output's luminance Y at most (1 + luminance_cap) x the input's.
fn cap_luminance(display: vec3<f32>, out: vec3<f32>) -> vec3<f32> {
    if (!EXTRAS || pc.luminance_cap <= 0.0) {
        return out;
    }
    let limit = (1.0 + pc.luminance_cap) * dot(RGB_TO_XYZ_1, display);
    let y = dot(RGB_TO_XYZ_1, out);
    return select(out, out * (limit / y), y > limit);
}

// The hue part E'_h of E's a*b* part against D's a*b* direction (chroma constraint); E'_ch is
// e_ab - E'_h. An achromatic D (|D'| <= 1e-6) has no chroma direction: all of E' is hue.
fn hue_part(e_ab: vec2<f32>, d_ab: vec2<f32>) -> vec2<f32> {
    let d2 = dot(d_ab, d_ab);
    let chroma = (dot(e_ab, d_ab) / max(d2, 1e-30)) * d_ab;
    return select(e_ab - chroma, e_ab, d2 <= 1e-12);
}

// Algorithm 1 in the scaled space; returns P (== D where nothing changes). One reciprocal of
// |I - D| serves both E's length and cos_l, since |E| = min(|I - D|, lambda_e).
fn enhance_scaled(d: vec3<f32>, b: vec3<f32>) -> vec3<f32> {
    let nb2 = dot(b, b);
    if (nb2 <= 1e-12) {
        return d;
    }
    let to_i = -b * (1.0 / sqrt(nb2)) - d;
    let n = sqrt(dot(to_i, to_i));
    let inv_n = select(0.0, 1.0 / n, n > 0.0);
    let e = (min(n, pc.lambda_e) * inv_n) * to_i;
    let hue_ab = hue_part(e.yz, d.yz);
    let hue = vec3<f32>(0.0, hue_ab);
    switch METHOD {
        case METHOD_HUE_ONLY: {
            return d + hue;
        }
        case METHOD_OTHER_HUE: {
            return d - hue;
        }
        case METHOD_LUM_CHROMA: {
            let nd = length(d);
            if (nd <= 1e-6) {
                return d;
            }
            return d + (length(hue_ab) / nd) * d;
        }
        default: {
            // E'_ch kept only when it does not reduce chroma (E'.D' >= 0).
            let keeps_chroma = dot(e.yz, d.yz) >= 0.0;
            let dir_ab = select(hue_ab, e.yz, keeps_chroma);
            let cos_l = to_i.x * inv_n;
            let p = d + vec3<f32>((1.0 - abs(cos_l)) * e.x, dir_ab);
            return jnd_constraint(d, achromatic_boost(d, p, b), b);
        }
    }
}

// The enhanced colour of a foreground pixel in linear light, clipped; returns false when the
// method leaves it unchanged.
struct Enhanced {
    linear: vec3<f32>,
    changed: bool,
}

fn enhance_linear(i: u32, display: vec3<f32>, b: vec3<f32>) -> Enhanced {
    if (METHOD == METHOD_SUBTRACTION) {
        let out = pc.k_v * display - pc.k_b * bg_linear[i].rgb;
        return Enhanced(cap_luminance(display, clamp(out, vec3<f32>(0.0), vec3<f32>(1.0))), true);
    }
    let d = linear_to_scaled(display);
    let p = enhance_scaled(d, b);
    if (all(p == d)) {
        return Enhanced(display, false);
    }
    return Enhanced(cap_luminance(display, clamp(scaled_to_linear(p), vec3<f32>(0.0), vec3<f32>(1.0))), true);
}

fn is_srgb() -> bool {
    return (FORMAT & FORMAT_SRGB_BIT) != 0u;
}

// Linear light of stored values (only the 8-bit formats are sRGB-encoded).
fn decode_stored(v: vec3<f32>) -> vec3<f32> {
    return select(v, srgb_decode(v), is_srgb());
}

// The stored value a linear colour is written as (before quantisation).
fn encode_stored(v: vec3<f32>) -> vec3<f32> {
    return select(v, srgb_encode(v), is_srgb());
}

// What a stored value reads back as after encode_words quantises it (float16 is taken as exact).
fn quantised(v: vec3<f32>) -> vec3<f32> {
    let pixel_layout = FORMAT & 255u;
    var levels = 255.0;
    if (pixel_layout == LAYOUT_A2B10G10R10) {
        levels = 1023.0;
    } else if (pixel_layout == LAYOUT_RGBA16_UNORM) {
        levels = 65535.0;
    } else if (pixel_layout == LAYOUT_RGBA16_FLOAT) {
        return v;
    }
    return floor(levels * v + 0.5) / levels;
}

// Unscaled CIE76 Delta E*ab between two scaled-space colours.
fn delta_e(x: vec3<f32>, y: vec3<f32>) -> f32 {
    return length((x - y) * vec3<f32>(50.0, 128.0, 128.0));
}

// Spec section 4's criterion on the output as stored: dE(B, P) > dE(B, D), dE(P, D) >= 2.3.
fn is_enhanced(b: vec3<f32>, display: vec3<f32>, stored: vec3<f32>) -> bool {
    let d = linear_to_scaled(display);
    let p = linear_to_scaled(decode_stored(quantised(stored)));
    return delta_e(b, p) > delta_e(b, d) && delta_e(p, d) >= 2.3;
}

// The new words of pixel p (column x) given its words and packed B; unchanged words where the
// method or mode leaves the pixel alone.
fn enhance_pixel(p: u32, x: u32, w: vec2<u32>, packed_b: vec2<u32>) -> vec2<u32> {
    if (MODE == MODE_BACKGROUND) {
        return encode_words(w, encode_stored(pc.transmittance * bg_linear[p].rgb));
    }
    if (MODE == MODE_SPLIT) {
        let half = pc.region_size.x / 2u;
        if (x + 1u == half || x == half) {
            return encode_words(w, vec3<f32>(1.0));
        }
        if (x < half) {
            return w;
        }
    }
    let px = decode_words(w);
    if (px.black || px.alpha == 0.0) {
        return w;
    }
    let display = decode_stored(px.rgb);
    let b = unpack_background(packed_b);
    let e = enhance_linear(p, display, b);
    if (!e.changed) {
        return w;
    }
    let stored = encode_stored(e.linear);
    if (MODE == MODE_HEATMAP) {
        if (is_enhanced(b, display, stored)) {
            return encode_words(w, vec3<f32>(0.0, 1.0, 1.0));
        }
        return w;
    }
    return encode_words(w, stored);
}

// One of four values by index (constant-indexed selects: no local array in memory).
fn pick4(a: vec4<u32>, b: vec4<u32>, c: vec4<u32>, d: vec4<u32>, i: u32) -> vec4<u32> {
    return select(select(a, b, i == 1u), select(c, d, i == 3u), i >= 2u);
}

// One invocation per tile row: 8 tiles per workgroup (local.x, so the 8 SIMD lanes of a CPU
// driver read neighbouring tiles of one row), 8 rows per tile (local.y). The row's pixels and
// B are all loaded first, in groups of 4 words, so that their cache misses overlap; each
// group of pixels is stored once.
@compute @workgroup_size(8, 8)
fn enhance(@builtin(workgroup_id) group: vec3<u32>, @builtin(local_invocation_id) local: vec3<u32>) {
    let k = (group.y * 32768u + group.x) * TILE + local.x;
    if (k >= tiles.total) {
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
    // Loads past the row's last pixel re-read its first group instead (never used).
    let b0 = load_background2(row);
    let b1 = load_background2(row + select(0u, 2u, 2u < valid));
    let b2 = load_background2(row + select(0u, 4u, 4u < valid));
    let b3 = load_background2(row + select(0u, 6u, 6u < valid));
    let w0 = load_words4(row * WORDS);
    let w1 = load_words4((row + select(0u, CHUNK_PIXELS, CHUNK_PIXELS < valid)) * WORDS);
    var w2 = w0;
    var w3 = w0;
    if (CHUNK_PIXELS == 2u) {
        w2 = load_words4((row + select(0u, 4u, 4u < valid)) * WORDS);
        w3 = load_words4((row + select(0u, 6u, 6u < valid)) * WORDS);
    }
    for (var c = 0u; c < TILE / CHUNK_PIXELS; c++) {
        let first = c * CHUNK_PIXELS;
        if (first >= valid) {
            break;
        }
        let v = pick4(w0, w1, w2, w3, c);
        var out = v;
        let n = min(CHUNK_PIXELS, valid - first);
        for (var j = 0u; j < n; j++) {
            let b4 = pick4(b0, b1, b2, b3, (first + j) / 2u);
            let packed_b = select(b4.xy, b4.zw, ((first + j) & 1u) == 1u);
            let r = enhance_pixel(row + first + j, x0 + first + j, group_pixel(v, j), packed_b);
            out[j * WORDS] = r.x;
            out[j * WORDS + WORDS - 1u] = select(r.x, r.y, WORDS == 2u);
        }
        store_words4((row + first) * WORDS, out, n * WORDS);
    }
}

// Whether a tile needs the enhancement pass in the current mode.
fn tile_wanted(tx: u32, ty: u32) -> bool {
    let x0 = tx * TILE;
    let y0 = ty * TILE;
    let width = pc.region_size.x;
    if (pc.mode == MODE_BACKGROUND) {
        return true;
    }
    var first_x = x0;
    if (pc.mode == MODE_SPLIT) {
        // The divider columns half - 1 and half are drawn on every row.
        let half = width / 2u;
        if (x0 <= half && half < x0 + TILE + 1u) {
            return true;
        }
        first_x = max(x0, half + 1u);
    }
    // Row by row, stopping at the first row with a foreground pixel (a full frame reads one
    // row per tile). Pixels outside the region or left of the split divider are masked.
    var found = false;
    for (var dy = 0u; dy < TILE && !found; dy++) {
        let y = y0 + dy;
        if (y >= pc.region_size.y) {
            break;
        }
        for (var c = 0u; c < TILE / CHUNK_PIXELS; c++) {
            let x = x0 + c * CHUNK_PIXELS;
            let v = load_words4(select(0u, (y * width + x) * WORDS, x < width));
            for (var j = 0u; j < CHUNK_PIXELS; j++) {
                let inside = x + j < width && x + j >= first_x;
                found = found || (inside && !is_see_through(group_pixel(v, j)));
            }
        }
    }
    return found;
}

// One invocation per tile: lists the tiles with any foreground pixel.
@compute @workgroup_size(8, 8)
fn classify(@builtin(global_invocation_id) id: vec3<u32>) {
    let rows = (pc.region_size.y + TILE - 1u) / TILE;
    if (id.x >= pc.tile_columns || id.y >= rows || !tile_wanted(id.x, id.y)) {
        return;
    }
    let k = atomicAdd(&tiles.count, 1u);
    tiles.index[k] = id.y * pc.tile_columns + id.x;
}

// Turns the tile count into the enhancement's indirect dispatch: TILE tiles per workgroup, at
// most 32768 workgroups per row (maxComputeWorkGroupCount is only guaranteed to be 65535).
// Zeroes the count for the next frame.
@compute @workgroup_size(1)
fn finish_tiles() {
    let n = atomicExchange(&tiles.count, 0u);
    let groups = (n + TILE - 1u) / TILE;
    tiles.total = n;
    tiles.groups[0] = min(groups, 32768u);
    tiles.groups[1] = (groups + 32767u) / 32768u;
    tiles.groups[2] = 1u;
}
