//! MJPEG frames (one baseline JPEG per frame) to RGBA, with zune-jpeg.
//!
//! Many UVC cameras omit the Huffman tables (DHT) and rely on the standard ones from the JPEG
//! specification (Annex K), as AVI MJPEG allows. zune-jpeg fills those in when the frame carries
//! an `AVI1` APP0 segment, so a frame with neither DHT nor `AVI1` gets that segment spliced in.

use crate::image::RgbaImage;

/// An APP0 segment naming the data AVI MJPEG: length 8, "AVI1\0", one padding byte.
const AVI1_APP0: [u8; 10] = [0xFF, 0xE0, 0x00, 0x08, b'A', b'V', b'I', b'1', 0, 0];

pub(crate) fn decode(data: &[u8]) -> Result<RgbaImage, String> {
    let patched;
    let data = if needs_default_tables(data) {
        patched = [&data[..2], &AVI1_APP0[..], &data[2..]].concat();
        &patched[..]
    } else {
        data
    };
    RgbaImage::decode_jpeg(data).map_err(|e| format!("MJPEG frame does not decode: {e}"))
}

/// True for a JPEG with no DHT and no AVI1 marker before its first scan.
fn needs_default_tables(data: &[u8]) -> bool {
    if data.len() < 4 || data[0] != 0xFF || data[1] != 0xD8 {
        return false;
    }
    let mut i = 2;
    while i + 4 <= data.len() && data[i] == 0xFF {
        let marker = data[i + 1];
        if marker == 0xC4 {
            return false;
        }
        if marker == 0xDA {
            return true;
        }
        let length = usize::from(u16::from_be_bytes([data[i + 2], data[i + 3]]));
        if marker == 0xE0 && data.get(i + 4..i + 8) == Some(&b"AVI1"[..]) {
            return false;
        }
        i += 2 + length;
    }
    false
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_missing_tables() {
        let no_dht = [0xFF, 0xD8, 0xFF, 0xDB, 0x00, 0x02, 0xFF, 0xDA, 0x00, 0x02];
        assert!(needs_default_tables(&no_dht));
        let dht = [0xFF, 0xD8, 0xFF, 0xC4, 0x00, 0x02, 0xFF, 0xDA, 0x00, 0x02];
        assert!(!needs_default_tables(&dht));
        let avi = [
            0xFF, 0xD8, 0xFF, 0xE0, 0x00, 0x08, b'A', b'V', b'I', b'1', 0, 0, 0xFF, 0xDA,
        ];
        assert!(!needs_default_tables(&avi));
    }

    #[test]
    fn garbage_is_an_error_not_a_panic() {
        assert!(decode(&[0xFF, 0xD8, 0xFF, 0xDA, 0, 2, 1, 2, 3]).is_err());
        assert!(decode(b"not a jpeg").is_err());
    }
}
