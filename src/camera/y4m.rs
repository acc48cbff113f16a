//! Y4M (YUV4MPEG2) files: 8-bit 4:2:0, 4:2:2, 4:4:4 and mono, indexed at open so any frame can
//! be read by seeking. Y4M carries no matrix, so BT.601 is assumed; range is limited unless the
//! header says `XCOLORRANGE=FULL`.

use crate::camera::convert::{bt601_full_to_rgb, bt601_limited_to_rgb};
use crate::image::{RgbaImage, Shrink};
use crate::user_file;
use std::fs::File;
use std::io::{BufRead, BufReader, Read, Seek, SeekFrom};
use std::path::{Path, PathBuf};

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Chroma {
    /// Horizontal and vertical subsampling shifts (4:2:0 = 1, 1).
    Planes {
        shift_x: u32,
        shift_y: u32,
    },
    Mono,
}

pub(crate) struct Y4m {
    path: PathBuf,
    pub(crate) width: u32,
    pub(crate) height: u32,
    pub(crate) fps: f64,
    chroma: Chroma,
    full_range: bool,
    /// File offset of each frame's pixel data.
    offsets: Vec<u64>,
    /// The last frame's YUV bytes, one buffer for every frame read: the whole frame when it
    /// is at most `whole_bytes`, else one row of each plane (a frame of the largest size a
    /// file may declare, 16384 a side, would be 384 MiB at 4:2:0).
    data: Vec<u8>,
    /// The largest frame read whole, in one read; a larger one is read row by row.
    whole_bytes: u64,
    /// The size frames are delivered at most (the camera size): a larger frame is shrunk row by
    /// row as it is converted, as an `image:` still is, so the RGBA frames a player keeps
    /// cost what camera frames do.
    most: (u32, u32),
}

impl Y4m {
    /// Opens `path`, whose frames are delivered at most `most` (width, height).
    pub(crate) fn open(path: &Path, most: (u32, u32)) -> Result<Y4m, String> {
        // Any length (a video), but a regular file: a FIFO or /dev/zero never hangs or floods.
        let file =
            user_file::open(path, u64::MAX).map_err(|why| format!("{} {why}", path.display()))?;
        let mut reader = BufReader::new(file);
        let mut header = Vec::new();
        (&mut reader)
            .take(MAX_LINE)
            .read_until(b'\n', &mut header)
            .map_err(|e| format!("cannot read {}: {e}", path.display()))?;
        if !header.ends_with(b"\n") {
            return Err(format!("{} has no Y4M header line", path.display()));
        }
        // The header is untrusted: bytes that are not text are no signature.
        let text = String::from_utf8_lossy(&header);
        let mut y4m = parse_header(text.trim_end())
            .map_err(|e| format!("{} is not a usable Y4M file: {e}", path.display()))?;
        y4m.path = path.to_path_buf();
        y4m.most = most;
        y4m.offsets = index_frames(&mut reader, header.len() as u64, y4m.frame_bytes())
            .map_err(|e| format!("{}: {e}", path.display()))?;
        if y4m.offsets.is_empty() {
            return Err(format!("{} holds no frames", path.display()));
        }
        Ok(y4m)
    }

    pub(crate) fn frame_count(&self) -> usize {
        self.offsets.len()
    }

    fn chroma_size(&self) -> (u32, u32) {
        match self.chroma {
            Chroma::Planes { shift_x, shift_y } => (
                (self.width + (1 << shift_x) - 1) >> shift_x,
                (self.height + (1 << shift_y) - 1) >> shift_y,
            ),
            Chroma::Mono => (0, 0),
        }
    }

    fn frame_bytes(&self) -> u64 {
        let (cw, ch) = self.chroma_size();
        u64::from(self.width) * u64::from(self.height) + 2 * u64::from(cw) * u64::from(ch)
    }

    /// Frame `index`, converted into `into` (whose buffer is reused when its size matches).
    pub(crate) fn read_frame(
        &mut self,
        index: usize,
        into: RgbaImage,
    ) -> Result<RgbaImage, String> {
        let mut file = user_file::open(&self.path, u64::MAX)
            .map_err(|why| format!("{} {why}", self.path.display()))?;
        let mut data = std::mem::take(&mut self.data);
        let image = if self.frame_bytes() <= self.whole_bytes {
            self.read_whole(&mut file, index, &mut data, into)
        } else {
            self.read_rows(&mut file, index, &mut data, into)
        };
        self.data = data;
        image.map_err(|e| format!("{}: frame {index}: {e}", self.path.display()))
    }

