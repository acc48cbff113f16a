//! A GL session's programs: what becomes of a view shape's programs when the session first
//! meets it (linked from the caches, built on a thread of the layer's own, or left to the
//! driver or the frame calls), and the builds off the app's threads as they end.

use super::{GlSession, PROGRAM_WAIT};
use crate::algorithm::params::Params;
use crate::gpu::opengl::ProgramBinaries;
use crate::layer::graphics::opengl::gl_frame_call::failed;
use crate::layer::graphics::opengl::program_builder::{BuildPriority, Built, ProgramBuilder};
use crate::layer::graphics::session_graphics::{NotDone, SessionGraphics};
use crate::layer::log;
use std::time::{Duration, Instant};

/// What became of a view shape's programs when the session first met it.
pub(super) enum Prepared {
    /// Met before.
    Seen,
    /// The caches held them: linked in the app's context.
    Cached,
    /// Their build on a thread of the layer's own started (or one of the same programs runs).
    Building,
    /// The driver compiles off the calling thread (GL_KHR_parallel_shader_compile on a GPU):
    /// frame calls start the builds and poll them, never waiting.
    InContext,
    /// It could not start (why): they are left to the app's context.
    NoBuilder(String),
    /// The engine refused the shape (the frame calls say why), or the app's context could not
    /// be made current (the shape is met again at a later call).
    Failed,
}

impl GlSession {
    /// For a view shape (internal format, width, settings) not met before: links its programs
    /// from the caches (the binary cache's file read again first at a `loading` call, never in
    /// a frame call), or leaves them to a driver that compiles off the calling thread, or
    /// starts their build on a thread of the layer's own (one build per set of programs), below
    /// the app's priority unless the app's frames `wait` for it.
    pub(super) fn prepare_shape(
        &mut self,
        shape: (u32, u32),
        params: &Params,
        (loading, wait): (bool, bool),
    ) -> Prepared {
        let (internal, width) = shape;
        // Every frame call asks: the settings are cloned only for a shape not met before.
        let seen = |(i, w, p): &(u32, u32, Params)| (*i, *w) == (internal, width) && p == params;
        if self.warmed.iter().any(seen) {
            return Prepared::Seen;
        }
        self.warmed.push((internal, width, params.clone()));
        let cached = self.in_context(|engine, _| {
            let ids = engine
                .shape_program_ids(internal, width, params)
                .map_err(failed)?;
            if loading {
                engine.reload_program_cache();
            }
            // SAFETY: inside `in_context`: the app's context is current on this thread.
            let cached = unsafe { engine.ready_from_cache(internal, width, params) };
            let caps = engine.caps();
            let parallel = caps.parallel_compile && !caps.software;
            let found = (caps.driver.clone(), ids, engine.in_place(), parallel);
            Ok((cached.map_err(failed)?, found))
        });
        let (driver, ids, in_place, parallel) = match cached {
            Ok((true, _)) => return Prepared::Cached,
            Ok((false, found)) => found,
            Err(NotDone::Unreachable(_)) => {
                // Not met after all: a later call, with the context reachable, prepares it.
                self.warmed.pop();
                return Prepared::Failed;
            }
            Err(_) => return Prepared::Failed,
        };
        if parallel {
            return Prepared::InContext;
        }
        if self.builders.iter().any(|b| b.ids == ids) {
            return Prepared::Building;
        }
        let priority = match wait {
            true => BuildPriority::App,
            false => BuildPriority::BelowTheApp,
        };
        match ProgramBuilder::start(&driver, (internal, width, in_place), params, ids, priority) {
            Ok(builder) => {
                log::debug(&format!(
                    "OpenGL programs for {} views {width} wide: building them on a thread of the layer's own, in an OpenGL context of its own",
                    self.format_name(i64::from(internal))
                ));
                self.builders.push(builder);
                Prepared::Building
            }
            Err(why) => Prepared::NoBuilder(why),
        }
    }

    /// Builds (or links from the caches) and runs once the programs of one view shape; the
    /// time it took.
    pub(super) fn warm_up(
        &mut self,
        internal: u32,
        width: u32,
        params: &Params,
        when: &str,
    ) -> Duration {
        let since = Instant::now();
        let warmed = self.in_context(|engine, _| {
            // SAFETY: inside `in_context`: the app's context is current on this thread.
            unsafe { engine.warm_up(internal, width, params, PROGRAM_WAIT) }.map_err(failed)
        });
        if let Ok(true) = warmed {
            log::debug(&format!(
                "OpenGL programs for {} views {width} wide built and run once {when} in {:.3} s",
                self.format_name(i64::from(internal)),
                since.elapsed().as_secs_f64()
            ));
        }
        since.elapsed()
    }

    /// Err(Pending) while a build off the app's threads runs (waited for with `wait`); one that
    /// ended is followed by linking its programs from the caches in the app's context.
    pub(super) fn await_builders(&mut self, wait: bool) -> Result<(), NotDone> {
        loop {
            let mut i = 0;
            while i < self.builders.len() {
                match self.builders[i].poll() {
                    Built::Running => i += 1,
                    Built::Ended(outcome) => {
                        let builder = self.builders.remove(i);
                        self.builder_ended(builder, outcome);
                    }
                }
            }
            if self.builders.is_empty() {
                return Ok(());
            }
            if !wait {
                return Err(NotDone::Pending);
            }
            std::thread::sleep(Duration::from_millis(5));
        }
    }

    /// A build ended: its programs are linked from the binaries it handed back (no file is
    /// read in the frame call) and run once in the app's context (milliseconds). What is not there (the build failed, or the driver
    /// refused a binary) is left to the frame calls, one program per call, frames passing
    /// through meanwhile: no frame call compiles a whole set.
    fn builder_ended(
        &mut self,
        builder: ProgramBuilder,
        outcome: Result<(Duration, ProgramBinaries), String>,
    ) {
        let (internal, width, params) = builder.shape.clone();
        drop(builder);
        let name = self.format_name(i64::from(internal));
        if let Err(why) = outcome {
            log::info(&format!(
                "the OpenGL programs for {name} views {width} wide were not built off the app's threads ({why}): frame calls build them, one program per call, and the frames go through untouched until they are ready"
            ));
            return;
        }
        let (took, binaries) = outcome.unwrap_or_default();
        self.beside_time = self.beside_time.max(took);
        self.unlinked.push(binaries);
        let linked = self.in_context(|engine, _| {
            // SAFETY: inside `in_context`: the app's context is current.
            unsafe { engine.ready_from_cache(internal, width, &params) }.map_err(failed)
        });
        log::debug(&format!(
            "OpenGL programs for {name} views {width} wide built off the app's threads in {:.3} s",
            took.as_secs_f64()
        ));
        if let Ok(true) = linked {
            let took = self.warm_up(internal, width, &params, "from the caches");
            self.after_builds_time += took;
        }
    }
}
