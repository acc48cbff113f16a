//! The perceptual contrast model and the `perceptual` method's CPU reference (docs/algorithm.md,
//! *The perceptual method*): how visible content is over the world it is added to, by
//! castleCSF and Kulikowski's rule, and a per-pixel method that spends the paper's colour change
//! where the eye gains most. Pure Rust in f64 (the f32 tables a shader evaluates are
//! `tables`); it knows nothing of images, the GPU, settings files or OpenXR.
//!
//! Sections of the model, one file each: `light` (the physical light and the pattern an edge of
//! content makes), `castle_csf` (the contrast sensitivities), `perceived` (c, C and c'),
//! `frequency` (which spatial frequency; the settings themselves are
//! `algorithm::perceptual_settings`, which `Params` holds); of the method: `directions`, `method`,
//! `tables` and `target_bound` (for the GPU) and `report` (per-frame statistics).

pub mod castle_csf;
pub mod directions;
pub mod frame_report;
pub mod frequency;
pub mod light;
pub mod perceived_contrast;
pub mod perceptual_pixel;
pub mod tables;
pub mod target_bound;
