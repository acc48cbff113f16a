// Background preprocessing of spec section 2, once per camera frame and view:
// decode -> separable Gaussian blur on the camera grid -> FoV bilinear sampling in linear light
// -> transmittance -> scaled LAB.

fn camera_linear(x: i32, y: i32) -> vec3<f32> {
    let w = i32(pc.camera_size.x);
    let h = i32(pc.camera_size.y);
    let i = u32(clamp(y, 0, h - 1) * w + clamp(x, 0, w - 1));
    let word = camera[i];
    return srgb_decode_code(vec3<u32>(word & 255u, (word >> 8u) & 255u, (word >> 16u) & 255u));
}

@compute @workgroup_size(8, 8)
fn decode_blur_h(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= pc.camera_size.x || id.y >= pc.camera_size.y) {
        return;
    }
    let x = i32(id.x);
    let y = i32(id.y);
    var acc = blur_tap(0u) * camera_linear(x, y);
    for (var k = 1u; k <= pc.blur_half; k++) {
        let o = i32(k);
        acc += blur_tap(k) * (camera_linear(x - o, y) + camera_linear(x + o, y));
    }
    blur_tmp[id.y * pc.camera_size.x + id.x] = vec4<f32>(acc, 1.0);
}

fn tmp_at(x: i32, y: i32) -> vec3<f32> {
    let h = i32(pc.camera_size.y);
    return blur_tmp[u32(clamp(y, 0, h - 1)) * pc.camera_size.x + u32(x)].rgb;
}

@compute @workgroup_size(8, 8)
fn blur_v(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= pc.camera_size.x || id.y >= pc.camera_size.y) {
        return;
    }
    let x = i32(id.x);
    let y = i32(id.y);
    var acc = blur_tap(0u) * tmp_at(x, y);
    for (var k = 1u; k <= pc.blur_half; k++) {
        let o = i32(k);
        acc += blur_tap(k) * (tmp_at(x, y - o) + tmp_at(x, y + o));
    }
    blurred[id.y * pc.camera_size.x + id.x] = vec4<f32>(acc, 1.0);
}

fn blurred_at(x: i32, y: i32) -> vec3<f32> {
    let w = i32(pc.camera_size.x);
    let h = i32(pc.camera_size.y);
    return blurred[u32(clamp(y, 0, h - 1) * w + clamp(x, 0, w - 1))].rgb;
}

@compute @workgroup_size(8, 8)
fn fov_map(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= pc.region_size.x || id.y >= pc.region_size.y) {
        return;
    }
    // Texel centres at (i + 0.5) / W, origin top-left (spec section 2, step 3).
    let display_uv = (vec2<f32>(id.xy) + 0.5) / vec2<f32>(pc.region_size);
    let camera_uv = pc.fov_scale * display_uv + pc.fov_offset;
    let texel = camera_uv * vec2<f32>(pc.camera_size) - 0.5;
    let base = floor(texel);
    let t = texel - base;
    let x = i32(base.x);
    let y = i32(base.y);
    let top = mix(blurred_at(x, y), blurred_at(x + 1, y), t.x);
    let bottom = mix(blurred_at(x, y + 1), blurred_at(x + 1, y + 1), t.x);
    let linear = mix(top, bottom, t.y);
    let i = id.y * pc.region_size.x + id.x;
    bg_linear[i] = vec4<f32>(linear, 1.0);
    store_background(i, pack_background(first_of(linear_to_scaled(single(pc.transmittance * linear)))));
}
