//! The CPU reference against independent expectations: the degenerate cases of docs/algorithm.md, Per-pixel optimisation
//! (values computed by hand or by the straightforward formulas below, never by the code under
//! test), the JND geometry, the invariants as property tests, and the sRGB<->LAB round trip.

use contrastxr::algorithm::{
    conformant, corner_cases, enhance_linear, enhance_scaled, enhance_srgb8, enhance_srgb8_trace,
    Method, Params,
};
use contrastxr::colour;
use glam::DVec3;
use proptest::prelude::*;

fn params(lambda_e: f32, r: f32) -> Params {
    Params {
        lambda_e,
        lambda_jnd_scaled: r,
        ..Params::default()
    }
}

fn assert_close(got: DVec3, want: DVec3, tol: f64) {
    assert!(
        (got - want).abs().max_element() <= tol,
        "got {got}, want {want}"
    );
}

/// Algorithm 1 without the JND step, written out plainly from the paper's pseudocode.
fn naive_p_before_jnd(d: DVec3, b: DVec3, lambda_e: f64) -> DVec3 {
    let i = -b / b.length();
    let e = (i - d).length().min(lambda_e) * (i - d).normalize();
    let e_ab = DVec3::new(0.0, e.y, e.z);
    let d_ab = DVec3::new(0.0, d.y, d.z);
    let dir_ab = if d_ab.length() <= 1e-6 {
        e_ab
    } else {
        let cos_ch = e_ab.dot(d_ab) / (e_ab.length() * d_ab.length());
        let e_ch = d_ab.normalize() * e_ab.dot(d_ab.normalize());
        let e_h = e_ab - e_ch;
        if cos_ch >= 0.0 {
            e_ch + e_h
        } else {
            e_h
        }
    };
    let cos_l = e.x / e.length();
    let dir_l = if cos_l >= 0.0 {
        (1.0 - cos_l) * e.x
    } else {
        (1.0 + cos_l) * e.x
    };
    d + DVec3::new(dir_l, dir_ab.y, dir_ab.z)
}

#[test]
fn mid_grey_background_has_no_direction() {
    let d = DVec3::new(0.2, 0.1, -0.1);
    for b in [DVec3::ZERO, DVec3::new(1e-7, 0.0, -5e-7)] {
        assert_eq!(enhance_scaled(d, b, &params(0.4, 0.046)), d);
    }
}

#[test]
fn display_at_ideal_point_stays() {
    // B on +a: I = (0, -1, 0) = D, so E = 0 and P = D.
    let d = DVec3::new(0.0, -1.0, 0.0);
    assert_eq!(
        enhance_scaled(d, DVec3::new(0.0, 0.6, 0.0), &params(0.4, 0.046)),
        d
    );
}

#[test]
fn achromatic_display_takes_all_of_e_ab() {
    // D = (0.2, 0, 0), B = (0, 0.5, 0): I = (0, -1, 0), |I - D| = sqrt(1.04),
    // E = 0.5 (-0.2, -1, 0) / sqrt(1.04), cos_l = -0.2 / sqrt(1.04),
    // dir.L = (1 - |cos_l|) E.L. (lambda_e 0.5: exact in the f32 Params.)
    let p = enhance_scaled(
        DVec3::new(0.2, 0.0, 0.0),
        DVec3::new(0.0, 0.5, 0.0),
        &params(0.5, 0.046),
    );
    assert_close(
        p,
        DVec3::new(0.12117270166167723, -0.49029033784546006, 0.0),
        1e-12,
    );
}

