//! `--check-gl-state` (with `--graphics opengl`): the host's GL state is the host's. Right
//! before each xrEndFrame the client sets non-default values of the GL state that a layer
//! working in the app's context could touch (the current context and drawables, the program and
//! program pipeline, the active texture unit, textures, samplers and image units on unit 0 and
//! every binding number of the layer's shaders, generic and indexed buffer bindings, the pixel
//! store, framebuffers, a few enables, viewport and scissor box) and leaves a GL error pending;
//! after xrEndFrame it reads all of it back, with glGet* and glXGetCurrent* (eglGetCurrent* with
//! --gl-binding egl, its pbuffers EGL surfaces) only, and records
//! every item that changed. Then it puts its own defaults back, so that the next frame's
//! uploads run as without the check.
//!
//! `--disturb-gl-state NAMES` changes the named items after they were set and before
//! xrEndFrame, as a layer that forgets to restore them would: the check must see it.

use crate::error::{fail, Result};
use crate::gl_state_enums::*;
use crate::gl_state_fns::{Fns, GLX_ITEMS};
use crate::gl_state_items::{items, Item, Query, CONTEXT_ITEM, READ_DRAWABLE_ITEM};
use crate::gl_state_objects::Objects;
use crate::glx::GlContext;
use serde::Serialize;
use std::ffi::c_void;

/// What --disturb-gl-state can change (each an item's name, without its unit).
pub const DISTURBABLE: [&str; 10] = [
    "glXGetCurrentDrawable",
    "glGetError",
    "GL_ACTIVE_TEXTURE",
    "GL_CURRENT_PROGRAM",
    "GL_TEXTURE_BINDING_2D",
    "GL_IMAGE_BINDING_NAME",
    "GL_PIXEL_UNPACK_BUFFER_BINDING",
    "GL_UNPACK_ALIGNMENT",
    "GL_DRAW_FRAMEBUFFER_BINDING",
    "GL_FRAMEBUFFER_SRGB",
];

/// One item that xrEndFrame changed.
#[derive(Serialize, Debug, Clone, PartialEq)]
pub struct Change {
    /// The xrEndFrame call's index in the run (frames ended before it).
    pub frame: u32,
    /// The query, with the unit or index in brackets: `GL_TEXTURE_BINDING_2D[5]`.
    pub what: String,
    /// A number, or an array for a query of several values.
    pub before: serde_json::Value,
    pub after: serde_json::Value,
}

/// The check over a run: its objects, and what it found.
pub struct GlStateCheck {
    f: Fns,
    objects: Objects,
    items: Vec<Item>,
    /// Every item as the client keeps it between checks (read once at the start).
    defaults: Vec<Vec<i64>>,
    display: *mut c_void,
    context: *mut c_void,
    drawable: u64,
    /// The read drawable of this check: every second check reads where it draws, as most
    /// apps do, the others from a pbuffer of their own.
    read_drawable: u64,
    disturb: Vec<String>,
    /// The frame of the set state, between `before_end_frame` and `after_end_frame`.
    frame: Option<u32>,
    pub checked: u32,
    pub changed: Vec<Change>,
}

fn json(v: &[i64]) -> serde_json::Value {
    match v {
        [one] => (*one).into(),
        many => many.into(),
    }
}

impl GlStateCheck {
    /// Creates the check's objects in `gl`'s context (current on this thread) and reads the
    /// client's own state; `disturb`: the names of DISTURBABLE to change before xrEndFrame.
    pub fn new(gl: &GlContext, disturb: &[String]) -> Result<GlStateCheck> {
        if let Some(bad) = disturb.iter().find(|d| !DISTURBABLE.contains(&d.as_str())) {
            return fail(format!(
                "--disturb-gl-state: unknown item {bad}, use some of {}",
                DISTURBABLE.join(",")
            ));
        }
        let f = Fns::load(gl)?;
        let objects = Objects::create(&f, gl)?;
        let mut check = GlStateCheck {
            items: items(&objects, gl.context, f.window_system.names()),
            f,
            objects,
            defaults: Vec::new(),
            display: gl.display,
            context: gl.context,
            drawable: gl.drawable,
            read_drawable: 0,
            disturb: disturb.to_vec(),
            frame: None,
            checked: 0,
            changed: Vec::new(),
        };
        check.gl_error("creating the check's objects")?;
        check.defaults = check.read_all();
        check.gl_error("reading the client's GL state")?;
        let same: Vec<_> = check
            .items
            .iter()
            .zip(&check.defaults)
            // The context is the client's one: the check makes it current on other drawables.
            .enumerate()
            .filter(|&(i, (item, default))| item.set == *default && i != CONTEXT_ITEM)
            .map(|(_, pair)| pair)
            .map(|(item, _)| item.what.as_str())
            .collect();
        if !same.is_empty() {
            return fail(format!(
                "--check-gl-state would set the client's own values of {}",
                same.join(" ")
            ));
        }
        Ok(check)
    }

