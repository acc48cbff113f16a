//! Every item of GL state `--check-gl-state` ([`super::gl_state`]) sets and reads back, with
//! the value it sets and how it is read.

use crate::gl_state_enums::*;
use crate::gl_state_fns::GLX_ITEMS;
use crate::gl_state_objects::Objects;
use std::ffi::c_void;

/// How an item is read back.
#[derive(Clone, Copy, Debug)]
pub enum Query {
    /// glGetInteger64v (up to 4 values).
    Integer(Enum),
    /// glGetInteger64i_v.
    Indexed(Enum, u32),
    /// glIsEnabled.
    Enabled(Enum),
    Context,
    Drawable,
    ReadDrawable,
}

/// One piece of state, and the value the check sets it to.
pub struct Item {
    pub what: String,
    pub query: Query,
    pub set: Vec<i64>,
}

/// Where the current context and the read drawable are among the items.
pub const CONTEXT_ITEM: usize = 0;
pub const READ_DRAWABLE_ITEM: usize = 2;

/// An item named `what`, read by `query`, that the check sets to `set`.
fn item(what: impl Into<String>, query: Query, set: &[i64]) -> Item {
    Item {
        what: what.into(),
        query,
        set: set.to_vec(),
    }
}

/// A GL object name as a query returns it.
fn name(n: u32) -> [i64; 1] {
    [n as i64]
}

/// Every item, with the value `set` gives it (the GLX_ITEMS first).
pub fn items(o: &Objects, context: *mut c_void, names: [&str; GLX_ITEMS]) -> Vec<Item> {
    let mut items = vec![
        item(names[0], Query::Context, &[context as i64]),
        item(names[1], Query::Drawable, &[o.draw as i64]),
        item(names[2], Query::ReadDrawable, &[o.read as i64]),
        item(
            "GL_CURRENT_PROGRAM",
            Query::Integer(CURRENT_PROGRAM),
            &name(o.program),
        ),
        item(
            "GL_PROGRAM_PIPELINE_BINDING",
            Query::Integer(PROGRAM_PIPELINE_BINDING),
            &name(o.pipeline),
        ),
        item(
            "GL_ACTIVE_TEXTURE",
            Query::Integer(ACTIVE_TEXTURE),
            &name(TEXTURE0 + ACTIVE_UNIT),
        ),
    ];
    for unit in 0..UNITS {
        items.extend(unit_items(o, unit));
        items.extend(indexed_buffer_items(o, unit));
    }
    items.extend(context_items(o));
    items
}

/// A unit's texture, sampler and image unit bindings.
fn unit_items(o: &Objects, unit: usize) -> [Item; 9] {
    let u = unit as u32;
    let at = |what: &str| format!("{what}[{unit}]");
    let image = |what: &str, pname, set: &[i64]| item(at(what), Query::Indexed(pname, u), set);
    [
        item(
            at("GL_TEXTURE_BINDING_2D"),
            Query::Indexed(TEXTURE_BINDING_2D, u),
            &name(o.textures_2d[unit]),
        ),
        item(
            at("GL_TEXTURE_BINDING_2D_ARRAY"),
            Query::Indexed(TEXTURE_BINDING_2D_ARRAY, u),
            &name(o.textures_array[unit]),
        ),
        item(
            at("GL_SAMPLER_BINDING"),
            Query::Indexed(SAMPLER_BINDING, u),
            &name(o.samplers[unit]),
        ),
        image(
            "GL_IMAGE_BINDING_NAME",
            IMAGE_BINDING_NAME,
            &name(o.textures_array[unit]),
        ),
        image("GL_IMAGE_BINDING_LEVEL", IMAGE_BINDING_LEVEL, &[1]),
        image("GL_IMAGE_BINDING_LAYERED", IMAGE_BINDING_LAYERED, &[1]),
        image("GL_IMAGE_BINDING_LAYER", IMAGE_BINDING_LAYER, &[1]),
        image(
            "GL_IMAGE_BINDING_ACCESS",
            IMAGE_BINDING_ACCESS,
            &name(READ_WRITE),
        ),
        image(
            "GL_IMAGE_BINDING_FORMAT",
            IMAGE_BINDING_FORMAT,
            &name(R32UI),
        ),
    ]
}

/// Index `unit` of the indexed storage and uniform buffer bindings: buffer, start and size.
fn indexed_buffer_items(o: &Objects, unit: usize) -> Vec<Item> {
    let u = unit as u32;
    let at = |what: &str| format!("{what}[{unit}]");
    let indexed = [
        (
            "GL_SHADER_STORAGE_BUFFER",
            [
                SHADER_STORAGE_BUFFER_BINDING,
                SHADER_STORAGE_BUFFER_START,
                SHADER_STORAGE_BUFFER_SIZE,
            ],
            o.storage[unit],
            o.storage_alignment,
        ),
        (
            "GL_UNIFORM_BUFFER",
            [
                UNIFORM_BUFFER_BINDING,
                UNIFORM_BUFFER_START,
                UNIFORM_BUFFER_SIZE,
            ],
            o.uniform[unit],
            o.uniform_alignment,
        ),
    ];
    let mut items = Vec::new();
    for (target, [binding, start, size], buffer, alignment) in indexed {
        let (offset, bytes) = Objects::range(alignment, unit);
        items.extend([
            item(
                at(&format!("{target}_BINDING")),
                Query::Indexed(binding, u),
                &name(buffer),
            ),
            item(
                at(&format!("{target}_START")),
                Query::Indexed(start, u),
                &[offset],
            ),
            item(
                at(&format!("{target}_SIZE")),
                Query::Indexed(size, u),
                &[bytes],
            ),
        ]);
    }
    items
}

/// The context-wide items: generic buffer bindings, pixel store, framebuffers, vertex array,
/// enables, viewport and scissor box.
fn context_items(o: &Objects) -> Vec<Item> {
    let mut items = Vec::new();
    for ((_, binding, what), buffer) in GENERIC_BUFFERS.iter().zip(o.generic) {
        items.push(item(*what, Query::Integer(*binding), &name(buffer)));
    }
    for (pname, what, value, _) in PIXEL_STORE {
        items.push(item(what, Query::Integer(pname), &[value as i64]));
    }
    items.extend([
        item(
            "GL_DRAW_FRAMEBUFFER_BINDING",
            Query::Integer(DRAW_FRAMEBUFFER_BINDING),
            &name(o.framebuffers[0]),
        ),
        item(
            "GL_READ_FRAMEBUFFER_BINDING",
            Query::Integer(READ_FRAMEBUFFER_BINDING),
            &name(o.framebuffers[1]),
        ),
        item(
            "GL_RENDERBUFFER_BINDING",
            Query::Integer(RENDERBUFFER_BINDING),
            &name(o.renderbuffer),
        ),
        item(
            "GL_VERTEX_ARRAY_BINDING",
            Query::Integer(VERTEX_ARRAY_BINDING),
            &name(o.vertex_array),
        ),
    ]);
    for (cap, what) in ENABLES {
        items.push(item(what, Query::Enabled(cap), &[1]));
    }
    let rect = |r: [i32; 4]| r.map(i64::from);
    items.push(item(
        "GL_VIEWPORT",
        Query::Integer(VIEWPORT),
        &rect(VIEWPORT_SET),
    ));
    items.push(item(
        "GL_SCISSOR_BOX",
        Query::Integer(SCISSOR_BOX),
        &rect(SCISSOR_SET),
    ));
    items
}
