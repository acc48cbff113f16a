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

fn pixel_words() -> u32 {
    let pixel_layout = FORMAT & 255u;
    return select(1u, 2u, pixel_layout == LAYOUT_RGBA16_UNORM || pixel_layout == LAYOUT_RGBA16_FLOAT);
}

fn load_pixel(i: u32) -> Pixel {
    let pixel_layout = FORMAT & 255u;
    let w0 = pixels[i * pixel_words()];
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
    let w1 = pixels[i * 2u + 1u];
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

// Writes new colour channels (stored encoding, [0, 1]) and keeps the alpha bits as they were.
fn store_rgb(i: u32, v: vec3<f32>) {
    let pixel_layout = FORMAT & 255u;
    if (pixel_layout == LAYOUT_RGBA8 || pixel_layout == LAYOUT_BGRA8) {
        let q = vec3<u32>(floor(255.0 * v + 0.5));
        let c = select(q, q.bgr, pixel_layout == LAYOUT_BGRA8);
        let old = pixels[i];
        pixels[i] = (old & 0xff000000u) | c.x | (c.y << 8u) | (c.z << 16u);
        return;
    }
    if (pixel_layout == LAYOUT_A2B10G10R10) {
        let q = vec3<u32>(floor(1023.0 * v + 0.5));
        let old = pixels[i];
        pixels[i] = (old & 0xc0000000u) | q.x | (q.y << 10u) | (q.z << 20u);
        return;
    }
    var w0: u32;
    var b: u32;
    if (pixel_layout == LAYOUT_RGBA16_UNORM) {
        let q = vec3<u32>(floor(65535.0 * v + 0.5));
        w0 = q.x | (q.y << 16u);
        b = q.z;
    } else {
        w0 = pack2x16float(v.rg);
        b = pack2x16float(vec2<f32>(v.b, 0.0)) & 0xffffu;
    }
    pixels[i * 2u] = w0;
    pixels[i * 2u + 1u] = (pixels[i * 2u + 1u] & 0xffff0000u) | b;
}

struct Split {
    // Chroma component of E' along D' (the paper's E'_ch) and the hue component E'_h.
    chroma: vec2<f32>,
    hue: vec2<f32>,
    // E'.D' >= 0: the change does not reduce chroma.
    keeps_chroma: bool,
}

// Splits the a*b* part of E against the display colour's a*b* direction (chroma constraint).
fn split_chroma(e_ab: vec2<f32>, d_ab: vec2<f32>) -> Split {
    let d2 = dot(d_ab, d_ab);
    if (sqrt(d2) <= 1e-6) {
        // Achromatic display colour: no chroma direction, all of E' counts as hue.
        return Split(vec2<f32>(0.0), e_ab, true);
    }
    let ed = dot(e_ab, d_ab);
    let chroma = (ed / d2) * d_ab;
    return Split(chroma, e_ab - chroma, ed >= 0.0);
}

// The JND constraint: if P is strictly inside the sphere |X - B| = r and D is not, move P back
// to the first point where the segment D->P meets the sphere.
fn jnd_constraint(d: vec3<f32>, p: vec3<f32>, b: vec3<f32>) -> vec3<f32> {
    let r = pc.lambda_jnd;
    if (length(p - b) >= r) {
        return p;
    }
    let db = d - b;
    let pd = p - d;
    let a = dot(pd, pd);
    if (length(db) < r || a == 0.0) {
        return p;
    }
    let h = dot(pd, db);
    let c = dot(db, db) - r * r;
    let s = c / (-h + sqrt(max(h * h - a * c, 0.0)));
    return d + s * pd;
}

// Beyond the paper (off at 0): on a near-grey background, move P further along D's own chroma
// direction by achromatic_boost x the room left under lambda_e (see src/algorithm/scaled.rs).
const ACHROMATIC_CHROMA: f32 = 0.08;

fn achromatic_boost(d: vec3<f32>, p: vec3<f32>, b: vec3<f32>) -> vec3<f32> {
    let b_chroma = length(b.yz);
    let d_chroma = length(d.yz);
    if (pc.achromatic_boost <= 0.0 || b_chroma >= ACHROMATIC_CHROMA || d_chroma <= 1e-6) {
        return p;
    }
    let room = max(pc.lambda_e - length(p - d), 0.0);
    let k = pc.achromatic_boost * (1.0 - b_chroma / ACHROMATIC_CHROMA) * room / d_chroma;
    return p + vec3<f32>(0.0, k * d.yz);
}

// Beyond the paper (off at 0): the output's luminance Y at most (1 + luminance_cap) x the input's.
fn cap_luminance(display: vec3<f32>, out: vec3<f32>) -> vec3<f32> {
    if (pc.luminance_cap <= 0.0) {
        return out;
    }
    let limit = (1.0 + pc.luminance_cap) * dot(RGB_TO_XYZ_1, display);
    let y = dot(RGB_TO_XYZ_1, out);
    return select(out, out * (limit / y), y > limit);
}

// Algorithm 1 in the scaled space; returns P (== D where nothing changes).
fn enhance_scaled(d: vec3<f32>, b: vec3<f32>) -> vec3<f32> {
    let nb = length(b);
    if (nb <= 1e-6) {
        return d;
    }
    let to_i = -b / nb - d;
    let n = length(to_i);
    var e = vec3<f32>(0.0);
    if (n > 0.0) {
        e = (min(n, pc.lambda_e) / n) * to_i;
    }
    let split = split_chroma(e.yz, d.yz);
    let hue = vec3<f32>(0.0, split.hue);
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
            return d + (length(split.hue) / nd) * d;
        }
        default: {
            let dir_ab = select(vec2<f32>(0.0), split.chroma, split.keeps_chroma) + split.hue;
            let ne = length(e);
            let cos_l = select(0.0, e.x / ne, ne > 0.0);
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

fn enhance_linear(i: u32, display: vec3<f32>) -> Enhanced {
    if (METHOD == METHOD_SUBTRACTION) {
        let out = pc.k_v * display - pc.k_b * bg_linear[i].rgb;
        return Enhanced(cap_luminance(display, clamp(out, vec3<f32>(0.0), vec3<f32>(1.0))), true);
    }
    let d = linear_to_scaled(display);
    let p = enhance_scaled(d, bg_scaled[i].xyz);
    if (all(p == d)) {
        return Enhanced(display, false);
    }
    return Enhanced(cap_luminance(display, clamp(scaled_to_linear(p), vec3<f32>(0.0), vec3<f32>(1.0))), true);
}

fn is_srgb() -> bool {
    return (FORMAT & FORMAT_SRGB_BIT) != 0u;
}

// Stored values are code / 255 exactly in 8-bit sRGB formats.
fn decode_stored(v: vec3<f32>) -> vec3<f32> {
    if (is_srgb()) {
        return srgb_decode_code(vec3<u32>(v * 255.0 + 0.5));
    }
    return v;
}

// The stored value a linear colour is written as (before quantisation).
fn encode_stored(v: vec3<f32>) -> vec3<f32> {
    return select(v, srgb_encode(v), is_srgb());
}

// What a stored value reads back as after store_rgb quantises it (float16 is taken as exact).
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
fn is_enhanced(i: u32, display: vec3<f32>, stored: vec3<f32>) -> bool {
    let b = bg_scaled[i].xyz;
    let d = linear_to_scaled(display);
    let p = linear_to_scaled(decode_stored(quantised(stored)));
    return delta_e(b, p) > delta_e(b, d) && delta_e(p, d) >= 2.3;
}

// The pixel of tile-list entry `group` at `local`, or none past the list or the region.
fn tile_pixel(group: vec3<u32>, local: vec3<u32>) -> vec2<u32> {
    let k = group.y * 32768u + group.x;
    if (k >= tiles.total) {
        return vec2<u32>(0xffffffffu);
    }
    let tile = tiles.index[k];
    return vec2<u32>(tile % pc.tile_columns, tile / pc.tile_columns) * TILE + local.xy;
}

// Runs once per listed tile (vkCmdDispatchIndirect): empty tiles cost nothing.
@compute @workgroup_size(8, 8)
fn enhance(@builtin(workgroup_id) group: vec3<u32>, @builtin(local_invocation_id) local: vec3<u32>) {
    let xy = tile_pixel(group, local);
    if (xy.x >= pc.region_size.x || xy.y >= pc.region_size.y) {
        return;
    }
    let i = xy.y * pc.region_size.x + xy.x;
    if (MODE == MODE_BACKGROUND) {
        store_rgb(i, encode_stored(pc.transmittance * bg_linear[i].rgb));
        return;
    }
    if (MODE == MODE_SPLIT) {
        let half = pc.region_size.x / 2u;
        if (xy.x + 1u == half || xy.x == half) {
            store_rgb(i, vec3<f32>(1.0));
            return;
        }
        if (xy.x < half) {
            return;
        }
    }
    let px = load_pixel(i);
    if (px.black || px.alpha == 0.0) {
        return;
    }
    let display = decode_stored(px.rgb);
    let e = enhance_linear(i, display);
    if (!e.changed) {
        return;
    }
    let stored = encode_stored(e.linear);
    if (MODE == MODE_HEATMAP) {
        if (is_enhanced(i, display, stored)) {
            store_rgb(i, vec3<f32>(0.0, 1.0, 1.0));
        }
        return;
    }
    store_rgb(i, stored);
}

// Whether a tile needs the enhancement pass in the current mode.
fn tile_wanted(tx: u32, ty: u32) -> bool {
    let x0 = tx * TILE;
    let y0 = ty * TILE;
    if (pc.mode == MODE_BACKGROUND) {
        return true;
    }
    var first_x = x0;
    if (pc.mode == MODE_SPLIT) {
        // The divider columns half - 1 and half are drawn on every row.
        let half = pc.region_size.x / 2u;
        if (x0 <= half && half < x0 + TILE + 1u) {
            return true;
        }
        first_x = max(x0, half + 1u);
    }
    // Constant trip counts (8 x 8) so the shader compiler unrolls the loops; pixels outside
    // the region or left of the split divider are masked instead of looped around.
    var found = false;
    for (var dy = 0u; dy < TILE; dy++) {
        let y = y0 + dy;
        for (var dx = 0u; dx < TILE; dx++) {
            let x = x0 + dx;
            let inside = y < pc.region_size.y && x < pc.region_size.x && x >= first_x;
            let px = load_pixel(select(0u, y * pc.region_size.x + x, inside));
            found = found || (inside && !(px.black || px.alpha == 0.0));
        }
    }
    return found;
}

// One invocation per tile: lists the tiles with any foreground pixel. A loop over the tile's
// pixels in one invocation (not one invocation per pixel) keeps this pass cheaper than a copy.
@compute @workgroup_size(8, 8)
fn classify(@builtin(global_invocation_id) id: vec3<u32>) {
    let rows = (pc.region_size.y + TILE - 1u) / TILE;
    if (id.x >= pc.tile_columns || id.y >= rows || !tile_wanted(id.x, id.y)) {
        return;
    }
    let k = atomicAdd(&tiles.count, 1u);
    tiles.index[k] = id.y * pc.tile_columns + id.x;
}

// Turns the tile count into the enhancement's indirect dispatch (at most 32768 workgroups per
// row: maxComputeWorkGroupCount is only guaranteed to be 65535) and zeroes the count.
@compute @workgroup_size(1)
fn finish_tiles() {
    let n = atomicExchange(&tiles.count, 0u);
    tiles.total = n;
    tiles.groups[0] = min(n, 32768u);
    tiles.groups[1] = (n + 32767u) / 32768u;
    tiles.groups[2] = 1u;
}
