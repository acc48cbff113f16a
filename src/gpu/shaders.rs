//! The SPIR-V compiled from `shaders/` by build.rs, embedded in the library.

/// One compute entry point's SPIR-V words.
pub struct ShaderModule {
    /// The SPIR-V file's name (the entry, or the entry and its specialisation).
    pub name: &'static str,
    pub entry: &'static str,
    bytes: &'static [u8],
}

impl ShaderModule {
    /// The SPIR-V as words (build.rs wrote them little-endian).
    pub fn words(&self) -> Vec<u32> {
        self.bytes
            .chunks_exact(4)
            .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
            .collect()
    }

    pub fn bytes(&self) -> &'static [u8] {
        self.bytes
    }
}

macro_rules! spirv {
    ($entry:literal) => {
        spirv!($entry, $entry)
    };
    ($name:literal, $entry:literal) => {
        ShaderModule {
            name: $name,
            entry: $entry,
            bytes: include_bytes!(concat!(env!("OUT_DIR"), "/", $name, ".spv")),
        }
    };
}

/// The background's first pass: decodes the camera texels (the blur passes read them).
pub const DECODE_CAMERA: ShaderModule = spirv!("decode_camera", "decode");
pub const FINISH_TILES: ShaderModule = spirv!("finish_tiles");
pub const COPY_PIXELS: ShaderModule = spirv!("copy_pixels");
pub const COPY_ROWS: ShaderModule = spirv!("copy_rows");

// DECODE_BLUR, ENHANCE_VARIANTS and CLASSIFY_VARIANTS, generated from src/gpu/interface.rs.
include!(concat!(env!("OUT_DIR"), "/enhance_variants.rs"));

/// Every embedded shader (for spirv-val in the tests).
pub fn all() -> Vec<&'static ShaderModule> {
    let fixed = [&DECODE_CAMERA, &FINISH_TILES, &COPY_PIXELS, &COPY_ROWS];
    fixed
        .into_iter()
        .chain(DECODE_BLUR.iter())
        .chain(ENHANCE_VARIANTS.iter().map(|(_, _, _, _, _, _, m)| m))
        .chain(CLASSIFY_VARIANTS.iter().map(|(_, _, m)| m))
        .collect()
}
