//! The GL enums and the tables of state that `--check-gl-state` ([`super::gl_state`]) sets
//! and reads back: which units, buffer targets, pixel-store parameters and capabilities, and
//! the values the check sets them to.

use contrastxr::gpu::core::interface::{BINDINGS, BINDING_APP_TEXELS};

pub type Enum = u32;

/// Units checked for textures, samplers and image units, and indices for indexed buffer
/// bindings: 0 up to the highest binding number of the layer's OpenGL programs (every binding
/// but the sampled read's, which only Vulkan has).
pub const UNITS: usize = {
    let (mut n, mut i) = (1, 0);
    while i < BINDINGS.len() {
        let gl = BINDINGS[i].number != BINDING_APP_TEXELS;
        if gl && BINDINGS[i].number as usize + 1 > n {
            n = BINDINGS[i].number as usize + 1;
        }
        i += 1;
    }
    n
};
// GL 4.5's smallest GL_MAX_IMAGE_UNITS and GL_MAX_SHADER_STORAGE_BUFFER_BINDINGS.
const _: () = assert!(UNITS <= 8);

/// The active texture unit the check sets (GL_TEXTURE5).
pub const ACTIVE_UNIT: u32 = 5;
const _: () = assert!((ACTIVE_UNIT as usize) < UNITS);

pub const NO_ERROR: Enum = 0;
pub const INVALID_ENUM: Enum = 0x0500;
/// Not a capability: glEnable raises GL_INVALID_ENUM, the error the client leaves pending.
pub const NOT_A_CAPABILITY: Enum = 0xFFFF;

pub const TEXTURE0: Enum = 0x84C0;
pub const ACTIVE_TEXTURE: Enum = 0x84E0;
pub const TEXTURE_2D: Enum = 0x0DE1;
pub const TEXTURE_2D_ARRAY: Enum = 0x8C1A;
pub const TEXTURE_BINDING_2D: Enum = 0x8069;
pub const TEXTURE_BINDING_2D_ARRAY: Enum = 0x8C1D;
pub const SAMPLER_BINDING: Enum = 0x8919;
pub const CURRENT_PROGRAM: Enum = 0x8B8D;
pub const PROGRAM_PIPELINE_BINDING: Enum = 0x825A;
pub const COMPUTE_SHADER: Enum = 0x91B9;
pub const LINK_STATUS: Enum = 0x8B82;
pub const RGBA8: Enum = 0x8058;
pub const R32UI: Enum = 0x8236;
pub const READ_WRITE: Enum = 0x88BA;
pub const IMAGE_BINDING_NAME: Enum = 0x8F3A;
pub const IMAGE_BINDING_LEVEL: Enum = 0x8F3B;
pub const IMAGE_BINDING_LAYERED: Enum = 0x8F3C;
pub const IMAGE_BINDING_LAYER: Enum = 0x8F3D;
pub const IMAGE_BINDING_ACCESS: Enum = 0x8F3E;
pub const IMAGE_BINDING_FORMAT: Enum = 0x906E;
pub const SHADER_STORAGE_BUFFER: Enum = 0x90D2;
pub const SHADER_STORAGE_BUFFER_BINDING: Enum = 0x90D3;
pub const SHADER_STORAGE_BUFFER_START: Enum = 0x90D4;
pub const SHADER_STORAGE_BUFFER_SIZE: Enum = 0x90D5;
pub const SHADER_STORAGE_BUFFER_OFFSET_ALIGNMENT: Enum = 0x90DF;
pub const UNIFORM_BUFFER: Enum = 0x8A11;
pub const UNIFORM_BUFFER_BINDING: Enum = 0x8A28;
pub const UNIFORM_BUFFER_START: Enum = 0x8A29;
pub const UNIFORM_BUFFER_SIZE: Enum = 0x8A2A;
pub const UNIFORM_BUFFER_OFFSET_ALIGNMENT: Enum = 0x8A34;
pub const PIXEL_UNPACK_BUFFER: Enum = 0x88EC;
pub const UNPACK_ALIGNMENT: Enum = 0x0CF5;
pub const DRAW_FRAMEBUFFER: Enum = 0x8CA9;
pub const READ_FRAMEBUFFER: Enum = 0x8CA8;
pub const DRAW_FRAMEBUFFER_BINDING: Enum = 0x8CA6;
pub const READ_FRAMEBUFFER_BINDING: Enum = 0x8CAA;
pub const RENDERBUFFER: Enum = 0x8D41;
pub const RENDERBUFFER_BINDING: Enum = 0x8CA7;
pub const VERTEX_ARRAY_BINDING: Enum = 0x85B5;
pub const FRAMEBUFFER_SRGB: Enum = 0x8DB9;
pub const VIEWPORT: Enum = 0x0BA2;
pub const SCISSOR_BOX: Enum = 0x0C10;

