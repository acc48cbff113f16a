//! The layer's configuration: a TOML file with per-app tables, environment overrides, every
//! value's origin, hot reload, and the edits behind `contrastxr set` and `toggle`.
//!
//! Sources, lowest first: defaults, the shipped device profiles' `[device."SYSTEM"]` table
//! ([`shipped`]), the file's top level, its `[device."SYSTEM"]` table (SYSTEM
//! is XrSystemProperties.systemName, known once the app creates a session), its `[app."NAME"]`
//! table (NAME is XrApplicationInfo.applicationName), the `CONTRASTXR_*` environment variables. The file is
//! `$CONTRASTXR_CONFIG`, else `$XDG_CONFIG_HOME/contrastxr/config.toml`, else
//! `/etc/xdg/contrastxr/config.toml`. Nothing here panics on any input, and nothing here knows
//! about OpenXR or the GPU: the layer and the CLI use it.

pub mod edit;
pub mod file;
pub mod keys;
pub mod load;
mod origin;
pub mod path;
pub mod resolve;
mod settings;
pub mod shipped;
mod startup_line;
pub mod value;
pub mod watch;

pub use keys::{key, Key, KEYS};
pub use load::{load, load_for};
pub use origin::{Origin, Table};
pub use path::Env;
pub use resolve::{check, is_off, resolve, resolve_for, resolve_with, Resolved, Source, Who};
pub use settings::{Capture, CopyBack, CopyIn, InPlace, Registration, Settings, EYES};
pub use startup_line::describe;
pub use value::{Kind, Value};
pub use watch::Live;
