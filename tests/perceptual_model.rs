//! The perceptual contrast model and the perceptual method's CPU reference (docs/algorithm.md,
//! *The perceptual method*): castleCSF's closed form and c' against published reference values,
//! its two floating-point traps, the GPU's f32 tables against the f64 closed form, and the
//! method's promises (never more change than the paper's, visible pixels untouched, the target
//! reached by the least change the bisection finds).

use contrastxr::algorithm::perception::castle_csf::{self, Sensitivities};
use contrastxr::algorithm::perception::frame_report::{frame_report, ReportPixel};
use contrastxr::algorithm::perception::frequency::{Frequencies, ENSEMBLE_CPD};
use contrastxr::algorithm::perception::light::{Light, Pattern};
use contrastxr::algorithm::perception::perceived_contrast::{contrast, Model};
use contrastxr::algorithm::perception::perceptual_pixel::{
    perceptual, perceptual_over_paper, Class, Outcome,
};
use contrastxr::algorithm::perception::tables::{
    PerceptualTables, SensitivityTable, LOG_LUMINANCE_MAX, LOG_LUMINANCE_MIN,
};
use contrastxr::algorithm::perceptual_settings::PerceptualSettings;
use contrastxr::algorithm::{enhance_linear, Params, Stored};
use contrastxr::colour;
use glam::{DVec3, Vec3};

fn assert_rel(got: f64, want: f64, tol: f64, what: &str) {
    assert!(
        ((got - want) / want).abs() <= tol,
        "{what}: got {got}, want {want} (relative {:.2e})",
        ((got - want) / want).abs()
    );
}

// ---------------------------------------------------------------------------------------------
// castleCSF and c' against the published reference values (f64, 1e-3 relative).

/// An achromatic D65 pattern of luminance `y` whose cone contrast is 1 %.
fn d65_pattern(y: f64) -> Pattern {
    Pattern {
        mean: [0.6991, 0.3009, 0.0198].map(|v| v * y),
        amplitude: [0.6855, 0.2951, 0.0194].map(|v| v * y * 0.01),
        luminance: y,
    }
}

#[test]
fn threshold_multiple_over_contrast_matches_the_reference_table() {
    let cpd = [1.0, 2.0, 4.0, 8.0, 16.0];
    let table: [(f64, [f64; 5]); 5] = [
        (0.1, [16.446, 12.930, 6.373, 1.803, 0.270]),
        (1.0, [35.380, 39.643, 27.847, 11.227, 2.390]),
        (10.0, [51.597, 81.341, 80.393, 45.603, 13.659]),
        (100.0, [51.483, 105.020, 134.312, 98.588, 38.210]),
        (1000.0, [50.085, 108.359, 151.165, 121.033, 51.168]),
    ];
    for (y, row) in table {
        for (f, want) in cpd.into_iter().zip(row) {
            let k = contrast(&d65_pattern(y), y, f);
            let got = k.threshold_multiple / k.physical;
            // 1e-3 relative, or half the last printed digit (0.270 is 0.2696 rounded).
            assert!(
                (got - want).abs() <= (1e-3 * want).max(5e-4),
                "C/c at Y {y}, f {f}: got {got}, want {want}"
            );
        }
    }
}

#[test]
fn channel_sensitivities_match_the_reference_values() {
    // (f, Y): S_ach, S_rg, S_yv.
    let points = [
        (4.0, 100.0, [134.2779, 148.8949, 14.7594]),
        (2.0, 10.0, [81.3198, 93.0842, 9.7684]),
        (1.0, 1.0, [35.3714, 30.4290, 3.8372]),
        (8.0, 0.1, [1.8025, 6.5112, 0.7789]),
    ];
    for (f, y, want) in points {
        let s = castle_csf::sensitivities(y, f);
        let got = [s.achromatic, s.red_green, s.yellow_violet];
        for (i, name) in ["ach", "rg", "yv"].iter().enumerate() {
            assert_rel(got[i], want[i], 1e-3, &format!("S_{name} at f {f}, Y {y}"));
        }
    }
}

