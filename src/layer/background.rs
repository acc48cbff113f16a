//! The layer's background frame from `CONTRASTXR_BACKGROUND`: `image:PATH` or `color:#RRGGBB`.
//! (Live camera sources come from the camera module.)

use crate::image::RgbaImage;
use std::sync::Arc;

/// Parses `#RRGGBB` (or `RRGGBB`).
pub fn parse_hex_colour(s: &str) -> Option<[u8; 3]> {
    let hex = s.trim().trim_start_matches('#');
    if hex.len() != 6 || !hex.chars().all(|c| c.is_ascii_hexdigit()) {
        return None;
    }
    let byte = |i: usize| u8::from_str_radix(&hex[i..i + 2], 16).ok();
    Some([byte(0)?, byte(2)?, byte(4)?])
}

/// Loads a static background source; the error is one sentence naming the problem.
pub fn load_static(spec: &str) -> Result<Arc<RgbaImage>, String> {
    if let Some(path) = spec.strip_prefix("image:") {
        return RgbaImage::load_png(std::path::Path::new(path)).map(Arc::new);
    }
    if let Some(colour) = spec.strip_prefix("color:") {
        let [r, g, b] = parse_hex_colour(colour)
            .ok_or_else(|| format!("background colour {colour:?} is not #RRGGBB"))?;
        return Ok(Arc::new(RgbaImage::new(64, 64, [r, g, b, 255])));
    }
    Err(format!(
        "background source {spec:?} is not image:PATH or color:#RRGGBB"
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn colours_parse() {
        assert_eq!(parse_hex_colour("#ff8000"), Some([255, 128, 0]));
        assert_eq!(parse_hex_colour("zz0000"), None);
        assert!(load_static("color:#123456").is_ok());
        assert!(load_static("nonsense").is_err());
        assert!(load_static("image:/nonexistent.png").is_err());
    }
}
