//! Pure CPU conversion of V4L2 pixel formats to 8-bit sRGB RGBA.
//!
//! YUYV and NV12 are read as BT.601 limited range (Y in 16..235, Cb/Cr in 16..240), which is
//! what UVC cameras send; JPEG/MJPEG is full range (JFIF) and handled in `mjpeg`. The YUV
//! transform is the usual 8-bit fixed-point form of the BT.601 equations
//! (R = 1.164 (Y-16) + 1.596 (Cr-128), G = 1.164 (Y-16) - 0.392 (Cb-128) - 0.813 (Cr-128),
//! B = 1.164 (Y-16) + 2.017 (Cb-128)), within one code value of the exact result.
//! The camera's RGB is taken as sRGB-encoded, as webcams deliver it.

use crate::image::RgbaImage;

/// The pixel formats a background camera may deliver.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum PixelFormat {
    Yuyv,
    Nv12,
    Mjpeg,
    Rgb24,
    Bgr24,
    Grey,
}

impl PixelFormat {
    pub const ALL: [PixelFormat; 6] = [
        PixelFormat::Yuyv,
        PixelFormat::Nv12,
        PixelFormat::Mjpeg,
        PixelFormat::Rgb24,
        PixelFormat::Bgr24,
        PixelFormat::Grey,
    ];

    /// The V4L2 fourcc code.
    pub fn fourcc(self) -> [u8; 4] {
        *match self {
            PixelFormat::Yuyv => b"YUYV",
            PixelFormat::Nv12 => b"NV12",
            PixelFormat::Mjpeg => b"MJPG",
            PixelFormat::Rgb24 => b"RGB3",
            PixelFormat::Bgr24 => b"BGR3",
            PixelFormat::Grey => b"GREY",
        }
    }

    pub fn from_fourcc(code: [u8; 4]) -> Option<PixelFormat> {
        PixelFormat::ALL.into_iter().find(|f| f.fourcc() == code)
    }

    /// Bytes per pixel of the first plane for a row stride, or `None` for compressed data.
    fn min_stride(self, width: u32) -> Option<usize> {
        let w = width as usize;
        match self {
            PixelFormat::Yuyv => Some(w * 2),
            PixelFormat::Nv12 | PixelFormat::Grey => Some(w),
            PixelFormat::Rgb24 | PixelFormat::Bgr24 => Some(w * 3),
            PixelFormat::Mjpeg => None,
        }
    }
}

/// BT.601 limited-range Y'CbCr to 8-bit R'G'B' (fixed point, see the module docs).
pub fn bt601_limited_to_rgb(y: u8, cb: u8, cr: u8) -> [u8; 3] {
    let c = 298 * (i32::from(y) - 16);
    let d = i32::from(cb) - 128;
    let e = i32::from(cr) - 128;
    let clamp = |v: i32| ((v + 128) >> 8).clamp(0, 255) as u8;
    [
        clamp(c + 409 * e),
        clamp(c - 100 * d - 208 * e),
        clamp(c + 516 * d),
    ]
}

/// BT.601 full-range Y'CbCr (JFIF, and Y4M files marked `XCOLORRANGE=FULL`) to R'G'B':
/// R = Y + 1.402 (Cr-128), G = Y - 0.344136 (Cb-128) - 0.714136 (Cr-128), B = Y + 1.772 (Cb-128),
/// in 16-bit fixed point.
pub fn bt601_full_to_rgb(y: u8, cb: u8, cr: u8) -> [u8; 3] {
    let c = i32::from(y) << 16;
    let d = i32::from(cb) - 128;
    let e = i32::from(cr) - 128;
    let clamp = |v: i32| ((v + 32768) >> 16).clamp(0, 255) as u8;
    [
        clamp(c + 91881 * e),
        clamp(c - 22554 * d - 46802 * e),
        clamp(c + 116130 * d),
    ]
}

/// Converts one frame. `stride` is the driver's bytes per line (0 = tightly packed).
pub fn to_rgba(
    format: PixelFormat,
    data: &[u8],
    width: u32,
    height: u32,
    stride: u32,
) -> Result<RgbaImage, String> {
    let empty = RgbaImage::new(0, 0, [0, 0, 0, 255]);
    to_rgba_into(format, data, (width, height, stride), empty)
}