    /// Sets the state (after the frame's rendering), reads it back, leaves GL_INVALID_ENUM
    /// pending, and disturbs what --disturb-gl-state names. `frame`: frames ended before.
    pub fn before_end_frame(&mut self, frame: u32) -> Result<()> {
        let o = &self.objects;
        self.read_drawable = if self.checked.is_multiple_of(2) {
            o.read
        } else {
            o.draw
        };
        self.items[READ_DRAWABLE_ITEM].set = vec![self.read_drawable as i64];
        self.set();
        self.gl_error("setting the GL state")?;
        let before = self.read_all();
        self.gl_error("reading the GL state back")?;
        for (item, got) in self.items.iter().zip(&before) {
            if item.set != *got {
                return fail(format!(
                    "--check-gl-state set {} to {:?} but reads {got:?}",
                    item.what, item.set
                ));
            }
        }
        // SAFETY: the context is current; an invalid capability only raises the error.
        unsafe { (self.f.enable)(NOT_A_CAPABILITY) };
        self.disturb();
        self.frame = Some(frame);
        Ok(())
    }

    /// Reads everything back after xrEndFrame, records what changed, and puts the client's
    /// own state back.
    pub fn after_end_frame(&mut self) -> Result<()> {
        let Some(frame) = self.frame.take() else {
            return Ok(());
        };
        let changed = self.changes(frame);
        self.changed.extend(changed);
        self.checked += 1;
        self.gl_error("reading the GL state after xrEndFrame")?;
        self.put_back()
    }

    /// Every item that differs from what `before_end_frame` set, read in the client's context.
    fn changes(&self, frame: u32) -> Vec<Change> {
        let mut changed = Vec::new();
        let mut note = |what: &str, before: &[i64], after: &[i64]| {
            if before != after {
                changed.push(Change {
                    frame,
                    what: what.to_string(),
                    before: json(before),
                    after: json(after),
                });
            }
        };
        // The current context and drawables first: GLX queries, no GL call before them.
        let (glx, gl_items) = self.items.split_at(GLX_ITEMS);
        for item in glx {
            note(&item.what, &item.set, &self.read(item));
        }
        // SAFETY: a GLX query of this thread's current context.
        if unsafe { self.f.window_system.current_context() } != self.context {
            // The rest is the client's context's state: read it there.
            // SAFETY: the client's own display, context and pbuffers.
            unsafe {
                self.f.window_system.make_current(
                    self.display,
                    self.objects.draw,
                    self.read_drawable,
                    self.context,
                )
            };
        }
        // SAFETY: the context is current; glGetError reads (and clears) the error flags.
        let errors = unsafe { [(self.f.get_error)(), (self.f.get_error)()] };
        note("glGetError", &[INVALID_ENUM as i64], &[errors[0] as i64]);
        note("glGetError (then)", &[NO_ERROR as i64], &[errors[1] as i64]);
        for item in gl_items {
            note(&item.what, &item.set, &self.read(item));
        }
        changed
    }

    /// Puts the client's own state back, and checks that it is all back.
    fn put_back(&self) -> Result<()> {
        self.restore();
        self.gl_error("putting the client's GL state back")?;
        let now = self.read_all();
        if let Some((item, _)) = self
            .items
            .iter()
            .zip(now.iter().zip(&self.defaults))
            .find(|(_, (now, default))| now != default)
        {
            return fail(format!("--check-gl-state could not put {} back", item.what));
        }
        Ok(())
    }

