//! What is left of the layer after the last xrDestroyInstance (`--linger-ms`): its threads (all
//! named `contrastxr-...`) and whether its library is still mapped into the process.

use serde::Serialize;

#[derive(Serialize, Debug, Default)]
pub struct Leftovers {
    /// The names of the layer's threads still running.
    pub layer_threads: Vec<String>,
    /// libcontrastxr.so is still mapped.
    pub layer_mapped: bool,
}

/// This thread's own name (the program's, cut to 15 bytes), which the client's threads share.
fn own_name() -> String {
    std::fs::read_to_string("/proc/thread-self/comm").map_or(String::new(), |n| n.trim().into())
}

pub fn look() -> Leftovers {
    let own = own_name();
    let tasks = std::fs::read_dir("/proc/self/task")
        .into_iter()
        .flatten()
        .flatten();
    let layer_threads = tasks
        .filter_map(|t| std::fs::read_to_string(t.path().join("comm")).ok())
        .map(|n| n.trim().to_string())
        .filter(|n| n.starts_with("contrastxr-") && *n != own)
        .collect();
    let maps = std::fs::read_to_string("/proc/self/maps").unwrap_or_default();
    Leftovers {
        layer_threads,
        layer_mapped: maps.contains("libcontrastxr.so"),
    }
}
