//! Choosing a camera mode: the smallest size at least as large as wanted, at the lowest rate at
//! least as fast as wanted, preferring formats that are cheap to convert and carry colour.

use crate::camera::convert::PixelFormat;

/// One (format, size, frame interval) a device offers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Mode {
    pub fourcc: [u8; 4],
    /// `None` when this module cannot convert the format.
    pub format: Option<PixelFormat>,
    pub width: u32,
    pub height: u32,
    /// Seconds per frame as (numerator, denominator); (0, 0) when the driver lists none.
    pub interval: (u32, u32),
}

impl Mode {
    /// Frames per second, 0 when unknown.
    pub fn fps(&self) -> f64 {
        match self.interval {
            (n, d) if n > 0 => f64::from(d) / f64::from(n),
            _ => 0.0,
        }
    }
}

/// Lower is better: uncompressed colour first (no decode), MJPEG next, grey last.
fn format_rank(f: PixelFormat) -> u32 {
    match f {
        PixelFormat::Yuyv | PixelFormat::Nv12 => 0,
        PixelFormat::Rgb24 | PixelFormat::Bgr24 => 1,
        PixelFormat::Mjpeg => 2,
        PixelFormat::Grey => 3,
    }
}

/// Picks the mode for a wanted size and rate; `None` when no mode has a usable format.
/// When nothing is both large and fast enough, size wins over rate (a small background would
/// be blurry everywhere; a slow one only lags), then the largest, fastest mode is taken.
pub fn choose_mode(modes: &[Mode], width: u32, height: u32, fps: u32) -> Option<Mode> {
    let usable = modes.iter().filter_map(|m| m.format.map(|f| (m, f)));
    let big = |m: &Mode| m.width >= width && m.height >= height;
    let fast = |m: &Mode| m.fps() + 0.01 >= f64::from(fps);
    usable
        .min_by(|(a, fa), (b, fb)| {
            let key = |m: &Mode, f: PixelFormat| {
                let area = u64::from(m.width) * u64::from(m.height);
                (
                    !(big(m) && fast(m)),
                    !big(m),
                    // Among good modes the smallest; otherwise the largest.
                    if big(m) { area } else { u64::MAX - area },
                    !fast(m),
                    format_rank(f),
                )
            };
            key(a, *fa).cmp(&key(b, *fb)).then_with(|| {
                // The slowest rate that is fast enough, or else the fastest.
                let (ra, rb) = (a.fps(), b.fps());
                if fast(a) {
                    ra.total_cmp(&rb)
                } else {
                    rb.total_cmp(&ra)
                }
            })
        })
        .map(|(m, _)| *m)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mode(code: &[u8; 4], width: u32, height: u32, fps: u32) -> Mode {
        Mode {
            fourcc: *code,
            format: PixelFormat::from_fourcc(*code),
            width,
            height,
            interval: (1, fps),
        }
    }

    #[test]
    fn smallest_size_at_least_wanted_at_the_lowest_good_rate() {
        let modes = [
            mode(b"YUYV", 320, 240, 30),
            mode(b"YUYV", 640, 480, 15),
            mode(b"YUYV", 640, 480, 30),
            mode(b"YUYV", 640, 480, 60),
            mode(b"YUYV", 1280, 720, 30),
        ];
        assert_eq!(choose_mode(&modes, 640, 480, 30), Some(modes[2]));
    }

    #[test]
    fn mjpeg_when_raw_is_too_slow_at_that_size() {
        // A typical UVC camera: YUYV 1280x720 only at 10 fps, MJPEG at 30.
        let modes = [
            mode(b"YUYV", 640, 480, 30),
            mode(b"YUYV", 1280, 720, 10),
            mode(b"MJPG", 1280, 720, 30),
        ];
        assert_eq!(choose_mode(&modes, 1280, 720, 30), Some(modes[2]));
        assert_eq!(choose_mode(&modes, 640, 480, 30), Some(modes[0]));
    }

    #[test]
    fn falls_back_to_size_then_to_the_largest() {
        let modes = [mode(b"YUYV", 640, 480, 15), mode(b"YUYV", 320, 240, 60)];
        assert_eq!(choose_mode(&modes, 640, 480, 30), Some(modes[0]));
        let small = [mode(b"GREY", 160, 120, 30), mode(b"GREY", 320, 240, 15)];
        assert_eq!(choose_mode(&small, 640, 480, 30), Some(small[1]));
    }

    #[test]
    fn unknown_formats_are_never_chosen() {
        assert_eq!(
            choose_mode(&[mode(b"H264", 640, 480, 30)], 640, 480, 30),
            None
        );
    }
}
