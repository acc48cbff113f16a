//! contrastxr: colour contrast enhanced rendering for optical see-through headsets
//! (Zhang et al., "Color Contrast Enhanced Rendering for OST-HMDs"), as a library, an OpenXR
//! API layer (this same library, loaded as a cdylib) and a command-line tool.
//!
//! Data flows one way through the modules:
//! `colour` + `algorithm` (pure, the CPU reference) -> `gpu` (ash engine, SPIR-V from `shaders/`)
//! -> `layer` (OpenXR FFI). `camera` feeds background frames to the engine.
//! Lower modules never import higher ones.

pub mod algorithm;
pub mod background_preparation;
pub mod camera;
pub mod colour;
pub mod config;
pub mod evaluate;
pub mod fault;
pub mod gpu;
pub mod image;
pub mod layer;
pub mod reference;
#[cfg(test)]
pub(crate) mod scratch;
pub mod user_file;