struct Example {
    display: [f64; 3],
    background: [f64; 3],
    /// P, W, t.
    light: [f64; 3],
    cpd: f64,
    y_display: f64,
    y_world: f64,
    c: f64,
    big_c: f64,
    perceived: f64,
}

const fn grey(v: f64) -> [f64; 3] {
    [v, v, v]
}

const EXAMPLES: [Example; 5] = [
    Example {
        display: grey(0.5),
        background: grey(0.2),
        light: [200.0, 500.0, 0.3],
        cpd: 2.0,
        y_display: 100.0,
        y_world: 30.0,
        c: 0.625,
        big_c: 64.969,
        perceived: 0.61538,
    },
    Example {
        display: grey(0.5),
        background: grey(0.8),
        light: [200.0, 5000.0, 0.3],
        cpd: 2.0,
        y_display: 100.0,
        y_world: 1200.0,
        c: 0.04,
        big_c: 4.298,
        perceived: 0.03069,
    },
    Example {
        display: grey(0.5),
        background: grey(0.8),
        light: [200.0, 5000.0, 0.3],
        cpd: 0.4685,
        y_display: 100.0,
        y_world: 1200.0,
        c: 0.04,
        big_c: 0.935,
        perceived: 0.0,
    },
    Example {
        display: [0.6, 0.05, 0.05],
        background: [0.1, 0.4, 0.1],
        light: [200.0, 1000.0, 0.3],
        cpd: 2.0,
        y_display: 33.386,
        y_world: 94.368,
        c: 0.14215,
        big_c: 19.676,
        perceived: 0.13493,
    },
    Example {
        display: [0.02, 0.02, 0.5],
        background: grey(0.3),
        light: [200.0, 1000.0, 0.3],
        cpd: 2.0,
        y_display: 10.931,
        y_world: 90.0,
        c: 0.19917,
        big_c: 10.266,
        perceived: 0.17977,
    },
];

fn light_of(e: &Example) -> Light {
    Light {
        display_peak_nits: e.light[0],
        world_nits_at_eye: e.light[2] * e.light[1],
    }
}

/// The crate's RGB -> XYZ matrix has more digits than the 4 of the examples' (both Rec. 709):
/// the examples hold to 1e-3 relative, as the reference table does.
#[test]
fn the_worked_examples_hold() {
    for e in &EXAMPLES {
        let light = light_of(e);
        let (d, b) = (DVec3::from(e.display), DVec3::from(e.background));
        let what = format!("D {:?} over B {:?} at f {}", e.display, e.background, e.cpd);
        assert_rel(light.display_xyz(d).y, e.y_display, 1e-3, &what);
        assert_rel(light.world_xyz(b).y, e.y_world, 1e-3, &what);
        let pattern = light.pattern(d, b);
        let k = contrast(&pattern, pattern.luminance, e.cpd);
        assert_rel(k.physical, e.c, 1e-3, &what);
        assert_rel(k.threshold_multiple, e.big_c, 1e-3, &what);
        if e.perceived == 0.0 {
            assert_eq!(k.perceived, 0.0, "{what}: C < 1 is invisible");
        } else {
            assert_rel(k.perceived, e.perceived, 1e-3, &what);
        }
    }
}

#[test]
fn the_ensemble_example_holds() {
    let e = &EXAMPLES[1];
    let light = light_of(e);
    let (d, b) = (DVec3::from(e.display), DVec3::from(e.background));
    let pattern = light.pattern(d, b);
    let want = [0.0233, 0.0293, 0.0328, 0.0314];
    for (f, w) in ENSEMBLE_CPD.into_iter().zip(want) {
        let got = contrast(&pattern, pattern.luminance, f).perceived;
        assert!((got - w).abs() <= 5e-5, "c' at {f} cpd: {got}, want {w}");
    }
    let settings = PerceptualSettings {
        display_peak_nits: e.light[0],
        world_nits: e.light[1],
        ..PerceptualSettings::default()
    };
    let model = Model::new(&settings, e.light[2], Frequencies::Ensemble);
    assert_rel(
        model.perceived_contrast(d, b),
        0.02920,
        1e-3,
        "ensemble mean",
    );
}

