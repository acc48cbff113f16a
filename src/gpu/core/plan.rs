//! A view's enhancement as steps, written once for every backend: from the method's passes (its
//! entry in src/algorithm/method/table.rs) and the view's size, which shader runs over which
//! grid and what each must see of the one before. A backend encodes the steps through
//! [`Encoder`] (Vulkan: commands and pipeline barriers; OpenGL: calls and memory barriers).

use super::interface::{CLASSIFY_WORKGROUP, TILE, TILE_LIST_DISPATCH_OFFSET};
use crate::algorithm::method::Pass;

/// The per-view shaders, by their job; each backend names its own variant of each through the
/// view's [`VariantKey`](super::VariantKey).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Shader {
    Classify,
    FinishTiles,
    Enhance,
}

/// How many workgroups a dispatch runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Grid {
    Groups(u32, u32),
    /// As many as the tile list's dispatch arguments say, at this byte offset of the tile buffer.
    TileList(u64),
}

/// What the next step reads of what the steps before it wrote.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Reads {
    /// The tile list, as storage.
    Tiles,
    /// The tile list, as storage and as a dispatch's arguments.
    TilesAndArguments,
    /// The view's pixels, whatever the backend does with them next (copy back, sample, capture).
    Pixels,
}

/// One step of a view's enhancement.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Step {
    /// The tile count set to 0, after whatever read the list last (the view before, the frame
    /// before) and before anything appends to it.
    ClearTiles,
    Dispatch(Shader, Grid),
    /// Orders the writes so far before the reads of the next step.
    Barrier(Reads),
}

/// How a `classify` variant covers a view's tiles, which its grid follows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ClassifyCover {
    /// An invocation per tile (`classify`), CLASSIFY_WORKGROUP tiles of a row per workgroup:
    /// it stops at the tile's first content, one row of a full frame.
    Tiles,
    /// An invocation per tile row (`classify_rows`, the perceptual method's, for the
    /// benchmark's `classify-rows`), TILE tiles of a row per workgroup: TILE times as many
    /// invocations check the pixels side by side.
    TileRows,
}

impl ClassifyCover {
    /// Its workgroups over a view of `tiles` (columns, rows).
    pub fn grid(self, tiles: (u32, u32)) -> Grid {
        let per_group = match self {
            ClassifyCover::Tiles => (CLASSIFY_WORKGROUP[0], CLASSIFY_WORKGROUP[1]),
            ClassifyCover::TileRows => (TILE, 1),
        };
        Grid::Groups(tiles.0.div_ceil(per_group.0), tiles.1.div_ceil(per_group.1))
    }
}

