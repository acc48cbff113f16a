//! Algorithm 1 of the paper and its comparison methods, as the CPU reference (pure Rust, glam).

pub mod params;

pub use params::{Method, Params};
