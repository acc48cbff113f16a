// Background preprocessing of spec section 2, once per camera frame, all on the camera grid:
// decode -> separable Gaussian blur, in linear light. The rest of section 2 (FoV bilinear
// sampling, transmittance, scaled LAB) runs in the enhancement pass (enhance.wgsl,
// sampled_background), only for the display pixels it enhances: per camera frame the work is
// proportional to the camera's pixels, never to the display's or the number of views.
//
// One pass, built once per blur half-width BLUR_HALF (0..=7, a constant here, so every loop
// has a constant trip count and a CPU driver unrolls it into registers). Each invocation
// makes a block of 4 x ROWS texels (and the right neighbour each entry of `blurred` also
// holds): it reads each camera row y0 - BLUR_HALF..y0 + ROWS + BLUR_HALF 16 bytes (4 pixels)
// at a time, decodes it, blurs it horizontally and adds it to the output rows it serves.
// Decoding a texel again for each neighbouring block costs arithmetic; it saves the
// intermediate image and the memory accesses (each a loop over the SIMD lanes on lavapipe) of
// a two-pass blur.

// The sRGB decode of 8-bit codes c / 255, exact to f32 rounding: the enhancement's polynomial
// (srgb_decode, 1.3e-5 relative at most, src/gpu/approx.rs) refined by one Newton step on
// y^5 = s^12 (y = s^2.4), which squares its error. The exact table of earlier versions cost a
// memory access per channel (a loop over the SIMD lanes on lavapipe); the polynomial alone is
// twice as fast here but its error, amplified by Algorithm 1 on some pixels, took 16-bit
// outputs past the reference's tolerance (tests/layer.rs, R16G16B16A16_UNORM).
fn srgb_decode_exact(v: vec4<f32>) -> vec4<f32> {
    let y0 = srgb_decode_poly(v);
    let s = (v + 0.055) * (1.0 / 1.055);
    let s2 = s * s;
    let s4 = s2 * s2;
    let s12 = s4 * s4 * s4;
    let y2 = y0 * y0;
    let y = 0.8 * y0 + 0.2 * s12 / (y2 * y2);
    return select(v * (1.0 / 12.92), y, v > vec4<f32>(0.04045));
}

const H: i32 = i32(BLUR_HALF);
// Texels of the window left of the first output, a whole number of 4-pixel entries.
const LEFT: i32 = 4 * ((H + 3) / 4);
// 4-pixel entries per window row: outputs x0..x0+4 need texels x0-H..x0+4+H.
const GROUPS: i32 = (LEFT + 5 + H + 3) / 4;

// Camera row stride in pixels (BackgroundFrame::upload pads rows to a multiple of 4).
fn camera_stride() -> u32 {
    return (pc.camera_size.x + 3u) & ~3u;
}

fn bytes_at(w: vec4<u32>, shift: u32) -> vec4<f32> {
    return vec4<f32>((w >> vec4<u32>(shift)) & vec4<u32>(255u)) * (1.0 / 255.0);
}

// Texel coordinate x0 - LEFT + k of window position k.
const WINDOW: i32 = 4 * GROUPS;
// Texels the taps read: x0 - H..x0 + 4 + H, decoded in groups of four.
const NEEDED_PADDED: i32 = 4 * ((5 + 2 * H + 3) / 4);

