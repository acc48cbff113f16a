//! A view's steps (src/gpu/core/plan.rs) as OpenGL calls on the current context: the programs
//! used and dispatched in turn, the tile count cleared through the buffer, memory barriers
//! between them. The caller binds the view's buffers and images first.

use crate::gpu::core::plan::{encode, Encoder, Grid, Reads, Shader, Step};
use crate::gpu::opengl::device::functions::{self as gl, Gl};
use crate::gpu::opengl::pipelines::Program;

/// One view's steps as GL calls.
struct ViewEncoder<'a> {
    g: &'a Gl,
    /// The view's tile buffer (bound as the tile list and the dispatch arguments).
    tiles: u32,
    /// classify, finish_tiles, enhance.
    programs: [&'a Program; 3],
}

impl Encoder for ViewEncoder<'_> {
    type Error = std::convert::Infallible;

    fn clear_tiles(&mut self) {
        let zero = 0u32;
        // SAFETY: the context is current and `tiles` is the caller's buffer of at least 4
        // bytes; GL orders the write before the dispatches that follow.
        unsafe { (self.g.named_buffer_sub_data)(self.tiles, 0, 4, (&zero as *const u32).cast()) };
    }

    fn dispatch(&mut self, shader: Shader, grid: Grid) -> Result<(), Self::Error> {
        let g = self.g;
        // SAFETY: the context is current; the program is linked and its bindings set by the
        // caller; the indirect buffer is bound to GL_DISPATCH_INDIRECT_BUFFER by the caller.
        unsafe {
            (g.use_program)(self.programs[shader as usize].raw);
            match grid {
                Grid::Groups(x, y) => (g.dispatch_compute)(x, y, 1),
                Grid::TileList(offset) => (g.dispatch_compute_indirect)(offset as isize),
            }
        }
        Ok(())
    }

    fn barrier(&mut self, reads: Reads) {
        let bits = match reads {
            Reads::Tiles | Reads::Pixels => gl::SHADER_STORAGE_BARRIER_BIT,
            Reads::TilesAndArguments => gl::SHADER_STORAGE_BARRIER_BIT | gl::COMMAND_BARRIER_BIT,
        };
        // SAFETY: the context is current.
        unsafe { (self.g.memory_barrier)(bits) };
    }
}

/// Runs `steps` with `programs` (classify, finish_tiles, enhance) and the view's tile buffer.
///
/// # Safety
/// The context is current, the programs linked with their parameters set, the view's buffers
/// and images bound, and `tiles` bound to GL_DISPATCH_INDIRECT_BUFFER.
pub(in crate::gpu::opengl) unsafe fn run_steps(
    g: &Gl,
    steps: &[Step],
    tiles: u32,
    programs: [&Program; 3],
) {
    let mut encoder = ViewEncoder { g, tiles, programs };
    encode(steps, &mut encoder).unwrap_or_else(|never| match never {});
}
