//! Algorithm 1 of the paper and its comparison methods, as the CPU reference (pure Rust, glam).
//!
//! This module is the definition the GPU shader is tested against: it follows
//! docs/algorithm.md (Per-pixel optimisation, Comparison methods) step by step, in f64. It
//! knows nothing about images, the GPU or OpenXR.

pub mod conformance;
mod constraints;
pub mod mapping;
pub mod method;
pub mod params;
pub mod perception;
pub mod perceptual_settings;
mod pixel;
pub mod reference_fn;
pub mod registration;
pub mod reprojection;
mod scaled;
pub mod stored;

pub use conformance::{conformant, corner_cases, PixelTrace, NEAR_ROUNDING, NEAR_THRESHOLD};
pub use mapping::CameraMapping;
pub use params::{Method, Params, ViewMode};
pub use pixel::{enhance_linear, enhance_srgb8, enhance_srgb8_trace};
pub use scaled::{enhance_scaled, enhance_scaled_traced, ScaledOutcome};
pub use stored::Stored;