// ---------------------------------------------------------------------------------------------
// The two floating-point traps.

/// The sustained channel's luminance factor as the model writes it, `1 - (1 + 5.58341e-7/Y)
/// ^-9.66862e9`, evaluated naively in f32: `1 + 5.58341e-7/Y` rounds to 1 and the factor to 0.
fn naive_sustained_factor_f32(y: f32) -> f32 {
    1.0 - (1.0 + 5.58341e-7f32 / y).powf(-9.66862e9)
}

#[test]
fn in_f32_the_sustained_channel_survives_where_the_naive_factor_vanishes() {
    for y in [10.0f32, 100.0, 1000.0, 10000.0] {
        // What the factor is: within 3e-4 of 1 - exp(-5398.4/Y) (5398.4 = 9.66862e9 x 5.58341e-7).
        let want = 1.0 - (-5398.4 / f64::from(y)).exp();
        let naive = naive_sustained_factor_f32(y);
        assert_eq!(
            naive, 0.0,
            "the naive f32 form at Y {y} is not the trap it should be"
        );
        let ours32 = f64::from(castle_csf::sustained_luminance_factor::<f32>(y));
        let ours64 = castle_csf::sustained_luminance_factor::<f64>(f64::from(y));
        assert!(
            (ours32 - want).abs() < 3e-4,
            "f32 at Y {y}: {ours32} vs {want}"
        );
        assert!(
            (ours64 - want).abs() < 3e-4,
            "f64 at Y {y}: {ours64} vs {want}"
        );
    }
    // The whole achromatic channel in f32 keeps the reference value S_ach(4 cpd, 100) = 134.2779;
    // with the naive factor its sustained part, nearly all of it, would be 0.
    let s32 = f64::from(castle_csf::achromatic::<f32>(100.0, 4.0));
    assert_rel(s32, 134.2779, 1e-3, "S_ach in f32");
    // With the naive factor, only the transient part would be left: under 1 % of it.
    let (y, f) = (100.0f32, 4.0f32);
    let sustained_without_factor =
        castle_csf::sustained(y, f) / castle_csf::sustained_luminance_factor(y);
    let naive = naive_sustained_factor_f32(y) * sustained_without_factor
        + castle_csf::transient_weight(y) * castle_csf::transient(y, f);
    assert!(f64::from(naive) < 0.01 * 134.2779, "naive S_ach {naive}");
    // And f32 follows f64 over the whole range the model uses.
    for i in 0..=110 {
        let y = 10f64.powf(-1.0 + 0.05 * f64::from(i));
        for f in [1.0, 4.0, 16.0] {
            let s64 = castle_csf::sensitivities(y, f);
            let s32 = castle_csf::sensitivities(y as f32, f as f32);
            for (a, b) in channels(s64).into_iter().zip(channels(s32)) {
                assert_rel(f64::from(b), a, 1e-4, &format!("f32 at Y {y}, f {f}"));
            }
        }
    }
}

fn channels<R: Copy>(s: Sensitivities<R>) -> [R; 3] {
    [s.achromatic, s.red_green, s.yellow_violet]
}

/// True when `g` never falls as its argument rises over `ys` (ascending).
fn nondecreasing(ys: &[f64], g: impl Fn(f64) -> f64) -> bool {
    ys.windows(2).all(|w| g(w[1]) >= g(w[0]))
}

