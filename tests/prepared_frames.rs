//! The layer's frame engine on the first Vulkan device (lavapipe in CI) with the validation
//! layer on, over consecutive frames of a live background: each frame's views get that frame's
//! enhancement, whether its texels went straight into a mapped image (the direct path), through
//! the staging copy (forced), or through the GPU's decode and blur passes, and the direct path
//! gives what the staging copy gives, bit for bit; on both, also when a source's thread writes
//! the texels into the ring before the frame (the engine's `texel_sink`), and while another
//! thread keeps offering other frames' texels.

use ash::vk;
use contrastxr::algorithm::perception::frequency::DEFAULT_PIXELS_PER_DEGREE;
use contrastxr::algorithm::Params;
use contrastxr::gpu::core::blurred_texels::{BlurTaps, BlurredTexels, TexelSink};
use contrastxr::gpu::vulkan::device::Commands;
use contrastxr::gpu::vulkan::device::DeviceImage;
use contrastxr::gpu::vulkan::device::GpuBuffer;
use contrastxr::gpu::vulkan::device::{
    record_first_layout, record_layout_barriers, record_region_copy, ImageRegion,
};
use contrastxr::gpu::{
    BackgroundInput, DeviceOptions, FrameOptions, FrameRunner, FrameView, GpuDevice, PixelFormat,
    PixelLayout, ViewKey, ViewPath, VkOffline,
};
use contrastxr::image::RgbaImage;
use gpu_allocator::MemoryLocation;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};

const OPTIONS: DeviceOptions = DeviceOptions {
    index: 0,
    validation: true,
    matching: None,
    shader_statistics: false,
};
const REGION: (u32, u32) = (40, 30);
const CAMERA: (u32, u32) = (96, 64);
const FORMAT: PixelFormat = PixelFormat {
    layout: PixelLayout::Rgba8,
    srgb: false,
};

/// A deterministic pseudo-random image (xorshift), opaque.
fn noise(width: u32, height: u32, seed: u32) -> RgbaImage {
    let mut s = seed.max(1);
    let mut img = RgbaImage::new(width, height, [0, 0, 0, 255]);
    for p in img.pixels.iter_mut() {
        s ^= s << 13;
        s ^= s >> 17;
        s ^= s << 5;
        *p = [(s >> 8) as u8, (s >> 16) as u8, (s >> 24) as u8, 255];
    }
    img
}

/// Runs one submission on the device's queue and waits for it.
fn submit(gpu: &GpuDevice, record: impl FnOnce(vk::CommandBuffer)) {
    let mut c = Commands::new(gpu).unwrap();
    c.begin(gpu).unwrap();
    record(c.cmd);
    c.submit(gpu).unwrap();
    c.destroy(gpu).unwrap();
}

/// Who writes a frame's prepared texels into the engine's texel ring.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Writer {
    /// The frame.
    Frame,
    /// The "source", before the frame (once the ring exists).
    Source,
    /// As `Source`, while a thread offers other frames' texels all along.
    Busy,
}

/// How prepared texels reach the views: `direct`, the ring's mapped images sampled (else its
/// staging buffers, copied into the background's image), written by `writer`.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Path {
    direct: bool,
    writer: Writer,
}

/// Two app images (two swapchains of one image each), left in COLOR_ATTACHMENT_OPTIMAL as an
/// app leaves them for the runtime, and a frame engine that enhances them.
struct Rig {
    engine: FrameRunner,
    images: [DeviceImage; 2],
    buffer: GpuBuffer,
    path: Path,
    /// The engine's sink as the busy thread sees it (refreshed after each frame).
    sink: Arc<Mutex<Option<Arc<dyn TexelSink>>>>,
}

impl Rig {
    fn new(path: Path) -> Rig {
        let gpu = GpuDevice::create(&OPTIONS).unwrap();
        let mut engine = FrameRunner::new(gpu, &[]).unwrap();
        engine.set_direct_texels(path.direct);
        let gpu = &engine.gpu;
        let images =
            [0, 1].map(|_| DeviceImage::new(gpu, REGION, vk::Format::R8G8B8A8_UNORM).unwrap());
        let bytes = u64::from(REGION.0 * REGION.1 * 4);
        let usage = vk::BufferUsageFlags::TRANSFER_SRC | vk::BufferUsageFlags::TRANSFER_DST;
        let buffer = GpuBuffer::new(gpu, bytes, usage, MemoryLocation::GpuToCpu, "test").unwrap();
        Rig {
            engine,
            images,
            buffer,
            path,
            sink: Arc::default(),
        }
    }

