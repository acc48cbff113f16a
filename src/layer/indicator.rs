//! The in-headset indicator: a short line such as `CONTRASTXR ENHANCE λE 0.40`, drawn into
//! each eye image for `indicator_seconds` after the session's first processed frame and after
//! each change of settings, so the wearer can tell the layer is on and what it does.
//!
//! The text is rendered on the CPU with the figures' bitmap font; its lit pixels, as runs, are
//! drawn by the GPU engine after the enhancement (gpu/vulkan/frame/overlay_copies.rs). The app's other pixels are
//! left as the enhancement made them, and captures show what the runtime gets.

use crate::algorithm::params::{Method, ViewMode};
use crate::config::Settings;
use crate::evaluate::font;
use crate::gpu::core::Run;
use crate::image::RgbaImage;
use std::time::{Duration, Instant};

/// The text's colour, sRGB-encoded: a bright green, which an additive display shows well.
pub const COLOUR: [u8; 4] = [64, 255, 64, 255];

/// What the indicator says for these settings.
pub fn text(settings: &Settings) -> String {
    let p = &settings.params;
    // A comparison method is shown in mode enhance: name the method then.
    let what = match (p.mode, p.method) {
        (ViewMode::Enhance, m) if m != Method::Paper => m.name(),
        (mode, _) => mode.name(),
    };
    format!("CONTRASTXR {} λE {:.2}", what.to_uppercase(), p.lambda_e)
}

/// When the indicator shows: from the first frame of each settings generation on, for a while.
#[derive(Default)]
pub struct Timer {
    generation: Option<u64>,
    since: Option<Instant>,
    text: String,
    shown_for: Duration,
    enabled: bool,
}

impl Timer {
    /// Called at each processed frame with the session's current settings.
    pub fn update(&mut self, settings: &Settings, now: Instant) {
        if self.generation == Some(settings.generation) {
            return;
        }
        self.generation = Some(settings.generation);
        self.since = Some(now);
        self.text = text(settings);
        self.shown_for = Duration::from_secs_f32(settings.indicator_seconds.clamp(0.0, 60.0));
        self.enabled = settings.indicator;
    }

    /// The text to draw now, if any.
    pub fn showing(&self, now: Instant) -> Option<&str> {
        let since = self.since.filter(|_| self.enabled)?;
        (now.saturating_duration_since(since) < self.shown_for).then_some(self.text.as_str())
    }
}

/// Where the text goes in a region: (x, y, scale). Centred, a fifth of the way down, about a
/// 25th of the region's height tall; None when it does not fit even at scale 1.
pub fn placement(text: &str, (w, h): (u32, u32)) -> Option<(u32, u32, u32)> {
    let mut scale = (h / (font::GLYPH_HEIGHT * 25)).max(1);
    while scale > 1 && font::text_width(text, scale) > w * 9 / 10 {
        scale -= 1;
    }
    let (tw, th) = (font::text_width(text, scale), font::text_height(scale));
    (tw <= w && th <= h).then(|| ((w - tw) / 2, h / 5, scale))
}

/// The runs of lit pixels of `text` placed in a region of size `region`.
pub fn runs(text: &str, region: (u32, u32)) -> Vec<Run> {
    let Some((x0, y0, scale)) = placement(text, region) else {
        return Vec::new();
    };
    let (tw, th) = (font::text_width(text, scale), font::text_height(scale));
    let mut mask = RgbaImage::new(tw, th, [0; 4]);
    font::draw_text(&mut mask, 0, 0, text, scale, [255; 4]);
    let mut out = Vec::new();
    for y in 0..th {
        let mut x = 0;
        while x < tw {
            if mask.get(x, y)[0] == 0 {
                x += 1;
                continue;
            }
            let start = x;
            while x < tw && mask.get(x, y)[0] != 0 {
                x += 1;
            }
            out.push(Run {
                x: x0 + start,
                y: y0 + y,
                len: x - start,
            });
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn text_names_the_mode_or_method_and_lambda() {
        let mut s = Settings::default();
        assert_eq!(text(&s), "CONTRASTXR ENHANCE λE 0.40");
        s.params.method = Method::HueOnly;
        s.params.lambda_e = 0.6;
        assert_eq!(text(&s), "CONTRASTXR HUE-ONLY λE 0.60");
        s.params.mode = ViewMode::Split;
        assert_eq!(text(&s), "CONTRASTXR SPLIT λE 0.60");
    }

    #[test]
    fn shows_after_start_and_after_each_change_then_expires() {
        let t0 = Instant::now();
        let mut s = Settings::default();
        let mut timer = Timer::default();
        timer.update(&s, t0);
        assert_eq!(timer.showing(t0), Some("CONTRASTXR ENHANCE λE 0.40"));
        let later = t0 + Duration::from_secs(2);
        timer.update(&s, later);
        assert!(
            timer.showing(later).is_some(),
            "same generation: still the first start"
        );
        let expired = t0 + Duration::from_secs_f32(3.01);
        timer.update(&s, expired);
        assert_eq!(timer.showing(expired), None);
        // A change of settings (a new generation) shows the new text for another 3 s.
        s.params.lambda_e = 0.7;
        s.generation += 1;
        timer.update(&s, expired);
        assert_eq!(timer.showing(expired), Some("CONTRASTXR ENHANCE λE 0.70"));
        assert_eq!(timer.showing(expired + Duration::from_secs(4)), None);
        // Switched off: never shown.
        s.indicator = false;
        s.generation += 1;
        timer.update(&s, expired);
        assert_eq!(timer.showing(expired), None);
    }

    #[test]
    fn runs_cover_the_glyphs_inside_the_region() {
        let text = "CONTRASTXR ENHANCE λE 0.40";
        let region = (160, 120);
        let runs = runs(text, region);
        let (x0, y0, scale) = placement(text, region).unwrap();
        assert_eq!(scale, 1);
        assert_eq!(y0, 24);
        // 26 glyphs of 5 columns plus 25 blank columns: 155 pixels wide, centred.
        assert_eq!(x0, (160 - 155) / 2);
        for r in &runs {
            assert!(r.x >= x0 && r.x + r.len <= x0 + 155, "{r:?}");
            assert!(r.y >= y0 && r.y < y0 + 7, "{r:?}");
        }
        // The 'C' of row 0 is the three middle columns of its first glyph.
        assert_eq!(
            runs[0],
            Run {
                x: x0 + 1,
                y: y0,
                len: 3
            }
        );
        assert!(
            super::runs(text, (100, 100)).is_empty(),
            "too narrow: not drawn"
        );
        let big = placement(text, (1268, 720)).unwrap();
        assert_eq!(big.2, 4);
    }
}
