// The interface between the engine (Rust) and its compute shaders (WGSL), defined once.
//
// build.rs includes this file: it writes the WGSL declarations from it (the bindings, the
// `Params` push-constant block, the tile list, the codes and sizes below) in front of every
// shader, and after naga has parsed a shader it checks the module's bindings, push-constant
// layout and workgroup sizes against it, failing the build with both sides named. The engine
// uses the same items, and `PushConstants` is checked against PARAMS at compile time. Changing
// a value here reaches every shader and every Rust user. Nothing here depends on anything else.

/// What a binding of descriptor set 0 holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BindingKind {
    /// A storage buffer (in the shader: `var<storage, read>` or `read_write`).
    StorageBuffer,
    /// A sampled image (in the shader: `texture_2d<u32>` or `texture_2d<f32>`).
    SampledImage,
    /// A storage image (in the shader: `texture_storage_2d<..., read_write>`).
    StorageImage,
}

/// How a per-pixel pass reaches a display region's pixels (the `ACCESS` code of a variant).
/// A copy of the region in the storage buffer `pixels`, one word per load:
pub const ACCESS_NARROW: u32 = 0;
/// The same, 16 bytes per load (rows 16-byte aligned; shaders/access_wide.wgsl):
pub const ACCESS_WIDE: u32 = 1;
/// The app's image itself, through a storage view `app_image` (shaders/access_in_place.wgsl):
pub const ACCESS_IN_PLACE: u32 = 2;
/// Read from the app's image through a sampled view `app_texels` (the sampler decodes sRGB; the
/// shader encodes it back to the stored codes), written to an image of the layer's own,
/// `app_image`, at the pixel's place in the region (shaders/texels_sampled.wgsl): no copy of
/// the region into the layer's image before the enhancement. For the formats `sampled_read`
/// names.
pub const ACCESS_SAMPLED: u32 = 3;

/// Whether views of a pixel format (a FORMAT code) can be read through a sampled view
/// (ACCESS_SAMPLED): the 8-bit sRGB formats, whose runtimes refuse storage usage, so that they
/// take the image-copy path. The shader's encode (within 0.002 of a code) rounds the
/// sampler's decode of a code back to that code wherever the decode errs by less than 0.4 of
/// a code; tests/gpu_engine.rs holds every code to it on the device at hand.
pub const fn sampled_read(format: u32) -> bool {
    let layout = format & !FORMAT_SRGB_BIT;
    format & FORMAT_SRGB_BIT != 0 && (layout == LAYOUT_RGBA8 || layout == LAYOUT_BGRA8)
}

/// The storage texel format through which a pixel format (a FORMAT code) is enhanced in place
/// (ACCESS_IN_PLACE); None where it is only enhanced through a buffer. Only formats every
/// Vulkan device can store without optional features, each converting to and from the
/// format's raw words exactly: an sRGB image is reached through a UNORM view of it (the shader
/// encodes sRGB itself), so its swapchain needs the mutable-format usage. The app's own images
/// are enhanced in place in the RGBA8 and RGBA16 float formats only (a view of the image's own
/// layout); the other formats' texels serve the image-copy path, where the region is copied
/// (vkCmdCopyImage, raw bytes) into an image of the layer's own in that texel format: BGRA8
/// as RGBA8 (the words keep their byte order, the shader reads them as BGRA), A2B10G10R10 as
/// one 32-bit word, RGBA16 UNORM as four 16-bit integers.
pub const fn in_place_texel(format: u32) -> Option<&'static str> {
    match format & !FORMAT_SRGB_BIT {
        LAYOUT_RGBA8 | LAYOUT_BGRA8 => Some("rgba8unorm"),
        LAYOUT_RGBA16_FLOAT => Some("rgba16float"),
        LAYOUT_A2B10G10R10 => Some("r32uint"),
        LAYOUT_RGBA16_UNORM => Some("rgba16uint"),
        _ => None,
    }
}

/// One binding of descriptor set 0, the one set every pass shares.
#[derive(Clone, Copy, Debug)]
pub struct Binding {
    pub number: u32,
    /// The shader's variable.
    pub name: &'static str,
    pub kind: BindingKind,
    /// The variable's declaration after `var`, given the pixel access (ACCESS_*) and the
    /// FORMAT code of the variant; None where that variant does not declare it.
    pub wgsl: fn(access: u32, format: u32) -> Option<String>,
}

