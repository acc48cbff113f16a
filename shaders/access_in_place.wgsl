// Pixel access straight in the app's image, through a storage view of its layer (`app_image`,
// declared by build.rs in the variant's texel format): word w of the region's tightly packed
// layout (the copy path's buffer) is read from and written to the pixel it stands for, so the
// per-pixel code is the same on both paths. The texel conversions (`texel_words`,
// `words_texel`, written in front of this file by build.rs for the variant's texel format) are
// exact both ways. Where a pixel is read and written (`load_at`, `store_at`) is the access's
// own file in front of this one: shaders/texels_in_place.wgsl or texels_sampled.wgsl.

// The image position of pixel p of the region, and whether p lies in the region.
fn pixel_position(p: u32) -> vec2<u32> {
    let origin = vec2<u32>(pc.region_origin & 0xffffu, pc.region_origin >> 16u);
    return origin + vec2<u32>(p % pc.region_size.x, p / pc.region_size.x);
}

fn in_region(p: u32) -> bool {
    return p < pc.region_size.x * pc.region_size.y;
}

// Pixel p's words; 0 outside the region.
fn load_pixel(p: u32) -> vec2<u32> {
    if (!in_region(p)) {
        return vec2<u32>(0u);
    }
    return load_at(pixel_position(p));
}

fn store_pixel(p: u32, w: vec2<u32>) {
    if (!in_region(p)) {
        return;
    }
    store_at(pixel_position(p), w);
}

// Words w..w+3 of the region (w a multiple of WORDS). Pixels of one row, the usual case, take
// one position computation; a group that wraps to the next row or leaves the region takes one
// per pixel.
fn load_words4(w: u32) -> vec4<u32> {
    let p = w / WORDS;
    let count = 4u / WORDS;
    let x = p % pc.region_size.x;
    if (x + count <= pc.region_size.x && in_region(p + count - 1u)) {
        let at = pixel_position(p);
        if (WORDS == 1u) {
            return vec4<u32>(load_at(at).x, load_at(at + vec2<u32>(1u, 0u)).x, load_at(at + vec2<u32>(2u, 0u)).x, load_at(at + vec2<u32>(3u, 0u)).x);
        }
        return vec4<u32>(load_at(at), load_at(at + vec2<u32>(1u, 0u)));
    }
    if (WORDS == 1u) {
        return vec4<u32>(load_pixel(p).x, load_pixel(p + 1u).x, load_pixel(p + 2u).x, load_pixel(p + 3u).x);
    }
    return vec4<u32>(load_pixel(p), load_pixel(p + 1u));
}

// Stores the first n (1..=4; even for 2-word formats) of words w.. (w a multiple of WORDS).
fn store_words4(w: u32, v: vec4<u32>, n: u32) {
    if (WORDS == 1u) {
        for (var k = 0u; k < n; k++) {
            store_pixel(w + k, vec2<u32>(v[k], 0u));
        }
        return;
    }
    store_pixel(w / 2u, v.xy);
    if (n > 2u) {
        store_pixel(w / 2u + 1u, v.zw);
    }
}
