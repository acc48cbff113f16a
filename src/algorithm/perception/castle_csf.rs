//! castleCSF's closed form for a static, foveal stimulus of 1 deg^2 (docs/algorithm.md,
//! *The contrast sensitivity model*): the sensitivities of the achromatic (sustained and
//! transient), red-green and yellow-violet channels at a mean luminance Y and a spatial
//! frequency f, and their combination into C, how many times its detection threshold a pattern
//! is.
//!
//! Written once over [`Real`], so that the same formulas run in f64 (the reference) and f32
//! (what a shader can afford; the tests hold the f32 form to the f64 one, which is how the
//! sustained channel's f32 trap is caught). Pure; it knows nothing of displays or pixels.
//!
//! The model and its parameters are castleCSF's, release v0.2.3:
//!
//! castleCSF, a contrast sensitivity function of colour, area, spatio-temporal frequency,
//! luminance and eccentricity. Copyright (c) 2024 Maliha Ashraf, Rafal K. Mantiuk, Alexandre
//! Chapiro, Sophie Wuerger. MIT licence:
//!
//! Permission is hereby granted, free of charge, to any person obtaining a copy of this software
//! and associated documentation files (the "Software"), to deal in the Software without
//! restriction, including without limitation the rights to use, copy, modify, merge, publish,
//! distribute, sublicense, and/or sell copies of the Software, and to permit persons to whom the
//! Software is furnished to do so, subject to the following conditions:
//!
//! The above copyright notice and this permission notice shall be included in all copies or
//! substantial portions of the Software.
//!
//! THE SOFTWARE IS PROVIDED "AS IS", WITHOUT WARRANTY OF ANY KIND, EXPRESS OR IMPLIED, INCLUDING
//! BUT NOT LIMITED TO THE WARRANTIES OF MERCHANTABILITY, FITNESS FOR A PARTICULAR PURPOSE AND
//! NONINFRINGEMENT. IN NO EVENT SHALL THE AUTHORS OR COPYRIGHT HOLDERS BE LIABLE FOR ANY CLAIM,
//! DAMAGES OR OTHER LIABILITY, WHETHER IN AN ACTION OF CONTRACT, TORT OR OTHERWISE, ARISING FROM,
//! OUT OF OR IN CONNECTION WITH THE SOFTWARE OR THE USE OR OTHER DEALINGS IN THE SOFTWARE.

use std::ops::{Add, Div, Mul, Neg, Sub};

/// The floating-point type the formulas run in: f64 for the reference, f32 for the checks of
/// what a shader would compute.
pub trait Real:
    Copy
    + PartialOrd
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
{
    /// A constant, rounded to this type.
    fn of(v: f64) -> Self;
    fn exp(self) -> Self;
    fn ln_1p(self) -> Self;
    fn log10(self) -> Self;
    fn powf(self, e: Self) -> Self;
    fn sqrt(self) -> Self;
    fn abs(self) -> Self;
    fn max(self, other: Self) -> Self;
}

macro_rules! impl_real {
    ($t:ty) => {
        impl Real for $t {
            fn of(v: f64) -> Self {
                v as $t
            }
            fn exp(self) -> Self {
                <$t>::exp(self)
            }
            fn ln_1p(self) -> Self {
                <$t>::ln_1p(self)
            }
            fn log10(self) -> Self {
                <$t>::log10(self)
            }
            fn powf(self, e: Self) -> Self {
                <$t>::powf(self, e)
            }
            fn sqrt(self) -> Self {
                <$t>::sqrt(self)
            }
            fn abs(self) -> Self {
                <$t>::abs(self)
            }
            fn max(self, other: Self) -> Self {
                <$t>::max(self, other)
            }
        }
    };
}

impl_real!(f32);
impl_real!(f64);

/// The stimulus area A in deg^2: castleCSF's size term at 1 deg^2.
pub const AREA_DEG2: f64 = 1.0;

