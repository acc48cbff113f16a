// `luminance` (docs/algorithm.md, Comparison methods): only L' moves, away from B's L', by
// lambda_e, clamped to [-1, 1] (L* in [0, 100]); a' and b' (hue and chroma) kept. Where D's
// L' equals B's: up where L'_D <= 0 (more room above), else down.
fn method_scaled(s: Step) -> Colours {
    let above = s.d[0] - s.b[0];
    let up = (above > vec4<f32>(0.0)) | ((above == vec4<f32>(0.0)) & (s.d[0] <= vec4<f32>(0.0)));
    let step = select(vec4<f32>(-pc.lambda_e), vec4<f32>(pc.lambda_e), up);
    let l = clamp(s.d[0] + step, vec4<f32>(-1.0), vec4<f32>(1.0));
    return Colours(l, s.d[1], s.d[2]);
}