#[test]
fn chroma_reduction_is_dropped() {
    // D' = (0.3, 0) and E' pointing to -a,-b: theta_ch > 90 degrees, so only the hue part
    // (0, 0, E.b) remains, E.b = -0.5 * 0.70711 / |I - D|.
    let b = DVec3::new(0.0, 0.5, 0.5);
    let p = enhance_scaled(DVec3::new(0.0, 0.3, 0.0), b, &params(0.5, 0.046));
    assert_close(p, DVec3::new(0.0, 0.3, -0.2873122861588217), 1e-12);
    // D' = (-0.3, 0): E' increases chroma, so all of E applies (E.L = 0).
    let p = enhance_scaled(DVec3::new(0.0, -0.3, 0.0), b, &params(0.5, 0.046));
    assert_close(
        p,
        DVec3::new(0.0, -0.5494751785386337, -0.43331528393666985),
        1e-12,
    );
}

#[test]
fn zero_lambda_e_is_no_change() {
    let d = DVec3::new(0.3, -0.2, 0.1);
    assert_eq!(
        enhance_scaled(d, DVec3::new(-0.1, 0.4, 0.2), &params(0.0, 0.046)),
        d
    );
    // Also inside the JND sphere: P == D is kept, not pushed onto the sphere.
    let b = d + DVec3::new(0.01, 0.0, 0.0);
    assert_eq!(enhance_scaled(d, b, &params(0.0, 0.046)), d);
}

/// Found by a search over a grid: D outside the sphere, Algorithm 1's P inside it.
const JND_D: DVec3 = DVec3::new(-0.22, 0.14, -0.32);
const JND_B: DVec3 = DVec3::new(-0.12, 0.13, -0.32);

#[test]
fn jnd_moves_p_back_to_first_sphere_crossing() {
    let r = 0.046;
    let before = naive_p_before_jnd(JND_D, JND_B, 0.5);
    assert!(
        (JND_D - JND_B).length() >= r && (before - JND_B).length() < r,
        "case no longer applies"
    );
    let p = enhance_scaled(JND_D, JND_B, &params(0.5, r as f32));
    // Independent: the textbook smaller root of |D + s (P - D) - B|^2 = r^2.
    let r = f64::from(r as f32);
    let (dp, db) = (before - JND_D, JND_D - JND_B);
    let (a, h, c) = (dp.length_squared(), dp.dot(db), db.length_squared() - r * r);
    let s = (-h - (h * h - a * c).sqrt()) / a;
    assert!((0.0..1.0).contains(&s));
    assert_close(p, JND_D + s * dp, 1e-12);
    // On the sphere, and on the segment D -> P_before.
    assert!(((p - JND_B).length() - r).abs() < 1e-12);
    let along = (p - JND_D).dot(dp) / a;
    assert!((p - (JND_D + along * dp)).length() < 1e-12 && (0.0..1.0).contains(&along));
}

#[test]
fn jnd_keeps_p_when_display_is_inside_the_sphere() {
    // Same geometry with a radius that contains D: P stays where Algorithm 1 put it.
    let r = 0.2;
    assert!((JND_D - JND_B).length() < r);
    let p = enhance_scaled(JND_D, JND_B, &params(0.5, r as f32));
    assert_close(p, naive_p_before_jnd(JND_D, JND_B, 0.5), 1e-12);
}

#[test]
fn jnd_ignores_p_outside_the_sphere() {
    let (d, b) = (DVec3::new(0.1, 0.2, -0.1), DVec3::new(0.3, 0.3, 0.3));
    let p = enhance_scaled(d, b, &params(0.5, 0.046));
    assert_close(p, naive_p_before_jnd(d, b, 0.5), 1e-12);
}

#[test]
fn black_and_transparent_pixels_are_skipped() {
    let bg_linear = DVec3::new(0.8, 0.7, 0.1);
    let bg_scaled = colour::linear_to_scaled(0.4 * bg_linear);
    for method in Method::ALL {
        let p = Params {
            method,
            ..Params::default()
        };
        for px in [[0, 0, 0, 255], [0, 0, 0, 7], [200, 10, 10, 0]] {
            assert_eq!(
                enhance_srgb8(px, bg_linear, bg_scaled, &p),
                px,
                "{method:?}"
            );
        }
        assert_eq!(
            enhance_linear(DVec3::ZERO, 1.0, bg_linear, bg_scaled, &p),
            None
        );
        assert_eq!(
            enhance_linear(DVec3::ONE, 0.0, bg_linear, bg_scaled, &p),
            None
        );
    }
}

