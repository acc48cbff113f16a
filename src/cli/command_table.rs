//! The tool's subcommands: name, summary, usage, options and what runs them.

use super::args::Args;
use super::args::Opt;
use super::error::CliError;
use super::{
    animate, bench, calibrate, camera, completions, config, control, doctor, enhance, evaluate,
    gl_programs, install, log, options, pan,
};

/// One subcommand of the tool.
pub struct Subcommand {
    pub name: &'static str,
    pub summary: &'static str,
    /// Its `--help` text.
    pub usage: fn() -> String,
    pub run: fn(&mut Args) -> Result<(), CliError>,
    /// Every option it reads from [`Args`], in groups (a group can be shared between commands).
    pub options: &'static [&'static [Opt]],
    /// The name of its positional arguments in the help (`KEY VALUE`); None: it takes none.
    pub positionals: Option<&'static str>,
}

const BENCH_OPTIONS: &[Opt] = &[
    Opt::value("--sizes", "WxH,..."),
    Opt::value("--views", "N"),
    Opt::value("--runs", "N"),
    Opt::value("--device", "N"),
    Opt::value("--content", "typical,full"),
    Opt::value("--path", "copy|in-place|both|image-copy|all"),
    Opt::value("--engine", "vulkan|opengl"),
    Opt::value(
        "--ablate",
        "method|background|codec|per-pixel|enhance-pass|shared-fetch|cube-root|directions|bisection|search|classify|all,...",
    ),
    Opt::flag("--json"),
    Opt::flag("--shader-stats"),
    Opt::flag("--compile-only"),
];

pub const COMMANDS: &[Subcommand] = &[
    Subcommand {
        name: "enhance",
        summary: "enhance a display image against a background (camera) image",
        usage: enhance::usage,
        run: enhance::run,
        options: &[
            enhance::OPTIONS,
            options::PPD_OPTIONS,
            options::METHOD_OPTIONS,
            options::ENGINE_OPTIONS,
        ],
        positionals: None,
    },
    Subcommand {
        name: "evaluate",
        summary: "measure an enhancement with the paper's metric, write figures, sweep lambda_e",
        usage: evaluate::usage,
        run: evaluate::run,
        options: &[
            evaluate::OPTIONS,
            options::PPD_OPTIONS,
            options::METHOD_OPTIONS,
            options::ENGINE_OPTIONS,
        ],
        positionals: None,
    },
    Subcommand {
        name: "animate",
        summary: "write an animated figure (APNG) from the layer's captures of consecutive frames",
        usage: animate::usage,
        run: animate::run,
        options: &[animate::OPTIONS, options::METHOD_OPTIONS],
        positionals: None,
    },
    Subcommand {
        name: "pan",
        summary: "write a video: background, PNG frames panning across images side by side",
        usage: pan::usage,
        run: pan::run,
        options: &[pan::OPTIONS],
        positionals: Some("IMAGE..."),
    },
    Subcommand {
        name: "camera",
        summary: "list V4L2 cameras, or test one as the layer would use it",
        usage: camera::usage,
        run: camera::run,
        options: &[camera::OPTIONS],
        positionals: Some("list | test DEVICE"),
    },
    Subcommand {
        name: "bench",
        summary: "time the enhancement against a plain copy on a Vulkan device",
        usage: bench::usage,
        run: bench::run,
        options: &[BENCH_OPTIONS, options::METHOD_OPTIONS],
        positionals: None,
    },
    Subcommand {
        name: "install",
        summary: "install the OpenXR layer for this user, or all (--system); on with CONTRASTXR=1",
        usage: install::usage,
        run: install::run,
        options: &[install::OPTIONS],
        positionals: None,
    },
    Subcommand {
        name: "uninstall",
        summary: "remove what install wrote: the manifest, the library copy and the tool",
        usage: install::usage,
        run: install::run_uninstall,
        options: &[install::SCOPE_OPTIONS],
        positionals: None,
    },
    Subcommand {
        name: "config",
        summary: "check a config file, print an app's effective settings, show the path",
        usage: config::usage,
        run: config::run,
        options: &[control::OPTIONS, config::OPTIONS],
        positionals: Some("check [FILE] | print | path"),
    },
    Subcommand {
        name: "toggle",
        summary: "switch running apps between mode off and a mode (through the config file)",
        usage: control::usage,
        run: control::run_toggle,
        options: &[control::OPTIONS],
        positionals: Some("[MODE]"),
    },
    Subcommand {
        name: "set",
        summary: "change one setting of running apps, e.g. `set lambda_e 0.6`",
        usage: control::usage,
        run: control::run_set,
        options: &[control::OPTIONS],
        positionals: Some("KEY VALUE"),
    },
    Subcommand {
        name: "log",
        summary: "show the layer's log lines of the last app that started it",
        usage: log::usage,
        run: log::run,
        options: &[log::OPTIONS],
        positionals: None,
    },
    Subcommand {
        name: "doctor",
        summary: "check that the layer can work here: manifest, runtime, Vulkan, camera, config",
        usage: doctor::usage,
        run: doctor::run,
        options: &[doctor::OPTIONS],
        positionals: None,
    },
    Subcommand {
        name: "completions",
        summary: "print a shell completion script: bash, zsh, fish, elvish or powershell",
        usage: completions::usage,
        run: completions::run,
        options: &[],
        positionals: Some("SHELL"),
    },
    Subcommand {
        name: "gl-programs",
        summary: "build an OpenGL app's programs into the caches ahead of time",
        usage: gl_programs::usage,
        run: gl_programs::run,
        options: &[gl_programs::OPTIONS, options::METHOD_OPTIONS],
        positionals: None,
    },
    Subcommand {
        name: "calibrate",
        summary: "line the camera's background up with each eye, with keys, while the app runs",
        usage: calibrate::usage,
        run: calibrate::run,
        options: &[calibrate::OPTIONS],
        positionals: None,
    },
];