#[test]
fn near_y_0_0113_the_transient_jump_is_in_the_closed_form_and_the_floor_keeps_the_model_clear() {
    // The closed form itself: at 4 cpd S is 0.975 at Y = 0.009, 3.78 at 0.0113, 1.345 at 0.013.
    for (y, want) in [(0.009, 0.975), (0.0113, 3.78), (0.013, 1.345)] {
        assert_rel(
            castle_csf::achromatic(y, 4.0),
            want,
            1e-3,
            &format!("S_ach at Y {y}"),
        );
    }
    // Content on a black world (c = 1 whatever its luminance) at mean luminances around the jump.
    let settings = PerceptualSettings::default();
    let model = Model::new(&settings, 0.4, Frequencies::One(4.0));
    let ys: Vec<f64> = (0..=60).map(|i| 0.005 * 1.05f64.powi(i)).collect();
    let display_of = |y: f64| DVec3::splat(2.0 * y / settings.display_peak_nits);
    // Taken at the raw mean luminance (no floor), more light makes the content less visible
    // just above the jump: the sensitivity is not monotone in luminance.
    let naive = |y: f64| {
        let p = model.light.pattern(display_of(y), DVec3::ZERO);
        contrast(&p, p.luminance, 4.0).threshold_multiple
    };
    assert!(
        (model
            .light
            .pattern(display_of(0.0113), DVec3::ZERO)
            .luminance
            - 0.0113)
            .abs()
            < 1e-8
    );
    assert!(!nondecreasing(&ys, naive), "the naive form shows no jump");
    assert!(naive(0.0113) > 2.0 * naive(0.013));
    // The model floors the luminance at min_luminance = 0.1 (above every Y of the sweep): no
    // jump, and the same sensitivity throughout.
    let floored = |y: f64| {
        let p = model.light.pattern(display_of(y), DVec3::ZERO);
        contrast(&p, model.sensitivity_luminance(p.luminance), 4.0).threshold_multiple
    };
    assert!(nondecreasing(&ys, floored));
    let at_floor = castle_csf::achromatic(0.1, 4.0);
    for &y in &ys {
        // An achromatic D65 display on black: C is S_ach at the floor to a few 1e-3 (the small
        // chromatic terms of a grey on the cone fundamentals).
        assert_rel(floored(y), at_floor, 1e-2, &format!("C at Y {y}"));
    }
}

// ---------------------------------------------------------------------------------------------
// The GPU's f32 tables against the f64 closed form.

/// How far the tables may be from the closed form, relative, per channel. Linear interpolation
/// over steps of h = 5.5/255 in log10 Y errs by about h^2/8 times the curvature of S in log Y;
/// the largest is the sustained channel's: 4e-4 at 30 cpd near the bottom of the range,
/// 3.5e-4 at 1 cpd where its band-pass floor sets in (f_max(Y) crossing f), 2.3e-4 at 2 to
/// 8 cpd near the top, where its luminance factor bends; then f32 rounding (6e-8).
/// Since c' = c - c/C and C is a norm of the three channels, a relative error e in each S moves
/// c' by at most e c/C <= e c: at 5e-4, well under the change in c' of one of the bisection's
/// 256ths (about c'/256, 2e-4 at the default target 0.05), so the tables shift the method's
/// output by at most one bisection step where a decision is within that noise, as the +-1
/// contract allows at decision points.
const TABLE_REL: f64 = 5e-4;

#[test]
fn the_tables_follow_the_closed_form_within_the_stated_bound() {
    for f in [1.0, 2.0, 4.0, 8.0, 16.0, 30.0]
        .into_iter()
        .chain(ENSEMBLE_CPD)
    {
        let t = SensitivityTable::new(f);
        let steps = 5000;
        for i in 0..=steps {
            let log_y = LOG_LUMINANCE_MIN
                + (LOG_LUMINANCE_MAX - LOG_LUMINANCE_MIN) * i as f64 / steps as f64;
            let want = castle_csf::sensitivities(10f64.powf(log_y), f);
            let got = t.lookup(log_y as f32);
            for (a, b) in channels(want).into_iter().zip(channels(got)) {
                assert_rel(
                    f64::from(b),
                    a,
                    TABLE_REL,
                    &format!("table at log Y {log_y}, f {f}"),
                );
            }
        }
        // Held at the ends.
        assert_eq!(t.lookup(-3.0), t.lookup(LOG_LUMINANCE_MIN as f32));
        assert_eq!(t.lookup(6.0), t.lookup(LOG_LUMINANCE_MAX as f32));
    }
}

