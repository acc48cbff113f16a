// Pixel access for regions whose rows are 16-byte aligned (width x words per
// pixel a multiple of 4): 16 bytes per load and store. CPU drivers such as lavapipe emulate
// every buffer access with a loop over the SIMD lanes, so four words per access cost about
// what one does (measured in docs/performance.md).

// Words w..w+3 of the region (w a multiple of 4).
fn load_words4(w: u32) -> vec4<u32> {
    return pixels[w / 4u];
}

// Stores words w..w+3 (w a multiple of 4; rows hold whole groups of 4 words, so n is 4).
fn store_words4(w: u32, v: vec4<u32>, n: u32) {
    pixels[w / 4u] = v;
}

// Words w..w+3 of the copy source (w a multiple of 4).
fn load_source4(w: u32) -> vec4<u32> {
    return source[w / 4u];
}
