//! The active OpenXR runtime (as the loader finds it) and the Vulkan devices.

use super::finding::{var, Finding};
use ash::vk;
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

/// `ID` and `VERSION_ID` of /etc/os-release (e.g. `debian`, `12`).
fn distribution() -> (String, String) {
    let text = std::fs::read_to_string("/etc/os-release").unwrap_or_default();
    let field = |name: &str| {
        text.lines()
            .find_map(|l| l.strip_prefix(name)?.strip_prefix('='))
            .map_or(String::new(), |v| v.trim_matches('"').to_string())
    };
    (field("ID"), field("VERSION_ID"))
}

fn install_runtime() -> String {
    let (id, version) = distribution();
    install_runtime_on(&id, &version)
}

/// How to get a runtime on distribution `id` `version`: Debian packages Monado from 13 on (and
/// in testing, which has no VERSION_ID); Debian 12 has none.
fn install_runtime_on(id: &str, version: &str) -> String {
    const ACTIVE: &str = "make it the active one (its manifest linked as \
        /etc/xdg/openxr/1/active_runtime.json), or point XR_RUNTIME_JSON at its manifest";
    let major: u32 = version
        .split('.')
        .next()
        .and_then(|v| v.parse().ok())
        .unwrap_or(0);
    match id {
        "debian" if major >= 13 || version.is_empty() => {
            "install Monado: `sudo apt install monado-service \
            libopenxr1-monado` (which makes it the active runtime)"
                .into()
        }
        "debian" => format!(
            "Debian {version} packages no OpenXR runtime: build Monado from source \
             (https://monado.freedesktop.org/getting-started.html) or install your headset's \
             own runtime, then {ACTIVE}"
        ),
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

fn device_type(t: vk::PhysicalDeviceType) -> &'static str {
    match t {
        vk::PhysicalDeviceType::DISCRETE_GPU => "discrete GPU",
        vk::PhysicalDeviceType::INTEGRATED_GPU => "integrated GPU",
        vk::PhysicalDeviceType::VIRTUAL_GPU => "virtual GPU",
        vk::PhysicalDeviceType::CPU => "CPU, software",
        _ => "other",
    }
}

/// Each physical device as `#N NAME (TYPE, Vulkan X.Y)`, and whether it is a CPU device.
fn describe(instance: &ash::Instance) -> Result<Vec<(String, bool)>, vk::Result> {
    // SAFETY: a valid instance.
    let physicals = unsafe { instance.enumerate_physical_devices() }?;
    Ok(physicals
        .iter()
        .enumerate()
        .map(|(i, &p)| {
            // SAFETY: p was enumerated from this instance.
            let props = unsafe { instance.get_physical_device_properties(p) };
            let name = props
                .device_name_as_c_str()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_else(|_| "unknown device".into());
            let v = props.api_version;
            let text = format!(
                "#{i} {name} ({}, Vulkan {}.{})",
                device_type(props.device_type),
                vk::api_version_major(v),
                vk::api_version_minor(v)
            );
            (text, props.device_type == vk::PhysicalDeviceType::CPU)
        })
        .collect())
}

/// The Vulkan devices, found the way the engine finds them (`src/gpu/device/gpu_device.rs`): the loader
/// `libvulkan.so.1` through ash, a Vulkan 1.1 instance, vkEnumeratePhysicalDevices.
pub fn vulkan() -> Finding {
    const NAME: &str = "vulkan";
    // SAFETY: loads libvulkan.so.1, whose initialisation has no preconditions.
    let entry = match unsafe { ash::Entry::load() } {
        Ok(e) => e,
        Err(e) => {
            return Finding::problem(
                NAME,
                format!("cannot load the Vulkan loader libvulkan.so.1 ({e})"),
                INSTALL_VULKAN,
            )
        }
    };
    let app = vk::ApplicationInfo::default()
        .application_name(c"contrastxr doctor")
        .api_version(vk::API_VERSION_1_1);
    let info = vk::InstanceCreateInfo::default().application_info(&app);
    // SAFETY: info and what it points to live until the call returns.
    let instance = match unsafe { entry.create_instance(&info, None) } {
        Ok(i) => i,
        Err(e) => {
            let why = match e {
                vk::Result::ERROR_INCOMPATIBLE_DRIVER => "no Vulkan driver is installed".into(),
                e => format!("vkCreateInstance failed: {e}"),
            };
            return Finding::problem(NAME, why, INSTALL_VULKAN);
        }
    };
    let devices = describe(&instance);
    // SAFETY: the instance has no children.
    unsafe { instance.destroy_instance(None) };
    match devices {
        Err(e) => Finding::problem(
            NAME,
            format!("vkEnumeratePhysicalDevices failed: {e}"),
            INSTALL_VULKAN,
        ),
        Ok(d) if d.is_empty() => Finding::problem(NAME, "no Vulkan device", INSTALL_VULKAN),
        Ok(d) => {
            let list: Vec<&str> = d.iter().map(|(t, _)| t.as_str()).collect();
            let detail = format!("{} device(s): {}", d.len(), list.join("; "));
            if d.iter().all(|(_, cpu)| *cpu) {
                Finding::warn(
                    NAME,
                    detail + "; only a software device, too slow for a headset",
                    "install your GPU's Vulkan driver (mesa-vulkan-drivers for AMD and Intel, \
                     the NVIDIA driver for NVIDIA); apps render on their own device",
                )
            } else {
                Finding::ok(NAME, detail)
            }
        }
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
}
