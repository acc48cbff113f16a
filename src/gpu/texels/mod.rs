//! Background texels a source prepared on the CPU: the ring of mapped images (or staging
//! buffers) they are written into, shared between the frame engine and a source's thread. The
//! slots, their sink and their rows name no Vulkan type: the OpenGL backend's mapped pixel
//! buffers (gpu/opengl/texel_buffers.rs) use them as they are.

mod mapped_rows;
mod prepared_staging;
mod ring_sink;
mod slot_state;
mod texel_ring;
mod texel_slots;

pub(crate) use mapped_rows::MappedRows;
pub(crate) use prepared_staging::staging_buffer;
pub(crate) use ring_sink::RingSink;
pub(crate) use slot_state::Taken;
pub(crate) use texel_ring::TexelRing;
pub(crate) use texel_slots::TexelSlots;