    /// The frame read in one piece into `data`, then converted.
    fn read_whole(
        &self,
        file: &mut File,
        index: usize,
        data: &mut Vec<u8>,
        into: RgbaImage,
    ) -> std::io::Result<RgbaImage> {
        data.resize(self.frame_bytes() as usize, 0);
        file.seek(SeekFrom::Start(self.offsets[index]))?;
        file.read_exact(data)?;
        let (w, h) = (self.width as usize, self.height as usize);
        let (luma, chroma) = data.split_at(w * h);
        let (cb, cr) = chroma.split_at(chroma.len() / 2);
        let cw = self.chroma_size().0 as usize;
        let shift_y = self.shift_y();
        self.to_rgba(into, |y, out| {
            let c = (y >> shift_y) * cw..((y >> shift_y) + 1) * cw;
            let (u, v) = (cb.get(c.clone()).unwrap_or(&[]), cr.get(c).unwrap_or(&[]));
            self.row_rgba(&luma[y * w..(y + 1) * w], u, v, out);
            Ok(())
        })
    }

    /// The frame read a row of each plane at a time into `data` (three rows' bytes), each
    /// converted as it comes.
    fn read_rows(
        &self,
        file: &mut File,
        index: usize,
        data: &mut Vec<u8>,
        into: RgbaImage,
    ) -> std::io::Result<RgbaImage> {
        let (w, h) = (u64::from(self.width), u64::from(self.height));
        let (cw, ch) = self.chroma_size();
        let (cw, ch) = (u64::from(cw), u64::from(ch));
        let start = self.offsets[index];
        data.resize((w + 2 * cw) as usize, 0);
        let (luma, chroma) = data.split_at_mut(w as usize);
        let (cb, cr) = chroma.split_at_mut(cw as usize);
        let shift_y = self.shift_y();
        let mut chroma_row = None;
        self.to_rgba(into, |y, out| {
            let mut read_at = |at: u64, into: &mut [u8]| {
                file.seek(SeekFrom::Start(at))?;
                file.read_exact(into)
            };
            read_at(start + y as u64 * w, luma)?;
            let c = (y >> shift_y) as u64;
            if cw > 0 && chroma_row != Some(c) {
                read_at(start + w * h + c * cw, cb)?;
                read_at(start + w * h + cw * ch + c * cw, cr)?;
                chroma_row = Some(c);
            }
            self.row_rgba(luma, cb, cr, out);
            Ok(())
        })
    }

    fn shift_y(&self) -> u32 {
        match self.chroma {
            Chroma::Planes { shift_y, .. } => shift_y,
            Chroma::Mono => 0,
        }
    }

    /// The frame whose row `y` `row` writes as RGBA, in `into`'s buffer where it fits: at the
    /// file's size, or shrunk to at most `most` when larger.
    fn to_rgba(
        &self,
        into: RgbaImage,
        mut row: impl FnMut(usize, &mut [[u8; 4]]) -> std::io::Result<()>,
    ) -> std::io::Result<RgbaImage> {
        let (w, h) = (self.width, self.height);
        if w <= self.most.0 && h <= self.most.1 {
            let mut image = crate::camera::pool::sized(into, w, h);
            for (y, out) in image.pixels.chunks_exact_mut(w as usize).enumerate() {
                row(y, out)?;
            }
            return Ok(image);
        }
        let mut shrink = Shrink::new((w, h), self.most, false, into.pixels);
        let mut pixels = vec![[0, 0, 0, 255]; w as usize];
        for y in 0..h as usize {
            row(y, &mut pixels)?;
            shrink.row(&pixels);
        }
        Ok(shrink.finish())
    }

    /// A row of the frame from its luma row and the chroma rows under it (empty for mono),
    /// converted into `out` (`width` pixels).
    fn row_rgba(&self, luma: &[u8], cb: &[u8], cr: &[u8], out: &mut [[u8; 4]]) {
        let convert = if self.full_range {
            bt601_full_to_rgb
        } else {
            bt601_limited_to_rgb
        };
        for (x, (px, &l)) in out.iter_mut().zip(luma).enumerate() {
            let (u, v) = match self.chroma {
                Chroma::Planes { shift_x, .. } => (cb[x >> shift_x], cr[x >> shift_x]),
                Chroma::Mono => (128, 128),
            };
            let [r, g, b] = convert(l, u, v);
            *px = [r, g, b, 255];
        }
    }
}

