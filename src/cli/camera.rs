//! `contrastxr camera list` and `contrastxr camera test DEVICE [--frames N] [-o DIR]`: how a
//! user checks their camera before putting on the headset.

use super::{Args, CliError, Opt};

pub const OPTIONS: &[Opt] = &[
    Opt::value("--frames", "N"),
    Opt::value("--output", "DIR").short('o'),
];
use contrastxr::camera::cli;
use std::path::PathBuf;

pub fn usage() -> String {
    "usage: contrastxr camera list\n\
     \x20      contrastxr camera test DEVICE [--frames N] [-o DIR]\n\n\
     list: V4L2 capture devices with their formats, sizes and frame rates.\n\
     test: opens DEVICE (/dev/videoN or auto) as the layer would, reports the achieved rate\n\
     and latency, and with -o saves the frames as PNG into DIR.\n"
        .to_string()
}

pub fn run(args: &mut Args) -> Result<(), CliError> {
    let frames = args.value(&["--frames"])?;
    let out_dir = args.value(&["-o", "--output"])?.map(PathBuf::from);
    let rest = args.positional();
    args.finish()?;
    let mut out = std::io::stdout().lock();
    match rest.as_slice() {
        [cmd] if cmd == "list" => cli::list(&mut out).map_err(CliError::Failure),
        [cmd, device] if cmd == "test" => {
            let frames = match frames {
                Some(f) => f
                    .parse()
                    .map_err(|_| CliError::Usage(format!("--frames {f:?} is not a count")))?,
                None => 30,
            };
            cli::test(device, frames, out_dir.as_deref(), &mut out).map_err(CliError::Failure)
        }
        _ => Err(CliError::Usage(
            "expected `camera list` or `camera test DEVICE`".into(),
        )),
    }
}
