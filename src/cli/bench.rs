//! `contrastxr bench`: GPU time of the enhancement, and of everything the layer records per
//! display frame and per camera frame, against a plain copy of the same pixels.

use super::args::Args;
use super::error::CliError;
use super::options::{self, method_usage};
use super::shader_stats::{self, ShaderReport};
use contrastxr::algorithm::{Method, Params};
use contrastxr::gpu::core::bench::{Ablation, BenchCase, BenchResult, Content, CAMERA_SIZE};
use contrastxr::gpu::opengl::GlOffline;
use contrastxr::gpu::{DeviceOptions, VkOffline};

const DEFAULT_SIZES: &str = "1268x720,1920x1080,2064x2208,3840x3840";

pub fn usage() -> String {
    format!(
        "usage: contrastxr bench [--sizes WxH,...] [--views N] [--runs N] [--json] [--device N]\n\
         \x20                       [--content typical,full] [--path P] [--engine vulkan|opengl]\n\
         \x20                       [--ablate LIST] [--shader-stats] [--compile-only]\n\
         \x20                       [method options]\n\n\
         Times on a Vulkan device, with timestamp queries, after {} warm-up runs, the median of\n\
         --runs runs (default 30) of: a plain per-pixel copy of the display regions (the floor),\n\
         the same copy with the enhancement's 16-byte accesses (copy16, ratio16: a stricter\n\
         floor, where rows are 16-byte aligned), the per-frame enhancement, everything the\n\
         layer records per display frame (frame: the enhancement plus its copies from and to\n\
         the app's images, frame ratio over the copy; img copy: those copies alone), and the\n\
         per-camera-frame background preparation (bg: decode and blur of a {}x{} camera\n\
         frame, once whatever the views; live = frame + bg, a display frame that also brings\n\
         a new camera frame). Sizes are per view (default {DEFAULT_SIZES}), --views 2; each size\n\
         with typical content (mostly black: panels and an object) and full frames\n\
         (--content picks one or both). --path copy|in-place|both|image-copy|all|tiles (default\n\
         both): the layer's frame through buffer copies (frame, always timed), in place (in\n\
         place: the app-like images made with storage usage and enhanced through storage\n\
         views, no copies; ip/frame: its ratio to the frame through buffer copies; with\n\
         in-place and both) and through the image-copy path (img path ms: each region copied\n\
         into an image of the layer's own with storage usage, enhanced there by the in-place\n\
         shaders, copied back, what the layer does for images it may not store to, such as\n\
         sRGB swapchains without storage usage; its copies alone, ic copies ms; ic/frame and\n\
         ic/ip: its ratio to the frame through buffer copies and in place; img tiles ms: the\n\
         same path with only the tiles the enhancement listed drawn back into the app's image\n\
         instead of the whole region copied back, it/ip its ratio to the frame in place; smp\n\
         tiles ms: the region read through a sampled view of the app's image instead of copied\n\
         in, enhanced into the layer's image and its listed tiles drawn back, st/ip its ratio\n\
         to the frame in place; with image-copy and all). all times the three. tiles: all,\n\
         with img tiles and smp tiles also on a CPU driver, which all and image-copy leave\n\
         them out on: once a draw has run there,\n\
         lavapipe's timestamps no longer bracket compute work, so the other columns of a tiles\n\
         run on a CPU driver are not to be read.\n\
         Validation is off (CONTRASTXR_VK_VALIDATION is ignored: it would distort the timing).\n\
         --engine opengl (default vulkan) times the OpenGL engine on an EGL context of its own\n\
         (GL_TIME_ELAPSED queries; --device and --path do not apply) in the same columns: copy\n\
         is glCopyImageSubData of the regions (no copy16), frame goes through a buffer object,\n\
         img copy is that buffer path's copies alone, in place stores through an image unit\n\
         (enh is the same figure: nothing else runs around the passes), bg is the upload of a\n\
         camera frame's texels (their blur runs on the source's CPU thread, not timed).\n\
         The method options set what is timed (--method perceptual, --world-nits 5000, ...); the\n\
         config file and the environment do not.\n\
         --ablate LIST (each case once per item, after none; either engine) takes one part out of\n\
         the enhancement to show what it costs, in every column that runs it (enh/none: its\n\
         enhancement over the case's none; the output is then no enhancement; on the bench's\n\
         RGBA8 sRGB; the sampled read, which has no ablated variants, is left out of an\n\
         ablation's rows). For --method paper: method (no CIELAB conversion or method, the display\n\
         colour kept), background (a constant grey, no camera texel reads), codec (no sRGB decode\n\
         or encode), per-pixel (the three: loads, quantisation and stores left), enhance-pass\n\
         (the enhance pass returns at once: classify, finish_tiles, the indirect dispatch),\n\
         shared-fetch (the general background sampling instead of shared fetches; Vulkan only),\n\
         cube-root (not taken out but replaced: the CIELAB cube roots the other way than the\n\
         engine's, by Newton steps where it takes the driver's pow (a GPU) and by pow where it\n\
         takes Newton steps (a CPU driver: the first line says which); the output is still the\n\
         enhancement, within 1 code value).\n\
         For --method perceptual: method, background, directions (the paper's colour the only\n\
         candidate), bisection (none back toward the display colour), search (both), classify\n\
         (the paper's classify, which lists every tile with content, instead of the method's\n\
         own), classify-rows (replaced: the method's own classify with an invocation per tile\n\
         row instead of per tile, the same tiles listed). all: every one the method has.\n\
         --shader-stats (Vulkan) adds what the driver's compiler says of the frame's per-pixel\n\
         shaders on RGBA8 sRGB for the method (classify and enhance, general and shared-fetch,\n\
         for the buffer path, in place and the sampled read; finish_tiles): registers,\n\
         instructions, spills, by the driver's own names (VK_KHR_pipeline_executable_properties;\n\
         a line saying so where the driver has none), after the rows or in the JSON\n\
         (shader_statistics).\n\
         --compile-only (Vulkan) reports those statistics alone, timing nothing: the device is\n\
         only asked to compile, so a compiler without its GPU serves, such as Mesa RADV's for\n\
         an AMD GPU named by RADV_FORCE_FAMILY (scripts/shader-stats).\n\n{}",
        contrastxr::gpu::core::bench::WARM_UP_RUNS,
        contrastxr::gpu::core::bench::CAMERA_SIZE.0,
        contrastxr::gpu::core::bench::CAMERA_SIZE.1,
        method_usage()
    )
}

