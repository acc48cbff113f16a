//! The shader codes (src/gpu/interface.rs) of the method's settings: which method, which view
//! mode. The algorithm names them; only the GPU engine needs them as numbers.

use super::interface::*;
use crate::algorithm::params::{Method, ViewMode};

/// The code the shaders use for a method.
pub fn method_code(method: Method) -> u32 {
    match method {
        Method::Paper => METHOD_PAPER,
        Method::HueOnly => METHOD_HUE_ONLY,
        Method::OtherHue => METHOD_OTHER_HUE,
        Method::LumChroma => METHOD_LUM_CHROMA,
        Method::Subtraction => METHOD_SUBTRACTION,
    }
}

/// The code the shaders use for a view mode.
pub fn mode_code(mode: ViewMode) -> u32 {
    match mode {
        ViewMode::Enhance => MODE_ENHANCE,
        ViewMode::Off => MODE_OFF,
        ViewMode::Split => MODE_SPLIT,
        ViewMode::Heatmap => MODE_HEATMAP,
        ViewMode::Background => MODE_BACKGROUND,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every method has a code of its own below METHODS (the variants build.rs makes).
    #[test]
    fn method_codes_are_distinct_and_built() {
        let codes: Vec<u32> = Method::ALL.into_iter().map(method_code).collect();
        let mut sorted = codes.clone();
        sorted.sort();
        sorted.dedup();
        assert_eq!(sorted.len(), codes.len(), "{codes:?}");
        assert!(codes.iter().all(|&c| c < METHODS), "{codes:?}");
    }

    #[test]
    fn mode_codes_are_distinct() {
        let mut codes: Vec<u32> = ViewMode::ALL.into_iter().map(mode_code).collect();
        codes.sort();
        codes.dedup();
        assert_eq!(codes.len(), ViewMode::ALL.len());
    }
}
