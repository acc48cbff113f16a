//! Named fault points for the hardening tests: `CONTRASTXR_FAULT=NAME` (or `NAME@N`, to fire
//! from the N-th time the point is reached on, counting from 0, or `NAME@N..M`, to fire from
//! the N-th time up to the M-th, not included: a failure that passes) makes that point fail as
//! the real failure would. The variable is read once; with it unset a fault point costs one
//! atomic load and a branch, so the calls stay in release builds.
//!
//! Points: `device-setup`, `pipeline-creation`, `allocation`, `image-capture`, `camera-open`,
//! `camera-loss`, `end-frame`, `queue-without-compute`, `build-panic`,
//! `destroy-bookkeeping`, `warm-up-device`, `device-lost`, `swapchain-wait`, `slow-build`,
//! `gl-program-link`, `gl-make-current`, `gl-old-context`, `gl-context-lost`,
//! `gl-program-thread`, `gl-program-build`, `gl-recipe-panic`, `gl-driver-message`,
//! `stalled-file-system`, `short-minute`, `write-back-build`
//! (see [`POINTS`]). This module must not depend on anything else in the crate.

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::OnceLock;

/// Every fault point, with where it fires.
pub const POINTS: [(&str, &str); 25] = [
    (
        "device-setup",
        "wrapping the app's Vulkan device (GpuDevice::borrow)",
    ),
    ("pipeline-creation", "building the compute pipelines"),
    ("allocation", "allocating GPU memory for a buffer"),
    (
        "image-capture",
        "copying a view out of the app's swapchain image",
    ),
    ("camera-open", "opening the background source"),
    (
        "camera-loss",
        "taking the newest background frame (the source is lost)",
    ),
    (
        "queue-without-compute",
        "checking the app's queue family for compute support (as if it had none)",
    ),
    (
        "build-panic",
        "a panic while building a shader pipeline on the pipeline thread",
    ),
    (
        "destroy-bookkeeping",
        "a panic in the layer's own part of xrDestroySwapchain, xrDestroySession and xrDestroyInstance",
    ),
    (
        "warm-up-device",
        "making a CPU driver's warm-up device (gpu/vulkan/frame/warm_up.rs)",
    ),
    (
        "device-lost",
        "the fence wait at the session's end (xrDestroySession) fails with VK_ERROR_DEVICE_LOST",
    ),
    (
        "swapchain-wait",
        "the fence wait in xrDestroySwapchain fails",
    ),
    (
        "slow-build",
        "a CPU driver's warm-up compile takes 5 s more (longer than any wait of the session's end)",
    ),
    (
        "gl-program-link",
        "linking an OpenGL program (linked with a second copy of its shader, so the driver refuses it)",
    ),
    (
        "gl-make-current",
        "making the app's OpenGL context current on the frame's thread (as if it were current on another)",
    ),
    (
        "gl-old-context",
        "reading the app's OpenGL context's version (as if it were OpenGL 3.3, without compute shaders)",
    ),
    (
        "gl-context-lost",
        "checking the app's OpenGL context before the frame's work (as if it were lost)",
    ),
    (
        "gl-program-thread",
        "starting the thread that builds an OpenGL app's programs off its threads",
    ),
    (
        "gl-program-build",
        "the build of an OpenGL app's programs off its threads (it ends without them)",
    ),
    (
        "gl-recipe-panic",
        "a panic inside the OpenGL recipe, with the layer's framebuffer bound in the app's context",
    ),
    (
        "gl-driver-message",
        "the driver sends a debug message about the OpenGL recipe's work (one inserted as a third party's while the recipe runs)",
    ),
    (
        "stalled-file-system",
        "every look-up or open of a user's file (config, device profiles, backgrounds, capture files) takes 2 s, as on a hung network or FUSE mount",
    ),
    (
        "end-frame",
        "a panic in the layer's xrEndFrame after the frame's images were enhanced and held",
    ),
    (
        "write-back-build",
        "building the image-copy path's write-back (copy_back = \"tiles\", copy_in = \"sampled\") for a format",
    ),
    (
        "short-minute",
        "the out-of-reach check's minute (its read-back of the views and the least time between its lines) lasts 2 s; no failure",
    ),
];

