//! Resident memory and open files over many session cycles (the client's `--sessions` report):
//! what tells a leak, which grows with every session, from one-off steps and glibc's arenas.

use serde_json::Value;

/// One sample of the client's report: resident memory and malloc's heap in use (KiB), and
/// open file descriptors.
#[derive(Clone, Copy, Debug)]
pub struct Sample {
    pub rss_kb: u64,
    pub heap_kb: u64,
    pub fds: u64,
}

/// The samples in `field` of the client's report (`sessions`: after each session; `memory`:
/// every 50 frames).
pub fn samples(report: &Value, field: &str) -> Vec<Sample> {
    let number = |s: &Value, key: &str| s[key].as_u64().unwrap_or_else(|| panic!("no {key}"));
    report[field]
        .as_array()
        .unwrap_or_else(|| panic!("no {field} samples in the client's report"))
        .iter()
        .map(|s| Sample {
            rss_kb: number(s, "rss_kb"),
            heap_kb: number(s, "heap_kb"),
            fds: number(s, "fds"),
        })
        .collect()
}

/// The growth of `value` over 100 sessions in four parts of 25, each part counted by its least
/// sample: from each part's floor to the next one's. A leak grows with every session and raises
/// each floor by what 25 sessions leak; a one-off step (a cache's first fill, the first
/// sessions' warm-up) raises one difference.
fn growth_by_parts(sessions: &[Sample], value: impl Fn(&Sample) -> u64) -> Vec<u64> {
    let floors: Vec<u64> = sessions
        .chunks(25)
        .map(|part| part.iter().map(&value).min().unwrap_or(0))
        .collect();
    floors
        .windows(2)
        .map(|w| w[1].saturating_sub(w[0]))
        .collect()
}

/// Checks 100 sessions by the growth between the floors of four parts ([`growth_by_parts`]):
/// - malloc's heap in use: a leak of 10 KiB per session or more grows each part by 256 KiB
///   (with the layer, parts after the first grow by 10-135 KiB on lavapipe and llvmpipe; a
///   64 KiB-per-session leak grows each by 1,600 KiB). Resident memory alone misses such a
///   leak: the leaked blocks fill the holes freed blocks left, and it stays flat.
/// - resident memory, for what is not malloc's (the driver's mappings): the least part grows
///   by less than 8 MiB (a leak of 330 KiB per session or more fails), and no step between
///   sessions reaches 16 MiB. Resident memory swings between two levels 4 MiB apart from
///   session to session on llvmpipe, so a part may gain 4 MiB and more without a leak;
/// - open files end where they began.
///
/// `what` names the run in the failure messages and the printed line.
#[track_caller]
pub fn assert_flat(what: &str, sessions: &[Sample]) {
    assert_eq!(sessions.len(), 100, "{what}: {sessions:?}");
    let heap = growth_by_parts(sessions, |s| s.heap_kb);
    let rss = growth_by_parts(sessions, |s| s.rss_kb);
    let largest_step = sessions[24..]
        .windows(2)
        .map(|w| w[1].rss_kb.saturating_sub(w[0].rss_kb))
        .max()
        .unwrap_or(0);
    let (warm, end) = (sessions[24], sessions[99]);
    eprintln!(
        "{what}: after 25 and 100 sessions: heap in use {} and {} KiB, resident {} and {} KiB; \
         growth by parts of 25: heap {heap:?} KiB, resident {rss:?} KiB, largest step \
         {largest_step} KiB",
        warm.heap_kb, end.heap_kb, warm.rss_kb, end.rss_kb
    );
    let least = |parts: &[u64]| parts.iter().copied().min().unwrap_or(0);
    assert!(
        least(&heap) < 256,
        "{what}: the heap in use grew in every 25 sessions ({heap:?} KiB): {sessions:?}"
    );
    assert!(
        least(&rss) < 8192,
        "{what}: resident memory grew in every 25 sessions ({rss:?} KiB): {sessions:?}"
    );
    assert!(
        largest_step < 16384,
        "{what}: resident memory jumped: {sessions:?}"
    );
    // A sample may count a file held for a moment (the log's writer thread keeps the log file
    // open until 200 ms after its last line, src/layer/log_file.rs; seen: 12 once among 11s).
    // A leak leaves every later sample higher; a file held for a moment does not.
    let first = sessions[0].fds;
    let late = sessions[90..].iter().map(|s| s.fds).min();
    assert_eq!(
        late,
        Some(first),
        "{what}: file descriptors leaked: {sessions:?}"
    );
    assert!(
        sessions.iter().all(|s| s.fds <= first + 1),
        "{what}: file descriptors: {sessions:?}"
    );
}