fn parse_size(s: &str) -> Result<(u32, u32), CliError> {
    let bad = || CliError::Usage(format!("size '{s}' is not WIDTHxHEIGHT"));
    let (w, h) = s.trim().split_once('x').ok_or_else(bad)?;
    let (w, h) = (w.parse().map_err(|_| bad())?, h.parse().map_err(|_| bad())?);
    if w == 0 || h == 0 || u64::from(w) * u64::from(h) > 1 << 26 {
        return Err(bad());
    }
    Ok((w, h))
}

fn parse_content(s: &str) -> Result<Content, CliError> {
    Content::ALL
        .into_iter()
        .find(|c| c.name() == s.trim())
        .ok_or_else(|| CliError::Usage(format!("content '{s}' is not typical or full")))
}

/// The ablations asked for, `none` first (the baseline each is read against); `all` for every
/// one `method` has.
fn parse_ablations(
    list: Option<String>,
    method: Method,
    opengl: bool,
) -> Result<Vec<Ablation>, CliError> {
    // The OpenGL engine has no shared fetches.
    let applies = |a: Ablation| a.applies_to(method) && !(opengl && a == Ablation::SharedFetch);
    let Some(list) = list else {
        return Ok(vec![Ablation::None]);
    };
    let mut out = vec![Ablation::None];
    for item in list.split(',').map(str::trim) {
        let found: Vec<Ablation> = match item {
            "all" => Ablation::ALL.into_iter().filter(|&a| applies(a)).collect(),
            _ => Ablation::ALL
                .into_iter()
                .filter(|a| a.name() == item)
                .collect(),
        };
        let Some(&first) = found.first() else {
            let names: Vec<&str> = Ablation::ALL.iter().map(|a| a.name()).collect();
            return Err(CliError::Usage(format!(
                "--ablate: '{item}' is not {} or all",
                names.join(", ")
            )));
        };
        if !applies(first) {
            let engine = if opengl { "OpenGL" } else { "Vulkan" };
            return Err(CliError::Usage(format!(
                "--ablate: {item} is not built for the method {} on the {engine} engine",
                method.name()
            )));
        }
        out.extend(
            found
                .into_iter()
                .filter(|a| !out.contains(a))
                .collect::<Vec<_>>(),
        );
    }
    Ok(out)
}

