// Pixel access for regions whose rows are not 16-byte aligned (and for the
// passes that are not per-pixel hot paths): one u32 per load.

// Words w..w+3 of the region (any w; words past the buffer read as 0).
fn load_words4(w: u32) -> vec4<u32> {
    return vec4<u32>(pixels[w], pixels[w + 1u], pixels[w + 2u], pixels[w + 3u]);
}

// Stores the first n (1..=4) of v at words w..
fn store_words4(w: u32, v: vec4<u32>, n: u32) {
    for (var k = 0u; k < n; k++) {
        pixels[w + k] = v[k];
    }
}
