// The background sampling of `enhance` where the view's mapping allows the four pixels of a
// group to share their texel reads (src/gpu/core/shared_fetch.rs says where; build.rs appends this
// file instead of sample_general.wgsl for those variants). A separate pipeline, not a branch:
// a CPU driver would run both paths.

// Per pixel, texel o (0, 1 or 2) of three: r0, r1, r2 (one channel each).
fn texel_at(o: vec4<u32>, r0: f32, r1: f32, r2: f32) -> vec4<f32> {
    return select(select(vec4<f32>(r2), vec4<f32>(r1), o == vec4<u32>(1u)), vec4<f32>(r0), o == vec4<u32>(0u));
}

// One camera row of the four pixels' bilinear samples: texels a..a+3 from entries a (e0) and
// a + 2 (e1), pixel k interpolating texels a + o[k] and a + o[k] + 1 by t[k].
fn shared_row(o: vec4<u32>, e0: vec4<u32>, e1: vec4<u32>, t: vec4<f32>) -> Colours {
    let r0 = unpack_linear(e0.xy);
    let r1 = unpack_linear(e0.zw);
    let r2 = unpack_linear(e1.xy);
    let r3 = unpack_linear(e1.zw);
    var out: Colours;
    for (var c = 0u; c < 3u; c++) {
        out[c] = mix(texel_at(o, r0[c], r1[c], r2[c]), texel_at(o, r1[c], r2[c], r3[c]), t);
    }
    return out;
}

// sample_general.wgsl's `sampled_background` with the four pixels' texel reads shared: 4 reads
// instead of 8, the same arithmetic per pixel, so the same values, where the four pixels
// sample one pair of camera rows (ty equal) and their floor(tx) lie within 2 of each other.
fn sampled_background(x: u32, y: u32) -> Background {
    let uv = camera_uv(x, y);
    let size = vec2<f32>(pc.camera_size);
    let tx = uv[0] * size.x - 0.5;
    let ty = uv[1].x * size.y - 0.5;
    let base_x = floor(tx);
    let base_y = floor(ty);
    let t_x = select(tx - base_x, vec4<f32>(0.0), base_x < vec4<f32>(0.0));
    let t_y = ty - base_y;
    let bx = vec4<u32>(clamp(base_x, vec4<f32>(0.0), vec4<f32>(size.x - 1.0)));
    let y0 = u32(clamp(base_y, 0.0, size.y - 1.0));
    let y1 = u32(clamp(base_y + 1.0, 0.0, size.y - 1.0));
    // The leftmost texel of the four (a mirrored mapping runs right to left).
    let a = min(min(bx.x, bx.y), min(bx.z, bx.w));
    let a2 = min(a + 2u, pc.camera_size.x - 1u);
    let o = bx - vec4<u32>(a);
    let upper = shared_row(o, textureLoad(blurred_texels, vec2<u32>(a, y0), 0), textureLoad(blurred_texels, vec2<u32>(a2, y0), 0), t_x);
    let lower = shared_row(o, textureLoad(blurred_texels, vec2<u32>(a, y1), 0), textureLoad(blurred_texels, vec2<u32>(a2, y1), 0), t_x);
    let linear = Colours(mix(upper[0], lower[0], t_y), mix(upper[1], lower[1], t_y), mix(upper[2], lower[2], t_y));
    return Background(linear, linear_to_scaled(pc.transmittance * linear));
}