/// The largest frame read in one piece (a 4096x4096 4:2:0 frame is 24 MiB); a larger one is
/// read a row of each plane at a time.
const WHOLE_FRAME_BYTES: u64 = 32 << 20;

/// The longest header line read (the stream header and each FRAME header are short).
const MAX_LINE: u64 = 4096;

fn parse_header(line: &str) -> Result<Y4m, String> {
    let mut tokens = line.split(' ');
    if tokens.next() != Some("YUV4MPEG2") {
        return Err("no YUV4MPEG2 signature".into());
    }
    let mut y4m = Y4m {
        path: PathBuf::new(),
        width: 0,
        height: 0,
        fps: 25.0,
        chroma: Chroma::Planes {
            shift_x: 1,
            shift_y: 1,
        },
        full_range: false,
        offsets: Vec::new(),
        data: Vec::new(),
        whole_bytes: WHOLE_FRAME_BYTES,
        most: (u32::MAX, u32::MAX),
    };
    for token in tokens.filter(|t| !t.is_empty()) {
        // The first character is the key (the header is untrusted: it may not be ASCII).
        let mut chars = token.chars();
        let key = chars.next().map(String::from).unwrap_or_default();
        let value = chars.as_str();
        match key.as_str() {
            "W" => y4m.width = value.parse().map_err(|_| format!("bad width {value}"))?,
            "H" => y4m.height = value.parse().map_err(|_| format!("bad height {value}"))?,
            "F" => y4m.fps = parse_rate(value)?,
            "C" => y4m.chroma = parse_chroma(value)?,
            "X" if value == "COLORRANGE=FULL" => y4m.full_range = true,
            _ => {} // interlacing, aspect and other extensions do not change the pixels
        }
    }
    if y4m.width == 0 || y4m.height == 0 {
        return Err("width or height missing".into());
    }
    // A bound keeps allocations sane (a header can declare any size).
    user_file::check_dimensions(y4m.width, y4m.height)?;
    Ok(y4m)
}

fn parse_rate(value: &str) -> Result<f64, String> {
    let (num, den) = value
        .split_once(':')
        .ok_or(format!("bad frame rate {value}"))?;
    let (num, den): (f64, f64) = (
        num.parse().map_err(|_| format!("bad frame rate {value}"))?,
        den.parse().map_err(|_| format!("bad frame rate {value}"))?,
    );
    // Any rate of non-negative numbers is taken (0, 1e300, inf): the player clamps it.
    if num >= 0.0 && den > 0.0 {
        Ok((num / den).min(f64::MAX))
    } else {
        Err(format!("bad frame rate {value}"))
    }
}

fn parse_chroma(value: &str) -> Result<Chroma, String> {
    match value {
        "420" | "420jpeg" | "420paldv" | "420mpeg2" => Ok(Chroma::Planes {
            shift_x: 1,
            shift_y: 1,
        }),
        "422" => Ok(Chroma::Planes {
            shift_x: 1,
            shift_y: 0,
        }),
        "444" => Ok(Chroma::Planes {
            shift_x: 0,
            shift_y: 0,
        }),
        "mono" => Ok(Chroma::Mono),
        other => Err(format!(
            "colour space C{other} is not supported (8-bit 420, 422, 444, mono)"
        )),
    }
}

