//! contrastxr-xr-client: the project's own OpenXR test app. It creates a Vulkan session through
//! XR_KHR_vulkan_enable2, renders known test patterns (content on black), or a PNG (`--content
//! image:PATH`), into the swapchain format and layout asked for, submits N frames, ends the
//! session cleanly, and exits non-zero on any OpenXR or Vulkan error (and on any Vulkan
//! validation error with --validation).
//! Run it inside the sandbox: `scripts/xr-sandbox run -- target/debug/contrastxr-xr-client`.

mod churn;
mod cli;
mod egl;
mod error;
mod frame_loop;
mod full_stderr;
mod gipa;
mod gl_binding;
mod gl_run;
mod gl_state;
mod gl_state_enums;
mod gl_state_fns;
mod gl_state_items;
mod gl_state_objects;
mod gl_swapchain;
mod glx;
mod gpu;
mod leftovers;
mod memory;
mod pattern;
mod pattern_swapchain;
mod picture;
mod run_report;
mod scene;
mod script;
mod swapchain_format;
mod timing;
mod untouched;
mod validation;
mod x_errors;

use std::process::ExitCode;

use ash::vk;
use openxr as xr;

use cli::{Layout, Options};
use error::{fail, Context, Result};
use frame_loop::Stats;
use gpu::Gpu;
use pattern::{LayerContent, Target};
use pattern_swapchain::PatternSwapchain;
use run_report::Report;
use scene::Scene;
use swapchain_format::SwapchainFormat;

const VIEW_TYPE: xr::ViewConfigurationType = xr::ViewConfigurationType::PRIMARY_STEREO;

fn main() -> ExitCode {
    // --timing's run_s: the whole process, as a user waiting for the app sees it.
    let started = std::time::Instant::now();
    let options = match cli::parse(std::env::args().skip(1)) {
        Ok(options) => options,
        Err(message) => {
            eprintln!("{message}");
            return ExitCode::from(2);
        }
    };
    if let Err(message) = pattern::set_content(&options.content) {
        eprintln!("{message}");
        return ExitCode::from(2);
    }
    let mut report = Report {
        frames_requested: options.frames,
        layout: options.layout.name().to_string(),
        views: 2,
        quad: options.quad,
        vk_validation: options.validation,
        graphics: options.graphics.name().to_string(),
        ..Report::default()
    };
    let mut stats = Stats {
        calls: timing::Calls::new(options.timing),
        create_calls: timing::Calls::new(options.timing),
        ..Stats::default()
    };
    for _ in 0..options.instances.max(1) {
        if let Err(e) = run(&options, &mut report, &mut stats) {
            report.errors.push(e.0);
            break;
        }
    }
    if let Some(ms) = options.linger_ms {
        std::thread::sleep(std::time::Duration::from_millis(ms));
        report.after_instances = Some(leftovers::look());
    }
    report.frames_submitted = stats.frames_submitted;
    report.script = std::mem::take(&mut stats.script);
    report.memory = std::mem::take(&mut stats.memory);
    report.frames_ended = stats.frames_ended;
    report.display_period_ms = stats.display_period_ns as f64 / 1e6;
    report.reached_focused = stats.reached_focused;
    if options.timing {
        let run_s = started.elapsed().as_secs_f64();
        report.timing = Some(run_report::Timing::new(&stats, run_s));
    }
    report.vk_validation_errors = validation::errors();
    report.vk_validation_warnings = validation::warnings();
    let ran = options.list_formats
        || stats.script_ran
        || (options.script.is_none()
            && (stats.stopped
                || stats.reached_modified
                || stats.frames_submitted
                    >= options.frames * options.sessions * options.instances));
    report.stopped_by_file = stats.stopped;
    report.stopped_by_modified = stats.reached_modified;
    report.ok = report.errors.is_empty() && report.vk_validation_errors == 0 && ran;
    print(&report, &options);
    if options.exit_marker {
        // SAFETY: a plain function of this program, registered once.
        unsafe { libc::atexit(say_exit_handler_ran) };
    }
    if report.ok {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    }
}

/// `--exit-marker`'s handler: newest first, so it runs before every earlier one, such as a
/// driver's destructors registered during the session.
extern "C" fn say_exit_handler_ran() {
    eprintln!("contrastxr-xr-client: exit handler ran");
}