/// The camera frame: RGBA8 sRGB, one u32 per pixel, four pixels per entry.
pub const BINDING_CAMERA: u32 = 0;
/// The camera frame decoded and blurred (linear light, packed pairs of texels).
pub const BINDING_BLURRED: u32 = 1;
/// The display region's raw pixels in the swapchain format.
pub const BINDING_PIXELS: u32 = 2;
/// The tile list of the enhancement (TILE_LIST_* below).
pub const BINDING_TILES: u32 = 3;
/// The copy passes' source (the benchmark's floor); the layer binds the pixels here.
pub const BINDING_SOURCE: u32 = 4;
/// `blurred` as an R32G32B32A32_UINT image, what the enhancement samples.
pub const BINDING_BLURRED_TEXELS: u32 = 5;
/// The app's image layer, for enhancing in place (ACCESS_IN_PLACE).
pub const BINDING_APP_IMAGE: u32 = 6;
/// The perceptual model of the view's frame (PERCEPTUAL_* below), which the `perceptual`
/// method reads: f32 words.
pub const BINDING_PERCEPTUAL: u32 = 7;
/// The app's image layer through a sampled view of its own format (ACCESS_SAMPLED).
pub const BINDING_APP_TEXELS: u32 = 8;

fn always(decl: &str) -> Option<String> {
    Some(decl.to_string())
}

/// Every binding, in binding order.
pub const BINDINGS: [Binding; 9] = [
    Binding {
        number: BINDING_CAMERA,
        name: "camera",
        kind: BindingKind::StorageBuffer,
        wgsl: |_, _| always("<storage, read> camera: array<vec4<u32>>"),
    },
    Binding {
        number: BINDING_BLURRED,
        name: "blurred",
        kind: BindingKind::StorageBuffer,
        wgsl: |_, _| always("<storage, read_write> blurred: array<vec4<u32>>"),
    },
    Binding {
        number: BINDING_PIXELS,
        name: "pixels",
        kind: BindingKind::StorageBuffer,
        wgsl: |access, _| match access {
            ACCESS_WIDE => always("<storage, read_write> pixels: array<vec4<u32>>"),
            ACCESS_NARROW => always("<storage, read_write> pixels: array<u32>"),
            _ => None,
        },
    },
    Binding {
        number: BINDING_TILES,
        name: "tiles",
        kind: BindingKind::StorageBuffer,
        wgsl: |_, _| always("<storage, read_write> tiles: TileList"),
    },
    Binding {
        number: BINDING_SOURCE,
        name: "source",
        kind: BindingKind::StorageBuffer,
        wgsl: |access, _| match access {
            ACCESS_WIDE => always("<storage, read> source: array<vec4<u32>>"),
            ACCESS_NARROW => always("<storage, read> source: array<u32>"),
            _ => None,
        },
    },
    Binding {
        number: BINDING_BLURRED_TEXELS,
        name: "blurred_texels",
        kind: BindingKind::SampledImage,
        wgsl: |_, _| always(" blurred_texels: texture_2d<u32>"),
    },
    Binding {
        number: BINDING_APP_IMAGE,
        name: "app_image",
        kind: BindingKind::StorageImage,
        wgsl: |access, format| match (access, in_place_texel(format)) {
            (ACCESS_IN_PLACE | ACCESS_SAMPLED, Some(texel)) => Some(format!(
                " app_image: texture_storage_2d<{texel}, read_write>"
            )),
            _ => None,
        },
    },
    Binding {
        number: BINDING_PERCEPTUAL,
        name: "perceptual",
        kind: BindingKind::StorageBuffer,
        // Fixed-size (the buffer is always PERCEPTUAL_WORDS words), so that naga proves the
        // header's constant indices in range: a run-time-sized array's are checked at run time.
        wgsl: |_, _| always("<storage, read> perceptual: array<vec4<f32>, PERCEPTUAL_WORDS / 4u>"),
    },
    Binding {
        number: BINDING_APP_TEXELS,
        name: "app_texels",
        kind: BindingKind::SampledImage,
        wgsl: |access, format| match access == ACCESS_SAMPLED && sampled_read(format) {
            true => always(" app_texels: texture_2d<f32>"),
            false => None,
        },
    },
];