/// A small deterministic generator (xorshift64*) for the sampled checks.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11) as f64 / (1u64 << 53) as f64
    }

    /// An 8-bit sRGB colour, decoded.
    fn colour(&mut self) -> DVec3 {
        let mut code = || (self.next() * 256.0).floor().min(255.0) as u8;
        colour::srgb8_to_linear([code(), code(), code()])
    }
}

#[test]
fn c_prime_from_the_tables_in_f32_follows_the_f64_model() {
    let mut rng = Rng(0x5eed_1234_abcd_0001);
    for (peak, world, t, freqs) in [
        (200.0, 1000.0, 0.4, Frequencies::One(2.0)),
        (200.0, 5000.0, 0.4, Frequencies::One(4.0)),
        (200.0, 20.0, 0.4, Frequencies::One(8.0)),
        (1000.0, 500.0, 0.2, Frequencies::Ensemble),
        (50.0, 80000.0, 1.0, Frequencies::One(30.0)),
    ] {
        let settings = PerceptualSettings {
            display_peak_nits: peak,
            world_nits: world,
            ..PerceptualSettings::default()
        };
        let model = Model::new(&settings, t, freqs);
        let tables = PerceptualTables::new(&model);
        for _ in 0..4000 {
            let (d, b) = (rng.colour(), rng.colour());
            let want = model.perceived_contrast(d, b);
            let got = f64::from(tables.perceived_contrast(d.as_vec3(), b.as_vec3()));
            let p = model.light.pattern(d, b);
            let c = contrastxr::algorithm::perception::perceived_contrast::rms_cone_contrast(
                p.mean,
                p.amplitude,
            );
            assert!(
                (got - want).abs() <= TABLE_REL * c + 2e-6,
                "c' {got} vs {want} (c {c}) for D {d} over B {b}, {peak}/{world}/{t}/{freqs:?}"
            );
        }
        assert_eq!(tables.perceived_contrast(Vec3::ZERO, Vec3::splat(0.5)), 0.0);
    }
}

// ---------------------------------------------------------------------------------------------
// The method.

fn model(world: f64, target: f64) -> Model {
    let settings = PerceptualSettings {
        world_nits: world,
        target_contrast: target,
        ..PerceptualSettings::default()
    };
    Model::new(
        &settings,
        f64::from(Params::default().transmittance),
        Frequencies::One(2.0),
    )
}

fn paper_output(d: DVec3, b: DVec3, params: &Params) -> DVec3 {
    let bg_scaled = colour::linear_to_scaled(f64::from(params.transmittance) * b);
    enhance_linear(d, 1.0, b, bg_scaled, params).unwrap()
}

fn change(a: DVec3, b: DVec3) -> f64 {
    colour::delta_e(colour::linear_to_lab(a), colour::linear_to_lab(b))
}

/// Random content pixels over random backgrounds, with the paper's output and the method's
/// (its output kept exact: the spec's method).
fn sampled(world: f64, target: f64, n: usize, seed: u64) -> Vec<(DVec3, DVec3, DVec3, Outcome)> {
    sampled_as(Stored::Exact, world, target, n, seed)
}

fn sampled_as(
    stored: Stored,
    world: f64,
    target: f64,
    n: usize,
    seed: u64,
) -> Vec<(DVec3, DVec3, DVec3, Outcome)> {
    let params = Params {
        stored,
        ..Params::default()
    };
    let m = model(world, target);
    let mut rng = Rng(seed);
    (0..n)
        .filter_map(|_| {
            let (d, b) = (rng.colour(), rng.colour());
            if d == DVec3::ZERO {
                return None;
            }
            let e = paper_output(d, b, &params);
            Some((d, b, e, perceptual_over_paper(d, 1.0, b, &params, &m)))
        })
        .collect()
}

