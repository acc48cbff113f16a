//! The shader interface, shared by every graphics backend: what the Rust side and the shaders
//! agree on (bindings, push constants, codes, tile and workgroup sizes, in `interface`), the
//! settings' codes, the push-constant block, the ids of the shaders and the embedded modules
//! build.rs compiles. Nothing here calls a graphics API.

// The shader's approximations mirrored in f32: only their accuracy tests use them.
#[cfg(test)]
mod approx;
pub mod codes;
pub mod interface;
pub mod modules;
pub mod push_constants;
pub mod shader_ids;
