//! The SPIR-V compiled from `shaders/` by build.rs, embedded in the library.

/// One compute entry point's SPIR-V words.
pub struct ShaderModule {
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
        ShaderModule {
            entry: $entry,
            bytes: include_bytes!(concat!(env!("OUT_DIR"), "/", $entry, ".spv")),
        }
    };
}

pub const DECODE_BLUR_H: ShaderModule = spirv!("decode_blur_h");
pub const BLUR_V: ShaderModule = spirv!("blur_v");
pub const FOV_MAP: ShaderModule = spirv!("fov_map");
pub const ENHANCE: ShaderModule = spirv!("enhance");
pub const COPY_PIXELS: ShaderModule = spirv!("copy_pixels");

/// Every embedded shader (for spirv-val in the tests).
pub const ALL: [&ShaderModule; 5] = [&DECODE_BLUR_H, &BLUR_V, &FOV_MAP, &ENHANCE, &COPY_PIXELS];