/// A method's passes that the steps cannot run.
#[derive(Debug, PartialEq, Eq)]
pub struct NoPlan(pub &'static str);

/// The steps of one view of `region` texels for `passes`, in their order: classify (of
/// `cover`) lists the tiles with content, finish_tiles turns their count into dispatch
/// arguments, enhance runs over the listed tiles only. Each pass needs the one before it.
pub fn view_steps(
    passes: &[Pass],
    region: (u32, u32),
    cover: ClassifyCover,
) -> Result<Vec<Step>, NoPlan> {
    let tiles = (region.0.div_ceil(TILE), region.1.div_ceil(TILE));
    let mut steps = Vec::new();
    let mut last = None;
    for &pass in passes {
        match (pass, last) {
            (Pass::Classify, None) => {
                steps.push(Step::ClearTiles);
                steps.push(Step::Dispatch(Shader::Classify, cover.grid(tiles)));
            }
            (Pass::FinishTiles, Some(Pass::Classify)) => {
                steps.push(Step::Barrier(Reads::Tiles));
                // One workgroup of one invocation.
                steps.push(Step::Dispatch(Shader::FinishTiles, Grid::Groups(1, 1)));
            }
            (Pass::Enhance, Some(Pass::FinishTiles)) => {
                steps.push(Step::Barrier(Reads::TilesAndArguments));
                let list = Grid::TileList(TILE_LIST_DISPATCH_OFFSET);
                steps.push(Step::Dispatch(Shader::Enhance, list));
            }
            (Pass::Classify, _) => return Err(NoPlan("classify runs first, once")),
            (Pass::FinishTiles, _) => return Err(NoPlan("finish_tiles needs classify's list")),
            (Pass::Enhance, _) => return Err(NoPlan("enhance needs finish_tiles' arguments")),
        }
        last = Some(pass);
    }
    if last != Some(Pass::Enhance) {
        return Err(NoPlan("the passes end with enhance"));
    }
    steps.push(Step::Barrier(Reads::Pixels));
    Ok(steps)
}

/// A backend's way of running steps.
pub trait Encoder {
    type Error;
    fn clear_tiles(&mut self);
    fn dispatch(&mut self, shader: Shader, grid: Grid) -> Result<(), Self::Error>;
    fn barrier(&mut self, reads: Reads);
}

/// Runs `steps` through `encoder`, in order.
pub fn encode<E: Encoder>(steps: &[Step], encoder: &mut E) -> Result<(), E::Error> {
    for step in steps {
        match *step {
            Step::ClearTiles => encoder.clear_tiles(),
            Step::Dispatch(shader, grid) => encoder.dispatch(shader, grid)?,
            Step::Barrier(reads) => encoder.barrier(reads),
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::algorithm::method::PER_PIXEL_PASSES;

    #[test]
    fn the_per_pixel_passes_in_steps() {
        // 100x40 texels: 13x5 tiles of 8 (interface.rs TILE), in classify's workgroups of 64
        // tiles of a row: 1x5 of them.
        assert_eq!((TILE, CLASSIFY_WORKGROUP), (8, [64, 1, 1]));
        let steps = view_steps(&PER_PIXEL_PASSES, (100, 40), ClassifyCover::Tiles).unwrap();
        assert_eq!(
            steps,
            [
                Step::ClearTiles,
                Step::Dispatch(Shader::Classify, Grid::Groups(1, 5)),
                Step::Barrier(Reads::Tiles),
                Step::Dispatch(Shader::FinishTiles, Grid::Groups(1, 1)),
                Step::Barrier(Reads::TilesAndArguments),
                Step::Dispatch(Shader::Enhance, Grid::TileList(TILE_LIST_DISPATCH_OFFSET)),
                Step::Barrier(Reads::Pixels),
            ]
        );
    }

    /// By tile rows, classify runs a workgroup per TILE tiles of a row; by tiles, one per
    /// CLASSIFY_WORKGROUP tiles.
    #[test]
    fn the_classify_grid_follows_its_cover() {
        // 100x40 texels: 13x5 tiles.
        let grid = |cover| view_steps(&PER_PIXEL_PASSES, (100, 40), cover).unwrap()[1];
        let rows = Step::Dispatch(Shader::Classify, Grid::Groups(2, 5));
        let tiles = Step::Dispatch(Shader::Classify, Grid::Groups(1, 5));
        assert_eq!(grid(ClassifyCover::TileRows), rows);
        assert_eq!(grid(ClassifyCover::Tiles), tiles);
    }

    /// Every method's passes (its entry in method/table.rs) make steps the backends run.
    #[test]
    fn every_method_has_a_plan() {
        for method in crate::algorithm::method::Method::ALL {
            let passes = method.entry().passes;
            let cover = ClassifyCover::Tiles;
            assert!(
                view_steps(passes, (64, 64), cover).is_ok(),
                "{}",
                method.name()
            );
        }
    }

    #[test]
    fn passes_out_of_order_have_no_plan() {
        use Pass::*;
        for passes in [
            &[Enhance][..],
            &[Classify, Enhance],
            &[FinishTiles, Classify, Enhance],
            &[Classify, FinishTiles],
            &[Classify, Classify, FinishTiles, Enhance],
            &[],
        ] {
            assert!(
                view_steps(passes, (8, 8), ClassifyCover::Tiles).is_err(),
                "{passes:?}"
            );
        }
    }

    /// Records what it is asked, to show `encode` keeps the steps' order and stops at an error.
    #[derive(Default)]
    struct Log(Vec<String>);

    impl Encoder for Log {
        type Error = String;
        fn clear_tiles(&mut self) {
            self.0.push("clear".into());
        }
        fn dispatch(&mut self, shader: Shader, grid: Grid) -> Result<(), String> {
            if shader == Shader::Enhance {
                return Err(format!("no enhance over {grid:?}"));
            }
            self.0.push(format!("{shader:?}"));
            Ok(())
        }
        fn barrier(&mut self, reads: Reads) {
            self.0.push(format!("{reads:?}"));
        }
    }

    #[test]
    fn encoding_keeps_the_order_and_stops_at_an_error() {
        let steps = view_steps(&PER_PIXEL_PASSES, (8, 8), ClassifyCover::Tiles).unwrap();
        let mut log = Log::default();
        let result = encode(&steps, &mut log);
        assert_eq!(result, Err("no enhance over TileList(4)".to_string()));
        assert_eq!(
            log.0,
            [
                "clear",
                "Classify",
                "Tiles",
                "FinishTiles",
                "TilesAndArguments"
            ]
        );
    }
}
