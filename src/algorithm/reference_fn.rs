//! The type of a method's CPU reference, which each entry of the method table names
//! (src/algorithm/method/method_entry.rs) and the per-pixel code calls (src/algorithm/pixel.rs, scaled.rs).
//! A file of its own: the entries name the reference functions, and those files name this type,
//! so neither can hold it without an import circle.

use glam::DVec3;

use super::constraints::Margin;
use super::params::Params;

/// A method's CPU reference (docs/algorithm.md, Per-pixel optimisation and Comparison methods).
#[derive(Clone, Copy)]
pub enum Reference {
    /// P from D, B and the change vector E, in the scaled space (called where E exists:
    /// |B| > 1e-6). `Margin` records how close each branch condition came to flipping.
    Scaled(fn(DVec3, DVec3, DVec3, &Params, &mut Margin) -> DVec3),
    /// The unclipped output from the display and the (unattenuated) background, linear light.
    Linear(fn(DVec3, DVec3, &Params) -> DVec3),
    /// The output, clipped to [0, 1], from the display, the (unattenuated) background and the
    /// paper method's output (clipped), linear light: a method that spends the paper's colour
    /// change its own way. A `Margin`, where one is given, records how close each decision
    /// came to flipping (the conformance trace; without it the reference skips that work).
    Perceptual(fn(DVec3, DVec3, DVec3, &Params, Option<&mut Margin>) -> DVec3),
}

impl std::fmt::Debug for Reference {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Reference::Scaled(_) => "Scaled",
            Reference::Linear(_) => "Linear",
            Reference::Perceptual(_) => "Perceptual",
        })
    }
}
