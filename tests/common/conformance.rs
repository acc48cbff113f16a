//! Each backend's output against the CPU reference (docs/algorithm.md, Conformance).

use contrastxr::algorithm::mapping::CameraMapping;
use contrastxr::algorithm::{Method, Params};
use contrastxr::gpu::OfflineBackend;
use contrastxr::image::RgbaImage;

/// Pixels where the backend's output does not conform to the CPU reference, with the CPU's own
/// background preparation as the reference's B.
pub fn nonconformant(
    b: &mut dyn OfflineBackend,
    display: &RgbaImage,
    camera: &RgbaImage,
    mapping: &CameraMapping,
    params: &Params,
) -> Vec<String> {
    use contrastxr::algorithm::{conformant, enhance_srgb8_trace};
    let api = b.api();
    let out = b
        .enhance_mapped(display, camera, mapping, params)
        .unwrap_or_else(|e| panic!("{api}: {e}"));
    let (w, h) = (display.width, display.height);
    let bg = contrastxr::background_preparation::prepare_mapped(camera, w, h, mapping, params);
    let view = reference_params(params, mapping, w, camera.width);
    let mut bad = Vec::new();
    for (i, (d, g)) in display.pixels.iter().zip(&out.pixels).enumerate() {
        let trace = enhance_srgb8_trace(*d, bg.linear[i], bg.scaled[i], &view);
        if !conformant(&trace, *g) {
            bad.push(format!(
                "pixel {i}: display {d:?} cpu {:?} {api} {g:?}",
                trace.out
            ));
        }
    }
    bad
}

/// The params the CPU reference takes for a view `width` pixels wide over a camera frame
/// `camera_width` wide placed by `mapping`, at the offline engines' pixels per degree: the
/// `blur` frequency resolved as the engines resolve it for the view.
pub fn reference_params(
    params: &Params,
    mapping: &CameraMapping,
    width: u32,
    camera_width: u32,
) -> Params {
    use contrastxr::algorithm::perception::frequency::{
        view_params, ViewGeometry, DEFAULT_PIXELS_PER_DEGREE,
    };
    let geometry = ViewGeometry {
        mapping,
        display_width: width,
        camera_width,
        pixels_per_degree: DEFAULT_PIXELS_PER_DEGREE,
    };
    view_params(params, &geometry)
}

pub fn check_all_methods(
    b: &mut dyn OfflineBackend,
    (display, camera): (&RgbaImage, &RgbaImage),
    mapping: &CameraMapping,
    base: &Params,
) {
    for method in Method::ALL {
        for lambda_e in [0.1, 0.4, 1.0] {
            let params = Params {
                method,
                lambda_e,
                ..base.clone()
            };
            let bad = nonconformant(b, display, camera, mapping, &params);
            assert!(
                bad.is_empty(),
                "{}: {method:?} lambda_e {lambda_e}: {} of {} pixels differ, e.g. {:?}",
                b.api(),
                bad.len(),
                display.pixels.len(),
                &bad[..bad.len().min(5)]
            );
        }
    }
}

/// A registered view's mapping (a plane-induced homography): not affine, the projective divide
/// varying by about 15% across the view, and reaching past the camera's edges (clamp-to-edge).
pub fn projective() -> CameraMapping {
    CameraMapping {
        rows: [[0.8, 0.06, 0.05], [-0.04, 0.7, 0.12], [0.12, -0.09, 0.98]],
    }
}

/// That every `classify` lists the same tiles for `raw` (one content pixel per tile, every
/// pixel below the target: `images::one_pixel_per_tile`): `run` enhances it under a choice,
/// and the outputs are the same word for word, with most of its 26 content pixels (a 96x17
/// view) changed.
pub fn assert_every_classify_lists_the_same(
    raw: &[u32],
    mut run: impl FnMut(contrastxr::gpu::core::ClassifyChoice) -> Vec<u32>,
    what: &str,
) {
    use contrastxr::gpu::core::ClassifyChoice;
    let own = run(ClassifyChoice::Own);
    for choice in [ClassifyChoice::OwnByRows, ClassifyChoice::Paper] {
        let out = run(choice);
        let differ = out.iter().zip(&own).filter(|(a, b)| a != b).count();
        assert_eq!(differ, 0, "{what}, {choice:?}: pixels differ");
    }
    // 12 + 12 + 2 content pixels (rows 0 to 7 of the tiles, then row 16 only).
    let content = raw.iter().filter(|&&w| w != 0).count();
    let changed = own.iter().zip(raw).filter(|(o, r)| o != r).count();
    assert_eq!(content, 26, "{what}");
    assert!(changed >= 20, "{what}: {changed} changed");
}

/// That the perceptual method's own `classify`, which settles most pixels at the target by a
/// lower bound of c' without the tables (src/algorithm/perception/target_bound.rs), lists every
/// tile whose pixel the enhancement changes: for `raw` (one content pixel per tile,
/// `images::one_pixel_per_tile`), at three light levels with the default target, `run`'s output
/// under the own classify is word for word its output with every content tile listed (the
/// paper's classify, after which the enhancement decides each pixel by c'). Each level must
/// leave some pixels alone and change others, so that both answers are tested.
pub fn assert_the_bound_lists_every_tile_that_changes(
    raw: &[u32],
    mut run: impl FnMut(contrastxr::gpu::core::ClassifyChoice, &Params) -> Vec<u32>,
    what: &str,
) {
    use contrastxr::gpu::core::ClassifyChoice;
    let content = raw.iter().filter(|&&w| w != 0).count();
    for world_nits in [20.0, 500.0, 5000.0] {
        let mut params = Params {
            method: Method::Perceptual,
            ..Params::default()
        };
        params.perceptual.world_nits = world_nits;
        let own = run(ClassifyChoice::Own, &params);
        let every = run(ClassifyChoice::Paper, &params);
        let differ = own.iter().zip(&every).filter(|(a, b)| a != b).count();
        assert_eq!(differ, 0, "{what}, {world_nits} cd/m²: pixels differ");
        let changed = own.iter().zip(raw).filter(|(o, r)| o != r).count();
        let alone = content - changed;
        assert!(
            changed >= content / 20 && alone >= content / 20,
            "{what}, {world_nits} cd/m²: {changed} of {content} changed"
        );
    }
}
