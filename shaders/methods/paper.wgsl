// `paper`: Algorithm 1 (docs/algorithm.md, Per-pixel optimisation). E'_ch kept only where it
// does not reduce chroma (E'.D' >= 0); luminance scaled by 1 - |cos_l|; the achromatic boost
// (beyond the paper, compiled out unless EXTRAS); then the JND constraint (enhance.wgsl).
fn method_scaled(s: Step) -> Colours {
    let keeps = s.ed >= vec4<f32>(0.0);
    let cos_l = s.to_i[0] * s.inv_n;
    let dir = Colours((1.0 - abs(cos_l)) * s.e[0], select(s.hue_a, s.e[1], keeps), select(s.hue_b, s.e[2], keeps));
    return jnd_constraint(s.d, achromatic_boost(s.d, s.d + dir, s.b), s.b);
}
