//! The settings' part of the layer's start-up line: the view mode and method, the settings the
//! method reads (its entry in the method table names them, and KEYS gives their values), then
//! the ones every method shares.

use super::keys::key;
use super::settings::Settings;
use crate::algorithm::registration::Lens;

/// `mode=... method=... lambda_e=... ... capture=...`.
pub fn describe(s: &Settings) -> String {
    let p = &s.params;
    let value = |name: &str| key(name).map_or_else(|| "?".into(), |k| k.get(s).to_string());
    let mut parts = vec![
        format!("mode={}", p.mode.name()),
        format!("method={}", p.method.name()),
    ];
    for name in p.method.entry().settings {
        parts.push(format!("{name}={}", value(name)));
    }
    let blur = if p.blur { p.blur_size } else { 1 };
    parts.extend([
        format!("transmittance={}", p.transmittance),
        format!("blur={blur}x{blur}/{}", p.blur_sigma),
        format!("fov_scale={:?}", p.fov_scale),
        format!("fov_offset={:?}", p.fov_offset),
        format!("fov={}", p.fov),
        format!("camera_profile={}", camera_profile(s)),
        format!("background={}", s.background),
        format!("force={}", s.force),
        format!("quad_layers={}", s.quad_layers),
        format!(
            "capture={}",
            s.capture_dir
                .as_ref()
                .map_or("off".into(), |d| d.display().to_string())
        ),
    ]);
    parts.join(" ")
}

/// Which camera profile the registration holds.
fn camera_profile(s: &Settings) -> String {
    let r = &s.registration;
    if Lens::from_intrinsics(r.camera_intrinsics).is_some() {
        format!("intrinsics{:?}", r.camera_intrinsics)
    } else if r.camera_fov != [0.0, 0.0] {
        format!("fov{:?}", r.camera_fov)
    } else {
        "none".into()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::algorithm::method::Method;

    /// The line names each setting the method in use reads, with its value, and no other
    /// method's.
    #[test]
    fn the_startup_line_names_the_methods_own_settings() {
        let mut s = Settings::default();
        let paper = describe(&s);
        let start = "mode=enhance method=paper lambda_e=0.4 ";
        assert!(paper.starts_with(start), "{paper}");
        assert!(paper.contains(" achromatic_boost=0 "), "{paper}");
        assert!(!paper.contains("world_nits"), "{paper}");
        s.params.method = Method::Perceptual;
        s.params.perceptual.world_nits = 5000.0;
        let perceptual = describe(&s);
        let said = [
            "method=perceptual",
            " world_nits=5000 ",
            " frequency=\"blur\" ",
        ];
        for said in said {
            assert!(perceptual.contains(said), "{said}: {perceptual}");
        }
        assert!(perceptual.contains(" capture=off"), "{perceptual}");
    }
}