    fn gl_error(&self, doing: &str) -> Result<()> {
        // SAFETY: the context is current.
        match unsafe { (self.f.get_error)() } {
            NO_ERROR => Ok(()),
            e => fail(format!("--check-gl-state: GL error 0x{e:04x} {doing}")),
        }
    }

    fn read_all(&self) -> Vec<Vec<i64>> {
        self.items.iter().map(|item| self.read(item)).collect()
    }

    fn read(&self, item: &Item) -> Vec<i64> {
        let f = &self.f;
        let mut v = [0i64; 4];
        // SAFETY: queries of valid names (units and indices below GL 4.5's minimums) into room
        // for 4 values, the most any of them returns.
        unsafe {
            match item.query {
                Query::Integer(pname) => (f.get_integer64v)(pname, v.as_mut_ptr()),
                Query::Indexed(pname, i) => (f.get_integer64i_v)(pname, i, v.as_mut_ptr()),
                Query::Enabled(cap) => v[0] = (f.is_enabled)(cap) as i64,
                Query::Context => v[0] = f.window_system.current_context() as i64,
                Query::Drawable => v[0] = f.window_system.current_drawable(false) as i64,
                Query::ReadDrawable => v[0] = f.window_system.current_drawable(true) as i64,
            }
        }
        v[..item.set.len()].to_vec()
    }

    /// Sets every item to the value the check gives it.
    fn set(&self) {
        let (f, o) = (&self.f, &self.objects);
        // SAFETY: the client's context and pbuffers; names this check created, units below
        // GL 4.5's minimums; valid pixel store values, capabilities and rectangles.
        unsafe {
            let ws = &f.window_system;
            ws.make_current(self.display, o.draw, self.read_drawable, self.context);
            (f.use_program)(o.program);
            (f.bind_program_pipeline)(o.pipeline);
            self.set_units();
            self.set_buffers();
            for (pname, _, value, _) in PIXEL_STORE {
                (f.pixel_store_i)(pname, value);
            }
            (f.bind_framebuffer)(DRAW_FRAMEBUFFER, o.framebuffers[0]);
            (f.bind_framebuffer)(READ_FRAMEBUFFER, o.framebuffers[1]);
            (f.bind_renderbuffer)(RENDERBUFFER, o.renderbuffer);
            (f.bind_vertex_array)(o.vertex_array);
            for (cap, _) in ENABLES {
                (f.enable)(cap);
            }
            let [x, y, w, h] = VIEWPORT_SET;
            (f.viewport)(x, y, w, h);
            let [x, y, w, h] = SCISSOR_SET;
            (f.scissor)(x, y, w, h);
        }
    }

    /// Every unit's textures, sampler and image unit, then the active unit.
    fn set_units(&self) {
        let (f, o) = (&self.f, &self.objects);
        // SAFETY: the client's context is current; names this check created, units below GL
        // 4.5's minimums, level and layer 1 of textures that have them.
        unsafe {
            for unit in 0..UNITS {
                (f.active_texture)(TEXTURE0 + unit as Enum);
                (f.bind_texture)(TEXTURE_2D, o.textures_2d[unit]);
                (f.bind_texture)(TEXTURE_2D_ARRAY, o.textures_array[unit]);
            }
            (f.active_texture)(TEXTURE0 + ACTIVE_UNIT);
            (f.bind_samplers)(0, UNITS as i32, o.samplers.as_ptr());
            for unit in 0..UNITS {
                let texture = o.textures_array[unit];
                (f.bind_image_texture)(unit as u32, texture, 1, 1, 1, READ_WRITE, R32UI);
            }
        }
    }

