//! Where an effective value came from: the default, a line of a config file (and the table it
//! stood in), or an environment variable. `config print` and the layer's log show it after
//! every value, so that a value from the shipped device profiles is told from the user's own.

use std::fmt;
use std::path::PathBuf;

/// The part of a config file a line belongs to.
#[derive(Clone, Debug, PartialEq)]
pub enum Table {
    /// The top level (every app, every headset).
    Top,
    /// `[device."SYSTEM"]`.
    Device(String),
    /// `[app."NAME"]`.
    App(String),
}

/// Where an effective value came from.
#[derive(Clone, Debug, PartialEq)]
pub enum Origin {
    Default,
    File {
        path: PathBuf,
        table: Table,
        line: usize,
    },
    Env(&'static str),
}

impl fmt::Display for Table {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Table::Top => Ok(()),
            Table::Device(name) => write!(f, "[device.{name:?}]"),
            Table::App(name) => write!(f, "[app.{name:?}]"),
        }
    }
}

impl fmt::Display for Origin {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Origin::Default => f.write_str("default"),
            Origin::File {
                path,
                table: Table::Top,
                line,
            } => write!(f, "{}:{line}", path.display()),
            Origin::File { path, table, line } => write!(f, "{} {table}:{line}", path.display()),
            Origin::Env(var) => write!(f, "env {var}"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_file_origin_names_its_table() {
        let at = |table, line| Origin::File {
            path: PathBuf::from("/usr/share/contrastxr/devices.toml"),
            table,
            line,
        };
        let device = Table::Device("Monado: Xreal Air Glasses".into());
        assert_eq!(
            at(device, 18).to_string(),
            "/usr/share/contrastxr/devices.toml [device.\"Monado: Xreal Air Glasses\"]:18"
        );
        assert_eq!(
            at(Table::App("hello_xr".into()), 4).to_string(),
            "/usr/share/contrastxr/devices.toml [app.\"hello_xr\"]:4"
        );
        assert_eq!(
            at(Table::Top, 2).to_string(),
            "/usr/share/contrastxr/devices.toml:2"
        );
        assert_eq!(Origin::Env("CONTRASTXR_X").to_string(), "env CONTRASTXR_X");
        assert_eq!(Origin::Default.to_string(), "default");
    }
}
