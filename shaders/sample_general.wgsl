// The background sampling of `enhance` for every mapping (build.rs appends this file, or
// sample_shared.wgsl where a view's mapping allows it, to enhance.wgsl).

// Bilinear interpolation, clamp-to-edge, of the blurred camera image at texel coordinates
// (tx, ty) (texel centres at integers). Entry x of `blurred` holds texels x and x + 1, so each
// row costs one read; left of the first texel centre the entry of texel 0 with weight 0.
fn bilinear(tx: f32, ty: f32) -> vec3<f32> {
    let size = vec2<f32>(pc.camera_size);
    let base = floor(vec2<f32>(tx, ty));
    var t = vec2<f32>(tx, ty) - base;
    if (base.x < 0.0) {
        t.x = 0.0;
    }
    let x = u32(clamp(base.x, 0.0, size.x - 1.0));
    let y0 = u32(clamp(base.y, 0.0, size.y - 1.0));
    let y1 = u32(clamp(base.y + 1.0, 0.0, size.y - 1.0));
    let top = textureLoad(blurred_texels, vec2<u32>(x, y0), 0);
    let bottom = textureLoad(blurred_texels, vec2<u32>(x, y1), 0);
    let upper = mix(unpack_linear(top.xy), unpack_linear(top.zw), t.x);
    let lower = mix(unpack_linear(bottom.xy), unpack_linear(bottom.zw), t.x);
    return mix(upper, lower, t.y);
}

// The background of display pixels (x..x+3, y) (docs/algorithm.md, Background preparation): the blurred camera image
// sampled through the view's mapping (bilinear, linear light), then the lens transmittance
// and the conversion to scaled LAB, in that order. Only the pixels the enhancement runs
// on pay for it (the camera image itself is prepared once per camera frame, background.wgsl).
fn sampled_background(x: u32, y: u32) -> Background {
    let uv = camera_uv(x, y);
    let tx = uv[0] * f32(pc.camera_size.x) - 0.5;
    let ty = uv[1] * f32(pc.camera_size.y) - 0.5;
    let linear = group_of(bilinear(tx.x, ty.x), bilinear(tx.y, ty.y), bilinear(tx.z, ty.z), bilinear(tx.w, ty.w));
    return Background(linear, linear_to_scaled(pc.transmittance * linear));
}
