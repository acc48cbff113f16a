//! Additive presentation on a display whose runtime reports only OPAQUE (the simulated HMD of
//! the real Monado runtime, sandbox): with `environment_blend_mode = "additive"` apps are offered
//! ADDITIVE, render black where they have no content, and their frames are enhanced without
//! `force`; without it, the runtime's answer stands.

mod common;

use common::{layer_lines, sandbox, scratch_dir, SandboxRun, XR_CLIENT};
use std::path::Path;

const SYSTEM: &str = "Monado: Simulated HMD";

/// Captured views: (metadata, display bytes, output bytes).
fn captures(dir: &Path) -> Vec<(serde_json::Value, Vec<u8>, Vec<u8>)> {
    let mut jsons: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "json"))
        .collect();
    jsons.sort();
    jsons
        .iter()
        .map(|j| {
            let stem = j.file_stem().unwrap().to_string_lossy().into_owned();
            let file = |s: &str| std::fs::read(j.with_file_name(format!("{stem}{s}"))).unwrap();
            let json = serde_json::from_str(&std::fs::read_to_string(j).unwrap()).unwrap();
            (json, file("-display.raw"), file("-output.raw"))
        })
        .collect()
}

/// The share of pixels whose colour channels (every byte but the alpha's) are all zero.
fn black_share(json: &serde_json::Value, raw: &[u8]) -> f64 {
    let bpp = json["bytes_per_pixel"].as_u64().unwrap() as usize;
    let colour = bpp * 3 / 4;
    let pixels = raw.len() / bpp;
    let black = raw
        .chunks_exact(bpp)
        .filter(|p| p[..colour].iter().all(|b| *b == 0))
        .count();
    black as f64 / pixels as f64
}

fn env_with(dir: &Path, extra: &[(&'static str, &'static str)]) -> Vec<(String, String)> {
    let mut env: Vec<(String, String)> = vec![
        ("CONTRASTXR".into(), "1".into()),
        ("CONTRASTXR_INDICATOR".into(), "0".into()),
        ("CONTRASTXR_BACKGROUND".into(), "color:#e0d020".into()),
        ("CONTRASTXR_CAPTURE_DIR".into(), dir.display().to_string()),
        ("CONTRASTXR_CAPTURE_SKIP".into(), "3".into()),
        ("CONTRASTXR_CAPTURE_FRAMES".into(), "2".into()),
    ];
    env.extend(extra.iter().map(|(k, v)| (k.to_string(), v.to_string())));
    env
}

fn run(cmd: &[&str], env: &[(String, String)]) -> Option<SandboxRun> {
    let sandbox = sandbox()?;
    let refs: Vec<(&str, &str)> = env.iter().map(|(k, v)| (k.as_str(), v.as_str())).collect();
    Some(sandbox.run(cmd, &refs))
}

#[test]
fn hello_xr_presents_additive_with_the_key_and_renders_black_around_its_content() {
    let dir = scratch_dir("additive-hello-xr");
    let env = env_with(&dir, &[("CONTRASTXR_ENVIRONMENT_BLEND_MODE", "additive")]);
    // At least 8 s, then until the two frames are captured (the pipelines may be cold).
    let script = format!(
        "{} | hello_xr -g Vulkan2 -bm Additive",
        common::stdin_until_captured(&dir, 4, 8)
    );
    let Some(run) = run(&["bash", "-c", &script], &env) else {
        return;
    };
    run.assert_success();
    let all = format!("{}{}", run.stdout, run.stderr);
    assert!(all.contains("FOCUSED"), "never FOCUSED: {}", run.describe());
    let lines = layer_lines(&run);
    assert!(
        lines
            .iter()
            .any(|l| l.contains("the runtime is handed OPAQUE")),
        "{lines:?}"
    );
    assert!(
        !lines.iter().any(|l| l.contains("not ADDITIVE")),
        "{lines:?}"
    );
    // Enhanced without force: two frames of two views captured.
    let views = captures(&dir);
    assert_eq!(views.len(), 4, "{lines:?}");
    for (json, display, output) in &views {
        let (shown, enhanced) = (black_share(json, display), black_share(json, output));
        // The app clears to black for ADDITIVE (to grey for OPAQUE): its cubes cover a little.
        assert!(shown > 0.5, "display {shown:.3} black");
        // Black is no light on an additive display: the layer leaves it black.
        assert!(
            enhanced >= shown,
            "output {enhanced:.3} < display {shown:.3}"
        );
        assert!(shown < 1.0, "no content at all");
    }
}

