//! The command line as the subcommands see it: each subcommand declares its options as [`Opt`]s,
//! clap parses the whole line against them (unknown options, missing values, `--help`,
//! `--version` and the completions all come from there), and [`Args`] hands the parsed values
//! to the subcommand by option name. An option's value is always the next argument, so
//! negative numbers work (`--fov-offset -0.1,0.2`), and positionals may be negative too
//! (`contrastxr set lambda_e -0.1`).

use super::error::CliError;
use clap::{Arg, ArgAction, ArgMatches};

/// One option a subcommand accepts: `--long` (with an optional `-s`), a flag or taking a value.
#[derive(Clone, Copy, Debug)]
pub struct Opt {
    /// `--name`, with the dashes.
    pub long: &'static str,
    pub short: Option<char>,
    /// The value's name in the help (`FILE`); None for a flag.
    pub value: Option<&'static str>,
}

impl Opt {
    pub const fn flag(long: &'static str) -> Opt {
        Opt {
            long,
            short: None,
            value: None,
        }
    }

    pub const fn value(long: &'static str, value: &'static str) -> Opt {
        Opt {
            long,
            short: None,
            value: Some(value),
        }
    }

    pub const fn short(self, short: char) -> Opt {
        Opt {
            short: Some(short),
            ..self
        }
    }

    fn id(&self) -> &'static str {
        self.long.trim_start_matches('-')
    }

    /// The clap argument; the id is the long name without dashes.
    pub fn arg(&self) -> Arg {
        let mut arg = Arg::new(self.id()).long(self.id());
        if let Some(s) = self.short {
            arg = arg.short(s);
        }
        match self.value {
            None => arg.action(ArgAction::SetTrue),
            // The next argument is the value even when it starts with '-' (negative numbers).
            Some(v) => arg
                .action(ArgAction::Set)
                .value_name(v)
                .allow_hyphen_values(true),
        }
    }
}

/// The id of the positional arguments of a subcommand that takes them.
pub const POSITIONALS: &str = "args";

/// The positionals argument: any number of them, negative numbers among them
/// (`set lambda_e -0.1`); other values starting with '-' need `KEY=VALUE` or `--` before them.
pub fn positionals_arg(name: &'static str) -> Arg {
    Arg::new(POSITIONALS)
        .value_name(name)
        .num_args(0..)
        .action(ArgAction::Append)
        .allow_negative_numbers(true)
}

/// A subcommand's parsed command line, taken out option by option.
pub struct Args {
    matches: ArgMatches,
    /// The whole command line's declaration, for the commands that describe it (completions).
    tree: Option<clap::Command>,
}

fn id_of(names: &[&str]) -> String {
    let long = names
        .iter()
        .find(|n| n.starts_with("--"))
        .unwrap_or(&names[0]);
    long.trim_start_matches('-').to_string()
}

impl Args {
    pub fn new(matches: ArgMatches) -> Self {
        Args {
            matches,
            tree: None,
        }
    }

    /// The same, with the declaration of every subcommand and option (the dispatcher's).
    pub fn with_tree(mut self, tree: clap::Command) -> Self {
        self.tree = Some(tree);
        self
    }

    /// The declaration of every subcommand and option, when the dispatcher gave it.
    pub fn tree(&mut self) -> Option<clap::Command> {
        self.tree.take()
    }

    /// Whether a boolean flag was given.
    pub fn flag(&mut self, name: &str) -> bool {
        let id = id_of(&[name]);
        match self.matches.try_get_one::<bool>(&id) {
            Ok(v) => v.copied().unwrap_or(false),
            Err(e) => panic!("the option {name} is not declared for this command: {e}"),
        }
    }

    /// The value of `--name VALUE` / `--name=VALUE` (any of `names`); the last occurrence wins.
    pub fn value(&mut self, names: &[&str]) -> Result<Option<String>, CliError> {
        let id = id_of(names);
        match self.matches.try_get_one::<String>(&id) {
            Ok(v) => Ok(v.cloned()),
            Err(e) => panic!(
                "the option {} is not declared for this command: {e}",
                names[0]
            ),
        }
    }

