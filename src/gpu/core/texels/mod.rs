//! Background texels a source prepares on its own thread: the slots it fills and the backend's
//! frame takes, shared between the two threads, and the sink the source writes into.

mod mapped_rows;
mod ring_sink;
mod slot_state;
mod texel_slots;

pub(crate) use mapped_rows::MappedRows;
pub(crate) use ring_sink::RingSink;
pub(crate) use slot_state::Taken;
pub(crate) use texel_slots::TexelSlots;
