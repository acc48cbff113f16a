// The per-pixel path's approximations, shared by build.rs (which writes them into the WGSL) and
// src/gpu/core/approx.rs (which checks their accuracy in f32). Fitted by
// scripts/fit-shader-polynomials.py: least squares reweighted towards the minimax error.

/// sRGB decode `((v + 0.055) / 1.055)^2.4` for stored values v in [0.04045, 1]: monomial
/// coefficients, lowest power first. 1.3e-5 largest relative error over the 8-bit codes.
pub const SRGB_DECODE_POLY: [f64; 9] = [
    8.404_388_177_332_358e-4,
    3.593_783_705_971_072e-2,
    4.752_281_821_621_8e-1,
    9.384_123_142_957_471e-1,
    -1.166_876_596_290_524,
    1.614_302_020_470_443,
    -1.560_391_332_841_176,
    8.699_105_342_677_222e-1,
    -2.073_758_604_894_97e-1,
];

/// `q^(5/3)` for q = v^(1/4), v in [0.0031308, 1] (so `1.055 * poly(q) - 0.055` is the sRGB
/// encode of v): lowest power first. 6.3e-6 largest absolute error (0.0017 of a code).
pub const SRGB_ENCODE_POLY: [f64; 6] = [
    -6.009_816_764_175_552e-3,
    1.535_807_830_521_201e-1,
    1.189_951_413_892_47,
    -5.473_672_105_632_817e-1,
    2.744_304_553_467_177e-1,
    -6.459_185_113_066_188e-2,
];

/// Bit-pattern seed for x^(-1/3): `MAGIC - bits(x) / 3` (3.5% off), tuned for two Newton steps.
pub const CBRT_SEED_MAGIC: u32 = 0x54a2_1dd8;
/// Newton steps on x^(-1/3) (quadratic convergence: 2.4e-3, 1.2e-5, then f32 rounding).
pub const CBRT_NEWTON_STEPS: u32 = 3;
