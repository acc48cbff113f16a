//! What a GPU's compiler makes of the frame's per-pixel shaders, with no GPU: Mesa's RADV
//! compiles them for an RDNA2 GPU (RADV_FORCE_FAMILY=navi21) on a device that only compiles,
//! through `scripts/shader-stats` (`contrastxr bench --compile-only`). Registers and spills are
//! what the shaders' time on a GPU hangs on, so they are held here to what a GPU needs.

use std::process::Command;

/// `scripts/shader-stats --json` with `args`: the device and each shader's statistics by
/// RADV's names.
fn compiled(args: &[&str]) -> (String, Vec<(String, serde_json::Value)>) {
    let o = Command::new(concat!(env!("CARGO_MANIFEST_DIR"), "/scripts/shader-stats"))
        .args(args)
        .arg("--json")
        .env("CONTRASTXR_BIN", env!("CARGO_BIN_EXE_contrastxr"))
        .output()
        .expect("scripts/shader-stats runs");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("one JSON object");
    let shaders = v["shader_statistics"].as_array().expect("statistics");
    let all = shaders
        .iter()
        .map(|s| {
            let name = s["shader"].as_str().expect("a shader's name").to_string();
            let executables = s["executables"].as_array().expect("executables");
            assert_eq!(executables.len(), 1, "one compute executable: {s}");
            (name, executables[0]["statistics"].clone())
        })
        .collect();
    (v["device"].as_str().unwrap_or_default().to_string(), all)
}

fn stat(stats: &serde_json::Value, name: &str) -> u64 {
    stats[name]
        .as_u64()
        .unwrap_or_else(|| panic!("no {name}: {stats}"))
}

#[test]
fn radv_compiles_every_per_pixel_shader_without_a_gpu() {
    // Per access (the buffer path's, in place, the sampled read): classify and enhance (the
    // paper's also with shared fetches), and in place and the sampled read the enhance again
    // with the cube roots by pow; finish_tiles and the perceptual method's classify by rows.
    for (method, shaders) in [("paper", 14), ("perceptual", 11)] {
        let (device, all) = compiled(&["--method", method]);
        assert!(device.contains("RADV NAVI21"), "{device}");
        assert_eq!(all.len(), shaders, "{method}: {all:?}");
        let by_pow = all.iter().filter(|(name, _)| name.ends_with("_p")).count();
        assert_eq!(by_pow, if method == "paper" { 4 } else { 2 }, "{method}");
        for (name, stats) in &all {
            assert!(stat(stats, "VGPRs") > 0, "{name}: {stats}");
            assert!(stat(stats, "Instructions") > 0, "{name}: {stats}");
        }
    }
}

/// A spilled register is a trip to memory inside the per-pixel arithmetic: none may spill, in
/// either method's shaders.
#[test]
fn no_per_pixel_shader_spills_registers_on_rdna2() {
    for method in ["paper", "perceptual"] {
        for (name, stats) in compiled(&["--method", method]).1 {
            assert_eq!(stat(&stats, "Spilled VGPRs"), 0, "{name}: {stats}");
            assert_eq!(stat(&stats, "Scratch size"), 0, "{name}: {stats}");
        }
    }
}
