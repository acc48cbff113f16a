//! The doctor command: runs every check and prints the findings as text or JSON.

use super::super::args::{Args, Opt};
use super::super::error::{print, CliError};
use super::finding::{Finding, Status};
use super::{app, camera, gpu_time_finding, manifest, profile, runtime, steam};

pub const OPTIONS: &[Opt] = &[Opt::flag("--json")];

pub fn usage() -> String {
    "usage: contrastxr doctor [--json]\n\n\
     Checks everything the layer needs and prints one line per finding (ok, warn or problem),\n\
     with a fix under each that is not ok, after a header naming the graphics APIs the layer\n\
     enhances (Vulkan, OpenGL):\n\
     \x20 manifest        the OpenXR loader finds the layer's manifest (implicit, or explicit\n\
     \x20                 through XR_API_LAYER_PATH) in its search paths: which file\n\
     \x20 library         the library the manifest names loads and exports\n\
     \x20                 xrNegotiateLoaderApiLayerInterface\n\
     \x20 runtime         the active OpenXR runtime (XR_RUNTIME_JSON or active_runtime.json)\n\
     \x20 vulkan          the Vulkan devices\n\
     \x20 config          the config file and its problems (file, line and key)\n\
     \x20 camera          the background source: the V4L2 cameras and their formats\n\
     \x20 camera-profile  whether the camera's position and lens are described\n\
     \x20 device-profile  the shipped device profile that matched the last app's headset (or\n\
     \x20                 the files searched, when none is found), and whether the camera the\n\
     \x20                 settings name (camera_usb_ids) is connected, before any app ran too\n\
     \x20 last-app        what the last app that loaded the layer logged: its session's\n\
     \x20                 graphics API, and the layer on, or why not\n\
     \x20 gpu-time        the GPU time the layer's work took per frame in the last app, as its\n\
     \x20                 log says it (median, 95th percentile, largest; once a minute and at\n\
     \x20                 each session's end)\n\
     \x20 steam           PRESSURE_VESSEL_IMPORT_OPENXR_1_LAYERS, which Steam games need: here,\n\
     \x20                 or in the games' launch options (Steam's localconfig.vdf)\n\
     --json: one JSON object: graphics_apis_enhanced and every finding (name, status, detail, fix).\n\
     Exit status 1 when a finding is a problem, 0 otherwise (warnings included).\n"
        .to_string()
}

/// Every check, in the order of the report.
fn findings() -> Vec<Finding> {
    let search = manifest::Search::run();
    let env = contrastxr::config::Env::capture();
    let last = app::LastApp::read();
    // The settings as the last app's headset gets them (its device tables applied).
    let who = contrastxr::config::Who {
        app: "",
        device: last.system(),
    };
    let settings = contrastxr::config::load_for(who, &env).settings;
    let mut all = vec![search.manifest_finding(), search.library_finding()];
    all.extend([
        runtime::runtime(),
        runtime::vulkan(),
        app::config(&env),
        camera::camera(&settings.background, settings.colour_camera),
        camera::profile(&env, last.system()),
        profile::device_profile(&env, last.system()),
        last.finding(),
        gpu_time_finding::finding(&last),
        steam::steam(),
    ]);
    all
}

fn count(findings: &[Finding], status: Status) -> usize {
    findings.iter().filter(|f| f.status == status).count()
}

fn text(findings: &[Finding]) -> String {
    let mut out = format!(
        "contrastxr doctor\n  graphics APIs enhanced: {}\n",
        app::ENHANCED_APIS
    );
    for f in findings {
        out += &format!("  {:<8} {:<15} {}\n", f.status.name(), f.name, f.detail);
        if let Some(fix) = &f.fix {
            out += &format!("  {:<8} {:<15} fix: {fix}\n", "", "");
        }
    }
    out += &format!(
        "{} problem(s), {} warning(s)\n",
        count(findings, Status::Problem),
        count(findings, Status::Warn)
    );
    out
}

fn json(findings: &[Finding]) -> String {
    let list: Vec<serde_json::Value> = findings
        .iter()
        .map(|f| {
            serde_json::json!({
                "name": f.name,
                "status": f.status.name(),
                "detail": f.detail,
                "fix": f.fix,
            })
        })
        .collect();
    let report = serde_json::json!({
        "ok": count(findings, Status::Problem) == 0,
        "problems": count(findings, Status::Problem),
        "warnings": count(findings, Status::Warn),
        "graphics_apis_enhanced": app::ENHANCED_APIS.split(", ").collect::<Vec<_>>(),
        "findings": list,
    });
    serde_json::to_string_pretty(&report).expect("JSON of strings") + "\n"
}

pub fn run(args: &mut Args) -> Result<(), CliError> {
    let as_json = args.flag("--json");
    args.finish()?;
    let findings = findings();
    print(&if as_json {
        json(&findings)
    } else {
        text(&findings)
    });
    match count(&findings, Status::Problem) {
        0 => Ok(()),
        n => Err(CliError::Failure(format!(
            "{n} problem(s) found, each with its fix"
        ))),
    }
}
