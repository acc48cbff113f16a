// Background preparation (docs/algorithm.md, Background preparation), once per camera frame, all on the camera grid:
// decode -> separable Gaussian blur, in linear light. The rest of the preparation (FoV bilinear
// sampling, transmittance, scaled LAB) runs in the enhancement pass (enhance.wgsl,
// sampled_background), only for the display pixels it enhances: per camera frame the work is
// proportional to the camera's pixels, never to the display's or the number of views.
//
// Two passes, both over the camera texels some view samples (plus the blur's reach):
// `decode` decodes each texel once into linear light (pack_linear, after the final texels in
// `blurred`); `decode_blur`, built once per blur half-width BLUR_HALF (0..=7, a constant here,
// so every loop has a constant trip count and a CPU driver unrolls it into registers), makes a
// block of 4 x ROWS texels per invocation (and the right neighbour each entry of `blurred` also
// holds): it reads each decoded row y0 - BLUR_HALF..y0 + ROWS + BLUR_HALF, blurs it
// horizontally and adds it to the output rows it serves. Decoding inside the blur, as earlier
// versions did, repeated the decode (most of the arithmetic) for every block a texel's window
// reaches; the separate pass costs one store and about one load per texel instead.

// The sRGB decode of 8-bit codes c / 255, exact to f32 rounding: the enhancement's polynomial
// (srgb_decode, 1.3e-5 relative at most, src/gpu/core/approx.rs) refined by one Newton step on
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

// Camera row stride in pixels (BackgroundFrame::upload pads rows to a multiple of 4).
fn camera_stride() -> u32 {
    return (pc.camera_size.x + 3u) & ~3u;
}

fn bytes_at(w: vec4<u32>, shift: u32) -> vec4<f32> {
    return vec4<f32>((w >> vec4<u32>(shift)) & vec4<u32>(255u)) * (1.0 / 255.0);
}

// The decoded camera texels live in `blurred` after its width x height final entries: two
// texels (pack_linear) per entry, rows of camera_stride() texels.
fn decoded_entry(x: u32, y: u32) -> u32 {
    return pc.camera_size.x * pc.camera_size.y + (y * camera_stride() + x) / 2u;
}

// First pass: decodes each camera texel of a rectangle once (four per invocation, at the
// rectangle's first texel, which the engine passes in region_size). The blur pass reads
// them; decoding inside it repeated the decode for every block a texel's window reaches.
@compute @workgroup_size(TILE, TILE)
fn decode(@builtin(global_invocation_id) id: vec3<u32>) {
    let x0 = pc.region_size.x + id.x * 4u;
    let y = pc.region_size.y + id.y;
    if (x0 >= pc.camera_size.x || y >= pc.camera_size.y) {
        return;
    }
    let e = camera[(y * camera_stride() + x0) / 4u];
    let r = srgb_decode_exact(bytes_at(e, 0u));
    let g = srgb_decode_exact(bytes_at(e, 8u));
    let b = srgb_decode_exact(bytes_at(e, 16u));
    let at = decoded_entry(x0, y);
    blurred[at] = vec4<u32>(pack_linear(vec3<f32>(r.x, g.x, b.x)), pack_linear(vec3<f32>(r.y, g.y, b.y)));
    blurred[at + 1u] = vec4<u32>(pack_linear(vec3<f32>(r.z, g.z, b.z)), pack_linear(vec3<f32>(r.w, g.w, b.w)));
}

// Entries read left of x0 (x0 is a multiple of 4), and texels per row window: texels
// x0 - 2 * LEFT_E .. x0 + 4 + H, a whole number of entries.
const LEFT_E: i32 = (H + 1) / 2;
const WINDOW: i32 = 2 * ((2 * LEFT_E + 5 + H + 1) / 2);

// Row `row` of the decoded camera, blurred horizontally at texels x0..x0+4 (clamp-to-edge;
// entries past the row's end are garbage the caller never stores).
fn hblur_row(row: i32, x0: i32) -> array<vec3<f32>, 5> {
    let w = i32(pc.camera_size.x);
    let first = i32(decoded_entry(u32(x0), u32(row))) - LEFT_E;
    var packed: array<vec2<u32>, WINDOW>;
    for (var m = 0; m < WINDOW / 2; m++) {
        // Entries before the row's start or past its end hold a neighbouring row's texels:
        // replaced below.
        let e = blurred[u32(max(first + m, 0))];
        packed[2 * m] = e.xy;
        packed[2 * m + 1] = e.zw;
    }
    // Clamp-to-edge: texels right of the row repeat its last, left of it its first.
    let left = x0 - 2 * LEFT_E;
    for (var k = 1; k < WINDOW; k++) {
        packed[k] = select(packed[k], packed[k - 1], left + k >= w);
    }
    for (var k = WINDOW - 2; k >= 0; k--) {
        packed[k] = select(packed[k], packed[k + 1], left + k < 0);
    }
    // Texel x0 - H + k is window position 2 * LEFT_E - H + k.
    var lin: array<vec3<f32>, 5 + 2 * H>;
    for (var k = 0; k < 5 + 2 * H; k++) {
        lin[k] = unpack_linear(packed[2 * LEFT_E - H + k]);
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

// Output rows per invocation: each decoded row the block's taps read is loaded and blurred
// horizontally once for all ROWS outputs.
const ROWS: i32 = i32(DECODE_ROWS);

// Prepares the camera texels of a rectangle only: the ones some view samples (the engine
// passes the rectangle's first texel in region_size, which this pass has no other use for,
// and dispatches over its size, 4 x ROWS texels per invocation).
@compute @workgroup_size(TILE, TILE)
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