/// The summary line (and with --timing the timing lines after it) on stdout, or on stderr
/// with --json, whose report must be stdout's last line; with --list-formats only on failure.
fn print(report: &Report, options: &Options) {
    let mut text = report.summary();
    if let Some(timing) = &report.timing {
        text = format!("{text}\n{}", timing.text());
    }
    if options.json {
        eprintln!("{text}");
        println!("{}", report.json());
    } else if !options.list_formats {
        println!("{text}");
    } else if !report.ok {
        eprintln!("{text}");
    }
}

fn run(options: &Options, report: &mut Report, stats: &mut Stats) -> Result<()> {
    let entry = load_openxr()?;
    if options.graphics == cli::Graphics::OpenGl {
        return gl_run::run(&entry, options, report, stats);
    }
    let available = entry
        .enumerate_extensions()
        .ctx("xrEnumerateInstanceExtensionProperties")?;
    if !available.khr_vulkan_enable2 {
        return fail("the runtime does not offer XR_KHR_vulkan_enable2");
    }
    let mut extensions = xr::ExtensionSet::default();
    extensions.khr_vulkan_enable2 = true;
    let instance = stats.create_calls.time("xrCreateInstance", || {
        create_instance(&entry, &extensions, report)
    })?;
    report.timespec_offered = available.khr_convert_timespec_time;
    report.timespec_lookup = timespec_lookup(&entry, &instance);
    if options.provoke_xr_error {
        // Invalid on purpose: an undefined form factor, which core validation must report.
        let _ = instance.system(xr::FormFactor::from_raw(0x7fff_fff0));
    }
    let system = instance
        .system(xr::FormFactor::HEAD_MOUNTED_DISPLAY)
        .ctx("xrGetSystem")?;
    let blend_modes = instance
        .enumerate_environment_blend_modes(system, VIEW_TYPE)
        .ctx("xrEnumerateEnvironmentBlendModes")?;
    let Some(&blend_mode) = blend_modes.first() else {
        return fail("the runtime offers no environment blend mode");
    };
    report.blend_mode = format!("{blend_mode:?}");
    let gpu = Gpu::new(&instance, system, options.validation)?;
    if options.provoke_vk_error {
        gpu.provoke_validation_error();
    }
    if options.provoke_leak {
        gpu.provoke_leak()?;
    }
    if options.provoke_sync_hazard {
        gpu.provoke_sync_hazard()?;
    }
    let world = World {
        instance: &instance,
        system,
        gpu: &gpu,
        blend_mode,
    };
    for _ in 0..options.sessions.max(1) {
        run_session(&world, options, report, stats)?;
        report.sessions_run += 1;
        report
            .sessions
            .push(run_report::Sample::now(stats.frames_submitted));
        if options.list_formats {
            break;
        }
    }
    // The device goes before the instance (a layer may still be closing a session's work).
    drop(gpu);
    std::thread::sleep(std::time::Duration::from_millis(options.after_device_ms));
    // The last reference to the instance: xrDestroyInstance.
    let t = std::time::Instant::now();
    drop(instance);
    report.teardown_ms.instance(t.elapsed());
    Ok(())
}

/// The client's instance with `extensions`; the runtime's name goes to the report.
fn create_instance(
    entry: &xr::Entry,
    extensions: &xr::ExtensionSet,
    report: &mut Report,
) -> Result<xr::Instance> {
    let app = xr::ApplicationInfo {
        application_name: "contrastxr-xr-client",
        application_version: 1,
        engine_name: "contrastxr",
        engine_version: 1,
        api_version: xr::Version::new(1, 0, 0),
    };
    let instance = entry
        .create_instance(&app, extensions, &[])
        .ctx("xrCreateInstance")?;
    let props = instance.properties().ctx("xrGetInstanceProperties")?;
    report.runtime = format!("{} {}", props.runtime_name, props.runtime_version);
    Ok(instance)
}

/// What every session of the run shares.
struct World<'a> {
    instance: &'a xr::Instance,
    system: xr::SystemId,
    gpu: &'a Gpu,
    blend_mode: xr::EnvironmentBlendMode,
}

