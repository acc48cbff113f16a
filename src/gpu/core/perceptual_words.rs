//! A view's `perceptual` buffer (src/gpu/core/interface.rs, PERCEPTUAL_*): the perceptual
//! model of its frame as the `perceptual` method's shader reads it, the f32 tables of
//! src/algorithm/perception/tables.rs laid out in words. Both backends upload these words as
//! they are; a view's words are made and uploaded again only when its model changes.

use crate::algorithm::params::{Method, Params};
use crate::algorithm::perception::frequency::{view_params, ViewGeometry};
use crate::algorithm::perception::perceived_contrast::Model;
use crate::algorithm::perception::tables::{
    PerceptualTables, LOG_LUMINANCE_MIN, LOG_LUMINANCE_STEP, TABLE_LEN,
};
use crate::algorithm::perception::target_bound::{TargetBound, BANDS};
use crate::gpu::core::interface::*;

const _: () = assert!(PERCEPTUAL_BANDS as usize == BANDS);

/// The words of a model (PERCEPTUAL_WORDS of them; unused frequencies zero).
pub fn model_words(model: &Model) -> Vec<u32> {
    let tables = PerceptualTables::new(model);
    let mut w = vec![0f32; PERCEPTUAL_WORDS as usize];
    let at = |i: u32| i as usize;
    for (r, row) in tables.rgb_to_lms.iter().enumerate() {
        w[at(PERCEPTUAL_AT_RGB_TO_LMS) + 3 * r..][..3].copy_from_slice(row);
    }
    w[at(PERCEPTUAL_AT_RGB_TO_LUMINANCE)..][..3].copy_from_slice(&tables.rgb_to_luminance);
    w[at(PERCEPTUAL_AT_HALF_PEAK)] = 0.5 * tables.display_peak_nits;
    w[at(PERCEPTUAL_AT_WORLD)] = tables.world_nits_at_eye;
    w[at(PERCEPTUAL_AT_LOG_MIN_LUMINANCE)] = tables.log_min_luminance;
    w[at(PERCEPTUAL_AT_TARGET)] = tables.target_contrast;
    let n = tables
        .frequencies
        .len()
        .min(PERCEPTUAL_MAX_FREQUENCIES as usize);
    w[at(PERCEPTUAL_AT_FREQUENCIES)] = n as f32;
    w[at(PERCEPTUAL_AT_LOG_Y_FIRST)] = LOG_LUMINANCE_MIN as f32;
    w[at(PERCEPTUAL_AT_ENTRIES_PER_LOG_Y)] = (1.0 / LOG_LUMINANCE_STEP) as f32;
    let bound = TargetBound::new(&tables);
    w[at(PERCEPTUAL_AT_SURE_TARGET)] = bound.sure_target;
    for (k, s) in bound.least.iter().enumerate() {
        let band = at(PERCEPTUAL_AT_BANDS) + 4 * k;
        w[band..band + 4].copy_from_slice(&[
            bound.floors[k],
            s.achromatic,
            s.red_green,
            s.yellow_violet,
        ]);
    }
    for (f, t) in tables.frequencies.iter().take(n).enumerate() {
        for i in 0..TABLE_LEN {
            let entry = at(PERCEPTUAL_HEADER_WORDS) + 4 * (f * TABLE_LEN + i);
            w[entry..entry + 3].copy_from_slice(&[
                t.achromatic[i],
                t.red_green[i],
                t.yellow_violet[i],
            ]);
        }
    }
    w.into_iter().map(f32::to_bits).collect()
}

/// The last model's words, kept: a view's model changes only with the settings or the view.
/// The view's buffer is uploaded again only when they change.
#[derive(Default)]
pub struct PerceptualWords {
    last: Option<(Model, Vec<u32>)>,
    /// The view's buffer holds `last`'s words (its backend said so once the upload was sure).
    held: bool,
}

