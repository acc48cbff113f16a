//! The `contrastxr` command-line tool. Subcommands live in `cli/`; this only hands over.

mod cli;

fn main() {
    let argv: Result<Vec<String>, _> = std::env::args_os()
        .skip(1)
        .map(std::ffi::OsString::into_string)
        .collect();
    match argv {
        Ok(argv) => std::process::exit(cli::main(argv)),
        // Paths in settings are UTF-8 text (as in the config file): another one is refused.
        Err(bad) => {
            eprintln!(
                "contrastxr: argument {} is not UTF-8 text; give its path in UTF-8",
                bad.to_string_lossy()
            );
            std::process::exit(1);
        }
    }
}