    fn region(&self, i: usize) -> ImageRegion {
        ImageRegion {
            image: self.images[i].raw,
            array_index: 0,
            offset: (0, 0),
            extent: REGION,
        }
    }

    fn view(&self, i: usize, params: &Params) -> FrameView {
        let key = ViewKey {
            swapchain: i as u64 + 1,
            offset: (0, 0),
            extent: REGION,
            array_index: 0,
        };
        let raw = self.images[i].raw;
        let vk_format = vk::Format::R8G8B8A8_UNORM;
        FrameView::new(
            key,
            raw,
            FORMAT,
            vk_format,
            ViewPath::BufferCopy,
            params.camera_mapping(),
            DEFAULT_PIXELS_PER_DEGREE,
        )
    }

    /// Writes `display` into both images.
    fn put(&mut self, display: &RgbaImage) {
        self.buffer.write(display.pixels.as_flattened()).unwrap();
        let gpu = &self.engine.gpu;
        for i in 0..2 {
            let region = self.region(i);
            submit(gpu, |cmd| {
                let transfer = (
                    vk::PipelineStageFlags::TRANSFER,
                    vk::AccessFlags::TRANSFER_WRITE,
                );
                record_first_layout(
                    gpu,
                    cmd,
                    &[region.image],
                    vk::ImageLayout::GENERAL,
                    transfer,
                );
                record_region_copy(gpu, cmd, &region, &self.buffer, false);
                record_layout_barriers(gpu, cmd, &[region], false);
            });
        }
    }

    /// Reads image `i` back, after every submission made so far.
    fn get(&self, i: usize) -> Vec<u8> {
        let gpu = &self.engine.gpu;
        let region = self.region(i);
        submit(gpu, |cmd| {
            record_layout_barriers(gpu, cmd, &[region], true);
            record_region_copy(gpu, cmd, &region, &self.buffer, true);
            record_layout_barriers(gpu, cmd, &[region], false);
            contrastxr::gpu::vulkan::device::barrier(
                gpu,
                cmd,
                vk::PipelineStageFlags::ALL_COMMANDS,
                vk::PipelineStageFlags::HOST,
            );
        });
        self.buffer.mapped().unwrap().to_vec()
    }

    /// One frame: image `i`'s view enhanced against `camera` (camera frame `sequence`), with
    /// its texels prepared on the CPU or not. Does not wait for the GPU.
    fn frame(&mut self, i: usize, camera: &RgbaImage, prepared: bool, sequence: u64) {
        self.frame_with(i, camera, (prepared, sequence), &Params::default());
    }

    /// `frame` with `params`.
    fn frame_with(
        &mut self,
        i: usize,
        camera: &RgbaImage,
        (prepared, sequence): (bool, u64),
        params: &Params,
    ) {
        let texels = BlurredTexels::prepare(camera, BlurTaps::of(params));
        let background = BackgroundInput {
            image: camera,
            prepared: prepared.then_some(&texels),
            sequence,
        };
        let options = FrameOptions {
            capture: false,
            wait_for_pipelines: true,
        };
        let views = [self.view(i, params)];
        let source = self.path.writer != Writer::Frame;
        if source && prepared {
            self.engine.texel_sink().offer(&texels);
        }
        let out = self
            .engine
            .pipelines_ready(&views, params, options.wait_for_pipelines)
            .and_then(|ready| {
                self.engine
                    .process(ready, &views, background, params, None, options)
            });
        assert!(out.is_ok(), "frame {sequence}: {:?}", out.err());
        *self.sink.lock().unwrap() = Some(self.engine.texel_sink());
    }

    fn finish(mut self) {
        let errors = self.engine.gpu.validation_errors();
        self.buffer.destroy(&self.engine.gpu);
        for image in &mut self.images {
            image.destroy(&self.engine.gpu);
        }
        self.engine.finish().unwrap();
        assert_eq!(errors, 0, "Vulkan validation errors (see stderr)");
    }
}

/// What the offline engine makes of `display` against `camera`, with the texels prepared on
/// the CPU (`prepared`) or by the GPU passes.
fn expected(display: &RgbaImage, camera: &RgbaImage, prepared: bool) -> Vec<u8> {
    expected_with(display, camera, prepared, &Params::default())
}

