//! Why Vulkan lists only a software device: the GPUs the kernel drives (their DRM render nodes,
//! as sysfs shows them), whether this user may open them, and which Vulkan drivers are
//! installed. The fix follows from that: no GPU at all, a variable limiting the loader, a
//! device node the user cannot open, or a missing or unusable driver for the GPU.

use super::finding::var;
use std::os::unix::fs::MetadataExt;
use std::path::{Path, PathBuf};

/// Whether this user can open a render node for reading and writing, as Vulkan drivers do.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Access {
    Open,
    /// Refused; the group that owns the node, when known.
    Denied(Option<String>),
    /// sysfs shows the GPU, but no node under /dev/dri (a container without it).
    Missing,
}

/// A GPU the kernel drives: its render node and the kernel driver's name.
#[derive(Clone, Debug)]
pub struct RenderNode {
    pub node: PathBuf,
    /// `amdgpu`, `i915`, `nvidia`, ...; None when sysfs does not say.
    pub driver: Option<String>,
    pub access: Access,
}

/// Where sysfs is: `$CONTRASTXR_SYSFS_ROOT` (tests) or `/sys`, as for the cameras.
fn sysfs() -> PathBuf {
    var("CONTRASTXR_SYSFS_ROOT").map_or_else(|| PathBuf::from("/sys"), PathBuf::from)
}

/// The name of group `gid` in /etc/group.
fn group_name(gid: u32) -> Option<String> {
    let text = std::fs::read_to_string("/etc/group").ok()?;
    text.lines().find_map(|l| {
        let mut fields = l.split(':');
        let name = fields.next()?;
        (fields.nth(1)?.parse::<u32>().ok()? == gid).then(|| name.to_string())
    })
}

fn access(node: &Path) -> Access {
    let opened = std::fs::OpenOptions::new()
        .read(true)
        .write(true)
        .open(node);
    match opened {
        Ok(_) => Access::Open,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Access::Missing,
        Err(_) => Access::Denied(
            std::fs::metadata(node)
                .ok()
                .and_then(|m| group_name(m.gid())),
        ),
    }
}

/// The render nodes sysfs lists under `class/drm`, in name order.
pub fn render_nodes() -> Vec<RenderNode> {
    let Ok(entries) = std::fs::read_dir(sysfs().join("class/drm")) else {
        return Vec::new();
    };
    let mut names: Vec<String> = entries
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with("renderD"))
        .collect();
    names.sort();
    names
        .into_iter()
        .map(|name| {
            let driver =
                std::fs::read_link(sysfs().join("class/drm").join(&name).join("device/driver"))
                    .ok()
                    .and_then(|l| Some(l.file_name()?.to_string_lossy().into_owned()));
            let node = Path::new("/dev/dri").join(&name);
            let access = access(&node);
            RenderNode {
                node,
                driver,
                access,
            }
        })
        .collect()
}

/// The file names of the installed Vulkan driver manifests (`radeon_icd.x86_64.json`, ...).
pub fn vulkan_drivers() -> Vec<String> {
    let mut dirs = vec![
        PathBuf::from("/etc/vulkan/icd.d"),
        PathBuf::from("/usr/local/share/vulkan/icd.d"),
        PathBuf::from("/usr/share/vulkan/icd.d"),
    ];
    if let Some(data) = var("XDG_DATA_HOME") {
        dirs.push(Path::new(&data).join("vulkan/icd.d"));
    }
    dirs.iter()
        .filter_map(|d| std::fs::read_dir(d).ok())
        .flatten()
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .collect()
}

/// A variable that limits the Vulkan loader to the drivers it names, and its value.
pub fn driver_override() -> Option<(&'static str, String)> {
    ["VK_DRIVER_FILES", "VK_ICD_FILENAMES"]
        .into_iter()
        .find_map(|name| var(name).map(|v| (name, v)))
}

