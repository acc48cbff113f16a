// `other-hue` (docs/algorithm.md, Comparison methods): P = D - E'_h.
fn method_scaled(s: Step) -> Colours {
    return s.d - Colours(vec4<f32>(0.0), s.hue_a, s.hue_b);
}
