//! Background texels a source prepared on the CPU: the ring of mapped images (or staging
//! buffers) they are written into, shared between the frame engine and a source's thread.

mod mapped_rows;
mod prepared_staging;
mod ring_sink;
mod slot_state;
mod texel_ring;
mod texel_slots;

pub(crate) use prepared_staging::staging_buffer;
pub(crate) use texel_ring::TexelRing;