/// One session: create it, run its frames, end it; dropping it here destroys it.
fn run_session(
    world: &World<'_>,
    options: &Options,
    report: &mut Report,
    stats: &mut Stats,
) -> Result<()> {
    let (instance, system, gpu) = (world.instance, world.system, world.gpu);
    let gipa_calls = gipa::calls();
    let create = || {
        // SAFETY: the Vulkan objects were made through this instance for this system, and
        // `gpu` outlives the session (`run` drops it after its sessions).
        unsafe { instance.create_session::<xr::Vulkan>(system, &gpu.session_create_info()) }
    };
    let (session, mut waiter, mut stream) = stats
        .create_calls
        .time("xrCreateSession", create)
        .ctx("xrCreateSession")?;
    report.vk_gipa_calls_in_create_session += gipa::calls() - gipa_calls;
    stats.startup.session_created();
    let offered = session
        .enumerate_swapchain_formats()
        .ctx("xrEnumerateSwapchainFormats")?;
    if options.list_formats {
        offered.iter().for_each(|&f| println!("{}", format_name(f)));
        return Ok(());
    }
    let format = choose_format(options.format, &offered)?;
    report.format = format.name.to_string();
    let churn_plan = churn::plan(
        format.vk.as_raw() as u32,
        &offered,
        options.churn_formats,
        churn::is_vk_depth,
    );
    let stop = std::sync::atomic::AtomicBool::new(false);
    let churned = std::sync::atomic::AtomicU32::new(0);
    // The churn thread starts as soon as the session exists: a layer that sets up on threads
    // of its own at xrCreateSession races the app's swapchain calls from the first moment.
    let result = std::thread::scope(|threads| {
        let churner = options
            .churn_swapchains
            .then(|| threads.spawn(|| churn::churn(&session, &churn_plan, &stop, &churned)));
        let streams = (&mut waiter, &mut stream);
        let result = run_frames(world, options, &session, streams, format, report, stats);
        stop.store(true, std::sync::atomic::Ordering::Relaxed);
        match churner.map(|t| t.join()) {
            Some(Ok(Some(e))) => report.errors.push(e),
            Some(Err(_)) => report.errors.push("the churn thread panicked".into()),
            _ => {}
        }
        result
    });
    report.swapchains_churned += churned.into_inner();
    // An app that stops ending frames (paused, idle) before it ends the session.
    std::thread::sleep(std::time::Duration::from_millis(options.idle_ms));
    // The last references to the session: xrDestroySession.
    let t = std::time::Instant::now();
    drop((session, waiter, stream));
    report.teardown_ms.session(t.elapsed());
    result
}

/// The session's swapchains and its frame loop; the frames' call times and checks go to the
/// report.
fn run_frames(
    world: &World<'_>,
    options: &Options,
    session: &xr::Session<xr::Vulkan>,
    (waiter, stream): (&mut xr::FrameWaiter, &mut xr::FrameStream<xr::Vulkan>),
    format: SwapchainFormat,
    report: &mut Report,
    stats: &mut Stats,
) -> Result<()> {
    let (instance, system, gpu) = (world.instance, world.system, world.gpu);
    let view_size = match options.size {
        Some(size) => size,
        None => recommended_size(instance, system)?,
    };
    report.view_size = [view_size.0, view_size.1];
    let space = session
        .create_reference_space(xr::ReferenceSpaceType::LOCAL, xr::Posef::IDENTITY)
        .ctx("xrCreateReferenceSpace")?;
    let check = options.check_untouched;
    let projection = stats
        .create_calls
        .time(
            "xrCreateSwapchain (projection, with its images' set-up)",
            || projection_swapchain(session, gpu, format, view_size, options.layout, check),
        )?
        .timed(options.timing);
    let quad = options
        .quad
        .then(|| {
            PatternSwapchain::new(
                session,
                gpu,
                format,
                (view_size.0 / 2, view_size.1 / 2),
                &[LayerContent::Whole(Target::Quad)],
                check,
            )
            .map(|quad| quad.timed(options.timing))
        })
        .transpose()?;
    let mut scene = Scene {
        session,
        space: &space,
        gpu,
        projection,
        quad,
        view_size,
        blend_mode: world.blend_mode,
        format,
        ahead: None,
    };
    // Only around the frame loop: the runtime's client library logs to stderr too, at
    // xrCreateInstance and at a session's changes.
    let stderr = options.stderr_full.then(full_stderr::install).flatten();
    let mut frames = frame_loop::VulkanFrames {
        scene: &mut scene,
        waiter,
        stream,
    };
    let result = frame_loop::run(instance, &mut frames, options, stats);
    stderr.into_iter().for_each(full_stderr::restore);
    stats.calls.absorb(scene.projection.calls(), "");
    if let Some(quad) = &scene.quad {
        stats.calls.absorb(quad.calls(), " (quad)");
    }
    for swapchain in std::iter::once(&scene.projection).chain(scene.quad.as_ref()) {
        let (checked, modified) = swapchain.check_result();
        report.frames_checked += checked;
        report.frames_modified.extend(modified);
    }
    result
}