/// [`to_rgba`] into `into`'s buffer when its size matches (MJPEG decodes into a new one).
pub(crate) fn to_rgba_into(
    format: PixelFormat,
    data: &[u8],
    (width, height, stride): (u32, u32, u32),
    into: RgbaImage,
) -> Result<RgbaImage, String> {
    if width == 0 || height == 0 {
        return Err(format!("frame of {width}x{height} is empty"));
    }
    let Some(min_stride) = format.min_stride(width) else {
        return crate::camera::mjpeg::decode(data);
    };
    let stride = (stride as usize).max(min_stride);
    let planes = if format == PixelFormat::Nv12 { 3 } else { 2 };
    // Every row but the last needs its full stride; NV12 adds half as many chroma rows.
    let rows = if format == PixelFormat::Nv12 {
        height as usize * planes / 2
    } else {
        height as usize
    };
    // Sizes come from the driver: a product too large for memory is as short as any.
    let needed = stride
        .checked_mul(rows.saturating_sub(1))
        .and_then(|n| n.checked_add(min_stride))
        .unwrap_or(usize::MAX);
    if data.len() < needed {
        return Err(format!(
            "{} frame of {width}x{height} has {} bytes, needs {needed}",
            String::from_utf8_lossy(&format.fourcc()),
            data.len()
        ));
    }
    let mut image = crate::camera::pool::sized(into, width, height);
    for y in 0..height as usize {
        let row = &data[y * stride..];
        let out = &mut image.pixels[y * width as usize..(y + 1) * width as usize];
        match format {
            PixelFormat::Yuyv => yuyv_row(row, out),
            PixelFormat::Nv12 => {
                let chroma = &data[stride * (height as usize + y / 2)..];
                nv12_row(row, chroma, out)
            }
            PixelFormat::Rgb24 => packed_row(row, out, [0, 1, 2]),
            PixelFormat::Bgr24 => packed_row(row, out, [2, 1, 0]),
            PixelFormat::Grey => grey_row(row, out),
            PixelFormat::Mjpeg => unreachable!("handled above"),
        }
    }
    Ok(image)
}

fn rgba([r, g, b]: [u8; 3]) -> [u8; 4] {
    [r, g, b, 255]
}

/// Y0 Cb Y1 Cr: two pixels share one chroma pair.
fn yuyv_row(row: &[u8], out: &mut [[u8; 4]]) {
    for (x, px) in out.iter_mut().enumerate() {
        let pair = &row[(x / 2) * 4..(x / 2) * 4 + 4];
        *px = rgba(bt601_limited_to_rgb(row[x * 2], pair[1], pair[3]));
    }
}

/// A full-resolution Y row and the interleaved CbCr row shared by two lines.
fn nv12_row(luma: &[u8], chroma: &[u8], out: &mut [[u8; 4]]) {
    for (x, px) in out.iter_mut().enumerate() {
        let c = (x / 2) * 2;
        *px = rgba(bt601_limited_to_rgb(luma[x], chroma[c], chroma[c + 1]));
    }
}

fn packed_row(row: &[u8], out: &mut [[u8; 4]], [r, g, b]: [usize; 3]) {
    for (px, src) in out.iter_mut().zip(row.as_chunks::<3>().0) {
        *px = [src[r], src[g], src[b], 255];
    }
}