/// The opponent combination K: rows achromatic (L + M), red-green (L - 2.3112 M) and
/// yellow-violet (-(L + M) + 50.9875 S), applied to cone responses (L, M, S).
pub const OPPONENT: [[f64; 3]; 3] = [[1.0, 1.0, 0.0], [1.0, -2.3112, 0.0], [-1.0, -1.0, 50.9875]];

/// One channel's band-pass and size parameters (its peak frequency f_max is separate: the
/// sustained channel's depends on Y).
struct Channel {
    /// Bandwidth b: the band-pass is 10^(-(log f - log f_max)^2 / 2^b).
    bandwidth: f64,
    /// Below f_max the band-pass stays at or above 1 - a (a = 0: it stays at 1).
    low_floor_a: f64,
    /// The size term's A0 and f0.
    a0: f64,
    f0: f64,
}

const SUSTAINED: Channel = Channel {
    bandwidth: 0.000213047,
    low_floor_a: 0.100207,
    a0: 157.103,
    f0: 0.702338,
};

const TRANSIENT_F_MAX: f64 = 0.000316696;
const TRANSIENT: Channel = Channel {
    bandwidth: 2.6761,
    low_floor_a: 0.000241177,
    a0: 3.81611,
    f0: 3.01389,
};

const RED_GREEN_F_MAX: f64 = 0.0178364;
const RED_GREEN: Channel = Channel {
    bandwidth: 2.42104,
    low_floor_a: 0.0,
    a0: 2816.44,
    f0: 0.0711058,
};

const YELLOW_VIOLET_F_MAX: f64 = 0.00425753;
const YELLOW_VIOLET: Channel = Channel {
    bandwidth: 2.68197,
    low_floor_a: 0.0,
    a0: 2.82789e7,
    f0: 0.000635093,
};

/// The chromatic channels' peak sensitivity p1 (1 + p2/Y)^-p3.
const RED_GREEN_PEAK: [f64; 3] = [681.434, 38.0038, 0.480386];
const YELLOW_VIOLET_PEAK: [f64; 3] = [166.683, 62.8974, 0.41193];

/// The size term G(f) = sqrt(Ac / (1 + Ac/A)) f, with Ac = A0 / (1 + (f/f0)^2).
fn size_term<R: Real>(f: R, ch: &Channel) -> R {
    let ratio = f / R::of(ch.f0);
    let ac = R::of(ch.a0) / (R::of(1.0) + ratio * ratio);
    (ac / (R::of(1.0) + ac / R::of(AREA_DEG2))).sqrt() * f
}

/// The band-pass LP(f) = 10^(-(log f - log f_max)^2 / 2^b), held at or above 1 - a below f_max.
fn band_pass<R: Real>(f: R, f_max: R, ch: &Channel) -> R {
    let decades = f.log10() - f_max.log10();
    let lp = R::of(10.0).powf(-(decades * decades) / R::of(2f64.powf(ch.bandwidth)));
    if f < f_max {
        lp.max(R::of(1.0 - ch.low_floor_a))
    } else {
        lp
    }
}

/// The sustained channel's luminance factor `1 - (1 + 5.58341e-7/Y)^-9.66862e9`, written as
/// `1 - exp(-9.66862e9 ln_1p(5.58341e-7/Y))`: in f32, `1 + 5.58341e-7/Y` rounds to 1 for Y above
/// about 10 cd/m^2 and the power form would make the whole sustained channel vanish.
pub fn sustained_luminance_factor<R: Real>(y: R) -> R {
    R::of(1.0) - (-(R::of(9.66862e9) * (R::of(5.58341e-7) / y).ln_1p())).exp()
}

/// The sustained channel's peak frequency, 1.78119 (1 + 91.5718/Y)^-0.256682.
fn sustained_f_max<R: Real>(y: R) -> R {
    R::of(1.78119) * (R::of(1.0) + R::of(91.5718) / y).powf(R::of(-0.256682))
}

/// The achromatic sustained channel's sensitivity at luminance `y` (cd/m^2), frequency `f` (cpd).
pub fn sustained<R: Real>(y: R, f: R) -> R {
    let peak = R::of(56.4947)
        * (R::of(1.0) + R::of(7.54726) / y).powf(R::of(-0.144532))
        * sustained_luminance_factor(y);
    peak * band_pass(f, sustained_f_max(y), &SUSTAINED) * size_term(f, &SUSTAINED)
}

