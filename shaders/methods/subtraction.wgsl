// `subtraction` (Weiland et al. 2009; docs/algorithm.md, Comparison methods), in linear light:
// k_v * display - k_b * background, the background not attenuated (clipped by the caller).
fn method_linear(display: Colours, bg: Background) -> Colours {
    return pc.k_v * display - pc.k_b * bg.linear;
}
