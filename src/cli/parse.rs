//! The whole command line on clap: the subcommands and their declared options become one
//! `clap::Command` (which also gives `--version` and the shell completions); its errors are
//! turned into the tool's one-sentence form with exit code 2.

use super::args::{positionals_arg, Args};
use super::command_table::{Subcommand, COMMANDS};
use super::error::CliError;
use clap::error::{ContextKind, ContextValue, ErrorKind};

fn overview() -> String {
    let mut s = format!(
        "contrastxr {}: colour contrast enhanced rendering for optical see-through headsets\n\n\
         usage: contrastxr <command> [options]   (contrastxr <command> --help for its options)\n\
         \x20      contrastxr --version\n\n\
         commands:\n",
        env!("CARGO_PKG_VERSION")
    );
    for c in COMMANDS {
        s.push_str(&format!("  {:<12} {}\n", c.name, c.summary));
    }
    s
}

fn subcommand(c: &Subcommand) -> clap::Command {
    let mut cmd = clap::Command::new(c.name)
        .about(c.summary)
        .override_help((c.usage)())
        // `--lambda-e 0.3 --lambda-e 0.5`: the last one wins, as with most tools.
        .args_override_self(true)
        .args(c.options.iter().flat_map(|g| g.iter()).map(|o| o.arg()));
    if let Some(name) = c.positionals {
        cmd = cmd.arg(positionals_arg(name));
    }
    cmd
}

/// The tool's whole command line, for parsing and for the completion scripts.
pub fn command() -> clap::Command {
    clap::Command::new("contrastxr")
        .version(env!("CARGO_PKG_VERSION"))
        .about("colour contrast enhanced rendering for optical see-through headsets")
        .override_help(overview())
        .subcommand_required(true)
        .disable_help_subcommand(true)
        .subcommands(COMMANDS.iter().map(subcommand))
}

/// The offending argument of a parse error, when clap names one.
fn context(e: &clap::Error, kind: ContextKind) -> Option<String> {
    match e.get(kind)? {
        ContextValue::String(s) => Some(s.clone()),
        ContextValue::Strings(v) => v.first().cloned(),
        _ => None,
    }
}

fn looks_negative(arg: &str) -> bool {
    arg.strip_prefix('-')
        .is_some_and(|r| r.starts_with(|c: char| c.is_ascii_digit() || c == '.'))
}

/// A clap error as one sentence in the tool's words.
fn sentence(e: &clap::Error) -> String {
    let arg = context(e, ContextKind::InvalidArg);
    match (e.kind(), arg) {
        (ErrorKind::UnknownArgument, Some(a)) if looks_negative(&a) => format!(
            "unknown option {a}: a value starting with '-' goes after `--`, or as KEY=VALUE"
        ),
        (ErrorKind::UnknownArgument, Some(a)) if a.starts_with('-') => {
            format!("unknown option {a}")
        }
        (ErrorKind::UnknownArgument, Some(a)) => format!("unexpected argument '{a}'"),
        (ErrorKind::InvalidValue, Some(a))
            if context(e, ContextKind::InvalidValue).is_none_or(|v| v.is_empty()) =>
        {
            format!(
                "{} needs a value",
                a.split_whitespace().next().unwrap_or(&a)
            )
        }
        _ => {
            let text = e.render().to_string();
            let first = text.lines().next().unwrap_or("invalid command line");
            first.trim_start_matches("error: ").to_string()
        }
    }
}

/// Runs the command line (without the program name) and returns the process exit code.
pub fn main(argv: Vec<String>) -> i32 {
    let Some(first) = argv.first() else {
        eprint!("{}", overview());
        return 2;
    };
    if first == "help" {
        super::error::print(&overview());
        return 0;
    }
    let name = COMMANDS
        .iter()
        .find(|c| c.name == first)
        .map(|c| c.name)
        .unwrap_or_default();
    let parsed = command().try_get_matches_from(std::iter::once("contrastxr".into()).chain(argv));
    let matches = match parsed {
        Ok(m) => m,
        Err(e) => return parse_error(&e, name),
    };
    let Some((name, sub)) = matches.subcommand() else {
        eprint!("{}", overview());
        return 2;
    };
    let command = COMMANDS
        .iter()
        .find(|c| c.name == name)
        .expect("clap only accepts declared subcommands");
    let mut args = Args::new(sub.clone()).with_tree(self::command());
    finish(name, (command.run)(&mut args))
}

fn parse_error(e: &clap::Error, name: &str) -> i32 {
    match e.kind() {
        ErrorKind::DisplayHelp | ErrorKind::DisplayVersion => {
            super::error::print(&e.render().to_string());
            0
        }
        ErrorKind::InvalidSubcommand => {
            let what = context(e, ContextKind::InvalidSubcommand).unwrap_or_default();
            eprintln!(
                "contrastxr: error: unknown command '{what}'; run `contrastxr --help` for the list."
            );
            2
        }
        _ if name.is_empty() => {
            eprintln!("contrastxr: error: {}", sentence(e));
            eprintln!("run `contrastxr --help` for usage.");
            2
        }
        _ => finish(name, Err(CliError::Usage(sentence(e)))),
    }
}

fn finish(name: &str, result: Result<(), CliError>) -> i32 {
    match result {
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_command_line_is_consistent() {
        // clap's own checks: no clashing ids, shorts or positionals.
        command().debug_assert();
    }
}
