//! `contrastxr completions bash|zsh|fish|elvish|powershell`: the shell completion script for
//! every subcommand and option, generated from the same declarations the parser uses.

use super::args::Args;
use super::error::CliError;
use clap_complete::Shell;

pub fn usage() -> String {
    "usage: contrastxr completions SHELL\n\n\
     Prints the completion script for SHELL (bash, zsh, fish, elvish or powershell), e.g.\n\
     \x20 contrastxr completions bash > ~/.local/share/bash-completion/completions/contrastxr\n\
     \x20 contrastxr completions zsh > ~/.zfunc/_contrastxr\n\
     \x20 contrastxr completions fish > ~/.config/fish/completions/contrastxr.fish\n\
     The Debian package installs the bash, zsh and fish scripts.\n"
        .to_string()
}

pub fn run(args: &mut Args) -> Result<(), CliError> {
    let shell = match args.positional().as_slice() {
        [name] => name.parse::<Shell>().map_err(|_| {
            CliError::Usage(format!(
                "unknown shell {name:?}: bash, zsh, fish, elvish or powershell"
            ))
        })?,
        _ => {
            return Err(CliError::Usage(
                "say which shell: bash, zsh, fish, elvish or powershell".into(),
            ))
        }
    };
    let mut tree = args
        .tree()
        .ok_or_else(|| CliError::Failure("no command declarations to describe".into()))?;
    let mut script = Vec::new();
    clap_complete::generate(shell, &mut tree, "contrastxr", &mut script);
    super::error::print(&String::from_utf8_lossy(&script));
    Ok(())
}
