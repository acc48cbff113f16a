//! The images a live source's thread fills, reused once no reader holds them.
//!
//! A camera frame is 1-4 MB. Allocating one per frame and freeing it a few frames later makes
//! glibc raise its mmap threshold past that size at the first free, so from then on the frames
//! come from the source thread's malloc arena, where the freed frames and the small allocations
//! between them leave holes the next frame does not fit: the heap grows in frame-sized steps for
//! as long as the session runs. Reusing a few images keeps the source's memory fixed.

use crate::image::RgbaImage;
use std::sync::Arc;

/// Published images kept for reuse: the mailbox, the consumer and the image being filled hold
/// at most three at once.
const KEPT: usize = 4;

#[derive(Default)]
pub(crate) struct ImagePool {
    /// The newest last; an image only this pool holds may be overwritten.
    kept: Vec<Arc<RgbaImage>>,
}

impl ImagePool {
    /// An image to overwrite: a published one no reader holds any more (of any size: the filler
    /// resizes it if needed), or an empty new one.
    pub(crate) fn take(&mut self) -> RgbaImage {
        let free = self.kept.iter().position(|i| Arc::strong_count(i) == 1);
        // Only the pool holds it, so no reader can clone it meanwhile and the unwrap succeeds.
        free.and_then(|at| Arc::try_unwrap(self.kept.remove(at)).ok())
            .unwrap_or_else(|| RgbaImage::new(0, 0, [0, 0, 0, 255]))
    }

    /// Shares a filled image for publishing and keeps a handle to reuse it.
    pub(crate) fn share(&mut self, image: RgbaImage) -> Arc<RgbaImage> {
        let shared = Arc::new(image);
        if self.kept.len() >= KEPT {
            self.kept.remove(0);
        }
        self.kept.push(shared.clone());
        shared
    }
}

/// `image` as a `width` x `height` image whose pixels the caller overwrites: its buffer is kept
/// when the size matches.
pub(crate) fn sized(image: RgbaImage, width: u32, height: u32) -> RgbaImage {
    let mut image = match (image.width, image.height) == (width, height) {
        true => image,
        false => RgbaImage::new(width, height, [0, 0, 0, 255]),
    };
    image.has_alpha = false;
    image
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_image_comes_back_only_once_no_reader_holds_it() {
        let mut pool = ImagePool::default();
        let image = sized(pool.take(), 4, 2);
        let first = pool.share(image);
        let address = first.pixels.as_ptr();
        // A reader still holds it: the pool hands out a new image.
        assert_eq!(pool.take().pixels.len(), 0);
        drop(first);
        let again = pool.take();
        assert_eq!(
            again.pixels.as_ptr(),
            address,
            "the buffer is reused, not reallocated"
        );
        let resized = sized(again, 4, 2);
        assert_eq!(resized.pixels.as_ptr(), address, "same size: same buffer");
        assert_eq!(
            sized(resized, 2, 2).pixels.len(),
            4,
            "another size: a new buffer"
        );
    }

    #[test]
    fn the_pool_keeps_at_most_a_few_images() {
        let mut pool = ImagePool::default();
        let held: Vec<_> = (0..2 * KEPT)
            .map(|_| pool.share(RgbaImage::new(1, 1, [0; 4])))
            .collect();
        assert_eq!(pool.kept.len(), KEPT);
        drop(held);
        for _ in 0..KEPT {
            assert_eq!(pool.take().pixels.len(), 1);
        }
        assert_eq!(pool.take().pixels.len(), 0);
    }
}
