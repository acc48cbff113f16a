//! The client's one error type: a message that says which call failed and how.

use std::fmt::{self, Display};

#[derive(Debug)]
pub struct ClientError(pub String);

pub type Result<T> = std::result::Result<T, ClientError>;

impl Display for ClientError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

/// Names the failed call: `xr_call().ctx("xrCreateSession")?`.
pub trait Context<T> {
    fn ctx(self, what: &str) -> Result<T>;
}

impl<T, E: Display> Context<T> for std::result::Result<T, E> {
    fn ctx(self, what: &str) -> Result<T> {
        self.map_err(|e| ClientError(format!("{what} failed: {e}")))
    }
}

pub fn fail<T>(message: impl Into<String>) -> Result<T> {
    Err(ClientError(message.into()))
}
