//! A diagnostic of the bench (CONTRASTXR_BENCH_PROBE=1): the spans of the image-copy and
//! sampled frames one by one, printed to standard error.

use super::bench_rig::Rig;
use super::offline_engine::VkOffline;
use crate::algorithm::params::Params;
use crate::gpu::core::bench::median;
use crate::gpu::vulkan::device::{
    barrier, record_first_layout, record_image_region_copy, record_layout_barriers, GpuError,
    VkResultExt,
};
use crate::gpu::vulkan::record::{record_write_back, record_write_back_barrier};
use ash::vk;

const NAMES: [&str; 11] = [
    "restore",
    "ic_frame_after_restore",
    "ic_frame_again",
    "ic_copies_after_restore",
    "ic_enhance_alone",
    "ip_frame_again",
    "ip_frame_after_restore",
    "copy_in_alone",
    "copy_back_alone",
    "draws_alone",
    "sampled_enhance_alone",
];

impl VkOffline {
    pub(super) fn probe(&mut self, rig: &Rig, params: &Params, runs: u32) -> Result<(), GpuError> {
        if rig.image_copy.is_empty() {
            return Ok(());
        }
        let mut samples: [Vec<f64>; 11] = Default::default();
        for _ in 0..runs + 3 {
            let t = self.probe_run(rig, params)?;
            for (s, v) in samples.iter_mut().zip(t) {
                s.push(v);
            }
        }
        let w = rig.image_copy[0].region;
        let line: Vec<String> = NAMES
            .iter()
            .zip(samples)
            .map(|(n, s)| format!("{n}={:.3}", median(s[3..].to_vec())))
            .collect();
        eprintln!("probe {}x{}: {}", w.0, w.1, line.join(" "));
        let mut samples: [Vec<f64>; 6] = Default::default();
        for _ in 0..runs + 3 {
            let t = self.probe_apart(rig, params)?;
            for (s, v) in samples.iter_mut().zip(t) {
                s.push(v);
            }
        }
        let names = [
            "apart_ic_frame",
            "apart_ic_copy_in",
            "apart_layouts",
            "apart_ip_frame",
            "apart_ic_after_ip",
            "apart_ic_frame_again",
        ];
        let line: Vec<String> = names
            .iter()
            .zip(samples)
            .map(|(n, s)| format!("{n}={:.3}", median(s[3..].to_vec())))
            .collect();
        eprintln!("probe {}x{} apart: {}", w.0, w.1, line.join(" "));
        self.probe_layouts(rig, runs)
    }

    /// Each timed span in a submission of its own, after a restore in another.
    fn probe_apart(&mut self, rig: &Rig, params: &Params) -> Result<[f64; 6], GpuError> {
        let regions = rig.regions(rig.views[0].region);
        let own: Vec<vk::Image> = rig.own_images.iter().map(|i| i.image.raw).collect();
        let ic = (regions.as_slice(), params);
        let gpu = &self.gpu;
        let mut out = [0.0; 6];
        let restore = |me: &Self| me.submit(|cmd| Ok(me.restore_images(cmd, rig, &regions)));
        restore(self)?;
        out[0] = self.time_one(rig.queries, &mut |cmd| self.record_frame_image_copy(cmd, rig, ic, (true, false)))?;
        restore(self)?;
        out[1] = self.time_one(rig.queries, &mut |cmd| {
            record_layout_barriers(gpu, cmd, &regions, true);
            for (r, o) in regions.iter().zip(&own) {
                record_image_region_copy(gpu, cmd, r, *o, true);
            }
            record_layout_barriers(gpu, cmd, &regions, false);
            Ok(())
        })?;
        restore(self)?;
        out[2] = self.time_one(rig.queries, &mut |cmd| {
            record_layout_barriers(gpu, cmd, &regions, true);
            record_layout_barriers(gpu, cmd, &regions, false);
            Ok(())
        })?;
        restore(self)?;
        out[3] = self.time_one(rig.queries, &mut |cmd| self.record_frame_in_place(cmd, rig, &regions, params))?;
        out[4] = self.time_one(rig.queries, &mut |cmd| self.record_frame_image_copy(cmd, rig, ic, (true, false)))?;
        out[5] = self.time_one(rig.queries, &mut |cmd| self.record_frame_image_copy(cmd, rig, ic, (true, false)))?;
        Ok(out)
    }

    /// `record`'s GPU time in a submission of its own.
    fn time_one(
        &self,
        q: vk::QueryPool,
        record: &mut dyn FnMut(vk::CommandBuffer) -> Result<(), GpuError>,
    ) -> Result<f64, GpuError> {
        self.submit(|cmd| {
            // SAFETY: cmd is recording; the pool is ours and idle.
            unsafe { self.gpu.device.cmd_reset_query_pool(cmd, q, 0, 2) };
            self.timestamp(cmd, q, 0);
            record(cmd)?;
            self.timestamp(cmd, q, 1);
            Ok(())
        })?;
        let mut ticks = [0u64; 2];
        // SAFETY: the submission was waited for; both queries were written by it.
        unsafe {
            self.gpu.device.get_query_pool_results(
                q,
                0,
                &mut ticks,
                vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT,
            )
        }
        .vk("vkGetQueryPoolResults")?;
        Ok(ticks[1].wrapping_sub(ticks[0]) as f64 * f64::from(self.gpu.timestamp_period()) / 1e6)
    }

