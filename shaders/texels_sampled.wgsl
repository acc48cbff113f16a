// Read through a sampled view, written to the layer's image (ACCESS_SAMPLED): the pixel at
// image position `at` of the app's image is read from `app_texels`, a view in the image's own
// 8-bit sRGB format whose sampler decodes the codes to linear light, and written to
// `app_image`, the layer's image of the region's size, at the pixel's place in the region. So
// the region is never copied into the layer's image first.

fn region_origin() -> vec2<u32> {
    return vec2<u32>(pc.region_origin & 0xffffu, pc.region_origin >> 16u);
}

// The stored words of the pixel at image position `at`: the sampler's linear colour encoded
// back to its sRGB codes (srgb_encode is within 0.002 of a code, so rounding restores the
// code), alpha as it is, in the format's byte order.
fn load_at(at: vec2<u32>) -> vec2<u32> {
    let t = textureLoad(app_texels, at, 0);
    let e = srgb_encode(clamp(t, vec4<f32>(0.0), vec4<f32>(1.0)));
    let c = vec4<u32>(round(clamp(vec4<f32>(e.xyz, t.w), vec4<f32>(0.0), vec4<f32>(1.0)) * 255.0));
    var bytes = c;
    if ((FORMAT & 255u) == LAYOUT_BGRA8) {
        bytes = c.zyxw;
    }
    return vec2<u32>(bytes.x | (bytes.y << 8u) | (bytes.z << 16u) | (bytes.w << 24u), 0u);
}

fn store_at(at: vec2<u32>, w: vec2<u32>) {
    textureStore(app_image, at - region_origin(), words_texel(w));
}
