// Background preprocessing of spec section 2, once per camera frame, all on the camera grid:
// decode -> separable Gaussian blur, in linear light. The rest of section 2 (FoV bilinear
// sampling, transmittance, scaled LAB) runs in the enhancement pass (enhance.wgsl,
// sampled_background), only for the display pixels it enhances: per camera frame the work is
// proportional to the camera's pixels, never to the display's or the number of views.

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

// The vertical pass at column x (clamped to the image).
fn blur_v_at(x: i32, y: i32) -> vec3<f32> {
    let xc = min(x, i32(pc.camera_size.x) - 1);
    var acc = blur_tap(0u) * tmp_at(xc, y);
    for (var k = 1u; k <= pc.blur_half; k++) {
        let o = i32(k);
        acc += blur_tap(k) * (tmp_at(xc, y - o) + tmp_at(xc, y + o));
    }
    return acc;
}

// Vertical blur of four neighbouring texels x0..x0+3 per invocation (each entry of `blurred`
// also holds its right neighbour, so five columns are blurred for four entries).
@compute @workgroup_size(8, 8)
fn blur_v(@builtin(global_invocation_id) id: vec3<u32>) {
    let x0 = id.x * 4u;
    if (x0 >= pc.camera_size.x || id.y >= pc.camera_size.y) {
        return;
    }
    let y = i32(id.y);
    var left = blur_v_at(i32(x0), y);
    for (var k = 0u; k < 4u; k++) {
        let x = x0 + k;
        if (x >= pc.camera_size.x) {
            break;
        }
        let right = blur_v_at(i32(x) + 1, y);
        blurred[id.y * pc.camera_size.x + x] = vec4<u32>(pack_linear(left), pack_linear(right));
        left = right;
    }
}