#[test]
fn hello_xr_additive_fails_without_the_key() {
    let dir = scratch_dir("additive-hello-xr-off");
    let env = env_with(&dir, &[]);
    // hello_xr fails at once where ADDITIVE is refused; were it accepted, it would run 8 s.
    let script = "sleep 8 | hello_xr -g Vulkan2 -bm Additive";
    let Some(run) = run(&["bash", "-c", script], &env) else {
        return;
    };
    assert!(!run.success(), "ADDITIVE accepted: {}", run.describe());
}

/// The key in the system's `[device."..."]` table: the test client takes the first mode offered
/// (ADDITIVE) and its frames are enhanced without force; another system's table does nothing.
#[test]
fn the_device_table_key_offers_additive_to_its_system_only() {
    for (system, expected) in [(SYSTEM, "ADDITIVE"), ("Other HMD", "OPAQUE")] {
        let dir = scratch_dir(&format!("additive-device-{}", expected));
        let config = dir.join("config.toml");
        let text = format!("[device.\"{system}\"]\nenvironment_blend_mode = \"additive\"\n");
        std::fs::write(&config, text).unwrap();
        let captures_dir = dir.join("captures");
        std::fs::create_dir_all(&captures_dir).unwrap();
        let mut env = env_with(&captures_dir, &[]);
        env.push(("CONTRASTXR_CONFIG".into(), config.display().to_string()));
        let cmd = [XR_CLIENT, "--json", "--frames", "8", "--size", "64x48"];
        let Some(run) = run(&cmd, &env) else { return };
        run.assert_success();
        let report = run.client_report();
        assert_eq!(report["blend_mode"], expected, "{}", run.describe());
        let enhanced = captures(&captures_dir).len();
        assert_eq!(enhanced > 0, expected == "ADDITIVE", "{}", run.describe());
    }
}

/// Shipped profiles (here at `$CONTRASTXR_DEVICES`) apply to their system, and the user's
/// device table overrides them.
#[test]
fn shipped_profiles_apply_below_the_users_device_table() {
    let dir = scratch_dir("additive-shipped");
    let shipped = dir.join("devices.toml");
    let text = format!("[device.\"{SYSTEM}\"]\nenvironment_blend_mode = \"additive\"\n");
    std::fs::write(&shipped, text).unwrap();
    let config = dir.join("config.toml");
    let text = format!("[device.\"{SYSTEM}\"]\nenvironment_blend_mode = \"\"\n");
    std::fs::write(&config, text).unwrap();
    let cmd = [XR_CLIENT, "--json", "--frames", "4", "--size", "64x48"];
    for (user, expected) in [(false, "ADDITIVE"), (true, "OPAQUE")] {
        let mut env = env_with(&dir.join("none"), &[]);
        env.push(("CONTRASTXR_DEVICES".into(), shipped.display().to_string()));
        let user_file = if user {
            config.clone()
        } else {
            dir.join("missing.toml")
        };
        env.push(("CONTRASTXR_CONFIG".into(), user_file.display().to_string()));
        let Some(run) = run(&cmd, &env) else { return };
        run.assert_success();
        assert_eq!(
            run.client_report()["blend_mode"],
            expected,
            "{}",
            run.describe()
        );
    }
}