#[test]
fn no_pixel_changes_more_than_the_paper_changes_it() {
    for (world, target) in [(20.0, 0.05), (500.0, 0.05), (5000.0, 0.05), (5000.0, 1.0)] {
        for (d, b, e, out) in sampled(world, target, 3000, 7 + world as u64) {
            let (mine, paper) = (change(d, out.output), change(d, e));
            assert!(
                mine <= paper + 1e-6,
                "D {d} over B {b}, world {world}, target {target}: {mine} > paper's {paper}"
            );
            assert!(out.output.cmpge(DVec3::ZERO).all() && out.output.cmple(DVec3::ONE).all());
        }
    }
}

#[test]
fn pixels_already_at_target_are_left_exactly_as_they_are() {
    let m = model(500.0, 0.05);
    let mut seen = 0;
    for (d, b, _, out) in sampled(500.0, 0.05, 3000, 11) {
        let before = m.perceived_contrast(d, b);
        assert_eq!(out.perceived_before, before);
        if before >= 0.05 {
            seen += 1;
            assert_eq!(out.output, d, "D {d} over B {b} (c' {before})");
            assert_eq!(out.class, Class::LeftAlone);
        } else {
            assert_ne!(out.class, Class::LeftAlone);
        }
    }
    assert!(seen > 100, "only {seen} pixels at target");
}

#[test]
fn with_target_1_every_pixel_spends_the_paper_budget_in_the_most_visible_direction() {
    let m = model(5000.0, 1.0);
    let mut full = 0;
    for (d, b, e, out) in sampled(5000.0, 1.0, 3000, 13) {
        // Never reached, so never cut back.
        assert_eq!(out.class, Class::OutOfReach, "D {d} over B {b}");
        let after = m.perceived_contrast(out.output, b);
        assert_eq!(out.perceived_after, after);
        // The paper's colour is a candidate: the best is at least as visible.
        assert!(after >= m.perceived_contrast(e, b), "D {d} over B {b}");
        let (mine, paper) = (change(d, out.output), change(d, e));
        if (mine - paper).abs() < 1e-6 && paper > 0.0 {
            full += 1;
        }
    }
    // Where nothing clips, the change is the paper's exactly: most pixels.
    assert!(full > 1500, "{full} pixels with the paper's change");
    // A mid grey (L* 52) with a budget of about 12: every candidate lies inside the gamut, so
    // the kept one spends the whole budget.
    let (d, b) = (DVec3::splat(0.2), DVec3::new(0.6, 0.5, 0.1));
    let params = Params {
        lambda_e: 0.1,
        ..Params::default()
    };
    let e = paper_output(d, b, &params);
    let out = perceptual_over_paper(d, 1.0, b, &params, &m);
    assert!((5.0..=15.0).contains(&change(d, e)), "{}", change(d, e));
    assert!((change(d, out.output) - change(d, e)).abs() < 1e-6);
    assert!(out.perceived_after > m.perceived_contrast(e, b));
}

#[test]
fn without_a_paper_change_the_pixel_is_left() {
    let m = model(5000.0, 0.05);
    let d = DVec3::new(0.1, 0.05, 0.02);
    let b = DVec3::splat(0.9);
    assert!(m.perceived_contrast(d, b) < 0.05);
    // The paper's lambda_e = 0 changes nothing, bit for bit; nor does this method.
    let params = Params {
        lambda_e: 0.0,
        ..Params::default()
    };
    let out = perceptual_over_paper(d, 1.0, b, &params, &m);
    assert_eq!(out.output, d);
    assert_eq!(out.class, Class::OutOfReach);
    // Given the paper's output D directly, likewise.
    let out = perceptual(d, 1.0, b, d, &m);
    assert_eq!(out.output, d);
    assert_eq!(out.class, Class::OutOfReach);
}

