//! The project's XR client with an OpenGL session, as the OpenGL tests run it.

use super::{sandbox, SandboxRun, XR_CLIENT};

/// Each view's size in these runs.
pub const GL_VIEW: (u64, u64) = (96, 72);

/// The client with an OpenGL session (`--graphics opengl`: the Xlib binding on a GLX 4.5 core
/// context, in the sandbox's X server) of `frames` frames of GL_VIEW views in `format` (the
/// client's Vulkan-style name), with `extra` arguments, through the layer with `env`, for at
/// most `timeout_s`; None without the sandbox.
pub fn client_opengl(
    format: &str,
    frames: u32,
    env: &[(&str, &str)],
    extra: &[&str],
    timeout_s: u64,
) -> Option<SandboxRun> {
    let sandbox = sandbox()?;
    let size = format!("{}x{}", GL_VIEW.0, GL_VIEW.1);
    let frames = frames.to_string();
    let mut cmd = vec![
        XR_CLIENT,
        "--graphics",
        "opengl",
        "--json",
        "--frames",
        &frames,
        "--size",
        &size,
        "--format",
        format,
    ];
    cmd.extend_from_slice(extra);
    Some(sandbox.run_x11_for(&cmd, env, timeout_s))
}
