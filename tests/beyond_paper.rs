//! The two options beyond the paper (its stated limitations): the chroma boost on near-grey
//! backgrounds and the luminance cap. Both are off by default, where the paper's method is
//! unchanged bit for bit.

use contrastxr::algorithm::params::ACHROMATIC_CHROMA;
use contrastxr::algorithm::{enhance_linear, enhance_scaled, Params};
use contrastxr::colour;
use glam::DVec3;
use proptest::prelude::*;

fn scaled() -> impl Strategy<Value = DVec3> {
    (-1.0f64..1.0, -0.8f64..0.8, -0.8f64..0.8).prop_map(|(l, a, b)| DVec3::new(l, a, b))
}

/// A background of chroma below ACHROMATIC_CHROMA (near grey), any lightness.
fn grey_background() -> impl Strategy<Value = DVec3> {
    (-0.9f64..0.9, 0.0f64..std::f64::consts::TAU, 0.0f64..0.079)
        .prop_map(|(l, angle, c)| DVec3::new(l, c * angle.cos(), c * angle.sin()))
}

fn linear() -> impl Strategy<Value = DVec3> {
    (0.001f64..1.0, 0.001f64..1.0, 0.001f64..1.0).prop_map(|(r, g, b)| DVec3::new(r, g, b))
}

fn chroma(v: DVec3) -> f64 {
    (v.y * v.y + v.z * v.z).sqrt()
}

proptest! {
    #[test]
    fn boost_keeps_the_change_within_lambda_e(d in scaled(), b in grey_background(), boost in 0.0f32..=1.0, lambda_e in 0.05f32..1.0) {
        let params = Params { achromatic_boost: boost, lambda_e, ..Params::default() };
        let p = enhance_scaled(d, b, &params);
        prop_assert!((p - d).length() <= f64::from(lambda_e) + 1e-9);
    }

    #[test]
    fn boost_raises_chroma_on_grey_backgrounds(d in scaled(), b in grey_background()) {
        prop_assume!(chroma(d) > 0.05);
        let off = enhance_scaled(d, b, &Params::default());
        let on = enhance_scaled(d, b, &Params { achromatic_boost: 1.0, ..Params::default() });
        prop_assert!(chroma(on) >= chroma(off) - 1e-12, "off {off:?} on {on:?}");
    }

    #[test]
    fn boost_changes_nothing_on_chromatic_backgrounds(d in scaled(), b in scaled()) {
        prop_assume!(chroma(b) >= ACHROMATIC_CHROMA);
        let off = enhance_scaled(d, b, &Params::default());
        let on = enhance_scaled(d, b, &Params { achromatic_boost: 1.0, ..Params::default() });
        prop_assert_eq!(off, on);
    }

    #[test]
    fn luminance_never_rises_past_the_cap(d in linear(), bg in linear(), cap in 0.01f32..0.5) {
        let bg_scaled = colour::linear_to_scaled(0.4 * bg);
        let params = Params { luminance_cap: cap, ..Params::default() };
        let out = enhance_linear(d, 1.0, bg, bg_scaled, &params).unwrap();
        let (y_in, y_out) = (colour::linear_to_xyz(d).y, colour::linear_to_xyz(out).y);
        prop_assert!(y_out <= (1.0 + f64::from(cap)) * y_in + 1e-12, "{y_in} -> {y_out}");
    }
}

#[test]
fn boost_enhances_much_more_of_a_scene_on_a_grey_wall() {
    // Independent of the code under test's metric: count pixels whose colour moved by at least
    // the JND (2.3 Delta E) with and without the boost, on a mid-grey background.
    let b = colour::linear_to_scaled(DVec3::splat(0.4 * 0.2));
    let samples: Vec<DVec3> = (0..400)
        .map(|k| {
            let t = f64::from(k) / 400.0;
            colour::linear_to_scaled(DVec3::new(
                0.2 + 0.6 * t,
                0.5 - 0.3 * t,
                0.3 + 0.2 * (7.0 * t).sin().abs(),
            ))
        })
        .collect();
    let moved = |params: &Params| {
        samples
            .iter()
            .filter(|&&d| {
                let p = enhance_scaled(d, b, params);
                ((p - d) * DVec3::new(50.0, 128.0, 128.0)).length() >= 2.3
            })
            .count()
    };
    let (off, on) = (
        moved(&Params::default()),
        moved(&Params {
            achromatic_boost: 1.0,
            ..Params::default()
        }),
    );
    assert!(
        on > off + 100,
        "boost moved {on} of 400 colours, the paper's method {off}"
    );
}
