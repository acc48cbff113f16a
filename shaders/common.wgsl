// Shared by every stage: the parameter block (push constants), the bindings and the colour
// science of docs/algorithm.md, Colour spaces, in f32. The CPU reference (src/colour.rs, src/algorithm/) is the same math in f64.

// One push-constant block for all passes (they share one pipeline layout). 128 bytes, the
// least maxPushConstantsSize Vulkan guarantees: keep it within.
struct Params {
    camera_size: vec2<u32>,
    // Size of the display region (one view), in pixels; buffers are tightly packed rows.
    region_size: vec2<u32>,
    lambda_e: f32,
    lambda_jnd: f32,
    transmittance: f32,
    // Gaussian taps at offsets -blur_half..=blur_half (blur_half <= 7).
    blur_half: u32,
    // Symmetric normalised taps: tap(k) = taps[k / 4][k % 4] for k = |offset|.
    taps: array<vec4<f32>, 2>,
    k_v: f32,
    k_b: f32,
    // What the view shows (MODE_*).
    mode: u32,
    // Tiles per row of the region (TILE x TILE pixels each).
    tile_columns: u32,
    // Beyond the paper (0 = off): chroma boost on near-grey backgrounds; luminance cap.
    achromatic_boost: f32,
    luminance_cap: f32,
    // The view's CameraMapping (src/algorithm/mapping.rs), row-major: camera_uv =
    // (M (display_uv, 1)).xy / (M (display_uv, 1)).z.
    map_00: f32,
    map_01: f32,
    map_02: f32,
    map_10: f32,
    map_11: f32,
    map_12: f32,
    map_20: f32,
    map_21: f32,
    map_22: f32,
}

var<immediate> pc: Params;

// Camera frame: RGBA8 sRGB, one u32 per pixel (R in the low byte), four pixels per entry;
// rows padded to a multiple of 4 pixels (camera_stride).
@group(0) @binding(0) var<storage, read> camera: array<vec4<u32>>;
// The camera frame decoded and blurred: linear light on the camera grid, NOT attenuated (the
// subtraction method needs it as is), the one image prepared per camera frame. Entry
// y * width + x holds texels x and x + 1 of row y (texel width - 1 twice at the right edge),
// packed by pack_linear_pair, so a bilinear sample reads one entry per row. After those
// width x height entries, the background pass's decoded camera texels (background.wgsl).
@group(0) @binding(1) var<storage, read_write> blurred: array<vec4<u32>>;
// The same, as an R32G32B32A32_UINT image (copied from `blurred` after each preparation): what
// the enhancement samples. A texel fetch is a gather on CPU drivers such as lavapipe, where a
// storage-buffer read at a per-pixel index is a loop over the SIMD lanes with a branch each.
@group(0) @binding(5) var blurred_texels: texture_2d<u32>;
// Bindings 2 (pixels: the display region's raw pixels in the swapchain format, 1 or 2 u32 per
// pixel) and 4 (source: the copy passes' source, the benchmark's floor) are declared by
// access_wide.wgsl or access_narrow.wgsl, which build.rs puts after this file.
// The tiles the enhancement runs on (classify and finish_tiles in enhance.wgsl).
struct TileList {
    // Tiles found so far by classify; finish_tiles moves it to `total` and zeroes it.
    count: atomic<u32>,
    // vkCmdDispatchIndirect arguments (byte offset 4): workgroups x, y, z.
    groups: array<u32, 3>,
    total: u32,
    pad: array<u32, 3>,
    // Tile index (row * tile_columns + column) of each listed tile.
    index: array<u32>,
}
@group(0) @binding(3) var<storage, read_write> tiles: TileList;

const LAYOUT_RGBA8: u32 = 0u;
const LAYOUT_BGRA8: u32 = 1u;
const LAYOUT_RGBA16_UNORM: u32 = 2u;
const LAYOUT_RGBA16_FLOAT: u32 = 3u;
const LAYOUT_A2B10G10R10: u32 = 4u;
const FORMAT_SRGB_BIT: u32 = 256u;

