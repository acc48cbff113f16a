//! Which programs a view's passes take: the variants of its format, access and settings
//! (`VariantKey`), or the benchmark's ablated ones (`contrastxr bench --ablate`).

use super::frame_runner::{rows_aligned, GlFrameRunner};
use super::frame_view::GlView;
use crate::algorithm::params::Params;
use crate::gpu::core::interface::{ACCESS_IN_PLACE, ACCESS_NARROW, ACCESS_WIDE};
use crate::gpu::core::plan::ClassifyCover;
use crate::gpu::core::{no_ablated_variant, ClassifyChoice, CubeRoots, VariantKey};
use crate::gpu::opengl::conv::GlFormat;
use crate::gpu::opengl::device::GlError;
use crate::gpu::opengl::pipelines;

impl GlFrameRunner {
    /// The programs a (checked) view needs: classify, finish_tiles, enhance (those of the
    /// benchmark's ablations where it sets them); and how its classify covers the tiles.
    pub(super) fn view_programs(
        &self,
        view: &GlView,
        params: &Params,
    ) -> Result<([usize; 3], ClassifyCover), GlError> {
        let in_place = self.store_through(view).is_some();
        let format = view.internal_format;
        let key = self.shape_key(format, view.rect.2, params, in_place)?;
        self.ablated(key, Self::key_programs(key, format)?)
    }

    /// The programs views of `internal_format`, `width` texels wide, need, in place or not.
    pub(super) fn shape_programs(
        &self,
        internal_format: u32,
        width: u32,
        params: &Params,
        in_place: bool,
    ) -> Result<[usize; 3], GlError> {
        let key = self.shape_key(internal_format, width, params, in_place)?;
        Self::key_programs(key, internal_format)
    }

    /// The variant views of `internal_format`, `width` texels wide, take, in place or not,
    /// with the cube roots the engine takes.
    fn shape_key(
        &self,
        internal_format: u32,
        width: u32,
        params: &Params,
        in_place: bool,
    ) -> Result<VariantKey, GlError> {
        let format = GlFormat::of(internal_format)?;
        let access = if in_place {
            ACCESS_IN_PLACE
        } else if rows_aligned(width, format.pixel.bytes_per_pixel()) {
            ACCESS_WIDE
        } else {
            ACCESS_NARROW
        };
        Ok(VariantKey::of(params, format.pixel, access).with_roots(self.roots))
    }

    /// The programs of a variant (views of `internal_format`).
    fn key_programs(key: VariantKey, internal_format: u32) -> Result<[usize; 3], GlError> {
        let missing = || GlError::Format(internal_format);
        Ok([
            pipelines::classify(
                key.format,
                key.access,
                key.classify_taken(ClassifyChoice::Own),
            )
            .ok_or_else(missing)?,
            pipelines::GL_FINISH_TILES,
            pipelines::enhance(key).ok_or_else(missing)?,
        ])
    }

    /// The benchmark's ablations (interface.rs ABLATE_*; 0, the default, for none): views then
    /// take the ablated `enhance`, built for the paper's and the perceptual method in mode
    /// enhance on RGBA8 sRGB only. Their output is not an enhancement.
    pub fn set_ablation(&mut self, ablate: u32) {
        self.ablate = ablate;
    }

    /// How views take the CIELAB cube roots: the device's way by default
    /// (`CubeRoots::for_device`); the other, to compare them or to test it on this device.
    pub fn set_cube_roots(&mut self, roots: CubeRoots) {
        self.roots = roots;
    }

    /// How views take the CIELAB cube roots (where their variant is built that way).
    pub fn cube_roots(&self) -> CubeRoots {
        self.roots
    }

    /// Which `classify` views take (their method's own by default), to compare them.
    pub fn set_classify(&mut self, choice: ClassifyChoice) {
        self.classify = choice;
    }

    /// The view's programs as the benchmark's ablations and tile list change them, and how
    /// the classify taken covers the tiles.
    fn ablated(
        &self,
        key: VariantKey,
        [classify, finish, enhance]: [usize; 3],
    ) -> Result<([usize; 3], ClassifyCover), GlError> {
        let taken = key.classify_taken(self.classify);
        let (classify, cover) = match pipelines::classify(key.format, key.access, taken) {
            Some(id) => (id, taken.1),
            None => (classify, ClassifyCover::Tiles),
        };
        if self.ablate == 0 {
            return Ok(([classify, finish, enhance], cover));
        }
        let pow = key.roots.by_pow();
        let enhance = pipelines::enhance_ablated(key.method, key.access, self.ablate, pow)
            .filter(|_| key.has_ablated_variants())
            .ok_or_else(|| GlError::Input(no_ablated_variant(self.ablate)))?;
        Ok(([classify, finish, enhance], cover))
    }
}
