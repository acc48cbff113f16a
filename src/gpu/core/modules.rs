//! The SPIR-V compiled from `shaders/` by build.rs, embedded in the library.

/// One compute entry point's SPIR-V words.
pub struct ShaderModule {
    /// The SPIR-V file's name (the entry, or the entry and its specialisation).
    pub name: &'static str,
    pub entry: &'static str,
    /// Works on the camera frame (the background's descriptor set) rather than on a view.
    pub camera: bool,
    /// The FORMAT code of a variant that writes `app_image` (in place, or read through a
    /// sampled view).
    pub in_place: Option<u32>,
    /// Reads the app's image through `app_texels` (interface.rs ACCESS_SAMPLED).
    pub sampled: bool,
    bytes: &'static [u8],
}

impl ShaderModule {
    /// The SPIR-V as words (build.rs wrote them little-endian).
    pub fn words(&self) -> Vec<u32> {
        self.bytes
            .as_chunks::<4>()
            .0
            .iter()
            .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
            .collect()
    }

    pub fn bytes(&self) -> &'static [u8] {
        self.bytes
    }
}

macro_rules! spirv {
    ($name:literal, $entry:literal, $camera:literal, $in_place:expr, $sampled:literal) => {
        ShaderModule {
            name: $name,
            entry: $entry,
            camera: $camera,
            in_place: $in_place,
            sampled: $sampled,
            bytes: include_bytes!(concat!(env!("OUT_DIR"), "/", $name, ".spv")),
        }
    };
}

/// A row of an `enhance` variant table (ENHANCE_VARIANTS, OpenGL's GL_ENHANCE_VARIANTS):
/// (method, mode, format, access, extras, shared fetches, cube roots by pow, id).
pub type VariantRow = (u32, u32, u32, u32, bool, bool, bool, usize);

// MODULES (every shader; a ShaderId is an index there), the single shaders' ids (ID_*) and
// the families' tables with their ids (DECODE_BLUR, ENHANCE_VARIANTS, CLASSIFY_VARIANTS,
// ENHANCE_ABLATED), all written together by build.rs from src/gpu/core/interface.rs.
include!(concat!(env!("OUT_DIR"), "/shader_table.rs"));

/// Every embedded shader (for spirv-val in the tests), in id order.
pub fn all() -> Vec<&'static ShaderModule> {
    MODULES.iter().collect()
}