#[test]
fn subtraction_is_weiland_in_linear_light() {
    // display' = clip(1.0 * display - 0.4 * unattenuated background) per linear channel.
    let p = Params {
        method: Method::Subtraction,
        ..Params::default()
    };
    let d = DVec3::new(0.9, 0.5, 0.1);
    let bg = DVec3::new(0.5, 0.5, 0.5);
    let out = enhance_linear(d, 1.0, bg, DVec3::ZERO, &p).unwrap();
    let k_b = f64::from(0.4f32);
    assert_close(
        out,
        DVec3::new(0.9 - 0.5 * k_b, 0.5 - 0.5 * k_b, 0.0),
        1e-12,
    );
}

#[test]
fn comparison_methods_follow_their_definitions() {
    // D = (0, 0.3, 0), B = (0, 0.5, 0.5): E'_h = (0, 0, -0.28731) (see chroma test above).
    let (d, b) = (DVec3::new(0.0, 0.3, 0.0), DVec3::new(0.0, 0.5, 0.5));
    let h = 0.2873122861588217;
    let with = |method| {
        enhance_scaled(
            d,
            b,
            &Params {
                method,
                ..params(0.5, 0.046)
            },
        )
    };
    assert_close(with(Method::HueOnly), DVec3::new(0.0, 0.3, -h), 1e-12);
    assert_close(with(Method::OtherHue), DVec3::new(0.0, 0.3, h), 1e-12);
    assert_close(
        with(Method::LumChroma),
        DVec3::new(0.0, 0.3 + h, 0.0),
        1e-12,
    );
    // Lum-chroma at mid grey has no direction OD.
    let p = Params {
        method: Method::LumChroma,
        ..Params::default()
    };
    assert_eq!(enhance_scaled(DVec3::ZERO, b, &p), DVec3::ZERO);
}

/// 8-bit sRGB -> LAB -> 8-bit for every colour (2^24), split over the machine's cores.
#[test]
fn srgb_lab_round_trip_all_colours() {
    let threads = std::thread::available_parallelism()
        .map_or(2, |n| n.get())
        .min(8) as u32;
    let handles: Vec<_> = (0..threads)
        .map(|t| {
            std::thread::spawn(move || {
                let mut bad = Vec::new();
                for r in (t..256).step_by(threads as usize) {
                    for g in 0..256u32 {
                        for b in 0..256u32 {
                            let c = [r as u8, g as u8, b as u8];
                            let back = colour::linear_to_srgb8(colour::scaled_to_linear(
                                colour::linear_to_scaled(colour::srgb8_to_linear(c)),
                            ));
                            if back != c && bad.len() < 5 {
                                bad.push((c, back));
                            }
                        }
                    }
                }
                bad
            })
        })
        .collect();
    let bad: Vec<_> = handles
        .into_iter()
        .flat_map(|h| h.join().unwrap())
        .collect();
    assert!(bad.is_empty(), "{bad:?}");
}

fn background_pair(bg: [u8; 3]) -> (DVec3, DVec3) {
    let linear = colour::srgb8_to_linear(bg);
    (linear, colour::linear_to_scaled(0.4 * linear))
}

fn chroma(v: DVec3) -> f64 {
    (v.y * v.y + v.z * v.z).sqrt()
}