// The `perceptual` buffer's layout (PERCEPTUAL_*), in a file of its own beside this one.
include!("perceptual_layout.rs");

/// Side of the square tiles the enhancement skips when they hold no foreground pixel, and the
/// workgroup size (TILE x TILE) of the per-pixel passes.
pub const TILE: u32 = 8;
/// `classify` runs a row of tiles per workgroup, so that tiles are listed (and then enhanced)
/// in row order: neighbouring memory, which a CPU driver's caches and prefetchers follow.
pub const CLASSIFY_WORKGROUP: [u32; 3] = [64, 1, 1];
/// Rows of texels one invocation of the background preparation makes.
pub const DECODE_ROWS: u32 = 8;
/// Workgroups per row of the enhancement's indirect dispatch (maxComputeWorkGroupCount is only
/// guaranteed to be 65535).
pub const INDIRECT_ROW_GROUPS: u32 = 32768;

/// Each entry point's workgroup size.
pub const WORKGROUPS: [(&str, [u32; 3]); 8] = [
    ("decode", [TILE, TILE, 1]),
    ("decode_blur", [TILE, TILE, 1]),
    ("copy_pixels", [TILE, TILE, 1]),
    ("copy_rows", [TILE, TILE, 1]),
    ("enhance", [TILE, TILE, 1]),
    ("classify", CLASSIFY_WORKGROUP),
    ("classify_rows", [TILE, TILE, 1]),
    ("finish_tiles", [1, 1, 1]),
];

/// Words (u32) of the tile list before the tile indices: the count, the indirect dispatch's
/// three workgroup counts, the total, padding and the indirect draw's four arguments (struct
/// TileList).
pub const TILE_LIST_HEADER_WORDS: u64 = 12;
/// Byte offset of the indirect dispatch's arguments in the tile list.
pub const TILE_LIST_DISPATCH_OFFSET: u64 = 4;
/// Byte offset of the indirect draw's arguments (vkCmdDrawIndirect: six vertices per listed
/// tile, one instance each) in the tile list: the image-copy path's write-back draws the
/// listed tiles (shaders/write_back.wgsl).
pub const TILE_LIST_DRAW_OFFSET: u64 = 32;
/// The tile list's declaration; its header must be TILE_LIST_HEADER_WORDS words and hold the
/// dispatch arguments at TILE_LIST_DISPATCH_OFFSET and the draw's at TILE_LIST_DRAW_OFFSET
/// (checked by build.rs).
pub const TILE_LIST_WGSL: &str = "struct TileList {
    // Tiles found so far by classify; finish_tiles moves it to `total` and zeroes it.
    count: atomic<u32>,
    // vkCmdDispatchIndirect arguments: workgroups x, y, z.
    groups: array<u32, 3>,
    total: u32,
    pad: array<u32, 3>,
    // vkCmdDrawIndirect arguments: vertices, instances, first vertex, first instance.
    draw: array<u32, 4>,
    // Tile index (row * tile_columns + column) of each listed tile.
    index: array<u32>,
}
";

/// The largest blur half-width (blur_size at most 2 * MAX_BLUR_HALF + 1); one background
/// pass is built per half-width 0..=MAX_BLUR_HALF.
pub const MAX_BLUR_HALF: u32 = 7;
/// Gaussian taps in the push constants: offsets 0..=MAX_BLUR_HALF.
pub const BLUR_TAPS: usize = MAX_BLUR_HALF as usize + 1;

/// A pixel's byte layout in a display region (the `FORMAT` code's low bits).
pub const LAYOUT_RGBA8: u32 = 0;
pub const LAYOUT_BGRA8: u32 = 1;
pub const LAYOUT_RGBA16_UNORM: u32 = 2;
pub const LAYOUT_RGBA16_FLOAT: u32 = 3;
pub const LAYOUT_A2B10G10R10: u32 = 4;
/// Set in a format code when the stored values are sRGB-encoded.
pub const FORMAT_SRGB_BIT: u32 = 256;
/// Every format code a shader is built for (the sRGB ones are 8-bit).
pub const FORMAT_CODES: [u32; 7] = [
    LAYOUT_RGBA8 | FORMAT_SRGB_BIT,
    LAYOUT_RGBA8,
    LAYOUT_BGRA8 | FORMAT_SRGB_BIT,
    LAYOUT_BGRA8,
    LAYOUT_RGBA16_UNORM,
    LAYOUT_RGBA16_FLOAT,
    LAYOUT_A2B10G10R10,
];

