// The layout of the `perceptual` buffer, part of the interface between the engine and its
// shaders (interface.rs includes this file, and build.rs includes interface.rs).

/// The `perceptual` buffer (src/gpu/core/perceptual_words.rs writes it), vec4s of f32: a
/// header of PERCEPTUAL_HEADER_WORDS words at the PERCEPTUAL_AT_* offsets, then for each of
/// the frame's frequencies (at most PERCEPTUAL_MAX_FREQUENCIES) PERCEPTUAL_TABLE_LEN entries
/// over log10 Y, each one vec4 of the three sensitivities (achromatic, red-green,
/// yellow-violet, then 0): one load per entry, which a CPU driver makes lane by lane.
pub const PERCEPTUAL_HEADER_WORDS: u32 = 56;
pub const PERCEPTUAL_TABLE_LEN: u32 = 256;
pub const PERCEPTUAL_MAX_FREQUENCIES: u32 = 4;
/// The buffer's size in words.
pub const PERCEPTUAL_WORDS: u32 =
    PERCEPTUAL_HEADER_WORDS + PERCEPTUAL_MAX_FREQUENCIES * 4 * PERCEPTUAL_TABLE_LEN;
const _: () = assert!(PERCEPTUAL_HEADER_WORDS.is_multiple_of(4));
/// Header offsets: linear RGB -> LMS (9 words, row-major), RGB -> luminance (3 words), then
/// one word each.
pub const PERCEPTUAL_AT_RGB_TO_LMS: u32 = 0;
pub const PERCEPTUAL_AT_RGB_TO_LUMINANCE: u32 = 9;
/// Half the display's peak luminance (the pattern's amplitude per unit of display colour).
pub const PERCEPTUAL_AT_HALF_PEAK: u32 = 12;
/// The world's luminance at the eye for the camera's linear 1.0 (t W).
pub const PERCEPTUAL_AT_WORLD: u32 = 13;
pub const PERCEPTUAL_AT_LOG_MIN_LUMINANCE: u32 = 14;
pub const PERCEPTUAL_AT_TARGET: u32 = 15;
/// The number of frequencies, as a float.
pub const PERCEPTUAL_AT_FREQUENCIES: u32 = 16;
/// log10 Y of the tables' first entry, and the entries per unit of log10 Y.
pub const PERCEPTUAL_AT_LOG_Y_FIRST: u32 = 17;
pub const PERCEPTUAL_AT_ENTRIES_PER_LOG_Y: u32 = 18;
/// The target times 1 + SURE_MARGIN, which the lower bound of c' must reach
/// (src/algorithm/perception/target_bound.rs).
pub const PERCEPTUAL_AT_SURE_TARGET: u32 = 19;
/// PERCEPTUAL_BANDS luminance bands, one vec4 each: the band's floor Y (cd/m^2) and its least
/// achromatic, red-green and yellow-violet sensitivities.
pub const PERCEPTUAL_AT_BANDS: u32 = 24;
pub const PERCEPTUAL_BANDS: u32 = 8;
const _: () = assert!(PERCEPTUAL_AT_BANDS + 4 * PERCEPTUAL_BANDS <= PERCEPTUAL_HEADER_WORDS);
