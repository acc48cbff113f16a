//! The image-copy path's listed tiles drawn back into the app's image
//! (`ViewPath::ImageCopyTiles`) in a session: the write-back's pipelines, built per format on a
//! thread of their own when a frame first needs them (until then the region is copied back
//! whole: the same pixels), each view's descriptor set and each app image layer's attachment.
//! The frame's draws are recorded in frame_record.rs.

use super::frame_view::{FrameView, ViewKey};
use super::prepared_view::PreparedView;
use crate::gpu::vulkan::device::{GpuDevice, GpuError};
use crate::gpu::vulkan::pipelines::{WriteBackAttachment, WriteBackPipelines};
use crate::gpu::vulkan::record::WriteBackDraw;
use ash::vk;
use std::collections::HashMap;

/// How long a session that waits for its pipelines (`pipelines = "wait"`) waits at most for
/// the write-back's.
const WAIT: std::time::Duration = std::time::Duration::from_secs(60);

/// (swapchain, image, array layer, the framebuffer's size): one attachment each.
type Layer = (u64, vk::Image, u32, (u32, u32));

#[derive(Default)]
pub struct TileWriteBack {
    /// Made when a frame first has a view whose tiles are drawn back.
    pub(super) pipelines: Option<WriteBackPipelines>,
    attachments: HashMap<Layer, WriteBackAttachment>,
    /// The frame being recorded: the draw of each view whose pass is built.
    pub(super) draws: HashMap<ViewKey, WriteBackDraw>,
    /// The attachment formats asked for so far.
    requested: Vec<vk::Format>,
    /// The first draw that could not be made (its set or attachment), by format.
    failed: Option<String>,
}

impl TileWriteBack {
    /// The draws of this frame's `items` whose tiles are drawn back, where their format's
    /// pass is built (else it is requested and, with `wait`, waited for). A view whose draw
    /// cannot be made (its set, its attachment) copies the region back, and `failure` says why.
    /// The GPU must be done with the previous frame.
    pub(super) fn prepare(
        &mut self,
        gpu: &GpuDevice,
        (items, wait): (&[FrameView], bool),
        views: &mut HashMap<ViewKey, PreparedView>,
    ) {
        self.draws.clear();
        for item in items.iter().filter(|i| i.path.draws_tiles_back()) {
            let view = views.get_mut(&item.key).expect("ensured before");
            match self.draw(gpu, (item, wait), view) {
                Ok(Some(draw)) => {
                    self.draws.insert(item.key, draw);
                }
                Ok(None) => {}
                Err(e) => {
                    self.failed
                        .get_or_insert_with(|| format!("{:?}: {e}", item.vk_format));
                }
            }
        }
    }

    /// `item`'s draw, None while its pass is being built or where it could not be.
    fn draw(
        &mut self,
        gpu: &GpuDevice,
        (item, wait): (&FrameView, bool),
        view: &mut PreparedView,
    ) -> Result<Option<WriteBackDraw>, GpuError> {
        let pipelines = match &mut self.pipelines {
            Some(p) => p,
            none => none.insert(WriteBackPipelines::new(gpu)?),
        };
        pipelines.request(gpu, (item.vk_format, item.format));
        if !self.requested.contains(&item.vk_format) {
            self.requested.push(item.vk_format);
        }
        if wait {
            pipelines.wait_for(item.vk_format, WAIT);
        }
        let (Some(pass), Some(own)) = (pipelines.ready(item.vk_format), view.own.as_ref()) else {
            return Ok(None);
        };
        let set = match view.write_back_set {
            Some((_, set)) => set,
            None => {
                let set = pipelines.view_set(gpu, view.target.tiles.raw, own.view)?;
                view.write_back_set = Some((pipelines.pool(), set));
                set
            }
        };
        let region = item.region();
        let far = region.far_corner();
        let layer = (item.key.swapchain, item.image, item.key.array_index, far);
        let attachment = match self.attachments.get(&layer) {
            Some(a) => a,
            None => {
                let image = (item.image, item.vk_format, item.key.array_index);
                let made = WriteBackAttachment::new(gpu, pass.render_pass(), image, far)?;
                self.attachments.entry(layer).or_insert(made)
            }
        };
        Ok(Some(WriteBackDraw::new(
            (pass, attachment.framebuffer()),
            (set, view.target.tiles.raw),
            region,
        )))
    }

    /// Why the write-back could not be made for a format a frame asked for, if it could not
    /// (its views then copy the region back).
    pub(super) fn failure(&self) -> Option<String> {
        if let Some(why) = &self.failed {
            return Some(why.clone());
        }
        let pipelines = self.pipelines.as_ref()?;
        self.requested
            .iter()
            .find_map(|&f| pipelines.failure(f).map(|e| format!("{f:?}: {e}")))
    }

    /// Destroys the attachments of a swapchain's images. The GPU must be done with them.
    pub(super) fn forget(&mut self, gpu: &GpuDevice, swapchain: u64) {
        self.draws.clear();
        self.attachments.retain(|&(s, _, _, _), a| {
            if s == swapchain {
                a.destroy(gpu);
            }
            s != swapchain
        });
    }

    /// Destroys everything (the views' sets with the pool). The GPU must be done with it.
    pub(super) fn destroy(&mut self, gpu: &GpuDevice) {
        self.draws.clear();
        for (_, mut a) in self.attachments.drain() {
            a.destroy(gpu);
        }
        if let Some(mut p) = self.pipelines.take() {
            p.destroy(gpu);
        }
    }
}