/// What a view shows (ViewMode).
pub const MODE_ENHANCE: u32 = 0;
pub const MODE_OFF: u32 = 1;
pub const MODE_SPLIT: u32 = 2;
pub const MODE_HEATMAP: u32 = 3;
pub const MODE_BACKGROUND: u32 = 4;
/// The modes an `enhance` variant is built for (MODE_OFF does no GPU work; MODE_BACKGROUND has
/// one variant of its own).
pub const ENHANCE_MODES: [u32; 3] = [MODE_ENHANCE, MODE_SPLIT, MODE_HEATMAP];

/// The benchmark's ablations (`contrastxr bench --ablate`), bits of the WGSL constant ABLATE:
/// each takes one part of the enhancement out, to show what it costs. 0 in every shader the
/// layer and the offline tools run; the ablated `enhance` variants are built for the paper's
/// and the perceptual method on RGBA8 sRGB only (build/variants.rs). Their output is not an
/// enhancement.
/// No scaled-space conversion and no method: each pixel's output is its display colour.
pub const ABLATE_METHOD: u32 = 1;
/// A constant mid-grey background: no camera texel reads (its conversion to the scaled space
/// kept).
pub const ABLATE_BACKGROUND: u32 = 2;
/// No sRGB decode or encode: the stored values are taken as linear.
pub const ABLATE_CODEC: u32 = 4;
/// The enhance pass returns at once: classify, finish_tiles and an empty indirect dispatch.
pub const ABLATE_ENHANCE_PASS: u32 = 8;
/// The perceptual method without its 18 directions: the paper's colour the only candidate.
pub const ABLATE_DIRECTIONS: u32 = 16;
/// The perceptual method without its bisection back toward the display colour.
pub const ABLATE_BISECTION: u32 = 32;
/// Not a part taken out but one replaced: the CIELAB conversions' cube roots by the driver's
/// `pow(x, 1/3)` (a GPU's own logarithm and exponential) instead of the bit-pattern seed and
/// the Newton steps, to show what they cost on a device. Its output is still an enhancement.
pub const ABLATE_CUBE_ROOT: u32 = 64;
/// The ablations the paper's `enhance` is built for: each part alone, the three per-pixel parts
/// together (only the loads, the quantisation and the stores left), the pass, the cube roots
/// by `pow`.
pub const ABLATIONS: [u32; 6] = [
    ABLATE_METHOD,
    ABLATE_BACKGROUND,
    ABLATE_CODEC,
    ABLATE_METHOD | ABLATE_BACKGROUND | ABLATE_CODEC,
    ABLATE_ENHANCE_PASS,
    ABLATE_CUBE_ROOT,
];
/// The ablations the perceptual method's `enhance` is built for: the method, the background,
/// its search's two parts alone and together.
pub const PERCEPTUAL_ABLATIONS: [u32; 5] = [
    ABLATE_METHOD,
    ABLATE_BACKGROUND,
    ABLATE_DIRECTIONS,
    ABLATE_BISECTION,
    ABLATE_DIRECTIONS | ABLATE_BISECTION,
];

// The method codes are the method table's (src/algorithm/method/table.rs, `code`).