fn any_method() -> impl Strategy<Value = Method> {
    prop::sample::select(Method::ALL.to_vec())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]

    #[test]
    fn lambda_e_zero_is_identity(px: [u8; 4], bg: [u8; 3], r in 0.0f32..0.5,
                                 method in prop::sample::select(vec![Method::Paper, Method::HueOnly, Method::OtherHue, Method::LumChroma])) {
        let (bl, bs) = background_pair(bg);
        let p = Params { lambda_e: 0.0, lambda_jnd_scaled: r, method, ..Params::default() };
        prop_assert_eq!(enhance_srgb8(px, bl, bs, &p), px);
    }

    #[test]
    fn change_is_bounded_and_chroma_never_drops(
        d in prop::array::uniform3(-1.2f64..1.2), b in prop::array::uniform3(-1.0f64..1.0),
        lambda_e in 0.0f32..1.5, r in 0.0f32..0.3,
    ) {
        let (d, b) = (DVec3::from(d), DVec3::from(b));
        let p = enhance_scaled(d, b, &params(lambda_e, r));
        prop_assert!((p - d).length() <= f64::from(lambda_e) + 1e-12, "{} > {}", (p - d).length(), lambda_e);
        prop_assert!(chroma(p) >= chroma(d) - 1e-12, "chroma {} < {}", chroma(p), chroma(d));
    }

    #[test]
    fn p_is_outside_the_jnd_sphere_unless_d_is_inside(
        d in prop::array::uniform3(-1.0f64..1.0), b in prop::array::uniform3(-1.0f64..1.0),
        r in 0.0f32..0.4,
    ) {
        let (d, b) = (DVec3::from(d), DVec3::from(b));
        let r64 = f64::from(r);
        let p = enhance_scaled(d, b, &params(0.4, r));
        prop_assert!((d - b).length() < r64 || (p - b).length() >= r64 - 1e-12);
    }

    #[test]
    fn transparent_pixels_untouched(rgb: [u8; 3], alpha: u8, bg: [u8; 3], method in any_method(),
                                    lambda_e in 0.0f32..1.0) {
        let (bl, bs) = background_pair(bg);
        let p = Params { lambda_e, method, ..Params::default() };
        let black = [0, 0, 0, alpha];
        prop_assert_eq!(enhance_srgb8(black, bl, bs, &p), black);
        let clear = [rgb[0], rgb[1], rgb[2], 0];
        prop_assert_eq!(enhance_srgb8(clear, bl, bs, &p), clear);
    }

    #[test]
    fn alpha_passes_through(px: [u8; 4], bg: [u8; 3], method in any_method()) {
        let (bl, bs) = background_pair(bg);
        let out = enhance_srgb8(px, bl, bs, &Params { method, ..Params::default() });
        prop_assert_eq!(out[3], px[3]);
    }
}

/// The background a uniform camera frame of colour `bg` gives after preprocessing.
fn uniform_background(bg: [u8; 3]) -> (DVec3, DVec3) {
    let linear = colour::srgb8_to_linear(bg);
    (linear, colour::linear_to_scaled(f64::from(0.4f32) * linear))
}

#[test]
fn trace_agrees_with_enhance_and_flags_thresholds() {
    let p = Params::default();
    let mut flagged = 0;
    for (d, b) in corner_cases() {
        let (bl, bs) = uniform_background(b);
        let px = [d[0], d[1], d[2], 255];
        let t = enhance_srgb8_trace(px, bl, bs, &p);
        assert_eq!(t.out, enhance_srgb8(px, bl, bs, &p));
        assert_eq!(
            t.exact.map(colour::quantize),
            [t.out[0], t.out[1], t.out[2]],
            "{d:?} on {b:?}"
        );
        assert!(conformant(&t, t.out));
        let off_by_two = [t.out[0] ^ 2, t.out[1], t.out[2], 255];
        assert_eq!(conformant(&t, off_by_two), t.near_threshold);
        // Exact greys have |D'| = 0: float32 noise decides their chroma branch.
        if d[0] == d[1] && d[1] == d[2] && d != [0, 0, 0] {
            assert!(t.near_threshold, "grey {d:?} on {b:?}");
        }
        flagged += usize::from(t.near_threshold);
    }
    // A chromatic display on a chromatic background far from every threshold is not flagged.
    let (bl, bs) = uniform_background([230, 210, 40]);
    assert!(!enhance_srgb8_trace([200, 60, 50, 255], bl, bs, &p).near_threshold);
    assert!(flagged < corner_cases().len());
}
