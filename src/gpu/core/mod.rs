//! What every graphics backend shares and no graphics API owns: the shader interface (bindings,
//! push constants, codes, tile and workgroup sizes, in `interface`), the settings' codes, the
//! push-constant block, the shaders' ids and the embedded modules build.rs compiles, pixel
//! formats and their codec, the camera rectangle a frame samples, the texel slots a source
//! fills, overlay runs, a frame's background, and the threads the builds keep between
//! sessions. Nothing here calls a graphics API (a test
//! holds it).

#[cfg(test)]
mod approx;
pub mod bench;
pub mod blurred_texels;
pub mod cache_files;
mod camera_rect;
pub mod codes;
mod frame_input;
pub mod interface;
pub mod kept_threads;
pub mod modules;
mod offline_backend;
mod overlay;
pub mod perceptual_words;
pub mod pixel_codec;
mod pixel_format;
pub mod plan;
pub mod process_exit;
pub mod push_constants;
pub mod shader_ids;
mod shared_fetch;
pub(crate) mod texels;
mod variant_key;

pub use camera_rect::CameraRect;
pub use frame_input::BackgroundInput;
pub use offline_backend::OfflineBackend;
pub use overlay::{encode as overlay_pixel, OverlayPixels, Run};
pub use pixel_format::{PixelFormat, PixelLayout};
pub use shared_fetch::shares_fetches;
pub use variant_key::{no_ablated_variant, ClassifyChoice, CubeRoots, VariantKey};