/// The codes written into every shader as WGSL constants, by name.
pub const CODES: [(&str, u32); 47] = [
    ("TILE", TILE),
    ("DECODE_ROWS", DECODE_ROWS),
    ("INDIRECT_ROW_GROUPS", INDIRECT_ROW_GROUPS),
    ("MAX_BLUR_HALF", MAX_BLUR_HALF),
    ("LAYOUT_RGBA8", LAYOUT_RGBA8),
    ("LAYOUT_BGRA8", LAYOUT_BGRA8),
    ("LAYOUT_RGBA16_UNORM", LAYOUT_RGBA16_UNORM),
    ("LAYOUT_RGBA16_FLOAT", LAYOUT_RGBA16_FLOAT),
    ("LAYOUT_A2B10G10R10", LAYOUT_A2B10G10R10),
    ("FORMAT_SRGB_BIT", FORMAT_SRGB_BIT),
    ("MODE_ENHANCE", MODE_ENHANCE),
    ("MODE_OFF", MODE_OFF),
    ("MODE_SPLIT", MODE_SPLIT),
    ("MODE_HEATMAP", MODE_HEATMAP),
    ("MODE_BACKGROUND", MODE_BACKGROUND),
    ("LINEAR_BITS", LINEAR_BITS),
    ("LINEAR_MAX", LINEAR_MAX),
    ("CLASSIFY_WORKGROUP_X", CLASSIFY_WORKGROUP[0]),
    ("CLASSIFY_WORKGROUP_Y", CLASSIFY_WORKGROUP[1]),
    ("BLUR_TAPS", BLUR_TAPS as u32),
    ("ACCESS_NARROW", ACCESS_NARROW),
    ("ACCESS_WIDE", ACCESS_WIDE),
    ("ACCESS_IN_PLACE", ACCESS_IN_PLACE),
    ("ACCESS_SAMPLED", ACCESS_SAMPLED),
    ("PERCEPTUAL_HEADER_WORDS", PERCEPTUAL_HEADER_WORDS),
    ("PERCEPTUAL_TABLE_LEN", PERCEPTUAL_TABLE_LEN),
    ("PERCEPTUAL_MAX_FREQUENCIES", PERCEPTUAL_MAX_FREQUENCIES),
    ("PERCEPTUAL_AT_RGB_TO_LMS", PERCEPTUAL_AT_RGB_TO_LMS),
    (
        "PERCEPTUAL_AT_RGB_TO_LUMINANCE",
        PERCEPTUAL_AT_RGB_TO_LUMINANCE,
    ),
    ("PERCEPTUAL_AT_HALF_PEAK", PERCEPTUAL_AT_HALF_PEAK),
    ("PERCEPTUAL_AT_WORLD", PERCEPTUAL_AT_WORLD),
    (
        "PERCEPTUAL_AT_LOG_MIN_LUMINANCE",
        PERCEPTUAL_AT_LOG_MIN_LUMINANCE,
    ),
    ("PERCEPTUAL_AT_TARGET", PERCEPTUAL_AT_TARGET),
    ("PERCEPTUAL_AT_SURE_TARGET", PERCEPTUAL_AT_SURE_TARGET),
    ("PERCEPTUAL_AT_BANDS", PERCEPTUAL_AT_BANDS),
    ("PERCEPTUAL_BANDS", PERCEPTUAL_BANDS),
    ("PERCEPTUAL_AT_FREQUENCIES", PERCEPTUAL_AT_FREQUENCIES),
    ("PERCEPTUAL_AT_LOG_Y_FIRST", PERCEPTUAL_AT_LOG_Y_FIRST),
    (
        "PERCEPTUAL_AT_ENTRIES_PER_LOG_Y",
        PERCEPTUAL_AT_ENTRIES_PER_LOG_Y,
    ),
    ("PERCEPTUAL_WORDS", PERCEPTUAL_WORDS),
    ("ABLATE_METHOD", ABLATE_METHOD),
    ("ABLATE_BACKGROUND", ABLATE_BACKGROUND),
    ("ABLATE_CODEC", ABLATE_CODEC),
    ("ABLATE_ENHANCE_PASS", ABLATE_ENHANCE_PASS),
    ("ABLATE_DIRECTIONS", ABLATE_DIRECTIONS),
    ("ABLATE_BISECTION", ABLATE_BISECTION),
    ("ABLATE_CUBE_ROOT", ABLATE_CUBE_ROOT),
];

/// The blurred background packs each texel's linear R, G, B into 21 bits each (two texels per
/// entry of `blurred`): values 0..=LINEAR_MAX stand for 0..=1.
pub const LINEAR_BITS: u32 = 21;
pub const LINEAR_MAX: u32 = (1 << LINEAR_BITS) - 1;