/// The generic buffer binding points: target, its binding query, the query's name.
pub const GENERIC_BUFFERS: [(Enum, Enum, &str); 9] = [
    (
        SHADER_STORAGE_BUFFER,
        SHADER_STORAGE_BUFFER_BINDING,
        "GL_SHADER_STORAGE_BUFFER_BINDING",
    ),
    (
        UNIFORM_BUFFER,
        UNIFORM_BUFFER_BINDING,
        "GL_UNIFORM_BUFFER_BINDING",
    ),
    (0x88EB, 0x88ED, "GL_PIXEL_PACK_BUFFER_BINDING"),
    (
        PIXEL_UNPACK_BUFFER,
        0x88EF,
        "GL_PIXEL_UNPACK_BUFFER_BINDING",
    ),
    (0x90EE, 0x90EF, "GL_DISPATCH_INDIRECT_BUFFER_BINDING"),
    (0x8F3F, 0x8F43, "GL_DRAW_INDIRECT_BUFFER_BINDING"),
    (0x8F36, 0x8F36, "GL_COPY_READ_BUFFER_BINDING"),
    (0x8F37, 0x8F37, "GL_COPY_WRITE_BUFFER_BINDING"),
    (0x8892, 0x8894, "GL_ARRAY_BUFFER_BINDING"),
];

/// The pixel store: parameter, its name, the value the check sets, the client's own value
/// (GL's default, but for the alignments: the client's transfers are tightly packed).
pub const PIXEL_STORE: [(Enum, &str, i32, i32); 16] = [
    (0x0D00, "GL_PACK_SWAP_BYTES", 1, 0),
    (0x0D01, "GL_PACK_LSB_FIRST", 1, 0),
    (0x0D02, "GL_PACK_ROW_LENGTH", 9, 0),
    (0x0D03, "GL_PACK_SKIP_ROWS", 3, 0),
    (0x0D04, "GL_PACK_SKIP_PIXELS", 2, 0),
    (0x0D05, "GL_PACK_ALIGNMENT", 8, 1),
    (0x806B, "GL_PACK_SKIP_IMAGES", 1, 0),
    (0x806C, "GL_PACK_IMAGE_HEIGHT", 5, 0),
    (0x0CF0, "GL_UNPACK_SWAP_BYTES", 1, 0),
    (0x0CF1, "GL_UNPACK_LSB_FIRST", 1, 0),
    (0x0CF2, "GL_UNPACK_ROW_LENGTH", 7, 0),
    (0x0CF3, "GL_UNPACK_SKIP_ROWS", 4, 0),
    (0x0CF4, "GL_UNPACK_SKIP_PIXELS", 3, 0),
    (UNPACK_ALIGNMENT, "GL_UNPACK_ALIGNMENT", 2, 1),
    (0x806D, "GL_UNPACK_SKIP_IMAGES", 2, 0),
    (0x806E, "GL_UNPACK_IMAGE_HEIGHT", 6, 0),
];

/// Capabilities the check enables (the client leaves them disabled).
pub const ENABLES: [(Enum, &str); 3] = [
    (FRAMEBUFFER_SRGB, "GL_FRAMEBUFFER_SRGB"),
    (0x0C11, "GL_SCISSOR_TEST"),
    (0x0BE2, "GL_BLEND"),
];

/// The viewport and scissor box the check sets (the client's are its 16x16 pbuffer's).
pub const VIEWPORT_SET: [i32; 4] = [1, 2, 11, 13];
pub const SCISSOR_SET: [i32; 4] = [3, 4, 5, 6];
pub const PBUFFER_RECT: [i32; 4] = [0, 0, 16, 16];
