//! The shader codes (src/gpu/core/interface.rs) of the method's settings: which method, which view
//! mode. The algorithm names them; only the GPU engine needs them as numbers.

use super::interface::*;
use crate::algorithm::params::{Method, ViewMode};

/// The code the shaders use for a method: its entry's (src/algorithm/method/table.rs), for
/// which build.rs builds its `enhance` variants.
pub fn method_code(method: Method) -> u32 {
    method.entry().code
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

    /// Every method has a code of its own, and build.rs built its variants.
    #[test]
    fn method_codes_are_distinct_and_built() {
        let codes: Vec<u32> = Method::ALL.into_iter().map(method_code).collect();
        let mut sorted = codes.clone();
        sorted.sort();
        sorted.dedup();
        assert_eq!(sorted.len(), codes.len(), "{codes:?}");
        for c in codes {
            let built = crate::gpu::core::modules::ENHANCE_VARIANTS.iter();
            assert!(
                built.clone().any(|v| v.0 == c && v.1 == MODE_ENHANCE),
                "{c}"
            );
        }
    }

    #[test]
    fn mode_codes_are_distinct() {
        let mut codes: Vec<u32> = ViewMode::ALL.into_iter().map(mode_code).collect();
        codes.sort();
        codes.dedup();
        assert_eq!(codes.len(), ViewMode::ALL.len());
    }
}
