//! The one place camera messages go. The capture threads log state changes once each; the lead
//! can redirect the sink (e.g. into the layer's log file) with [`set_log_sink`].

use std::sync::OnceLock;

type Sink = Box<dyn Fn(&str) + Send + Sync>;

static SINK: OnceLock<Sink> = OnceLock::new();

/// Sends camera messages to `sink` instead of stderr. Only the first call takes effect.
pub fn set_log_sink(sink: Box<dyn Fn(&str) + Send + Sync>) {
    let _ = SINK.set(sink);
}

pub(crate) fn log(message: &str) {
    match SINK.get() {
        Some(sink) => sink(message),
        None => eprintln!("contrastxr: camera: {message}"),
    }
}
