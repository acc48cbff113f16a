//! Animations: figure frames as one animated PNG (APNG), which browsers play and which other
//! viewers show as its first frame. Pure CPU; the caller writes the bytes.

use crate::image::RgbaImage;

/// One frame of an animation and how long it stays, in milliseconds.
pub struct AnimationFrame {
    pub image: RgbaImage,
    pub delay_ms: u16,
}

/// Encodes `frames` (all of one size, opaque RGB) as an APNG that loops forever.
pub fn encode_apng(frames: &[AnimationFrame]) -> Result<Vec<u8>, String> {
    let first = frames
        .first()
        .ok_or("an animation needs at least one frame")?;
    let (width, height) = (first.image.width, first.image.height);
    if let Some(f) = frames
        .iter()
        .find(|f| (f.image.width, f.image.height) != (width, height))
    {
        return Err(format!(
            "animation frames differ in size: {}x{} and {width}x{height}",
            f.image.width, f.image.height
        ));
    }
    let err = |e: png::EncodingError| format!("cannot encode the animation: {e}");
    let mut bytes = Vec::new();
    let mut encoder = png::Encoder::new(&mut bytes, width, height);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    // Photographs behind the panels: the best compression keeps a few seconds small.
    encoder.set_compression(png::Compression::Best);
    encoder.set_adaptive_filter(png::AdaptiveFilterType::Adaptive);
    encoder.set_animated(frames.len() as u32, 0).map_err(err)?;
    let mut writer = encoder.write_header().map_err(err)?;
    for frame in frames {
        writer
            .set_frame_delay(frame.delay_ms.max(1), 1000)
            .map_err(err)?;
        let rgb: Vec<u8> = frame
            .image
            .pixels
            .iter()
            .flat_map(|p| [p[0], p[1], p[2]])
            .collect();
        writer.write_image_data(&rgb).map_err(err)?;
    }
    writer.finish().map_err(err)?;
    Ok(bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame(colour: [u8; 4], delay_ms: u16) -> AnimationFrame {
        AnimationFrame {
            image: RgbaImage::new(5, 3, colour),
            delay_ms,
        }
    }

    #[test]
    fn apng_holds_every_frame_with_its_delay() {
        let frames = [
            frame([255, 0, 0, 255], 40),
            frame([0, 255, 0, 255], 60),
            frame([0, 0, 255, 255], 80),
        ];
        let bytes = encode_apng(&frames).unwrap();
        let mut reader = png::Decoder::new(bytes.as_slice()).read_info().unwrap();
        let control = reader.info().animation_control.unwrap();
        assert_eq!((control.num_frames, control.num_plays), (3, 0));
        assert_eq!((reader.info().width, reader.info().height), (5, 3));
        let mut buf = vec![0; reader.output_buffer_size()];
        for f in &frames {
            reader.next_frame(&mut buf).unwrap();
            let fc = reader.info().frame_control.unwrap();
            assert_eq!((fc.delay_num, fc.delay_den), (f.delay_ms, 1000));
            assert_eq!(&buf[..3], &f.image.pixels[0][..3]);
        }
    }

    #[test]
    fn frames_of_different_sizes_are_refused() {
        let mut frames = vec![frame([0, 0, 0, 255], 10)];
        frames.push(AnimationFrame {
            image: RgbaImage::new(4, 3, [0, 0, 0, 255]),
            delay_ms: 10,
        });
        assert!(encode_apng(&frames).unwrap_err().contains("differ in size"));
        assert!(encode_apng(&[]).is_err());
    }
}