fn parse_count(what: &str, s: Option<String>, default: u32) -> Result<u32, CliError> {
    match s {
        None => Ok(default),
        Some(s) => {
            s.parse().ok().filter(|&n| n > 0).ok_or_else(|| {
                CliError::Usage(format!("{what} must be a positive count, got '{s}'"))
            })
        }
    }
}

pub fn run(args: &mut Args) -> Result<(), CliError> {
    let sizes = args
        .value(&["--sizes"])?
        .unwrap_or_else(|| DEFAULT_SIZES.into());
    let sizes: Vec<(u32, u32)> = sizes.split(',').map(parse_size).collect::<Result<_, _>>()?;
    let views = parse_count("--views", args.value(&["--views"])?, 2)?;
    let runs = parse_count("--runs", args.value(&["--runs"])?, 30)?;
    let device = match args.value(&["--device"])? {
        None => 0,
        Some(d) => d
            .parse()
            .map_err(|_| CliError::Usage(format!("--device must be an index, got '{d}'")))?,
    };
    let params = options::params(args)?;
    let contents = match args.value(&["--content"])? {
        None => Content::ALL.to_vec(),
        Some(list) => list
            .split(',')
            .map(parse_content)
            .collect::<Result<_, _>>()?,
    };
    // (in place, image copy, tiles: None where it depends on the device); the frame through
    // buffer copies is always timed.
    let (in_place, image_copy, tiles) = match args.value(&["--path"])?.as_deref() {
        None | Some("both") | Some("in-place") => (true, false, Some(false)),
        Some("copy") => (false, false, Some(false)),
        Some("image-copy") => (false, true, None),
        Some("all") => (true, true, None),
        Some("tiles") => (true, true, Some(true)),
        Some(p) => {
            return Err(CliError::Usage(format!(
                "--path must be copy, in-place, both, image-copy, all or tiles, got '{p}'"
            )))
        }
    };
    let opengl = match args.value(&["--engine"])?.as_deref() {
        None | Some("vulkan") => false,
        Some("opengl") => true,
        Some(e) => {
            return Err(CliError::Usage(format!(
                "--engine must be vulkan or opengl, got '{e}'"
            )))
        }
    };
    let ablations = parse_ablations(args.value(&["--ablate"])?, params.method, opengl)?;
    let json = args.flag("--json");
    let compile_only = args.flag("--compile-only");
    let shader_stats = args.flag("--shader-stats") || compile_only;
    args.finish()?;
    if opengl && shader_stats {
        return Err(CliError::Usage(
            "--shader-stats and --compile-only are Vulkan's (VK_KHR_pipeline_executable_properties)"
                .into(),
        ));
    }
    let cases = |tiles: bool| {
        bench_cases(
            &sizes,
            (views, runs),
            (&contents, &ablations),
            (in_place, image_copy, tiles),
        )
    };
    if opengl {
        return run_opengl(&cases(false), &params, json);
    }
    let options = DeviceOptions {
        index: device,
        validation: false,
        matching: None,
        shader_statistics: shader_stats,
    };
    if compile_only {
        return report_compiled(&options, &params, json);
    }
    let mut engine = VkOffline::with_views(
        &options,
        views.saturating_mul(VkOffline::BENCH_TARGETS_PER_VIEW),
    )
    .map_err(|e| CliError::Failure(e.to_string()))?;
    let device = engine.device_name().to_string();
    let cases = cases(tiles.unwrap_or(!engine.gpu.is_cpu()));
    let stats = shader_stats.then(|| {
        engine
            .bench_shader_statistics(&params)
            .map_err(|e| e.to_string())
    });
    let roots = engine.cube_roots().name();
    let output = Output { json, stats, roots };
    report(&device, &output, &cases, |case| {
        engine
            .bench(case, &params)
            .map_err(|e| CliError::Failure(e.to_string()))
    })
}

/// How the rows are printed: as text, or as JSON at the end; with the shaders' statistics
/// where `--shader-stats` asked for them.
struct Output {
    json: bool,
    stats: Option<ShaderReport>,
    /// How the engine takes the CIELAB cube roots ("pow" on a GPU, "newton" on a CPU driver).
    roots: &'static str,
}