/// What to say, after the device list, when Vulkan lists only software devices, and the fix:
/// one that gives Vulkan a GPU device when followed, or, with no GPU here, says so.
pub fn software_only(
    nodes: &[RenderNode],
    drivers: &[String],
    limited: Option<(&str, String)>,
) -> (String, String) {
    const NO_GPU: &str = "; no GPU device, only a software one: too slow for a headset";
    let Some(first) = nodes.first() else {
        return (
            format!("{NO_GPU} (and no GPU here: sysfs shows no DRM render node)"),
            "none to install: this machine has no GPU the kernel drives; run the app on one \
             that has (the layer uses the app's own Vulkan device)"
                .into(),
        );
    };
    if let Some((name, value)) = limited {
        return (
            NO_GPU.into(),
            format!("unset {name}: it limits the Vulkan loader to {value}"),
        );
    }
    let has = |prefix: &str| drivers.iter().any(|d| d.starts_with(prefix));
    let node = first.node.display();
    let fix = match (&first.access, first.driver.as_deref()) {
        (Access::Denied(Some(group)), _) => format!(
            "your user cannot open {node}: add it to the group {group} (`sudo usermod -aG \
             {group} $USER`), then log in again"
        ),
        (Access::Denied(None), _) => {
            format!("your user cannot open {node}: give it read and write access")
        }
        (Access::Missing, _) => format!(
            "{node} is missing though the kernel drives a GPU: in a container, pass /dev/dri \
             into it"
        ),
        (Access::Open, Some(kernel @ ("amdgpu" | "radeon" | "i915" | "xe"))) => {
            let icd = if kernel.starts_with('a') || kernel == "radeon" {
                "radeon_icd"
            } else {
                "intel"
            };
            if has(icd) {
                format!(
                    "Mesa's Vulkan driver for this {kernel} GPU is installed but offers no \
                     device (`vulkaninfo --summary` says why): a Mesa older than the GPU is the \
                     usual cause; update Mesa"
                )
            } else {
                format!(
                    "install Mesa's Vulkan driver for this {kernel} GPU: `sudo apt install \
                     mesa-vulkan-drivers`"
                )
            }
        }
        (Access::Open, Some("nvidia")) if has("nvidia") => {
            "NVIDIA's Vulkan driver is installed but offers no device: its version must match \
             the kernel module's (`nvidia-smi` says if not); reboot after an update"
                .into()
        }
        (Access::Open, Some("nvidia")) => {
            "install the Vulkan part of NVIDIA's driver (its nvidia_icd.json; on Debian the \
             nvidia-vulkan-icd package, from non-free)"
                .into()
        }
        (Access::Open, Some("nouveau")) if !has("nouveau") => {
            "the nouveau kernel driver has no Vulkan driver in this Mesa (NVK came with Mesa \
             24.1): install NVIDIA's own driver, or a newer Mesa"
                .into()
        }
        (Access::Open, driver) => format!(
            "install the Vulkan driver of this GPU's vendor (kernel driver {}); \
             `vulkaninfo --summary` says which drivers the loader tried",
            driver.unwrap_or("unknown")
        ),
    };
    (NO_GPU.into(), fix)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn node(driver: Option<&str>, access: Access) -> RenderNode {
        RenderNode {
            node: PathBuf::from("/dev/dri/renderD128"),
            driver: driver.map(str::to_string),
            access,
        }
    }

    /// The Debian 12 host with lavapipe only: mesa-vulkan-drivers is what supplies it.
    const MESA: [&str; 4] = [
        "intel_hasvk_icd.x86_64.json",
        "intel_icd.x86_64.json",
        "lvp_icd.x86_64.json",
        "radeon_icd.x86_64.json",
    ];

    fn mesa() -> Vec<String> {
        MESA.iter().map(|s| s.to_string()).collect()
    }

    #[test]
    fn no_gpu_says_so_and_installs_nothing() {
        let (detail, fix) = software_only(&[], &mesa(), None);
        assert!(detail.contains("no GPU device"), "{detail}");
        assert!(detail.contains("no GPU here"), "{detail}");
        assert!(!fix.contains("install mesa"), "{fix}");
        assert!(!fix.contains("apt"), "{fix}");
        // Also when a variable limits the loader: there is no GPU to let through.
        let (_, fix) = software_only(&[], &mesa(), Some(("VK_ICD_FILENAMES", "x".into())));
        assert!(fix.starts_with("none to install"), "{fix}");
    }

    #[test]
    fn each_cause_gets_its_own_fix() {
        let open = |d| vec![node(Some(d), Access::Open)];
        let limited = Some(("VK_ICD_FILENAMES", "/x/lvp_icd.json".to_string()));
        let (_, fix) = software_only(&open("amdgpu"), &mesa(), limited);
        assert_eq!(
            fix,
            "unset VK_ICD_FILENAMES: it limits the Vulkan loader to /x/lvp_icd.json"
        );
        let denied = [node(Some("i915"), Access::Denied(Some("render".into())))];
        let (_, fix) = software_only(&denied, &mesa(), None);
        assert!(fix.contains("`sudo usermod -aG render $USER`"), "{fix}");
        let missing = [node(Some("i915"), Access::Missing)];
        assert!(software_only(&missing, &mesa(), None)
            .1
            .contains("/dev/dri"));
        // Mesa's driver for the GPU installed already: not "install mesa-vulkan-drivers".
        let (_, fix) = software_only(&open("amdgpu"), &mesa(), None);
        assert!(!fix.contains("apt install"), "{fix}");
        assert!(fix.contains("update Mesa"), "{fix}");
        let lvp_only = vec!["lvp_icd.x86_64.json".to_string()];
        let (_, fix) = software_only(&open("i915"), &lvp_only, None);
        assert!(
            fix.contains("`sudo apt install mesa-vulkan-drivers`"),
            "{fix}"
        );
        let (_, fix) = software_only(&open("nvidia"), &mesa(), None);
        assert!(fix.contains("nvidia-vulkan-icd"), "{fix}");
        let with_nvidia = [mesa(), vec!["nvidia_icd.json".into()]].concat();
        let (_, fix) = software_only(&open("nvidia"), &with_nvidia, None);
        assert!(fix.contains("nvidia-smi"), "{fix}");
        assert!(software_only(&open("nouveau"), &mesa(), None)
            .1
            .contains("NVK"));
    }
}