/// The armed point and the hits at which it fires: from `from_hit` up to `until_hit`, not
/// included.
struct Armed {
    name: String,
    from_hit: u64,
    until_hit: u64,
    hits: AtomicU64,
}

fn parse(spec: &str) -> Option<Armed> {
    let spec = spec.trim();
    let (name, hits) = match spec.split_once('@') {
        Some((name, hits)) => (name, hits.trim()),
        None => (spec, "0"),
    };
    let (from_hit, until_hit) = match hits.split_once("..") {
        Some((from, until)) => (from.trim().parse().ok()?, until.trim().parse().ok()?),
        None => (hits.parse().ok()?, u64::MAX),
    };
    (!name.is_empty() && from_hit < until_hit).then(|| Armed {
        name: name.trim().to_string(),
        from_hit,
        until_hit,
        hits: AtomicU64::new(0),
    })
}

impl Armed {
    /// Counts a hit: whether it is one at which the point fails.
    fn fires(&self) -> bool {
        let hit = self.hits.fetch_add(1, Ordering::Relaxed);
        (self.from_hit..self.until_hit).contains(&hit)
    }
}

fn armed() -> Option<&'static Armed> {
    static ARMED: OnceLock<Option<Armed>> = OnceLock::new();
    ARMED
        .get_or_init(|| {
            std::env::var("CONTRASTXR_FAULT")
                .ok()
                .and_then(|v| parse(&v))
        })
        .as_ref()
}

/// True when the fault point `name` must fail now.
pub fn hit(name: &str) -> bool {
    match armed() {
        Some(a) if a.name == name => a.fires(),
        _ => false,
    }
}

/// The armed point and how often it was reached so far (None when none is armed): the layer
/// says so at xrDestroyInstance, for the tests that count how often a failure is retried.
pub fn reached() -> Option<(&'static str, u64)> {
    armed().map(|a| (a.name.as_str(), a.hits.load(Ordering::Relaxed)))
}

/// Pause points: no failure, a short sleep that widens a race window, for the tests that race
/// two threads through the layer (`CONTRASTXR_FAULT=NAME` arms one as it arms a fault point).
pub const PAUSES: [(&str, &str); 1] = [(
    "release-held",
    "at xrEndFrame, between listing the swapchains and locking each to hand over its release",
)];

/// Sleeps a few milliseconds when the pause point `name` is armed.
pub fn pause(name: &str) {
    if hit(name) {
        std::thread::sleep(std::time::Duration::from_millis(3));
    }
}

/// `Err` with the text an injected fault carries (so its one log line names it) when the
/// fault point `name` must fail now. Call sites stay one line:
/// `crate::fault::check("allocation").map_err(GpuError::Unsupported)?;`
pub fn check(name: &str) -> Result<(), String> {
    if hit(name) {
        Err(format!("fault injected at {name} (CONTRASTXR_FAULT)"))
    } else {
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_name_and_first_hit() {
        let a = parse(" camera-loss@10 ").unwrap();
        assert_eq!((a.name.as_str(), a.from_hit), ("camera-loss", 10));
        assert_eq!(a.until_hit, u64::MAX);
        assert_eq!(parse("allocation").unwrap().from_hit, 0);
        let passing = parse("gl-make-current@2..5").unwrap();
        assert_eq!((passing.from_hit, passing.until_hit), (2, 5));
        assert!(parse("").is_none());
        assert!(parse("x@many").is_none());
        assert!(parse("x@5..5").is_none());
        assert!(parse("x@1..").is_none());
    }

    #[test]
    fn fires_only_at_the_hits_named() {
        let fired = |spec: &str| -> Vec<bool> {
            let a = parse(spec).unwrap();
            (0..7).map(|_| a.fires()).collect()
        };
        let (t, f) = (true, false);
        assert_eq!(fired("p"), [t, t, t, t, t, t, t]);
        assert_eq!(fired("p@3"), [f, f, f, t, t, t, t]);
        assert_eq!(fired("p@2..5"), [f, f, t, t, t, f, f]);
    }
}
