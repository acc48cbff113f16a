//! The `contrastxr` command-line tool. Subcommands live in `cli/`; this only hands over.

mod cli;

fn main() {
    std::process::exit(cli::main(std::env::args().skip(1).collect()));
}