impl PerceptualWords {
    /// The words a view of `params` at `view` needs where its buffer does not hold them yet;
    /// None unless its method is `perceptual`, or when the buffer already holds them.
    pub fn to_upload(&mut self, params: &Params, view: &ViewGeometry) -> Option<&[u32]> {
        if params.method != Method::Perceptual {
            return None;
        }
        let model = Model::of_params(&view_params(params, view));
        if self.last.as_ref().map(|(m, _)| m) != Some(&model) {
            self.last = Some((model, model_words(&model)));
            self.held = false;
        }
        match self.held {
            true => None,
            false => self.last.as_ref().map(|(_, w)| w.as_slice()),
        }
    }

    /// The view's buffer now holds the words `to_upload` returned last: the upload ran, or
    /// was submitted to the queue.
    pub fn set_held(&mut self) {
        self.held = self.last.is_some();
    }
}

const _: () = assert!(TABLE_LEN == PERCEPTUAL_TABLE_LEN as usize);

#[cfg(test)]
mod tests {
    use super::*;
    use crate::algorithm::mapping::CameraMapping;
    use crate::algorithm::perception::frequency::Frequencies;
    use crate::algorithm::perceptual_settings::PerceptualSettings;

    #[test]
    fn the_words_hold_the_tables_where_the_interface_says() {
        let model = Model::new(&PerceptualSettings::default(), 0.4, Frequencies::Ensemble);
        let tables = PerceptualTables::new(&model);
        let w: Vec<f32> = model_words(&model)
            .into_iter()
            .map(f32::from_bits)
            .collect();
        assert_eq!(w.len(), PERCEPTUAL_WORDS as usize);
        assert_eq!(w[PERCEPTUAL_AT_FREQUENCIES as usize], 4.0);
        assert_eq!(w[PERCEPTUAL_AT_HALF_PEAK as usize], 100.0);
        assert_eq!(w[PERCEPTUAL_AT_WORLD as usize], 400.0);
        assert_eq!(w[PERCEPTUAL_AT_TARGET as usize], 0.05);
        assert_eq!(
            w[PERCEPTUAL_AT_RGB_TO_LMS as usize + 4],
            tables.rgb_to_lms[1][1]
        );
        // The third frequency's entry 100: its three sensitivities, then 0.
        let at = PERCEPTUAL_HEADER_WORDS as usize + 4 * (2 * TABLE_LEN + 100);
        let t = &tables.frequencies[2];
        let entry = [
            t.achromatic[100],
            t.red_green[100],
            t.yellow_violet[100],
            0.0,
        ];
        assert_eq!(w[at..at + 4], entry);
        // The bound's third band: its floor, then its three least sensitivities.
        let bound = TargetBound::new(&tables);
        let band = PERCEPTUAL_AT_BANDS as usize + 4 * 2;
        assert_eq!(w[band], bound.floors[2]);
        assert!((w[band] - 3.162_277_7).abs() < 1e-6, "10^0.5 cd/m^2");
        assert_eq!(w[band + 2], bound.least[2].red_green);
        assert_eq!(w[PERCEPTUAL_AT_SURE_TARGET as usize], bound.sure_target);
        let last = &w[w.len() - 4..];
        assert_eq!(last[2], tables.frequencies[3].yellow_violet[TABLE_LEN - 1]);
    }

    #[test]
    fn only_the_perceptual_method_has_words_and_a_new_model_makes_new_ones() {
        let mapping = CameraMapping::IDENTITY;
        let view = ViewGeometry {
            mapping: &mapping,
            display_width: 640,
            camera_width: 640,
            pixels_per_degree: 20.0,
        };
        let mut words = PerceptualWords::default();
        assert!(words.to_upload(&Params::default(), &view).is_none());
        let mut params = Params {
            method: Method::Perceptual,
            ..Params::default()
        };
        let first = words.to_upload(&params, &view).unwrap().to_vec();
        // Not yet said to be held (a recording that was never submitted): again.
        assert_eq!(words.to_upload(&params, &view).unwrap(), first);
        words.set_held();
        assert!(words.to_upload(&params, &view).is_none());
        params.perceptual.world_nits = 5000.0;
        let second = words.to_upload(&params, &view).unwrap().to_vec();
        assert_ne!(first, second);
        let at = PERCEPTUAL_AT_WORLD as usize;
        assert_eq!(f32::from_bits(second[at]), 2000.0);
        words.set_held();
        assert!(words.to_upload(&params, &view).is_none());
    }
}