    /// The indexed storage and uniform buffer ranges, then the generic bindings (after the
    /// indexed ones, which set them too).
    fn set_buffers(&self) {
        let (f, o) = (&self.f, &self.objects);
        // SAFETY: the client's context is current; buffers this check created, indices below
        // GL 4.5's minimums, ranges inside the buffers at aligned offsets.
        unsafe {
            for i in 0..UNITS {
                let (offset, size) = Objects::range(o.storage_alignment, i);
                let (target, buffer) = (SHADER_STORAGE_BUFFER, o.storage[i]);
                (f.bind_buffer_range)(target, i as u32, buffer, offset as isize, size as isize);
                let (offset, size) = Objects::range(o.uniform_alignment, i);
                let (target, buffer) = (UNIFORM_BUFFER, o.uniform[i]);
                (f.bind_buffer_range)(target, i as u32, buffer, offset as isize, size as isize);
            }
            for ((target, _, _), buffer) in GENERIC_BUFFERS.iter().zip(o.generic) {
                (f.bind_buffer)(*target, buffer);
            }
        }
    }

    /// The client's own state: its pbuffer current, nothing bound, its pixel store.
    fn restore(&self) {
        let f = &self.f;
        let none = std::ptr::null();
        // SAFETY: the client's context and pbuffer; unbinding with null name lists (the
        // multi-bind calls) and zero names; valid pixel store values.
        unsafe {
            let ws = &f.window_system;
            ws.make_current(self.display, self.drawable, self.drawable, self.context);
            (f.use_program)(0);
            (f.bind_program_pipeline)(0);
            (f.bind_textures)(0, UNITS as i32, none);
            (f.active_texture)(TEXTURE0);
            (f.bind_samplers)(0, UNITS as i32, none);
            (f.bind_image_textures)(0, UNITS as i32, none);
            (f.bind_buffers_base)(SHADER_STORAGE_BUFFER, 0, UNITS as i32, none);
            (f.bind_buffers_base)(UNIFORM_BUFFER, 0, UNITS as i32, none);
            for (target, _, _) in GENERIC_BUFFERS {
                (f.bind_buffer)(target, 0);
            }
            for (pname, _, _, value) in PIXEL_STORE {
                (f.pixel_store_i)(pname, value);
            }
            (f.bind_framebuffer)(DRAW_FRAMEBUFFER, 0);
            (f.bind_framebuffer)(READ_FRAMEBUFFER, 0);
            (f.bind_renderbuffer)(RENDERBUFFER, 0);
            (f.bind_vertex_array)(0);
            for (cap, _) in ENABLES {
                (f.disable)(cap);
            }
            let [x, y, w, h] = PBUFFER_RECT;
            (f.viewport)(x, y, w, h);
            (f.scissor)(x, y, w, h);
        }
    }

    /// What a layer that forgets to restore would leave: each item of --disturb-gl-state
    /// changed to another value.
    fn disturb(&self) {
        let (f, o) = (&self.f, &self.objects);
        for name in &self.disturb {
            // SAFETY: as in `set`: the client's own objects, pbuffers and valid values.
            unsafe {
                match name.as_str() {
                    "glXGetCurrentDrawable" => {
                        f.window_system.make_current(
                            self.display,
                            self.drawable,
                            self.read_drawable,
                            self.context,
                        );
                    }
                    "glGetError" => {
                        (f.get_error)();
                    }
                    "GL_ACTIVE_TEXTURE" => (f.active_texture)(TEXTURE0),
                    "GL_CURRENT_PROGRAM" => (f.use_program)(0),
                    "GL_TEXTURE_BINDING_2D" => (f.bind_textures)(ACTIVE_UNIT, 1, &o.textures_2d[0]),
                    "GL_IMAGE_BINDING_NAME" => {
                        (f.bind_image_texture)(0, o.textures_array[1], 1, 1, 1, READ_WRITE, R32UI)
                    }
                    "GL_PIXEL_UNPACK_BUFFER_BINDING" => (f.bind_buffer)(PIXEL_UNPACK_BUFFER, 0),
                    "GL_UNPACK_ALIGNMENT" => (f.pixel_store_i)(UNPACK_ALIGNMENT, 4),
                    "GL_DRAW_FRAMEBUFFER_BINDING" => (f.bind_framebuffer)(DRAW_FRAMEBUFFER, 0),
                    "GL_FRAMEBUFFER_SRGB" => (f.disable)(FRAMEBUFFER_SRGB),
                    _ => unreachable!("checked in new"),
                }
            }
        }
    }
}
