//! Background texels a source prepared, on the Vulkan device: the ring of mapped images or
//! staging buffers the frame and offline rooms upload them through.

mod prepared_staging;
mod texel_ring;

pub(crate) use prepared_staging::staging_buffer;
pub(crate) use texel_ring::TexelRing;
