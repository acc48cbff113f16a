//! Y4M (YUV4MPEG2) files: 8-bit 4:2:0, 4:2:2, 4:4:4 and mono, indexed at open so any frame can
//! be read by seeking. Y4M carries no matrix, so BT.601 is assumed; range is limited unless the
//! header says `XCOLORRANGE=FULL`.

use crate::camera::convert::{bt601_full_to_rgb, bt601_limited_to_rgb};
use crate::image::RgbaImage;
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
    /// The last frame's YUV bytes: one buffer for every frame read.
    data: Vec<u8>,
}

impl Y4m {
    pub(crate) fn open(path: &Path) -> Result<Y4m, String> {
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
        u64::from(self.width * self.height) + 2 * u64::from(cw * ch)
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
        data.resize(self.frame_bytes() as usize, 0);
        let read = file
            .seek(SeekFrom::Start(self.offsets[index]))
            .and_then(|_| file.read_exact(&mut data))
            .map_err(|e| format!("{}: frame {index}: {e}", self.path.display()));
        let image = read.map(|_| self.to_rgba(&data, into));
        self.data = data;
        image
    }

    fn to_rgba(&self, data: &[u8], into: RgbaImage) -> RgbaImage {
        let (w, h) = (self.width, self.height);
        let (cw, ch) = self.chroma_size();
        let (luma, chroma) = data.split_at((w * h) as usize);
        let (cb, cr) = chroma.split_at((cw * ch) as usize);
        let convert = if self.full_range {
            bt601_full_to_rgb
        } else {
            bt601_limited_to_rgb
        };
        let mut image = crate::camera::pool::sized(into, w, h);
        for y in 0..h {
            for x in 0..w {
                let (u, v) = match self.chroma {
                    Chroma::Planes { shift_x, shift_y } => {
                        let i = ((y >> shift_y) * cw + (x >> shift_x)) as usize;
                        (cb[i], cr[i])
                    }
                    Chroma::Mono => (128, 128),
                };
                let [r, g, b] = convert(luma[(y * w + x) as usize], u, v);
                image.set(x, y, [r, g, b, 255]);
            }
        }
        image
    }
}

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
    // Frame sizes are computed in u32: a bound keeps them exact (and allocations sane).
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
}