fn grey_row(row: &[u8], out: &mut [[u8; 4]]) {
    for (px, &v) in out.iter_mut().zip(row) {
        *px = [v, v, v, 255];
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Reference values worked out by hand from the floating-point BT.601 limited-range
    /// equations (Kr = 0.299, Kb = 0.114, scale 255/219 for Y and 255/224 for chroma).
    const REFERENCE: [([u8; 3], [u8; 3]); 6] = [
        ([16, 128, 128], [0, 0, 0]),        // black
        ([235, 128, 128], [255, 255, 255]), // white: 1.164383 * 219 = 255.0
        ([126, 128, 128], [128, 128, 128]), // 1.164383 * 110 = 128.08
        // Y'=65, Cb'=-38, Cr'=112: R = 75.685 + 178.755 = 254.4; G = 75.685 + 14.887 - 91.052
        // = -0.48; B = 75.685 - 76.655 = -0.97 (BT.601 red).
        ([81, 90, 240], [254, 0, 0]),
        // Y'=129, Cb'=-74, Cr'=-94: R = 150.205 - 150.027 = 0.18; G = 150.205 + 28.990
        // + 76.419 = 255.6 (clamped); B = 150.205 - 149.275 = 0.93 (BT.601 green).
        ([145, 54, 34], [0, 255, 1]),
        // Y'=100, Cb'=40, Cr'=-20: R = 116.438 - 31.921 = 84.52; G = 116.438 - 15.670
        // + 16.259 = 117.0; B = 116.438 + 80.689 = 197.1.
        ([116, 168, 108], [85, 117, 197]),
    ];

    fn close(a: [u8; 3], b: [u8; 3]) -> bool {
        a.iter()
            .zip(b)
            .all(|(&x, y)| (i32::from(x) - i32::from(y)).abs() <= 1)
    }

    #[test]
    fn bt601_matches_hand_computed_values() {
        for ([y, cb, cr], want) in REFERENCE {
            let got = bt601_limited_to_rgb(y, cb, cr);
            assert!(
                close(got, want),
                "YCbCr {y},{cb},{cr}: got {got:?}, want {want:?}"
            );
        }
    }

    #[test]
    fn bt601_full_range_matches_hand_computed_values() {
        // Cr' = 112: R = 81 + 1.402 * 112 = 238.0; G = 81 + 0.344136 * 38 - 0.714136 * 112
        // = 81 + 13.077 - 79.983 = 14.09; B = 81 - 1.772 * 38 = 13.66.
        assert!(close(bt601_full_to_rgb(81, 90, 240), [238, 14, 14]));
        assert_eq!(bt601_full_to_rgb(0, 128, 128), [0, 0, 0]);
        assert_eq!(bt601_full_to_rgb(255, 128, 128), [255, 255, 255]);
    }

    #[test]
    fn yuyv_pairs_share_chroma() {
        // Two pixels: black and white luma with neutral chroma, then red's triple twice.
        let data = [16, 128, 235, 128, 81, 90, 81, 240];
        let img = to_rgba(PixelFormat::Yuyv, &data, 4, 1, 0).unwrap();
        assert_eq!(img.pixels[0], [0, 0, 0, 255]);
        assert_eq!(img.pixels[1], [255, 255, 255, 255]);
        assert!(close(
            [img.pixels[2][0], img.pixels[2][1], img.pixels[2][2]],
            [254, 0, 0]
        ));
        assert_eq!(img.pixels[2], img.pixels[3]);
    }

    #[test]
    fn nv12_reads_the_half_resolution_chroma_plane() {
        // 2x2 luma (stride 4 with padding), then one CbCr pair for the 2x2 block.
        let data = [81, 81, 9, 9, 81, 81, 9, 9, 90, 240, 9, 9];
        let img = to_rgba(PixelFormat::Nv12, &data, 2, 2, 4).unwrap();
        for px in &img.pixels {
            assert!(close([px[0], px[1], px[2]], [254, 0, 0]), "{px:?}");
        }
    }

    #[test]
    fn packed_formats_keep_their_order() {
        let data = [10, 20, 30, 40, 50, 60];
        let rgb = to_rgba(PixelFormat::Rgb24, &data, 2, 1, 0).unwrap();
        assert_eq!(rgb.pixels, vec![[10, 20, 30, 255], [40, 50, 60, 255]]);
        let bgr = to_rgba(PixelFormat::Bgr24, &data, 2, 1, 0).unwrap();
        assert_eq!(bgr.pixels, vec![[30, 20, 10, 255], [60, 50, 40, 255]]);
        let grey = to_rgba(PixelFormat::Grey, &[7, 200], 2, 1, 0).unwrap();
        assert_eq!(grey.pixels, vec![[7, 7, 7, 255], [200, 200, 200, 255]]);
    }

    #[test]
    fn short_frames_are_an_error() {
        assert!(to_rgba(PixelFormat::Yuyv, &[0; 7], 2, 2, 0).is_err());
        assert!(to_rgba(PixelFormat::Nv12, &[0; 5], 2, 2, 0).is_err());
    }

    #[test]
    fn fourcc_round_trips() {
        for f in PixelFormat::ALL {
            assert_eq!(PixelFormat::from_fourcc(f.fourcc()), Some(f));
        }
        assert_eq!(PixelFormat::from_fourcc(*b"H264"), None);
    }
}
