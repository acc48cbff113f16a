//! The call-semantics A/B of the client's `--script` mode (tests/call_semantics.rs for Vulkan
//! sessions, tests/opengl_client.rs for OpenGL ones): the scripted cases with the answer each must
//! reach and the frames the layer enhances in it, the scripts' answers from a run's report, and
//! the frames the layer enhanced from its captures.

use super::SandboxRun;
use std::collections::BTreeSet;
use std::path::Path;

/// A script (the client's `--script` ops), an answer it must contain (so the run reached the case
/// it is about), and the frames the layer enhances with it (why, in the comment of each case).
#[derive(Clone, Copy, Debug)]
pub struct Case {
    pub script: &'static str,
    pub answer: &'static str,
    pub enhanced: usize,
}

/// Nothing acquired: the runtime refuses; nothing to enhance.
pub const RELEASE_WITHOUT_ACQUIRE: Case = Case {
    script: "release",
    answer: "release ERROR_CALL_ORDER_INVALID",
    enhanced: 0,
};
/// Nothing acquired, as above.
pub const WAIT_WITHOUT_ACQUIRE: Case = Case {
    script: "wait",
    answer: "wait ERROR_CALL_ORDER_INVALID",
    enhanced: 0,
};
/// The first release is refused (not waited); the second is held, then dropped with the
/// swapchain when the script ends (never submitted).
pub const RELEASE_WITHOUT_WAIT: Case = Case {
    script: "acquire,release,wait,release",
    answer: "release ERROR_CALL_ORDER_INVALID",
    enhanced: 0,
};
pub const DOUBLE_WAIT: Case = Case {
    script: "acquire,wait,wait,release",
    answer: "wait ERROR_CALL_ORDER_INVALID",
    enhanced: 0,
};
/// The held release goes to the runtime (enhanced) before the second, which it refuses.
pub const DOUBLE_RELEASE: Case = Case {
    script: "acquire,wait,release,release",
    answer: "release ERROR_CALL_ORDER_INVALID",
    enhanced: 1,
};
/// Waiting again after a (held) release: refused with and without the layer.
pub const WAIT_AFTER_RELEASE: Case = Case {
    script: "acquire,wait,release,wait",
    answer: "wait ERROR_CALL_ORDER_INVALID",
    enhanced: 0,
};
/// Monado has 3 images: the 4th acquire is refused. The first two releases come while
/// later images are acquired (enhanced at once); the last is held and dropped.
pub const ACQUIRE_PAST_THE_IMAGE_COUNT: Case = Case {
    script: "acquire,acquire,acquire,acquire,wait,release,wait,release,wait,release",
    answer: "acquire ERROR_CALL_ORDER_INVALID",
    enhanced: 2,
};
pub const RELEASE_AFTER_THE_NEXT_ACQUIRE: Case = Case {
    script: "acquire,acquire,wait,release,wait,release",
    answer: "release SUCCESS",
    enhanced: 1,
};
/// The held image dies with its swapchain; the new swapchain's frame is enhanced.
pub const DESTROY_WITH_A_HELD_IMAGE: Case = Case {
    script: "begin,acquire,wait,release,destroy,create,acquire,wait,release,end",
    answer: "destroy SUCCESS",
    enhanced: 1,
};
/// The discarded frame's held image goes (enhanced) when the next is acquired.
pub const RELEASE_ACROSS_A_DISCARDED_FRAME: Case = Case {
    script: "begin,acquire,wait,release,begin,acquire,wait,release,end",
    answer: "begin FRAME_DISCARDED",
    enhanced: 2,
};
pub const PLAIN_FRAMES: Case = Case {
    script: "begin,acquire,wait,release,end,begin,acquire,wait,release,end",
    answer: "end SUCCESS",
    enhanced: 2,
};
/// Each next image is acquired and waited before xrEndFrame of the current frame.
pub const PIPELINED_FRAMES: Case = Case {
    script: "begin,acquire,wait,release,acquire,wait,end,begin,release,acquire,wait,end,begin,release,end",
    answer: "end SUCCESS",
    enhanced: 3,
};
/// A frame ended with the image still acquired: the runtime refuses the layer (not released).
pub const END_WITHOUT_RELEASE: Case = Case {
    script: "begin,acquire,wait,end,release,end-empty",
    answer: "end ERROR_",
    enhanced: 0,
};
/// Without environment_blend_mode the runtime's blend modes stand, in every call form.
pub const BLEND_MODES_UNTOUCHED: Case = Case {
    script: "blend-count,blend-short,blend-fill,blend-bad-view",
    answer: "blend-fill SUCCESS",
    enhanced: 0,
};
/// The runtime refuses the ADDITIVE frame; the layer had enhanced its released image (it
/// acts before the runtime answers), and the app gets the runtime's error.
pub const ADDITIVE_FRAMES_REFUSED: Case = Case {
    script: "begin,acquire,wait,release,end-additive",
    answer: "end-additive ERROR_",
    enhanced: 1,
};

/// The layer's processed frames, from the capture files' names (`frame-<n>-view-<k>...`).
pub fn enhanced_frames(dir: &Path) -> usize {
    let frames: BTreeSet<String> = std::fs::read_dir(dir)
        .unwrap()
        .filter_map(|e| e.ok())
        .filter_map(|e| {
            let name = e.file_name().to_string_lossy().into_owned();
            name.strip_prefix("frame-")
                .and_then(|rest| rest.split('-').next())
                .map(String::from)
        })
        .collect();
    frames.len()
}

/// The `path` of every captured view (how the layer enhanced it).
pub fn capture_paths(dir: &Path) -> Vec<String> {
    std::fs::read_dir(dir)
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.path().extension().is_some_and(|x| x == "json"))
        .map(|e| {
            let text = std::fs::read_to_string(e.path()).unwrap();
            let json: serde_json::Value = serde_json::from_str(&text).unwrap();
            json["path"].as_str().unwrap_or("?").to_string()
        })
        .collect()
}

pub fn script_of(run: &SandboxRun) -> Vec<String> {
    let report = run.client_report();
    assert_eq!(report["ok"], true, "{}", run.describe());
    report["script"]
        .as_array()
        .unwrap_or_else(|| panic!("no script results: {report}"))
        .iter()
        .map(|v| v.as_str().unwrap().to_string())
        .collect()
}

/// The A/B itself: `off` and `on` answered every op of `case` alike, and reached its answer.
pub fn assert_same_answers(
    tag: &str,
    case: Case,
    off: &SandboxRun,
    on: &SandboxRun,
) -> Vec<String> {
    let (bare, layered) = (script_of(off), script_of(on));
    assert_eq!(
        bare, layered,
        "{tag}: the layer changed what the calls returned (left: off, right: on)"
    );
    assert_eq!(
        bare.len(),
        case.script.split(',').count(),
        "{tag}: {bare:?}"
    );
    // The script reached the case it is about (the runtime's answer is the expected one).
    assert!(
        bare.iter().any(|r| r.contains(case.answer)),
        "{tag}: no call answered {}: {bare:?}",
        case.answer
    );
    bare
}