    pub fn required(&mut self, names: &[&str]) -> Result<String, CliError> {
        self.value(names)?
            .ok_or_else(|| CliError::Usage(format!("{} is required", names[0])))
    }

    /// The positional arguments (empty for a subcommand that takes none).
    pub fn positional(&mut self) -> Vec<String> {
        match self.matches.try_get_many::<String>(POSITIONALS) {
            Ok(Some(v)) => v.cloned().collect(),
            _ => Vec::new(),
        }
    }

    /// Nothing is left over: the parser already refused unknown options and arguments.
    pub fn finish(&self) -> Result<(), CliError> {
        Ok(())
    }
}

/// A number option; `what` names it in the error.
pub fn parse_f32(what: &str, s: &str) -> Result<f32, CliError> {
    s.trim()
        .parse::<f32>()
        .ok()
        .filter(|v| v.is_finite())
        .ok_or_else(|| CliError::Failure(format!("{what} must be a number, got '{s}'")))
}

/// A comma-separated list of numbers.
pub fn parse_list(what: &str, s: &str) -> Result<Vec<f32>, CliError> {
    s.split(',').map(|p| parse_f32(what, p)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(opts: &[Opt], positional: bool, line: &str) -> Result<Args, clap::Error> {
        let mut cmd = clap::Command::new("t")
            .args_override_self(true)
            .args(opts.iter().map(Opt::arg));
        if positional {
            cmd = cmd.arg(positionals_arg("ARGS"));
        }
        cmd.try_get_matches_from(std::iter::once("t").chain(line.split_whitespace()))
            .map(Args::new)
    }

    const OPTS: &[Opt] = &[
        Opt::value("--display", "FILE"),
        Opt::value("--output", "FILE").short('o'),
        Opt::flag("--no-blur"),
        Opt::flag("--no-fov"),
        Opt::value("--lambda-e", "F"),
        Opt::value("--fov-offset", "X,Y"),
    ];

    #[test]
    fn values_flags_and_leftovers() {
        let mut a = parse(
            OPTS,
            false,
            "--display d.png -o=o.png --no-blur --lambda-e 0.3 --lambda-e=0.5",
        )
        .unwrap();
        assert_eq!(a.value(&["--display"]).unwrap().as_deref(), Some("d.png"));
        assert_eq!(
            a.value(&["-o", "--output"]).unwrap().as_deref(),
            Some("o.png")
        );
        assert!(a.flag("--no-blur") && !a.flag("--no-fov"));
        assert_eq!(a.value(&["--lambda-e"]).unwrap().as_deref(), Some("0.5"));
        let unknown = parse(OPTS, false, "--display d.png extra").err().unwrap();
        assert_eq!(unknown.kind(), clap::error::ErrorKind::UnknownArgument);
        let missing = parse(OPTS, false, "--display").err().unwrap();
        assert_eq!(missing.kind(), clap::error::ErrorKind::InvalidValue);
    }

    #[test]
    fn negative_values_are_values() {
        let mut a = parse(OPTS, false, "--fov-offset -0.1,0.2 --lambda-e -1").unwrap();
        assert_eq!(
            a.value(&["--fov-offset"]).unwrap().as_deref(),
            Some("-0.1,0.2")
        );
        assert_eq!(a.value(&["--lambda-e"]).unwrap().as_deref(), Some("-1"));
        let mut a = parse(&[Opt::value("--app", "NAME")], true, "lambda_e -0.1").unwrap();
        assert_eq!(a.positional(), ["lambda_e", "-0.1"]);
        let mut a = parse(&[Opt::value("--app", "NAME")], true, "x -2 --app a").unwrap();
        assert_eq!(a.positional(), ["x", "-2"]);
        assert_eq!(a.value(&["--app"]).unwrap().as_deref(), Some("a"));
        let mut a = parse(&[Opt::value("--app", "NAME")], true, "-- x -2,1").unwrap();
        assert_eq!(a.positional(), ["x", "-2,1"]);
    }

    #[test]
    fn numbers() {
        assert!(parse_f32("x", "nan").is_err());
        assert_eq!(parse_list("l", "0.2,1").unwrap(), vec![0.2, 1.0]);
    }
}