// Row `row` of the camera, decoded and blurred horizontally at texels x0..x0+4 (clamp-to-edge;
// entries past the row's end are garbage the caller never stores).
fn hblur_row(row: i32, x0: i32) -> array<vec3<f32>, 5> {
    let w = i32(pc.camera_size.x);
    let first = row * i32(camera_stride() / 4u) + x0 / 4 - LEFT / 4;
    var words: array<u32, WINDOW>;
    for (var g = 0; g < GROUPS; g++) {
        // Entries before the row's start or past its end read a neighbouring row (or 0 past
        // the buffer): replaced below.
        let e = camera[u32(first + g)];
        words[4 * g] = e.x;
        words[4 * g + 1] = e.y;
        words[4 * g + 2] = e.z;
        words[4 * g + 3] = e.w;
    }
    // Clamp-to-edge: texels right of the row repeat its last, left of it its first.
    for (var k = 1; k < WINDOW; k++) {
        words[k] = select(words[k], words[k - 1], x0 - LEFT + k >= w);
    }
    for (var k = WINDOW - 2; k >= 0; k--) {
        words[k] = select(words[k], words[k + 1], x0 - LEFT + k < 0);
    }
    // Decode only the NEEDED texels the taps use (window positions LEFT - H onwards), four
    // at a time: the decode is most of this pass's arithmetic.
    var lin: array<vec3<f32>, NEEDED_PADDED>;
    for (var g = 0; g < NEEDED_PADDED / 4; g++) {
        let k = LEFT - H + 4 * g;
        let at = vec4<i32>(k, k + 1, k + 2, k + 3);
        let m = vec4<i32>(WINDOW - 1);
        let e = vec4<u32>(words[min(at.x, m.x)], words[min(at.y, m.y)], words[min(at.z, m.z)], words[min(at.w, m.w)]);
        let r = srgb_decode_exact(bytes_at(e, 0u));
        let gr = srgb_decode_exact(bytes_at(e, 8u));
        let b = srgb_decode_exact(bytes_at(e, 16u));
        for (var c = 0; c < 4; c++) {
            lin[4 * g + c] = vec3<f32>(r[c], gr[c], b[c]);
        }
    }
    var out: array<vec3<f32>, 5>;
    for (var j = 0; j < 5; j++) {
        var a = blur_tap(0u) * lin[H + j];
        for (var o = 1; o <= H; o++) {
            a += blur_tap(u32(o)) * (lin[H + j - o] + lin[H + j + o]);
        }
        out[j] = a;
    }
    return out;
}

// Output rows per invocation: each camera row the block's taps read is decoded and blurred
// horizontally once for all ROWS outputs (a pass of one row per invocation decoded every row
// 2 * BLUR_HALF + 1 times, and the decode is most of this pass's arithmetic).
const ROWS: i32 = 8;

// Prepares the camera texels of a rectangle only: the ones some view samples (the engine
// passes the rectangle's first texel in region_size, which this pass has no other use for,
// and dispatches over its size, 4 x ROWS texels per invocation).
@compute @workgroup_size(8, 8)
fn decode_blur(@builtin(global_invocation_id) id: vec3<u32>) {
    let x0 = i32(pc.region_size.x + id.x * 4u);
    let w = i32(pc.camera_size.x);
    let h = i32(pc.camera_size.y);
    let y0 = i32(pc.region_size.y + id.y * u32(ROWS));
    if (x0 >= w || y0 >= h) {
        return;
    }
    // acc[i] is output row y0 + i; camera row y0 - H + r feeds outputs i with |r - H - i| <= H.
    var acc: array<array<vec3<f32>, 5>, ROWS>;
    for (var r = 0; r < ROWS + 2 * H; r++) {
        let row = hblur_row(clamp(y0 - H + r, 0, h - 1), x0);
        // Constant trip counts only (whether a row feeds an output is a branch on constants
        // once unrolled), so a CPU driver unrolls both loops and keeps `acc` in registers.
        for (var i = 0; i < ROWS; i++) {
            let d = abs(r - H - i);
            if (d <= H) {
                let t = blur_tap(u32(d));
                for (var j = 0; j < 5; j++) {
                    acc[i][j] += t * row[j];
                }
            }
        }
    }
    for (var i = 0; i < ROWS; i++) {
        let y = y0 + i;
        if (y >= h) {
            break;
        }
        let base = u32(y) * pc.camera_size.x;
        for (var j = 0; j < 4; j++) {
            let x = x0 + j;
            if (x >= w) {
                break;
            }
            // Entry x holds texels x and x + 1; the last column's neighbour is itself.
            let right = select(acc[i][j + 1], acc[i][j], x + 1 >= w);
            blurred[base + u32(x)] = vec4<u32>(pack_linear(acc[i][j]), pack_linear(right));
        }
    }
}
