//! The `contrastxr` subcommands and their dispatcher. Adding a subcommand: a module with
//! `usage() -> String` and `run(&mut Args) -> Result<(), CliError>`, and an entry in `COMMANDS`
//! that declares its options (the parser refuses any other; reading an undeclared one panics).

mod animate;
mod args;
mod backend_choice;
mod bench;
mod calibrate;
mod camera;
mod command_table;
mod completions;
mod config;
mod control;
mod doctor;
mod enhance;
mod error;
mod evaluate;
mod gl_programs;
mod install;
mod log;
mod options;
mod pan;
mod parse;
mod shader_stats;

pub use parse::main;