#[test]
fn black_and_transparent_pixels_are_no_content() {
    let m = model(500.0, 0.05);
    let b = DVec3::splat(0.5);
    let out = perceptual(DVec3::ZERO, 1.0, b, DVec3::ONE, &m);
    assert_eq!((out.output, out.class), (DVec3::ZERO, Class::NoContent));
    let d = DVec3::new(0.01, 0.02, 0.03);
    let out = perceptual(d, 0.0, b, DVec3::ONE, &m);
    assert_eq!((out.output, out.class), (d, Class::NoContent));
}

/// c' along the straight CIELAB line from D through `out`, at `n + 1` points up to a change of
/// `length`.
fn along(m: &Model, d: DVec3, out: DVec3, b: DVec3, length: f64, n: usize) -> Vec<(f64, f64)> {
    let (dl, ol) = (colour::linear_to_lab(d), colour::linear_to_lab(out));
    let u = (ol - dl).normalize();
    (0..=n)
        .map(|i| {
            let s = length * i as f64 / n as f64;
            let x = colour::xyz_to_linear(colour::lab_to_xyz(dl + s * u));
            (s, m.perceived_contrast(x.clamp(DVec3::ZERO, DVec3::ONE), b))
        })
        .collect()
}

#[test]
fn the_bisection_reaches_the_target_with_the_least_change_to_one_256th() {
    let target = 0.05;
    let m = model(500.0, target);
    let mut checked = 0;
    for (d, b, e, out) in sampled(500.0, target, 12000, 17) {
        if out.class != Class::BroughtToTarget {
            continue;
        }
        let after = m.perceived_contrast(out.output, b);
        assert!(after >= target, "D {d} over B {b}: c' {after}");
        assert_eq!(out.perceived_after, after);
        // The least change on the line that reaches the target, by a fine scan; where c' rises
        // along the line (nearly everywhere) the bisection stops within 1/256 of the kept
        // candidate's change (at most the paper's) above it.
        let budget = change(d, e);
        let mine = change(d, out.output);
        let scan = along(&m, d, out.output, b, mine, 2000);
        if !scan.windows(2).all(|w| w[1].1 >= w[0].1) {
            continue;
        }
        let least = scan.iter().find(|(_, c)| *c >= target).unwrap().0;
        assert!(
            mine >= least - 1e-6 && mine <= least + budget / 256.0 + mine / 2000.0 + 1e-6,
            "D {d} over B {b}: change {mine}, least {least}, budget {budget}"
        );
        checked += 1;
    }
    assert!(
        checked > 100,
        "only {checked} pixels brought to target and checked"
    );
}

/// In 8-bit sRGB, as an image stores it: every pixel brought to the target is shown at the
/// target, its output a stored colour, changed no more than the paper's change and one code
/// value. Judged before rounding (the exact method, then rounded), many would not be.
#[test]
fn a_pixel_brought_to_target_is_at_target_as_stored() {
    let target = 0.05;
    let m = model(500.0, target);
    let exact = sampled(500.0, target, 12000, 23);
    let stored = sampled_as(Stored::Srgb8, 500.0, target, 12000, 23);
    let (mut brought, mut short_if_exact) = (0, 0);
    for ((d, b, e, x), (_, _, _, out)) in exact.iter().zip(&stored) {
        if out.class != Class::BroughtToTarget {
            continue;
        }
        brought += 1;
        let shown = colour::linear_to_srgb8(out.output).map(colour::code_to_linear);
        assert_eq!(out.output.to_array(), shown, "D {d} over B {b}");
        let after = m.perceived_contrast(out.output, *b);
        assert!(after >= target, "D {d} over B {b}: c' {after} as stored");
        assert_eq!(out.perceived_after, after);
        let one_code = colour::linear_to_srgb8(*e).map(|c| c.saturating_add(1));
        let slack = change(*e, DVec3::from_array(one_code.map(colour::code_to_linear)));
        assert!(
            change(*d, out.output) <= change(*d, *e) + slack,
            "D {d} over B {b}"
        );
        let rounded =
            DVec3::from_array(colour::linear_to_srgb8(x.output).map(colour::code_to_linear));
        short_if_exact += usize::from(m.perceived_contrast(rounded, *b) < target);
    }
    assert!(brought > 150, "only {brought} pixels brought to target");
    assert!(
        short_if_exact * 5 > brought,
        "judged before rounding, {short_if_exact} of {brought} fall short as stored"
    );
}

