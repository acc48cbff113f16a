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
    let pixel_layout = pc.format & 255u;
    return select(1u, 2u, pixel_layout == LAYOUT_RGBA16_UNORM || pixel_layout == LAYOUT_RGBA16_FLOAT);
}

fn load_pixel(i: u32) -> Pixel {
    let pixel_layout = pc.format & 255u;
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
    let pixel_layout = pc.format & 255u;
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
    switch pc.method {
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
            return jnd_constraint(d, p, b);
        }
    }
}

@compute @workgroup_size(8, 8)
fn enhance(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= pc.region_size.x || id.y >= pc.region_size.y) {
        return;
    }
    let i = id.y * pc.region_size.x + id.x;
    let px = load_pixel(i);
    if (px.black || px.alpha == 0.0) {
        return;
    }
    let srgb = (pc.format & FORMAT_SRGB_BIT) != 0u;
    var display = px.rgb;
    if (srgb) {
        // sRGB formats are 8-bit: the stored value is code / 255 exactly.
        display = srgb_decode_code(vec3<u32>(px.rgb * 255.0 + 0.5));
    }
    var out: vec3<f32>;
    if (pc.method == METHOD_SUBTRACTION) {
        out = pc.k_v * display - pc.k_b * bg_linear[i].rgb;
    } else {
        let d = linear_to_scaled(display);
        let p = enhance_scaled(d, bg_scaled[i].xyz);
        if (all(p == d)) {
            return;
        }
        out = scaled_to_linear(p);
    }
    out = clamp(out, vec3<f32>(0.0), vec3<f32>(1.0));
    store_rgb(i, select(out, srgb_encode(out), srgb));
}
