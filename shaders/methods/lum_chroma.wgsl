// `lum-chroma` (docs/algorithm.md, Comparison methods): P = D + |E'_h| * OD/|OD|; D where
// |D| <= 1e-6.
fn method_scaled(s: Step) -> Colours {
    let nd = sqrt(dots(s.d, s.d));
    let moved = s.d + per_pixel(sqrt(s.hue_a * s.hue_a + s.hue_b * s.hue_b) / nd, s.d);
    return pick(moved, s.d, nd <= vec4<f32>(1e-6));
}
