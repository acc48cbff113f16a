//! The `contrastxr` subcommands and their dispatcher. Adding a subcommand: a module with
//! `usage() -> String` and `run(&mut Args) -> Result<(), CliError>`, and one line in `COMMANDS`.

mod args;
mod bench;
mod calibrate;
mod camera;
mod config;
mod control;
mod engine;
mod enhance;
mod evaluate;
mod install;
mod options;

pub use args::Args;

/// Why a command failed; decides the exit code.
#[derive(Debug)]
pub enum CliError {
    /// The command line itself is wrong (exit code 2).
    Usage(String),
    /// The command could not do its job: missing file, unreadable PNG, bad value (exit code 1).
    Failure(String),
}

pub type Command = fn(&mut Args) -> Result<(), CliError>;

/// One subcommand of the tool.
pub struct Subcommand {
    pub name: &'static str,
    pub summary: &'static str,
    pub usage: fn() -> String,
    pub run: Command,
}

const COMMANDS: &[Subcommand] = &[
    Subcommand {
        name: "enhance",
        summary: "enhance a display image against a background (camera) image",
        usage: enhance::usage,
        run: enhance::run,
    },
    Subcommand {
        name: "evaluate",
        summary: "measure an enhancement with the paper's metric, write figures, sweep lambda_e",
        usage: evaluate::usage,
        run: evaluate::run,
    },
    Subcommand {
        name: "camera",
        summary: "list V4L2 cameras, or test one as the layer would use it",
        usage: camera::usage,
        run: camera::run,
    },
    Subcommand {
        name: "bench",
        summary: "time the enhancement against a plain copy on a Vulkan device",
        usage: bench::usage,
        run: bench::run,
    },
    Subcommand {
        name: "install",
        summary: "install the OpenXR layer's implicit manifest (enable with CONTRASTXR=1)",
        usage: install::usage,
        run: install::run,
    },
    Subcommand {
        name: "uninstall",
        summary: "remove the OpenXR layer's implicit manifest",
        usage: install::usage,
        run: install::run_uninstall,
    },
    Subcommand {
        name: "config",
        summary: "check a config file, print an app's effective settings, show the path",
        usage: config::usage,
        run: config::run,
    },
    Subcommand {
        name: "toggle",
        summary: "switch running apps between mode off and a mode (through the config file)",
        usage: control::usage,
        run: control::run_toggle,
    },
    Subcommand {
        name: "set",
        summary: "change one setting of running apps, e.g. `set lambda_e 0.6`",
        usage: control::usage,
        run: control::run_set,
    },
    Subcommand {
        name: "calibrate",
        summary: "line the camera's background up with each eye, with keys, while the app runs",
        usage: calibrate::usage,
        run: calibrate::run,
    },
];

fn overview() -> String {
    let mut s = String::from(
        "contrastxr: colour contrast enhanced rendering for optical see-through headsets\n\n\
         usage: contrastxr <command> [options]   (contrastxr <command> --help for its options)\n\n\
         commands:\n",
    );
    for c in COMMANDS {
        s.push_str(&format!("  {:<10} {}\n", c.name, c.summary));
    }
    s
}

/// Runs the command line (without the program name) and returns the process exit code.
pub fn main(argv: Vec<String>) -> i32 {
    let Some(name) = argv.first() else {
        eprint!("{}", overview());
        return 2;
    };
    if name == "--help" || name == "-h" || name == "help" {
        print!("{}", overview());
        return 0;
    }
    let Some(command) = COMMANDS.iter().find(|c| c.name == name) else {
        eprintln!(
            "contrastxr: error: unknown command '{name}'; run `contrastxr --help` for the list."
        );
        return 2;
    };
    let mut args = Args::new(argv[1..].to_vec());
    if args.flag("--help") || args.flag("-h") {
        print!("{}", (command.usage)());
        return 0;
    }
    match (command.run)(&mut args) {
        Ok(()) => 0,
        Err(CliError::Usage(msg)) => {
            eprintln!("contrastxr {name}: error: {msg}");
            eprintln!("run `contrastxr {name} --help` for usage.");
            2
        }
        Err(CliError::Failure(msg)) => {
            eprintln!("contrastxr {name}: error: {msg}");
            1
        }
    }
}

/// Writes to stdout; a reader that went away (`| head`) is not an error worth a panic.
pub fn print(text: &str) {
    use std::io::Write;
    let mut out = std::io::stdout().lock();
    let _ = out.write_all(text.as_bytes()).and_then(|()| out.flush());
}
