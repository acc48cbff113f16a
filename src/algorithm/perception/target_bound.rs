//! A lower bound of c' without table lookups, for the perceptual method's first question of
//! every content pixel: is it seen at the target already? (docs/algorithm.md, *The method, per
//! pixel*, on the GPU). c' = c max(1 - 1/C, 0) grows with C, and C grows with each channel's
//! sensitivity; the sensitivities at a pattern's luminance Y are at least the least of the
//! tables' entries from Y's band up (castleCSF's sensitivities are taken from the tables as
//! they are, wherever they fall). So a pattern whose C from those least sensitivities already
//! puts c' at the target is at the target: the shader then skips the logarithm and the lookups,
//! and decides as it would have. Pure, f32, as a shader evaluates it.
use glam::Vec3;

use super::castle_csf::{threshold_multiple, Sensitivities};
use super::perceived_contrast::rms_cone_contrast;
use super::tables::{PerceptualTables, LOG_LUMINANCE_MIN, LOG_LUMINANCE_STEP, TABLE_LEN};

/// Luminance bands: band k holds the Y (cd/m^2) at or above `10^BAND_LOG_FLOORS[k]`.
pub const BANDS: usize = 8;
pub const BAND_LOG_FLOORS: [f64; BANDS] = [-0.5, 0.0, 0.5, 1.0, 1.5, 2.0, 2.5, 3.0];

/// The bound settles a pixel only past the target by this fraction: far more than the f32
/// rounding between the bound and c' from the tables.
pub const SURE_MARGIN: f64 = 1e-4;

/// The least sensitivities of each band, and the target the bound must reach.
#[derive(Clone, Debug, PartialEq)]
pub struct TargetBound {
    /// Y at each band's floor (cd/m^2).
    pub floors: [f32; BANDS],
    /// Per band, each channel's least entry over every frequency's table, from the entry at or
    /// below the band's floor to the last (the lookup holds the last entry above it).
    pub least: [Sensitivities<f32>; BANDS],
    /// The target times 1 + SURE_MARGIN.
    pub sure_target: f32,
}

impl TargetBound {
    pub fn new(tables: &PerceptualTables) -> TargetBound {
        let least = BAND_LOG_FLOORS.map(|log_floor| {
            // One entry lower than the floor's, against the rounding of a shader's log10 Y.
            let first = ((log_floor - LOG_LUMINANCE_MIN) / LOG_LUMINANCE_STEP).floor() as i64 - 1;
            let from = first.clamp(0, TABLE_LEN as i64 - 1) as usize;
            let least_of = |column: fn(&super::tables::SensitivityTable) -> &[f32; TABLE_LEN]| {
                tables
                    .frequencies
                    .iter()
                    .flat_map(|t| column(t)[from..].iter().copied())
                    .fold(f32::INFINITY, f32::min)
            };
            Sensitivities {
                achromatic: least_of(|t| &t.achromatic),
                red_green: least_of(|t| &t.red_green),
                yellow_violet: least_of(|t| &t.yellow_violet),
            }
        });
        TargetBound {
            floors: BAND_LOG_FLOORS.map(|l| 10f64.powf(l) as f32),
            least,
            sure_target: (tables.target_contrast as f64 * (1.0 + SURE_MARGIN)) as f32,
        }
    }

    /// The least sensitivities of luminance `y`: its band's, none below the first band.
    pub fn least_at(&self, y: f32) -> Sensitivities<f32> {
        let none = Sensitivities {
            achromatic: 0.0,
            red_green: 0.0,
            yellow_violet: 0.0,
        };
        (0..BANDS)
            .rfind(|&k| y >= self.floors[k])
            .map_or(none, |k| self.least[k])
    }

    /// Whether c' of linear display colour `display` over the linear, unattenuated background
    /// `background` surely reaches the target (false where it may not: then c' decides).
    pub fn surely_at_target(
        &self,
        tables: &PerceptualTables,
        display: Vec3,
        background: Vec3,
    ) -> bool {
        let (mean, amplitude, y) = tables.pattern(display, background);
        let c = rms_cone_contrast(mean, amplitude);
        let over = c - self.sure_target;
        // c (1 - 1/C) >= target  <=>  C (c - target) >= c, for c > target.
        over > 0.0 && threshold_multiple(mean, amplitude, self.least_at(y)) * over >= c
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::algorithm::perception::frequency::Frequencies;
    use crate::algorithm::perception::perceived_contrast::Model;
    use crate::algorithm::perceptual_settings::PerceptualSettings;

    fn tables(world_nits: f64, frequencies: Frequencies) -> PerceptualTables {
        let settings = PerceptualSettings {
            world_nits,
            ..PerceptualSettings::default()
        };
        PerceptualTables::new(&Model::new(&settings, 0.4, frequencies))
    }

    /// Colours over the unit cube on a grid, dark ones included.
    fn colours() -> Vec<Vec3> {
        let steps = [0.0, 0.002, 0.01, 0.05, 0.2, 0.5, 1.0];
        let mut all = Vec::new();
        for r in steps {
            for g in steps {
                for b in steps {
                    all.push(Vec3::new(r, g, b));
                }
            }
        }
        all
    }

    /// Wherever the bound says "at the target", c' from the tables is at it; and it says so of
    /// most of the pairs that are, at every light level (a bound of 0 would settle none).
    #[test]
    fn the_bound_settles_only_pixels_at_the_target_and_most_of_them() {
        for world in [20.0, 500.0, 1000.0, 5000.0] {
            for frequencies in [Frequencies::One(2.0), Frequencies::Ensemble] {
                let t = tables(world, frequencies);
                let bound = TargetBound::new(&t);
                let (mut at_target, mut settled) = (0, 0);
                for display in colours() {
                    for background in colours() {
                        let sure = bound.surely_at_target(&t, display, background);
                        let reached =
                            t.perceived_contrast(display, background) >= t.target_contrast;
                        assert!(!sure || reached, "{world} {display} {background}");
                        at_target += reached as u32;
                        settled += sure as u32;
                    }
                }
                assert!(
                    settled as f64 >= 0.7 * at_target as f64,
                    "world {world}: {settled} of {at_target} settled"
                );
            }
        }
    }

    #[test]
    fn each_band_is_at_most_the_tables_above_its_floor() {
        let t = tables(1000.0, Frequencies::Ensemble);
        let bound = TargetBound::new(&t);
        for (k, &log_floor) in BAND_LOG_FLOORS.iter().enumerate() {
            for log_y in [log_floor as f32, 3.7, 4.5, 6.0] {
                for table in &t.frequencies {
                    let s = table.lookup(log_y);
                    assert!(bound.least[k].achromatic <= s.achromatic, "{k} {log_y}");
                    assert!(bound.least[k].red_green <= s.red_green, "{k} {log_y}");
                    assert!(
                        bound.least[k].yellow_violet <= s.yellow_violet,
                        "{k} {log_y}"
                    );
                }
            }
        }
        // Higher bands, higher floors: the least sensitivities do not fall.
        for k in 1..BANDS {
            assert!(bound.floors[k] > bound.floors[k - 1]);
            assert!(bound.least[k].achromatic >= bound.least[k - 1].achromatic);
        }
    }
}
