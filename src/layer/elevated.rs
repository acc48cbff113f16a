//! Whether the app runs with privileges its user lacks (setuid, setgid or file capabilities:
//! the kernel's AT_SECURE). Such a process must not trust its environment: the layer's config,
//! log, cache and device paths (`XDG_*`, `HOME`, `CONTRASTXR_*`) would let the user who started
//! it write files, or read devices, with its privileges. The layer then does nothing for it:
//! its instances are the runtime's alone, and one line on stderr says why.

/// The one line the layer writes for an elevated process.
pub const LINE: &str = "this app runs with privileges its user lacks (setuid, \
    setgid or file capabilities): the layer ignores its environment and files, and passes \
    everything through";

/// Whether this process runs elevated (AT_SECURE).
pub fn elevated() -> bool {
    static ELEVATED: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    // SAFETY: getauxval reads the process's auxiliary vector; it has no preconditions.
    *ELEVATED.get_or_init(|| unsafe { libc::getauxval(libc::AT_SECURE) } != 0)
}
