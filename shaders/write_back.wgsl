// The image-copy path's write-back by drawing: the tiles the enhancement ran on, drawn from the
// engine's image (`own`, the view's region at its origin, in the format's storage texel) into
// the app's image as a colour attachment. Only those tiles reach the app's image; the rest of
// it is left as the app rendered it. The attachment is the app's image in its own format, so
// the fragment returns the value whose encoding (sRGB, UNORM, float) is the stored words:
// exact for every UNORM and float format, and for sRGB as exact as the device's sRGB encoding.
//
// build.rs writes in front of this file: TILE, the layout codes, FORMAT, the push constants
// `wb` (WriteBack), the read-only tile list `tiles` (binding 0; its header of
// TILE_LIST_HEADER_WORDS words, then the tile indices) and `own` (binding 1), read-only, in the
// format's storage texel, and `own_value`, which turns an `own` texel into the attachment's
// value.

struct Corner {
    @builtin(position) position: vec4<f32>,
    // The position in the engine's image, interpolated: x + 0.5 at the centre of pixel x.
    @location(0) at: vec2<f32>,
    // The tile's first and last pixel, against rounding of `at`.
    @location(1) @interpolate(flat) first: vec2<u32>,
    @location(2) @interpolate(flat) last: vec2<u32>,
}

// Two triangles per listed tile (instance k: tile k of the list), corners (0,0) (1,0) (0,1)
// and (0,1) (1,0) (1,1); the viewport is the view's region in the app's image.
@vertex
fn write_back_vertex(@builtin(vertex_index) v: u32, @builtin(instance_index) k: u32) -> Corner {
    let tile = tiles.index[k];
    let first = vec2<u32>(tile % wb.tile_columns, tile / wb.tile_columns) * TILE;
    let end = min(first + vec2<u32>(TILE), wb.region_size);
    let corner = array<vec2<u32>, 6>(
        vec2<u32>(0u, 0u), vec2<u32>(1u, 0u), vec2<u32>(0u, 1u),
        vec2<u32>(0u, 1u), vec2<u32>(1u, 0u), vec2<u32>(1u, 1u),
    )[v % 6u];
    let at = vec2<f32>(select(first, end, corner == vec2<u32>(1u)));
    let clip = at / vec2<f32>(wb.region_size) * 2.0 - 1.0;
    return Corner(vec4<f32>(clip, 0.0, 1.0), at, first, end - 1u);
}

@fragment
fn write_back_fragment(c: Corner) -> @location(0) vec4<f32> {
    let at = clamp(vec2<u32>(floor(c.at)), c.first, c.last);
    return own_value(textureLoad(own, at));
}

// sRGB-encoded values to linear light, as the attachment's sRGB encoding inverts them.
fn srgb_to_linear(c: vec3<f32>) -> vec3<f32> {
    let low = c / 12.92;
    let high = pow((c + 0.055) / 1.055, vec3<f32>(2.4));
    return select(high, low, c <= vec3<f32>(0.04045));
}