/// Every case: each size, content and ablation.
fn bench_cases(
    sizes: &[(u32, u32)],
    (views, runs): (u32, u32),
    (contents, ablations): (&[Content], &[Ablation]),
    (in_place, image_copy, tiles): (bool, bool, bool),
) -> Vec<BenchCase> {
    let mut cases = Vec::new();
    for &region in sizes {
        for &content in contents {
            for &ablation in ablations {
                cases.push(BenchCase {
                    region,
                    views,
                    content,
                    runs,
                    in_place,
                    image_copy,
                    // The sampled read has no ablated variants: an ablation's row times
                    // the other paths.
                    tiles: image_copy && tiles && ablation == Ablation::None,
                    ablation,
                });
            }
        }
    }
    cases
}

/// The cases on the OpenGL engine's own EGL context.
fn run_opengl(cases: &[BenchCase], params: &Params, json: bool) -> Result<(), CliError> {
    let mut gl = GlOffline::new().map_err(|e| CliError::Failure(e.to_string()))?;
    let device = format!("OpenGL: {}", gl.engine().caps().driver);
    let roots = gl.engine().cube_roots().name();
    let output = Output {
        json,
        stats: None,
        roots,
    };
    report(&device, &output, cases, |case| {
        gl.bench(case, params)
            .map_err(|e| CliError::Failure(e.to_string()))
    })
}

/// `--compile-only`: the shader statistics alone, from a device that need not run anything.
fn report_compiled(options: &DeviceOptions, params: &Params, json: bool) -> Result<(), CliError> {
    let (device, stats) = contrastxr::gpu::compiled_shader_statistics(options, params)
        .map_err(|e| CliError::Failure(e.to_string()))?;
    let stats: ShaderReport = Ok(stats);
    if json {
        let mut all = serde_json::Map::new();
        all.insert("device".into(), device.into());
        shader_stats::json(&stats, &mut all);
        super::error::print(&format!("{}\n", serde_json::Value::Object(all)));
    } else {
        super::error::print(&format!("device: {device}\n{}", shader_stats::text(&stats)));
    }
    Ok(())
}

/// Runs every case, printing each row as it comes (or the JSON at the end).
fn report(
    device: &str,
    output: &Output,
    cases: &[BenchCase],
    mut bench: impl FnMut(&BenchCase) -> Result<BenchResult, CliError>,
) -> Result<(), CliError> {
    let json = output.json;
    if !json {
        let roots = output.roots;
        super::error::print(&format!(
            "device: {device}, cube roots: {roots}\n{}\n",
            header()
        ));
    }
    let mut results = Vec::new();
    let mut baseline = f64::NAN;
    for case in cases {
        let r = bench(case)?;
        if r.case.ablation == Ablation::None {
            baseline = r.enhance_ms;
        }
        // An ablation's enhancement over its case's baseline, measured just before it.
        let vs_none = (r.case.ablation != Ablation::None).then_some(r.enhance_ms / baseline);
        if !json {
            super::error::print(&row(&r, vs_none));
        }
        results.push((r, vs_none));
    }
    match (&output.stats, json) {
        (_, true) => super::error::print(&format!(
            "{}\n",
            to_json((device, output.roots), &results, output.stats.as_ref())
        )),
        (Some(stats), false) => super::error::print(&shader_stats::text(stats)),
        (None, false) => {}
    }
    Ok(())
}

fn header() -> String {
    format!(
        "{:>11} {:>5} {:>8} {:>6} {:>9} {:>9} {:>9} {:>9} {:>11} {:>9} {:>9} {:>7} {:>10} {:>7} {:>9} {:>6} {:>11} {:>8} {:>11} {:>13} {:>8} {:>6} {:>12} {:>6} {:>12} {:>6} {:>13} {:>8}",
        "size",
        "views",
        "content",
        "fg %",
        "copy ms",
        "copy16 ms",
        "enh ms",
        "frame ms",
        "img copy ms",
        "bg ms",
        "live ms",
        "ratio",
        "ratio16",
        "frame r",
        "enh Mpx/s",
        "Mpx",
        "in place ms",
        "ip/frame",
        "img path ms",
        "ic copies ms",
        "ic/frame",
        "ic/ip",
        "img tiles ms",
        "it/ip",
        "smp tiles ms",
        "st/ip",
        "ablation",
        "enh/none"
    )
}

