//! How a command ends: its error (which decides the exit code) and its output.

/// Why a command failed; decides the exit code.
#[derive(Debug)]
pub enum CliError {
    /// The command line itself is wrong (exit code 2).
    Usage(String),
    /// The command could not do its job: missing file, unreadable PNG, bad value (exit code 1).
    Failure(String),
}

/// Writes to stdout; a reader that went away (`| head`) is not an error worth a panic.
pub fn print(text: &str) {
    use std::io::Write;
    let mut out = std::io::stdout().lock();
    let _ = out.write_all(text.as_bytes()).and_then(|()| out.flush());
}