/// `expected` with `params`.
fn expected_with(
    display: &RgbaImage,
    camera: &RgbaImage,
    prepared: bool,
    params: &Params,
) -> Vec<u8> {
    let mut e = VkOffline::with_options(&OPTIONS).unwrap();
    e.set_cpu_background(prepared);
    let words: Vec<u32> = display
        .pixels
        .iter()
        .map(|p| u32::from_le_bytes(*p))
        .collect();
    let out = e
        .enhance_raw_mapped(
            &words,
            (REGION, FORMAT),
            camera,
            &params.camera_mapping(),
            params,
        )
        .unwrap();
    assert_eq!(e.validation_errors(), 0);
    out.iter().flat_map(|w| w.to_le_bytes()).collect()
}

/// Pairs of frames, one per image, the second recorded while the first may still run: (camera,
/// prepared on the CPU, sequence). A camera frame shown twice, frames prepared on the GPU
/// between prepared ones, and a camera of another size (camera 4) and back.
const PAIRS: [[(usize, bool, u64); 2]; 6] = [
    [(0, true, 1), (1, true, 2)],
    [(2, true, 3), (2, true, 3)],
    [(3, false, 4), (0, true, 5)],
    [(1, true, 6), (3, false, 7)],
    [(4, true, 8), (4, true, 8)],
    [(2, true, 9), (0, true, 10)],
];

/// A thread offering texels of `others` to the rig's current sink until stopped.
fn busy_source(
    sink: Arc<Mutex<Option<Arc<dyn TexelSink>>>>,
    others: Vec<RgbaImage>,
    stop: Arc<AtomicBool>,
) -> std::thread::JoinHandle<u64> {
    let blur = BlurTaps::of(&Params::default());
    let texels: Vec<BlurredTexels> = others
        .iter()
        .map(|c| BlurredTexels::prepare(c, blur))
        .collect();
    std::thread::spawn(move || {
        let mut offered = 0;
        while !stop.load(Ordering::Relaxed) {
            let current = sink.lock().unwrap().clone();
            if let Some(sink) = current {
                sink.offer(&texels[offered as usize % texels.len()]);
                offered += 1;
            }
            std::thread::yield_now();
        }
        offered
    })
}

/// The outputs of every frame of PAIRS, by the engine taking `path`.
fn outputs(path: Path, display: &RgbaImage, cameras: &[RgbaImage]) -> Vec<Vec<u8>> {
    let mut rig = Rig::new(path);
    let direct = path.direct;
    assert_eq!(
        rig.engine.direct_texels(),
        direct,
        "direct path on lavapipe"
    );
    let stop = Arc::new(AtomicBool::new(false));
    let others: Vec<RgbaImage> = (0..3).map(|k| noise(CAMERA.0, CAMERA.1, 90 + k)).collect();
    let busy =
        (path.writer == Writer::Busy).then(|| busy_source(rig.sink.clone(), others, stop.clone()));
    let mut out = Vec::new();
    for pair in PAIRS {
        rig.put(display);
        for (i, (camera, prepared, sequence)) in pair.into_iter().enumerate() {
            rig.frame(i, &cameras[camera], prepared, sequence);
        }
        out.extend([rig.get(0), rig.get(1)]);
    }
    stop.store(true, Ordering::Relaxed);
    if let Some(busy) = busy {
        assert!(busy.join().unwrap() > 0, "the busy source offered nothing");
    }
    if path.writer == Writer::Source {
        // Every prepared frame but those that made the ring (the first, and the first after
        // each of the two size changes) used what the source wrote; through the staging
        // buffers, a frame of a camera frame the background's image holds uses no slot.
        let counts = rig.engine.texels_from_source();
        let want = if direct { (7, 10) } else { (5, 8) };
        assert_eq!(
            counts, want,
            "frames using the source's texels, of the ring's"
        );
    }
    // Still on after the camera's size changed (the images made again).
    assert_eq!(rig.engine.direct_texels(), direct, "direct path kept");
    rig.finish();
    out
}