/// The achromatic transient channel's sensitivity (before its weight R_trans).
pub fn transient<R: Real>(y: R, f: R) -> R {
    let peak = R::of(2748.09) * y.powf(R::of(0.193434));
    peak * band_pass(f, R::of(TRANSIENT_F_MAX), &TRANSIENT) * size_term(f, &TRANSIENT)
}

/// The transient channel's weight for a static stimulus, exp(-|w0|^0.3796 / 0.0844836) with
/// w0 = 2.41482 log Y + 4.7036 (the magnitude of castleCSF's complex power reduces to this).
/// It is 1 at w0 = 0 (Y ~ 0.0113 cd/m^2) and falls steeply either side: the jump the luminance
/// floor keeps the method away from.
pub fn transient_weight<R: Real>(y: R) -> R {
    let w0 = R::of(2.41482) * y.log10() + R::of(4.7036);
    (-(w0.abs().powf(R::of(0.3796)) / R::of(0.0844836))).exp()
}

/// The achromatic sensitivity, S_sust + R_trans S_trans.
pub fn achromatic<R: Real>(y: R, f: R) -> R {
    sustained(y, f) + transient_weight(y) * transient(y, f)
}

fn chromatic<R: Real>(y: R, f: R, peak: &[f64; 3], f_max: f64, ch: &Channel) -> R {
    let s_max = R::of(peak[0]) * (R::of(1.0) + R::of(peak[1]) / y).powf(R::of(-peak[2]));
    s_max * band_pass(f, R::of(f_max), ch) * size_term(f, ch)
}

/// The red-green sensitivity.
pub fn red_green<R: Real>(y: R, f: R) -> R {
    chromatic(y, f, &RED_GREEN_PEAK, RED_GREEN_F_MAX, &RED_GREEN)
}

/// The yellow-violet sensitivity.
pub fn yellow_violet<R: Real>(y: R, f: R) -> R {
    chromatic(
        y,
        f,
        &YELLOW_VIOLET_PEAK,
        YELLOW_VIOLET_F_MAX,
        &YELLOW_VIOLET,
    )
}

/// The three channels' sensitivities at one luminance and frequency.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sensitivities<R> {
    pub achromatic: R,
    pub red_green: R,
    pub yellow_violet: R,
}

/// All three channels at luminance `y` (cd/m^2) and frequency `f` (cpd).
pub fn sensitivities<R: Real>(y: R, f: R) -> Sensitivities<R> {
    Sensitivities {
        achromatic: achromatic(y, f),
        red_green: red_green(y, f),
        yellow_violet: yellow_violet(y, f),
    }
}

/// K applied to cone responses.
pub fn opponent<R: Real>(lms: [R; 3]) -> [R; 3] {
    OPPONENT.map(|row| R::of(row[0]) * lms[0] + R::of(row[1]) * lms[1] + R::of(row[2]) * lms[2])
}

/// C, the multiple of the detection threshold, of a pattern with cone-response mean `mean` and
/// amplitude `amplitude`:
/// `sqrt((d1/m1 S_ach)^2 + (d2/m1 S_rg)^2 + (d3/m1 S_yv)^2)` with `m = |K mean|`,
/// `d = |K amplitude|`. Every channel's contrast is taken against the achromatic mean m1.
/// 0 where m1 is 0 (no light at all).
pub fn threshold_multiple<R: Real>(mean: [R; 3], amplitude: [R; 3], s: Sensitivities<R>) -> R {
    let m1 = opponent(mean)[0].abs();
    if m1 <= R::of(0.0) {
        return R::of(0.0);
    }
    let d = opponent(amplitude);
    let a = d[0].abs() / m1 * s.achromatic;
    let rg = d[1].abs() / m1 * s.red_green;
    let yv = d[2].abs() / m1 * s.yellow_violet;
    (a * a + rg * rg + yv * yv).sqrt()
}