/// Walks the `FRAME` headers, recording where each frame's data starts.
fn index_frames(
    reader: &mut BufReader<File>,
    start: u64,
    frame_bytes: u64,
) -> Result<Vec<u64>, String> {
    let len = reader
        .get_ref()
        .metadata()
        .map_err(|e| e.to_string())?
        .len();
    let mut offsets = Vec::new();
    let mut pos = start;
    while pos < len {
        reader
            .seek(SeekFrom::Start(pos))
            .map_err(|e| e.to_string())?;
        let mut line = Vec::new();
        (&mut *reader)
            .take(MAX_LINE)
            .read_until(b'\n', &mut line)
            .map_err(|e| e.to_string())?;
        if !line.starts_with(b"FRAME") {
            return Err(format!("no FRAME header at byte {pos}"));
        }
        let data = pos + line.len() as u64;
        if data + frame_bytes > len {
            break; // a truncated last frame is dropped
        }
        offsets.push(data);
        pos = data + frame_bytes;
    }
    Ok(offsets)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn header_fields() {
        let y = parse_header("YUV4MPEG2 W6 H4 F30000:1001 Ip A1:1 C444 XYSCSS=444").unwrap();
        assert_eq!((y.width, y.height), (6, 4));
        assert!((y.fps - 29.97).abs() < 0.01);
        assert_eq!(
            y.chroma,
            Chroma::Planes {
                shift_x: 0,
                shift_y: 0
            }
        );
        assert_eq!(y.frame_bytes(), 72);
        let y = parse_header("YUV4MPEG2 W5 H3 F10:1").unwrap();
        // 4:2:0 by default, chroma rounded up: 3x2 per plane.
        assert_eq!(y.frame_bytes(), 15 + 12);
        assert!(parse_header("YUV4MPEG2 W5 H3 C420p10").is_err());
        assert!(parse_header("YUV4MPEG W5 H3").is_err());
    }

    /// A frame read a row at a time (as a frame over `WHOLE_FRAME_BYTES` is) gives what the
    /// whole read gives, in every chroma layout, at the file's size and shrunk, and keeps only
    /// a row of each plane.
    #[test]
    fn frames_read_row_by_row_equal_frames_read_whole() {
        let dir = crate::scratch::ScratchDir::new("y4m-rows");
        let (w, h) = (13u32, 7u32);
        for (tag, (sx, sy)) in [
            ("420", (1, 1)),
            ("422", (1, 0)),
            ("444", (0, 0)),
            ("mono", (9, 9)),
        ] {
            let path = dir.join(format!("{tag}.y4m"));
            let (cw, ch) = match tag {
                "mono" => (0, 0),
                _ => ((w + (1 << sx) - 1) >> sx, (h + (1 << sy) - 1) >> sy),
            };
            let mut bytes = format!("YUV4MPEG2 W{w} H{h} F10:1 C{tag}\n").into_bytes();
            for frame in 0..2u32 {
                bytes.extend(b"FRAME\n");
                let n = w * h + 2 * cw * ch;
                bytes.extend((0..n).map(|i| (i * 37 + frame * 11 + i / w) as u8));
            }
            std::fs::write(&path, bytes).unwrap();
            for most in [(w, h), (5, 3)] {
                let empty = || RgbaImage::new(0, 0, [0; 4]);
                let mut whole = Y4m::open(&path, most).unwrap();
                let mut rows = Y4m::open(&path, most).unwrap();
                rows.whole_bytes = 0;
                for frame in 0..2 {
                    let a = whole.read_frame(frame, empty()).unwrap();
                    let b = rows.read_frame(frame, empty()).unwrap();
                    assert_eq!(a, b, "{tag}, frame {frame}, at most {most:?}");
                }
                assert_eq!(whole.data.len() as u64, whole.frame_bytes(), "{tag}");
                assert_eq!(rows.data.len() as u32, w + 2 * cw, "{tag}");
            }
        }
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn frames_larger_than_the_camera_are_shrunk_into_the_pooled_buffer() {
        let dir = crate::scratch::ScratchDir::new("y4m-within");
        let path = dir.join("clip.y4m");
        let (w, h) = (30u8, 20u8);
        let mut bytes = format!("YUV4MPEG2 W{w} H{h} F10:1 C444\nFRAME\n").into_bytes();
        let plane = |f: fn(u8, u8) -> u8| (0..h).flat_map(move |y| (0..w).map(move |x| f(x, y)));
        bytes.extend(plane(|x, y| 16 + 7 * x + y));
        bytes.extend(plane(|x, _| 100 + x));
        bytes.extend(plane(|_, y| 150 - y));
        std::fs::write(&path, bytes).unwrap();
        let empty = || RgbaImage::new(0, 0, [0; 4]);
        let whole = Y4m::open(&path, (30, 20)).unwrap().read_frame(0, empty());
        let whole = whole.unwrap();
        assert_eq!((whole.width, whole.height), (30, 20));
        let mut clip = Y4m::open(&path, (8, 6)).unwrap();
        let small = clip.read_frame(0, empty()).unwrap();
        assert_eq!(small, whole.shrunk((8, 6)));
        let buffer = small.pixels.as_ptr();
        let again = clip.read_frame(0, small).unwrap();
        assert_eq!(again.pixels.as_ptr(), buffer, "the pooled buffer is reused");
        let _ = std::fs::remove_dir_all(&dir);
    }
}
