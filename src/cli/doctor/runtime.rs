//! The active OpenXR runtime (as the loader finds it) and the Vulkan devices.

use super::finding::{var, Finding};
use super::render_nodes;
use contrastxr::gpu::vulkan::device::physical_devices;
use contrastxr::gpu::GpuError;
use std::path::{Path, PathBuf};

/// Where the loader looks for the active runtime, in its order (`FindXDGConfigFile`):
/// `$XDG_CONFIG_HOME` (default `~/.config`), each of `$XDG_CONFIG_DIRS` (default `/etc/xdg`),
/// then `/etc`; in each `openxr/1/active_runtime.<arch>.json`, then `active_runtime.json`.
fn config_bases() -> Vec<PathBuf> {
    let mut bases: Vec<PathBuf> = var("XDG_CONFIG_HOME")
        .map(PathBuf::from)
        .or_else(|| var("HOME").map(|h| Path::new(&h).join(".config")))
        .into_iter()
        .collect();
    let dirs = var("XDG_CONFIG_DIRS").unwrap_or_else(|| "/etc/xdg".into());
    bases.extend(dirs.split(':').filter(|d| !d.is_empty()).map(PathBuf::from));
    bases.push(PathBuf::from("/etc"));
    bases
}

fn candidates() -> Vec<PathBuf> {
    let arch = format!("active_runtime.{}.json", std::env::consts::ARCH);
    config_bases()
        .iter()
        .flat_map(|b| {
            let dir = b.join("openxr/1");
            [dir.join(&arch), dir.join("active_runtime.json")]
        })
        .collect()
}

/// `ID`, `VERSION_ID` and `ID_LIKE` of /etc/os-release (e.g. `debian`, `12`, ``).
fn distribution() -> (String, String, String) {
    let text = std::fs::read_to_string("/etc/os-release").unwrap_or_default();
    let field = |name: &str| {
        text.lines()
            .find_map(|l| l.strip_prefix(name)?.strip_prefix('='))
            .map_or(String::new(), |v| v.trim_matches('"').to_string())
    };
    (field("ID"), field("VERSION_ID"), field("ID_LIKE"))
}

fn install_runtime() -> String {
    let (id, version, like) = distribution();
    // A derivative of Ubuntu (Mint, Pop!_OS) has Ubuntu's packages, under its own version.
    if id != "debian" && id != "ubuntu" && like.split_whitespace().any(|l| l == "ubuntu") {
        return install_runtime_on("ubuntu", "");
    }
    install_runtime_on(&id, &version)
}

/// How to get a runtime on distribution `id` `version`: Debian packages Monado from 13 on (and
/// in testing, which has no VERSION_ID); Debian 12 has none. Ubuntu has it in universe from
/// 22.04 on (the same packaging as Debian's).
fn install_runtime_on(id: &str, version: &str) -> String {
    const ACTIVE: &str = "make it the active one (its manifest linked as \
        /etc/xdg/openxr/1/active_runtime.json), or point XR_RUNTIME_JSON at its manifest";
    const FROM_SOURCE: &str = "build Monado from source \
        (https://monado.freedesktop.org/getting-started.html) or install your headset's own \
        runtime";
    let mut numbers = version.split('.').map(|v| v.parse::<u32>().unwrap_or(0));
    let major = numbers.next().unwrap_or(0);
    let minor = numbers.next().unwrap_or(0);
    match id {
        "debian" if major >= 13 || version.is_empty() => {
            "install Monado: `sudo apt install monado-service \
            libopenxr1-monado` (which makes it the active runtime)"
                .into()
        }
        "debian" => {
            format!("Debian {version} packages no OpenXR runtime: {FROM_SOURCE}, then {ACTIVE}")
        }
        "ubuntu" if (major, minor) >= (22, 4) || version.is_empty() => {
            "install Monado from universe: `sudo apt install monado-service \
             libopenxr1-monado`; if doctor still finds no active runtime, link its manifest: \
             `sudo mkdir -p /etc/xdg/openxr/1 && sudo ln -sf \
             /usr/share/openxr/1/openxr_monado.json /etc/xdg/openxr/1/active_runtime.json`"
                .into()
        }
        "ubuntu" => {
            format!("Ubuntu {version} packages no OpenXR runtime: {FROM_SOURCE}, then {ACTIVE}")
        }
        _ => format!("install an OpenXR runtime (e.g. Monado) and {ACTIVE}"),
    }
}

/// The runtime manifest's name and library, resolved as the loader resolves it.
fn read_runtime(file: &Path) -> Result<(String, PathBuf), String> {
    // XR_RUNTIME_JSON may name anything: read as every named file is (user_file).
    let text = contrastxr::user_file::read_text(file)?;
    let v: serde_json::Value =
        serde_json::from_str(&text).map_err(|e| format!("not valid JSON ({e})"))?;
    let runtime = &v["runtime"];
    let library = runtime["library_path"]
        .as_str()
        .ok_or("it has no runtime.library_path")?;
    let name = runtime["name"].as_str().unwrap_or("(unnamed)").to_string();
    let path = Path::new(library);
    if !library.contains('/') || path.is_absolute() {
        return Ok((name, path.to_path_buf()));
    }
    let real = file.canonicalize().unwrap_or_else(|_| file.to_path_buf());
    Ok((name, real.parent().unwrap_or(Path::new("/")).join(path)))
}