#[test]
fn the_method_classes_are_those_the_report_derives_from_c_prime() {
    for (world, target) in [(20.0, 0.05), (5000.0, 0.05), (500.0, 0.2)] {
        let m = model(world, target);
        for (d, b, _, out) in sampled(world, target, 2000, 19) {
            let after = m.perceived_contrast(out.output, b);
            assert_eq!(
                Class::of(out.perceived_before, after, target),
                out.class,
                "D {d} over B {b}"
            );
        }
    }
}

#[test]
fn the_frame_report_sums_the_worked_examples() {
    // Examples 4 and 5 share their lights (P 200, W 1000, t 0.3) and have c' 0.13493 and
    // 0.17977 at 2 cpd; the world behind them is 94.368 and 90.0 cd/m^2.
    let settings = PerceptualSettings {
        world_nits: 1000.0,
        target_contrast: 0.15,
        ..PerceptualSettings::default()
    };
    let m = Model::new(&settings, 0.3, Frequencies::One(2.0));
    let (e4, e5) = (&EXAMPLES[3], &EXAMPLES[4]);
    let pixel =
        |display: [f64; 3], background: [f64; 3], output: [f64; 3], alpha: f64| ReportPixel {
            display: DVec3::from(display),
            alpha,
            background: DVec3::from(background),
            output: DVec3::from(output),
        };
    let dim = [0.0002, 0.0002, 0.005];
    let pixels = [
        // Below the target and unchanged: out of reach.
        pixel(e4.display, e4.background, e4.display, 1.0),
        // At the target already: left alone.
        pixel(e5.display, e5.background, e5.display, 1.0),
        // A dim blue brought up to example 5's colour: brought to the target.
        pixel(dim, e5.background, e5.display, 1.0),
        // No content: black, and transparent.
        pixel([0.0; 3], e4.background, [1.0; 3], 1.0),
        pixel(e4.display, e4.background, [1.0; 3], 0.0),
    ];
    let r = frame_report(pixels, &m);
    assert_eq!(r.content_pixels, 3);
    let third = 1.0 / 3.0;
    for (got, what) in [
        (r.left_alone, "left"),
        (r.brought_to_target, "brought"),
        (r.out_of_reach, "out"),
    ] {
        assert!((got - third).abs() < 1e-12, "{what}: {got}");
    }
    assert_rel(
        r.perceived_after,
        (0.13493 + 2.0 * 0.17977) / 3.0,
        1e-3,
        "after",
    );
    let before_dim = r.perceived_before * 3.0 - 0.13493 - 0.17977;
    assert!(
        before_dim.abs() < 2e-3,
        "the dim pixel's c' before: {before_dim}"
    );
    assert_rel(
        r.gain,
        r.perceived_after / r.perceived_before,
        1e-12,
        "gain",
    );
    assert_rel(r.log2_gain, r.gain.log2(), 1e-12, "log2 gain");
    assert_rel(
        r.mean_world_luminance,
        (94.368 + 2.0 * 90.0) / 3.0,
        1e-3,
        "world",
    );
    let moved = change(DVec3::from(dim), DVec3::from(e5.display));
    assert_rel(r.mean_delta_e, moved / 3.0, 1e-12, "delta E");
    assert_rel(r.max_delta_e, moved, 1e-12, "largest delta E");
    assert_eq!(r.frequencies, Frequencies::One(2.0));
    // Without content: nothing to gain.
    let empty = frame_report([pixel([0.0; 3], [0.5; 3], [0.0; 3], 1.0)], &m);
    assert_eq!(
        (empty.content_pixels, empty.gain, empty.log2_gain),
        (0, 1.0, 0.0)
    );
}