    fn probe_run(&mut self, rig: &Rig, params: &Params) -> Result<[f64; 11], GpuError> {
        use vk::PipelineStageFlags as S;
        let all = S::ALL_COMMANDS;
        let regions = rig.regions(rig.views[0].region);
        let mapping = params.camera_mapping();
        let own: Vec<vk::Image> = rig.own_images.iter().map(|i| i.image.raw).collect();
        let ic = (regions.as_slice(), params);
        self.submit(|cmd| {
            let (gpu, engine, q) = (&self.gpu, &self.engine, rig.queries);
            // SAFETY: cmd is recording; the pool is ours and idle.
            unsafe { gpu.device.cmd_reset_query_pool(cmd, q, 0, 22) };
            let timed = |k: u32, record: &mut dyn FnMut() -> Result<(), GpuError>| {
                barrier(gpu, cmd, all, all);
                self.timestamp(cmd, q, 2 * k);
                let done = record();
                self.timestamp(cmd, q, 2 * k + 1);
                done
            };
            timed(0, &mut || {
                self.restore_images(cmd, rig, &regions);
                Ok(())
            })?;
            timed(1, &mut || self.record_frame_image_copy(cmd, rig, ic, (true, false)))?;
            timed(2, &mut || self.record_frame_image_copy(cmd, rig, ic, (true, false)))?;
            barrier(gpu, cmd, all, all);
            self.restore_images(cmd, rig, &regions);
            timed(3, &mut || self.record_frame_image_copy(cmd, rig, ic, (false, false)))?;
            timed(4, &mut || {
                for v in &rig.image_copy {
                    engine.record_enhance(gpu, cmd, v, params, &mapping)?;
                }
                Ok(())
            })?;
            timed(5, &mut || self.record_frame_in_place(cmd, rig, &regions, params))?;
            barrier(gpu, cmd, all, all);
            self.restore_images(cmd, rig, &regions);
            timed(6, &mut || self.record_frame_in_place(cmd, rig, &regions, params))?;
            for (k, to_own) in [(7, true), (8, false)] {
                timed(k, &mut || {
                    record_layout_barriers(gpu, cmd, &regions, true);
                    for (r, o) in regions.iter().zip(&own) {
                        record_image_region_copy(gpu, cmd, r, *o, to_own);
                    }
                    record_layout_barriers(gpu, cmd, &regions, false);
                    Ok(())
                })?;
            }
            timed(9, &mut || {
                if let Some(p) = rig.write_back.as_ref() {
                    record_layout_barriers(gpu, cmd, &regions, true);
                    record_write_back_barrier(gpu, cmd);
                    for (draw, _) in &rig.write_back_draws {
                        record_write_back(gpu, cmd, p, draw);
                    }
                    record_layout_barriers(gpu, cmd, &regions, false);
                }
                Ok(())
            })?;
            timed(10, &mut || {
                record_layout_barriers(gpu, cmd, &regions, true);
                let write = (S::COMPUTE_SHADER, vk::AccessFlags::SHADER_WRITE);
                record_first_layout(gpu, cmd, &own, vk::ImageLayout::GENERAL, write);
                for v in &rig.sampled {
                    engine.record_enhance(gpu, cmd, v, params, &mapping)?;
                }
                record_layout_barriers(gpu, cmd, &regions, false);
                Ok(())
            })
        })?;
        let mut ticks = [0u64; 22];
        // SAFETY: the submission was waited for; every query was written by it.
        unsafe {
            self.gpu.device.get_query_pool_results(
                rig.queries,
                0,
                &mut ticks,
                vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT,
            )
        }
        .vk("vkGetQueryPoolResults")?;
        let ms = f64::from(self.gpu.timestamp_period()) / 1e6;
        Ok(std::array::from_fn(|k| {
            ticks[2 * k + 1].wrapping_sub(ticks[2 * k]) as f64 * ms
        }))
    }
}

fn transition(
    gpu: &crate::gpu::vulkan::device::GpuDevice,
    cmd: vk::CommandBuffer,
    (image, layer): (vk::Image, u32),
    (old, new): (vk::ImageLayout, vk::ImageLayout),
) {
    let any = vk::AccessFlags::MEMORY_READ | vk::AccessFlags::MEMORY_WRITE;
    let range = vk::ImageSubresourceRange::default()
        .aspect_mask(vk::ImageAspectFlags::COLOR)
        .base_array_layer(layer)
        .level_count(1)
        .layer_count(1);
    let b = [vk::ImageMemoryBarrier::default()
        .old_layout(old)
        .new_layout(new)
        .src_access_mask(any)
        .dst_access_mask(any)
        .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .image(image)
        .subresource_range(range)];
    let all = vk::PipelineStageFlags::ALL_COMMANDS;
    // SAFETY: cmd is recording; the image is the probe's own or the rig's.
    unsafe {
        gpu.device
            .cmd_pipeline_barrier(cmd, all, all, vk::DependencyFlags::empty(), &[], &[], &b)
    };
}

