//! What a run passed through by the layer must show: the client's images read back as the app
//! wrote them (`--check-untouched`), and one line of the layer's naming why.

use super::{layer_lines, SandboxRun};

/// The client's report says it read back at least 8 frames' images, every one as written.
pub fn assert_untouched(run: &SandboxRun) {
    let report = run.client_report();
    let what = run.describe();
    assert!(report["frames_checked"].as_u64() >= Some(8), "{what}");
    assert_eq!(report["frames_modified"], serde_json::json!([]), "{what}");
}

/// The layer said once that it passes the session through, naming `why`, and nothing about
/// frames it processed or views it registered.
pub fn assert_one_pass_through_line(run: &SandboxRun, why: &str) {
    let what = run.describe();
    let lines = layer_lines(run);
    let passing: Vec<_> = lines.iter().filter(|l| l.contains("passing")).collect();
    assert_eq!(passing.len(), 1, "{what}");
    assert!(passing[0].contains(why), "{why}: {passing:?}");
    assert!(
        !lines.iter().any(|l| l.contains("processing frames")),
        "{what}"
    );
    // A session passed through has no views to register.
    assert!(
        !lines.iter().any(|l| l.contains("camera mapping")),
        "{what}"
    );
}

/// The layer said once that frames pass through while it cannot reach what they need, naming
/// `why`, and that it tries again; it neither passed the session through for good nor
/// processed a frame.
pub fn assert_one_retry_line(run: &SandboxRun, why: &str) {
    let what = run.describe();
    let lines = layer_lines(run);
    let tries: Vec<_> = lines.iter().filter(|l| l.contains("tries again")).collect();
    assert_eq!(tries.len(), 1, "{what}");
    assert!(tries[0].contains(why), "{why}: {tries:?}");
    for never in ["passing", "processing frames", "camera mapping"] {
        assert!(
            !lines.iter().any(|l| l.contains(never)),
            "{never:?}: {what}"
        );
    }
}