pub fn runtime() -> Finding {
    const NAME: &str = "runtime";
    let (file, how) = match var("XR_RUNTIME_JSON") {
        Some(f) => (PathBuf::from(f), " (XR_RUNTIME_JSON)"),
        None => match candidates().into_iter().find(|p| p.exists()) {
            Some(f) => (f, ""),
            None => {
                let dirs: Vec<String> = config_bases()
                    .iter()
                    .map(|b| b.join("openxr/1").display().to_string())
                    .collect();
                return Finding::problem(
                    NAME,
                    format!(
                        "no active OpenXR runtime: XR_RUNTIME_JSON is unset and none of {} holds \
                         active_runtime.json (or active_runtime.{}.json)",
                        dirs.join(", "),
                        std::env::consts::ARCH
                    ),
                    install_runtime(),
                );
            }
        },
    };
    let (name, library) = match read_runtime(&file) {
        Ok(r) => r,
        Err(why) => {
            return Finding::problem(
                NAME,
                format!("active runtime manifest {}{how}: {why}", file.display()),
                install_runtime(),
            )
        }
    };
    let lib = library.display();
    if library.is_absolute() && !library.exists() {
        return Finding::problem(
            NAME,
            format!(
                "active runtime {name} ({}{how}) names {lib}, which does not exist",
                file.display()
            ),
            format!(
                "reinstall the runtime, or select another one; {}",
                install_runtime()
            ),
        );
    }
    let lookup = if library.is_absolute() {
        ""
    } else {
        " (looked up by the dynamic linker)"
    };
    Finding::ok(
        NAME,
        format!(
            "active runtime {name} from {}{how}, library {lib}{lookup}",
            file.display()
        ),
    )
}

const INSTALL_VULKAN: &str = "install the Vulkan loader and a driver: `sudo apt install \
    libvulkan1 mesa-vulkan-drivers` (or your GPU vendor's Vulkan driver)";

/// The Vulkan devices, listed by the engine's device room as it finds them (the loader
/// `libvulkan.so.1`, a Vulkan 1.1 instance, vkEnumeratePhysicalDevices).
pub fn vulkan() -> Finding {
    const NAME: &str = "vulkan";
    let devices = match physical_devices() {
        Ok(d) => d,
        Err(GpuError::NoLoader(e)) => {
            return Finding::problem(
                NAME,
                format!("cannot load the Vulkan loader libvulkan.so.1 ({e})"),
                INSTALL_VULKAN,
            )
        }
        Err(GpuError::NoDevice(_)) => {
            return Finding::problem(NAME, "no Vulkan driver is installed", INSTALL_VULKAN)
        }
        // vkCreateInstance or vkEnumeratePhysicalDevices failed: the error names the call.
        Err(e) => return Finding::problem(NAME, e.to_string(), INSTALL_VULKAN),
    };
    if devices.is_empty() {
        return Finding::problem(NAME, "no Vulkan device", INSTALL_VULKAN);
    }
    let list: Vec<String> = devices
        .iter()
        .enumerate()
        .map(|(i, d)| {
            let (major, minor) = d.version;
            format!("#{i} {} ({}, Vulkan {major}.{minor})", d.name, d.kind)
        })
        .collect();
    let detail = format!("{} device(s): {}", devices.len(), list.join("; "));
    if devices.iter().all(|d| d.cpu) {
        let (why, fix) = render_nodes::software_only(
            &render_nodes::render_nodes(),
            &render_nodes::vulkan_drivers(),
            render_nodes::driver_override(),
        );
        Finding::warn(NAME, detail + &why, fix)
    } else {
        Finding::ok(NAME, detail)
    }
}

#[cfg(test)]
mod tests {
    use super::install_runtime_on;

    #[test]
    fn the_runtime_fix_fits_the_distribution() {
        let apt = "sudo apt install monado-service libopenxr1-monado";
        assert!(install_runtime_on("debian", "13").contains(apt));
        assert!(
            install_runtime_on("debian", "").contains(apt),
            "testing, sid"
        );
        let bookworm = install_runtime_on("debian", "12");
        assert!(!bookworm.contains("apt install"), "{bookworm}");
        assert!(bookworm.contains("Debian 12 packages no OpenXR runtime"));
        assert!(bookworm.contains("monado.freedesktop.org"));
        assert!(!install_runtime_on("fedora", "41").contains("apt"));
    }

    /// Ubuntu gets a command (universe has Monado from 22.04 on), not only "install one".
    #[test]
    fn ubuntu_gets_a_command() {
        let apt = "sudo apt install monado-service libopenxr1-monado";
        for version in ["22.04", "24.04", "25.10", ""] {
            let fix = install_runtime_on("ubuntu", version);
            assert!(fix.contains(apt), "{version}: {fix}");
            assert!(
                fix.contains("/usr/share/openxr/1/openxr_monado.json"),
                "{fix}"
            );
        }
        let focal = install_runtime_on("ubuntu", "20.04");
        assert!(!focal.contains("apt install"), "{focal}");
        assert!(
            focal.contains("Ubuntu 20.04 packages no OpenXR runtime"),
            "{focal}"
        );
    }
}