fn copy(
    gpu: &crate::gpu::vulkan::device::GpuDevice,
    cmd: vk::CommandBuffer,
    (src, src_layout): (vk::Image, vk::ImageLayout),
    (dst, dst_layout): (vk::Image, vk::ImageLayout),
    size: (u32, u32),
) {
    let layer = vk::ImageSubresourceLayers::default()
        .aspect_mask(vk::ImageAspectFlags::COLOR)
        .layer_count(1);
    let c = [vk::ImageCopy::default()
        .src_subresource(layer)
        .dst_subresource(layer)
        .extent(vk::Extent3D {
            width: size.0,
            height: size.1,
            depth: 1,
        })];
    // SAFETY: cmd is recording; both images hold the region, in the layouts named.
    unsafe {
        gpu.device
            .cmd_copy_image(cmd, src, src_layout, dst, dst_layout, &c)
    };
}

impl VkOffline {
    /// Copies in and back with TRANSFER_*_OPTIMAL layouts, and with an app-like twin image.
    pub(super) fn probe_layouts(&mut self, rig: &Rig, runs: u32) -> Result<(), GpuError> {
        use vk::ImageLayout as L;
        use vk::ImageUsageFlags as U;
        let regions = rig.regions(rig.views[0].region);
        let size = regions[0].extent;
        let gpu_twins: Vec<crate::gpu::vulkan::device::DeviceImage> = regions
            .iter()
            .map(|_| {
                crate::gpu::vulkan::device::DeviceImage::with_usage(
                    &self.gpu,
                    size,
                    vk::Format::R8G8B8A8_SRGB,
                    U::COLOR_ATTACHMENT | U::TRANSFER_SRC | U::TRANSFER_DST,
                )
            })
            .collect::<Result<_, _>>()?;
        let own: Vec<vk::Image> = rig.own_images.iter().map(|i| i.image.raw).collect();
        let twins: Vec<vk::Image> = gpu_twins.iter().map(|i| i.raw).collect();
        let att = L::COLOR_ATTACHMENT_OPTIMAL;
        let (s, d) = (L::TRANSFER_SRC_OPTIMAL, L::TRANSFER_DST_OPTIMAL);
        let mut samples: [Vec<f64>; 4] = Default::default();
        for run in 0..runs + 3 {
            let gpu = &self.gpu;
            // Twins and own images first into their steady layouts.
            self.submit(|cmd| {
                for (&o, &t) in own.iter().zip(&twins) {
                    if run == 0 {
                        transition(gpu, cmd, (o, 0), (L::UNDEFINED, L::GENERAL));
                        transition(gpu, cmd, (t, 0), (L::UNDEFINED, att));
                    }
                }
                Ok(())
            })?;
            let mut one = |k: usize, from_app: bool, other: &[vk::Image], other_rest: L| {
                let restore = |me: &Self| me.submit(|cmd| Ok(me.restore_images(cmd, rig, &regions)));
                restore(self)?;
                let t = self.time_one(rig.queries, &mut |cmd| {
                    for (r, &o) in regions.iter().zip(other) {
                        let (app_l, o_l) = if from_app { (s, d) } else { (d, s) };
                        transition(gpu, cmd, (r.image, r.array_index), (att, app_l));
                        transition(gpu, cmd, (o, 0), (other_rest, o_l));
                        match from_app {
                            true => copy(gpu, cmd, (r.image, s), (o, d), size),
                            false => copy(gpu, cmd, (o, s), (r.image, d), size),
                        }
                        transition(gpu, cmd, (r.image, r.array_index), (app_l, att));
                        transition(gpu, cmd, (o, 0), (o_l, other_rest));
                    }
                    Ok(())
                })?;
                samples[k].push(t);
                Ok::<(), GpuError>(())
            };
            one(0, true, &own, L::GENERAL)?;
            one(1, false, &own, L::GENERAL)?;
            one(2, true, &twins, att)?;
            one(3, false, &twins, att)?;
        }
        let names = ["opt_copy_in", "opt_copy_back", "twin_copy_in", "twin_copy_back"];
        let line: Vec<String> = names
            .iter()
            .zip(samples)
            .map(|(n, s)| format!("{n}={:.3}", median(s[3..].to_vec())))
            .collect();
        eprintln!("probe {}x{} layouts: {}", size.0, size.1, line.join(" "));
        let gpu = &self.gpu;
        for mut t in gpu_twins {
            t.destroy(gpu);
        }
        Ok(())
    }
}