fn row(r: &BenchResult, vs_none: Option<f64>) -> String {
    let (w, h) = r.case.region;
    format!(
        "{:>11} {:>5} {:>8} {:>6.1} {:>9.3} {:>9} {:>9.3} {:>9.3} {:>11.3} {:>9.3} {:>9.3} {:>7.2} {:>10} {:>7.2} {:>9.0} {:>6.2} {:>11} {:>8} {:>11} {:>13} {:>8} {:>6} {:>12} {:>6} {:>12} {:>6} {:>13} {:>8}\n",
        format!("{w}x{h}"),
        r.case.views,
        r.case.content.name(),
        100.0 * r.foreground,
        r.copy_ms,
        optional(r.copy_wide_ms, 3),
        r.enhance_ms,
        r.frame_ms,
        r.image_copy_ms,
        r.background_ms,
        r.live_frame_ms(),
        r.ratio(),
        optional(r.ratio_wide(), 2),
        r.frame_ratio(),
        r.megapixels() / (r.enhance_ms / 1e3),
        r.megapixels(),
        optional(r.frame_in_place_ms, 3),
        optional(r.in_place_ratio(), 2),
        optional(r.frame_image_copy_ms, 3),
        optional(r.image_copy_copies_ms, 3),
        optional(r.image_copy_frame_ratio(), 2),
        optional(r.image_copy_in_place_ratio(), 2),
        optional(r.frame_image_copy_tiles_ms, 3),
        optional(r.image_copy_tiles_in_place_ratio(), 2),
        optional(r.frame_sampled_tiles_ms, 3),
        optional(r.sampled_tiles_in_place_ratio(), 2),
        r.case.ablation.name(),
        optional(vs_none, 2),
    )
}

/// A figure, or "-" where it was not measured.
fn optional(v: Option<f64>, decimals: usize) -> String {
    v.map_or_else(|| "-".into(), |v| format!("{v:.decimals$}"))
}

fn to_json(
    (device, roots): (&str, &str),
    results: &[(BenchResult, Option<f64>)],
    stats: Option<&ShaderReport>,
) -> String {
    let rows: Vec<serde_json::Value> = results
        .iter()
        .map(|(r, vs_none)| {
            serde_json::json!({
                "width": r.case.region.0,
                "height": r.case.region.1,
                "views": r.case.views,
                "content": r.case.content.name(),
                "ablation": r.case.ablation.name(),
                "enhance_vs_none": vs_none,
                "foreground_fraction": r.foreground,
                "runs": r.case.runs,
                "copy_ms": r.copy_ms,
                "copy_wide_ms": r.copy_wide_ms,
                "enhance_ms": r.enhance_ms,
                "background_ms": r.background_ms,
                "ratio": r.ratio(),
                "ratio_wide": r.ratio_wide(),
                "frame_ms": r.frame_ms,
                "frame_ratio": r.frame_ratio(),
                "image_copy_ms": r.image_copy_ms,
                "frame_in_place_ms": r.frame_in_place_ms,
                "in_place_ratio": r.in_place_ratio(),
                "frame_image_copy_ms": r.frame_image_copy_ms,
                "image_copy_copies_ms": r.image_copy_copies_ms,
                "image_copy_frame_ratio": r.image_copy_frame_ratio(),
                "image_copy_in_place_ratio": r.image_copy_in_place_ratio(),
                "frame_image_copy_tiles_ms": r.frame_image_copy_tiles_ms,
                "image_copy_tiles_in_place_ratio": r.image_copy_tiles_in_place_ratio(),
                "frame_sampled_tiles_ms": r.frame_sampled_tiles_ms,
                "sampled_tiles_in_place_ratio": r.sampled_tiles_in_place_ratio(),
                "live_frame_ms": r.live_frame_ms(),
                "live_ratio": r.live_frame_ms() / r.copy_ms,
                "camera_width": CAMERA_SIZE.0,
                "camera_height": CAMERA_SIZE.1,
            })
        })
        .collect();
    let mut all = serde_json::Map::new();
    all.insert("device".into(), device.into());
    all.insert("cube_roots".into(), roots.into());
    all.insert("results".into(), rows.into());
    if let Some(stats) = stats {
        shader_stats::json(stats, &mut all);
    }
    serde_json::Value::Object(all).to_string()
}