#[test]
fn consecutive_live_frames_each_get_their_own_background() {
    let display = noise(REGION.0, REGION.1, 21);
    let mut cameras: Vec<RgbaImage> = (0..4).map(|k| noise(CAMERA.0, CAMERA.1, 5 + k)).collect();
    cameras.push(noise(CAMERA.0 - 16, CAMERA.1 + 8, 11));
    let writers = [Writer::Frame, Writer::Source, Writer::Busy];
    let paths = [true, false]
        .into_iter()
        .flat_map(|direct| writers.map(|writer| Path { direct, writer }));
    let runs: Vec<(Path, Vec<Vec<u8>>)> = paths
        .map(|path| (path, outputs(path, &display, &cameras)))
        .collect();
    for (n, (camera, prepared, sequence)) in PAIRS.iter().flatten().enumerate() {
        let want = expected(&display, &cameras[*camera], *prepared);
        for (path, out) in &runs {
            assert!(out[n] == want, "frame {n} (sequence {sequence}): {path:?}");
        }
    }
    // The cameras give different outputs: a frame sampling another's texels would show.
    let distinct: Vec<Vec<u8>> = cameras
        .iter()
        .map(|c| expected(&display, c, true))
        .collect();
    for a in 0..cameras.len() {
        assert_ne!(distinct[a], display.pixels.as_flattened());
        for b in a + 1..cameras.len() {
            assert_ne!(distinct[a], distinct[b], "cameras {a} and {b}");
        }
    }
}

/// The perceptual method's model, uploaded into a view's buffer only when it changes, follows
/// every change of the settings: frames alternating between two world luminances (and one
/// repeated) each give what an engine that uploads every time gives.
#[test]
fn the_perceptual_model_follows_each_change_of_the_settings() {
    use contrastxr::algorithm::Method;
    let display = noise(REGION.0, REGION.1, 31);
    let camera = noise(CAMERA.0, CAMERA.1, 32);
    let at = |world: f64| {
        let mut p = Params {
            method: Method::Perceptual,
            ..Params::default()
        };
        p.perceptual.world_nits = world;
        p
    };
    let (office, outdoors) = (at(500.0), at(5000.0));
    let want_office = expected_with(&display, &camera, true, &office);
    let want_outdoors = expected_with(&display, &camera, true, &outdoors);
    assert_ne!(
        want_office, want_outdoors,
        "the two settings give one output"
    );
    let mut rig = Rig::new(Path {
        direct: false,
        writer: Writer::Frame,
    });
    let frames = [&office, &outdoors, &outdoors, &office, &outdoors];
    for (n, params) in frames.into_iter().enumerate() {
        rig.put(&display);
        rig.frame_with(0, &camera, (true, 1), params);
        let want = match params.perceptual.world_nits == 500.0 {
            true => &want_office,
            false => &want_outdoors,
        };
        assert!(
            rig.get(0) == *want,
            "frame {n}: {} cd/m²",
            params.perceptual.world_nits
        );
    }
    rig.finish();
}

/// The layer's submits on an app's queue wait while a forwarded runtime call that may submit on
/// it (xrCreateSwapchain) holds the app-queue lock; a device of the engine's own does not.
#[test]
fn submits_on_the_apps_queue_wait_for_the_runtimes_swapchain_calls() {
    use contrastxr::gpu::vulkan::device::app_queue;
    use std::sync::mpsc;
    let own = GpuDevice::create(&OPTIONS).unwrap();
    // SAFETY: `own`'s handles, valid while `own` lives, which outlives `apps`.
    let apps = unsafe {
        GpuDevice::borrow(
            own.entry.clone(),
            own.instance.handle(),
            own.physical,
            own.device.handle(),
            own.queue_family,
            0,
        )
    }
    .unwrap();
    assert!(apps.is_the_apps() && !own.is_the_apps());
    for (gpu, waits) in [(&own, false), (&apps, true)] {
        let released = Arc::new(AtomicBool::new(false));
        let (held_tx, held_rx) = mpsc::channel();
        let holder = {
            let released = released.clone();
            std::thread::spawn(move || {
                let queue = app_queue::hold();
                held_tx.send(()).unwrap();
                std::thread::sleep(std::time::Duration::from_millis(300));
                released.store(true, Ordering::SeqCst);
                drop(queue);
            })
        };
        held_rx.recv().unwrap();
        let mut c = Commands::new(gpu).unwrap();
        c.begin(gpu).unwrap();
        c.submit(gpu).unwrap();
        let after_release = released.load(Ordering::SeqCst);
        c.destroy(gpu).unwrap();
        holder.join().unwrap();
        assert_eq!(after_release, waits, "app's device: {waits}");
    }
    drop(apps);
    assert_eq!(own.validation_errors(), 0);
}
