// In place (ACCESS_IN_PLACE): the pixel at image position `at` is read from and written to
// the app's image (or the layer's image of the image-copy path), `app_image`.

// The words of the pixel at image position `at` (the second only for 2-word formats).
fn load_at(at: vec2<u32>) -> vec2<u32> {
    return texel_words(textureLoad(app_image, at));
}

fn store_at(at: vec2<u32>, w: vec2<u32>) {
    textureStore(app_image, at, words_texel(w));
}