fn projection_swapchain(
    session: &xr::Session<xr::Vulkan>,
    gpu: &Gpu,
    format: SwapchainFormat,
    (w, h): (u32, u32),
    layout: Layout,
    check: bool,
) -> Result<PatternSwapchain> {
    match layout {
        Layout::Array => {
            let views = [
                LayerContent::Whole(Target::View(0)),
                LayerContent::Whole(Target::View(1)),
            ];
            PatternSwapchain::new(session, gpu, format, (w, h), &views, check)
        }
        Layout::SideBySide => PatternSwapchain::new(
            session,
            gpu,
            format,
            (2 * w, h),
            &[LayerContent::SideBySide],
            check,
        ),
    }
}

/// The loader by its ABI name, as apps linked against it find it; the unversioned name (what the
/// `openxr` crate asks for) exists only where the loader's -dev package is installed.
fn load_openxr() -> Result<xr::Entry> {
    // SAFETY: loads the system OpenXR loader, which this process has not loaded otherwise.
    unsafe {
        xr::Entry::load_from(std::path::Path::new("libopenxr_loader.so.1"))
            .or_else(|_| xr::Entry::load())
    }
    .ctx("loading the OpenXR loader (libopenxr_loader.so.1)")
}

fn choose_format(wanted: Option<SwapchainFormat>, offered: &[u32]) -> Result<SwapchainFormat> {
    let offered_known = || {
        offered
            .iter()
            .filter_map(|&f| SwapchainFormat::by_vk(vk::Format::from_raw(f as i32)))
    };
    let chosen = match wanted {
        Some(format) => offered_known().find(|&f| f == format),
        None => offered_known().next(),
    };
    chosen.map_or_else(
        || {
            let names: Vec<_> = offered.iter().map(|&f| format_name(f)).collect();
            let asked = wanted.map_or("any known format", |f| f.name);
            fail(format!(
                "the runtime does not offer {asked}; it offers {}",
                names.join(" ")
            ))
        },
        Ok,
    )
}

fn format_name(raw: u32) -> String {
    SwapchainFormat::by_vk(vk::Format::from_raw(raw as i32))
        .map_or_else(|| format!("VkFormat({raw})"), |f| f.name.to_string())
}

pub fn recommended_size(instance: &xr::Instance, system: xr::SystemId) -> Result<(u32, u32)> {
    let views = instance
        .enumerate_view_configuration_views(system, VIEW_TYPE)
        .ctx("xrEnumerateViewConfigurationViews")?;
    if views.len() != 2 {
        return fail(format!(
            "expected 2 stereo views, the runtime has {}",
            views.len()
        ));
    }
    Ok((
        views[0].recommended_image_rect_width,
        views[0].recommended_image_rect_height,
    ))
}

/// What xrGetInstanceProcAddr answers for an extension function this app did not enable (the
/// spec: XR_ERROR_FUNCTION_UNSUPPORTED), as the XrResult's name.
fn timespec_lookup(entry: &xr::Entry, instance: &xr::Instance) -> String {
    let mut f = None;
    // SAFETY: a valid instance, a NUL-terminated name and a valid out pointer.
    let r = unsafe {
        (entry.fp().get_instance_proc_addr)(
            instance.as_raw(),
            c"xrConvertTimespecTimeToTimeKHR".as_ptr(),
            &mut f,
        )
    };
    format!("{r:?}")
}
