//! The per-pixel methods as one table (`table.rs`, one entry each, also read by build.rs): the
//! `Method` type and its names (`kind.rs`), and each method's entry with the names derived from
//! the table for the settings, the command line and their help (`method_entry.rs`).

mod kind;
mod method_entry;

pub use kind::Method;
pub use method_entry::{MethodEntry, Pass, METHOD_DOC, MODES, MODE_DOC, PER_PIXEL_PASSES};