const MODE_ENHANCE: u32 = 0u;
const MODE_OFF: u32 = 1u;
const MODE_SPLIT: u32 = 2u;
const MODE_HEATMAP: u32 = 3u;
const MODE_BACKGROUND: u32 = 4u;

// Side of a square tile; the workgroup size of the per-pixel passes.
const TILE: u32 = 8u;

const METHOD_PAPER: u32 = 0u;
const METHOD_HUE_ONLY: u32 = 1u;
const METHOD_OTHER_HUE: u32 = 2u;
const METHOD_LUM_CHROMA: u32 = 3u;
const METHOD_SUBTRACTION: u32 = 4u;

// Four pixels' colours, one column per channel: column k holds channel k (R, G, B or L', a',
// b') of pixels 0..3. The per-pixel pass works on four pixels at once in this form, so that a
// CPU driver (lavapipe) sees four independent chains of arithmetic instead of one long one.
alias Colours = mat3x4<f32>;

// Each pixel's colour times its own factor.
fn per_pixel(s: vec4<f32>, c: Colours) -> Colours {
    return Colours(s * c[0], s * c[1], s * c[2]);
}

// Each pixel's dot product.
fn dots(a: Colours, b: Colours) -> vec4<f32> {
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

// Per pixel: b where m, else a.
fn pick(a: Colours, b: Colours, m: vec4<bool>) -> Colours {
    return Colours(select(a[0], b[0], m), select(a[1], b[1], m), select(a[2], b[2], m));
}

// A matrix row times each pixel's colour.
fn row_times(m: vec3<f32>, c: Colours) -> vec4<f32> {
    return m.x * c[0] + m.y * c[1] + m.z * c[2];
}

// A row of a matrix whose rows sum to 1 (RGB_TO_T, T_TO_RGB) times each pixel's colour, as
// c.y + m.x (c.x - c.y) + m.z (c.z - c.y): equal channels give exactly that value, so greys
// stay exactly grey (a* = b* = 0) whatever the rounding of the matrix.
fn unit_row_times(m: vec3<f32>, c: Colours) -> vec4<f32> {
    return c[1] + m.x * (c[0] - c[1]) + m.z * (c[2] - c[1]);
}

// Four colours as a group, pixel j from the j-th argument.
fn group_of(p0: vec3<f32>, p1: vec3<f32>, p2: vec3<f32>, p3: vec3<f32>) -> Colours {
    let c = transpose(mat4x3<f32>(p0, p1, p2, p3));
    return Colours(c[0], c[1], c[2]);
}

// sRGB decode of stored values v in [0, 1] without a table: the linear segment, else a
// polynomial (src/gpu/approx_constants.rs, 1.3e-5 largest relative error over the 8-bit codes).
fn srgb_decode(v: vec4<f32>) -> vec4<f32> {
    return select(v * (1.0 / 12.92), srgb_decode_poly(v), v > vec4<f32>(0.04045));
}

// Cube root of positive values without pow or division: Newton's method on x^(-1/3) from a
// bit-pattern seed (src/gpu/approx_constants.rs; 4e-7 relative error), then x * x^(-2/3).
fn cbrt(x: vec4<f32>) -> vec4<f32> {
    let third_bits = vec4<u32>(vec4<f32>(bitcast<vec4<u32>>(x)) * (1.0 / 3.0));
    var r = bitcast<vec4<f32>>(vec4<u32>(CBRT_SEED_MAGIC) - third_bits);
    let x3 = x * (1.0 / 3.0);
    for (var k = 0; k < CBRT_NEWTON_STEPS; k++) {
        r = r * (vec4<f32>(4.0 / 3.0) - x3 * (r * r * r));
    }
    return x * r * r;
}

// sRGB encode without pow: v^(1/2.4) = q^(5/3) for q = v^(1/4), a polynomial in q
// (src/gpu/approx_constants.rs; 0.002 of an 8-bit code at most).
fn srgb_encode(v: vec4<f32>) -> vec4<f32> {
    let q = sqrt(sqrt(max(v, vec4<f32>(0.0031308))));
    return select(srgb_encode_poly(q), 12.92 * v, v <= vec4<f32>(0.0031308));
}

const LAB_DELTA: f32 = 0.20689655; // 6/29

fn lab_f(t: vec4<f32>) -> vec4<f32> {
    let d3 = LAB_DELTA * LAB_DELTA * LAB_DELTA;
    let lin = t * (1.0 / (3.0 * LAB_DELTA * LAB_DELTA)) + 4.0 / 29.0;
    let cube = cbrt(max(t, vec4<f32>(d3)));
    return select(lin, cube, t > vec4<f32>(d3));
}

fn lab_f_inv(f: vec4<f32>) -> vec4<f32> {
    let lin = (3.0 * LAB_DELTA * LAB_DELTA) * (f - 4.0 / 29.0);
    return select(lin, f * f * f, f > vec4<f32>(LAB_DELTA));
}

// linear sRGB -> scaled LAB (L' = (L*-50)/50, a' = a*/128, b' = b*/128), the white point and
// the scaling folded into the constants.
fn linear_to_scaled(rgb: Colours) -> Colours {
    let fx = lab_f(unit_row_times(RGB_TO_T_0, rgb));
    let fy = lab_f(unit_row_times(RGB_TO_T_1, rgb));
    let fz = lab_f(unit_row_times(RGB_TO_T_2, rgb));
    // L' = (116 fy - 16 - 50) / 50, a' = 500 (fx - fy) / 128, b' = 200 (fy - fz) / 128.
    return Colours(2.32 * fy - 1.32, (500.0 / 128.0) * (fx - fy), (200.0 / 128.0) * (fy - fz));
}

// scaled LAB -> linear sRGB (not clipped).
fn scaled_to_linear(s: Colours) -> Colours {
    // fy = (L* + 16) / 116 with L* = 50 L' + 50; fx = fy + a* / 500; fz = fy - b* / 200.
    let fy = s[0] * (50.0 / 116.0) + 66.0 / 116.0;
    let t = Colours(lab_f_inv(fy + s[1] * (128.0 / 500.0)), lab_f_inv(fy), lab_f_inv(fy - s[2] * (128.0 / 200.0)));
    return Colours(unit_row_times(T_TO_RGB_0, t), unit_row_times(T_TO_RGB_1, t), unit_row_times(T_TO_RGB_2, t));
}

// A linear-light colour in [0, 1] in 8 bytes: each channel as a 21-bit code over [0, 1]
// (steps of 4.8e-7, a few f32 ulps near 1; scaled LAB moves by at most 4e-6 per step, in the
// darkest shades). R in bits 0-20, G in 21-41, B in 42-62. Two texels per 16-byte entry.
// Mirrored by src/gpu/offline.rs (unpack_linear).
const LINEAR_MAX_CODE: f32 = 2097151.0; // 2^21 - 1: the code of 1.0

fn pack_linear(c: vec3<f32>) -> vec2<u32> {
    let q = vec3<u32>(round(clamp(c, vec3<f32>(0.0), vec3<f32>(1.0)) * LINEAR_MAX_CODE));
    return vec2<u32>(q.x | (q.y << 21u), (q.y >> 11u) | (q.z << 10u));
}

fn unpack_linear(w: vec2<u32>) -> vec3<f32> {
    let q = vec3<u32>(w.x & 0x1fffffu, (w.x >> 21u) | ((w.y & 0x3ffu) << 11u), w.y >> 10u);
    return vec3<f32>(q) * (1.0 / LINEAR_MAX_CODE);
}

fn blur_tap(k: u32) -> f32 {
    return pc.taps[k / 4u][k % 4u];
}