/// A field type of the push-constant block, with its WGSL name, size and alignment in bytes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ParamType {
    U32,
    F32,
    Vec2U32,
    /// `array<vec4<f32>, N>` holding N * 4 floats.
    Vec4F32Array(u32),
}

impl ParamType {
    pub fn wgsl(self) -> String {
        match self {
            ParamType::U32 => "u32".into(),
            ParamType::F32 => "f32".into(),
            ParamType::Vec2U32 => "vec2<u32>".into(),
            ParamType::Vec4F32Array(n) => format!("array<vec4<f32>, {n}>"),
        }
    }

    pub const fn size(self) -> u32 {
        match self {
            ParamType::U32 | ParamType::F32 => 4,
            ParamType::Vec2U32 => 8,
            ParamType::Vec4F32Array(n) => 16 * n,
        }
    }

    pub const fn align(self) -> u32 {
        match self {
            ParamType::U32 | ParamType::F32 => 4,
            ParamType::Vec2U32 => 8,
            ParamType::Vec4F32Array(_) => 16,
        }
    }
}

/// The push-constant block `Params` every pass shares, in order: WGSL lays it out (and the
/// Rust `PushConstants` mirrors it) with each field at the next multiple of its alignment.
pub const PARAMS: [(&str, ParamType); 23] = [
    ("camera_size", ParamType::Vec2U32),
    // Size of the display region (one view), in pixels; buffers are tightly packed rows.
    ("region_size", ParamType::Vec2U32),
    ("lambda_e", ParamType::F32),
    ("lambda_jnd", ParamType::F32),
    ("transmittance", ParamType::F32),
    // Gaussian taps at offsets -blur_half..=blur_half (blur_half <= MAX_BLUR_HALF).
    ("blur_half", ParamType::U32),
    // Symmetric normalised taps: tap(k) = taps[k / 4][k % 4] for k = |offset|.
    ("taps", ParamType::Vec4F32Array(BLUR_TAPS as u32 / 4)),
    ("k_v", ParamType::F32),
    ("k_b", ParamType::F32),
    // What the view shows (MODE_*).
    ("mode", ParamType::U32),
    // Tiles per row of the region (TILE x TILE pixels each).
    ("tile_columns", ParamType::U32),
    // Beyond the paper (0 = off): chroma boost on near-grey backgrounds; luminance cap.
    ("achromatic_boost", ParamType::F32),
    ("luminance_cap", ParamType::F32),
    // The view's camera mapping, row-major: camera_uv = (M (display_uv, 1)).xy / .z.
    ("map_00", ParamType::F32),
    ("map_01", ParamType::F32),
    ("map_02", ParamType::F32),
    ("map_10", ParamType::F32),
    ("map_11", ParamType::F32),
    ("map_12", ParamType::F32),
    ("map_20", ParamType::F32),
    ("map_21", ParamType::F32),
    ("map_22", ParamType::F32),
    // Where the region starts in the app's image (ACCESS_IN_PLACE): x in the low 16 bits, y
    // in the high 16 bits.
    ("region_origin", ParamType::U32),
];

/// The byte offset of each PARAMS field, and the block's size (a multiple of its largest
/// alignment), as WGSL lays them out.
pub const fn params_layout() -> ([u32; PARAMS.len()], u32) {
    layout_of(&PARAMS)
}

/// `params_layout` of any field list (the tests lay out altered copies of PARAMS).
pub const fn layout_of<const N: usize>(params: &[(&str, ParamType); N]) -> ([u32; N], u32) {
    let mut offsets = [0u32; N];
    let (mut at, mut align, mut i) = (0u32, 4u32, 0);
    while i < N {
        let ty = params[i].1;
        at = at.div_ceil(ty.align()) * ty.align();
        offsets[i] = at;
        at += ty.size();
        if ty.align() > align {
            align = ty.align();
        }
        i += 1;
    }
    (offsets, at.div_ceil(align) * align)
}

/// The push-constant block's size: at most 128 bytes, the least maxPushConstantsSize Vulkan
/// guarantees.
pub const PARAMS_SIZE: u32 = params_layout().1;
const _: () = assert!(PARAMS_SIZE <= 128);
