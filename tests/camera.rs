//! Background sources end to end: file sources in-process, and the real V4L2 path (the `v4l`
//! crate, unchanged) against tests/fake-v4l2, an LD_PRELOAD stand-in for a capture device.
//!
//! LD_PRELOAD must be set when a process starts, so each V4L2 case re-executes this test
//! binary with the stand-in preloaded and `CONTRASTXR_CAMERA_CHILD` naming the case; the
//! `child_dispatch` test runs that case in the child and does nothing in a normal run.
//! Expected pixels are computed here from the BT.601 / JFIF equations in floating point,
//! independently of the crate's fixed-point conversion.

mod common;

use contrastxr::camera::usb_id::UsbId;
use contrastxr::camera::v4l2;
use contrastxr::camera::{parse_source, Background, CaptureConfig, SourceSpec, SourceStatus};
use contrastxr::image::RgbaImage;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::OnceLock;
use std::time::{Duration, Instant};

const CHILD: &str = "CONTRASTXR_CAMERA_CHILD";
const W: u32 = 640;
const H: u32 = 480;

// ---------------------------------------------------------------- expected colours

fn clamp_round(v: f64) -> u8 {
    v.round().clamp(0.0, 255.0) as u8
}

/// BT.601 limited range, from the defining equations (Kr = 0.299, Kb = 0.114).
fn ref_limited(y: u8, cb: u8, cr: u8) -> [u8; 4] {
    let (y, cb, cr) = (
        (f64::from(y) - 16.0) * 255.0 / 219.0,
        (f64::from(cb) - 128.0) * 255.0 / 224.0,
        (f64::from(cr) - 128.0) * 255.0 / 224.0,
    );
    ref_rgb(y, cb, cr)
}

/// JFIF full range.
fn ref_full(y: u8, cb: u8, cr: u8) -> [u8; 4] {
    ref_rgb(f64::from(y), f64::from(cb) - 128.0, f64::from(cr) - 128.0)
}

fn ref_rgb(y: f64, cb: f64, cr: f64) -> [u8; 4] {
    let (kr, kb) = (0.299, 0.114);
    let kg = 1.0 - kr - kb;
    let r = y + 2.0 * (1.0 - kr) * cr;
    let b = y + 2.0 * (1.0 - kb) * cb;
    let g = (y - kr * r - kb * b) / kg;
    [clamp_round(r), clamp_round(g), clamp_round(b), 255]
}

/// Eight YCbCr triples for eight vertical bands of 80 pixels.
const PALETTE: [[u8; 3]; 8] = [
    [16, 128, 128],
    [235, 128, 128],
    [81, 90, 240],
    [145, 54, 34],
    [41, 240, 110],
    [116, 168, 108],
    [200, 100, 160],
    [60, 150, 90],
];

fn band(x: u32) -> usize {
    (x / 80) as usize
}

fn yuv_expected(palette: &[[u8; 3]; 8], full: bool) -> RgbaImage {
    let mut img = RgbaImage::new(W, H, [0; 4]);
    for y in 0..H {
        for x in 0..W {
            let [l, cb, cr] = palette[band(x)];
            img.set(
                x,
                y,
                if full {
                    ref_full(l, cb, cr)
                } else {
                    ref_limited(l, cb, cr)
                },
            );
        }
    }
    img
}

/// One raw frame in `fourcc` and the RGBA it must decode to.
fn test_frame(fourcc: &str, variant: u8) -> (Vec<u8>, RgbaImage) {
    let mut palette = PALETTE;
    palette.rotate_left(variant as usize);
    match fourcc {
        "YUYV" => (yuyv(&palette), yuv_expected(&palette, false)),
        "NV12" => (nv12(&palette), yuv_expected(&palette, false)),
        "MJPG" => (jpeg::encode(&palette), yuv_expected(&palette, true)),
        "RGB3" | "BGR3" | "GREY" => packed(fourcc, &palette),
        _ => unreachable!(),
    }
}

fn yuyv(p: &[[u8; 3]; 8]) -> Vec<u8> {
    let mut out = Vec::new();
    for _ in 0..H {
        for x in (0..W).step_by(2) {
            let [y, cb, cr] = p[band(x)];
            out.extend([y, cb, y, cr]);
        }
    }
    out
}

fn nv12(p: &[[u8; 3]; 8]) -> Vec<u8> {
    let mut out: Vec<u8> = (0..W * H).map(|i| p[band(i % W)][0]).collect();
    for _ in 0..H / 2 {
        for x in (0..W).step_by(2) {
            out.extend([p[band(x)][1], p[band(x)][2]]);
        }
    }
    out
}

/// RGB3, BGR3 and GREY frames, taking the palette bytes as colours.
fn packed(fourcc: &str, p: &[[u8; 3]; 8]) -> (Vec<u8>, RgbaImage) {
    let mut raw = Vec::new();
    let mut img = RgbaImage::new(W, H, [0; 4]);
    for y in 0..H {
        for x in 0..W {
            let [a, b, c] = p[band(x)];
            let rgba = match fourcc {
                "RGB3" => {
                    raw.extend([a, b, c]);
                    [a, b, c, 255]
                }
                "BGR3" => {
                    raw.extend([a, b, c]);
                    [c, b, a, 255]
                }
                _ => {
                    raw.push(a);
                    [a, a, a, 255]
                }
            };
            img.set(x, y, rgba);
        }
    }
    (raw, img)
}

/// A baseline JPEG the way UVC cameras send MJPEG: 4:4:4, no Huffman tables (the standard ones
/// of JPEG Annex K are implied), each 8x8 block flat (DC only), quantisation all ones.
mod jpeg {
    use super::{band, H, W};

    const DC_LUMA_BITS: [u8; 16] = [0, 1, 5, 1, 1, 1, 1, 1, 1, 0, 0, 0, 0, 0, 0, 0];
    const DC_CHROMA_BITS: [u8; 16] = [0, 3, 1, 1, 1, 1, 1, 1, 1, 1, 1, 0, 0, 0, 0, 0];
    /// End-of-block codes of the standard AC tables (K.5 luminance, K.6 chrominance).
    const EOB: [(u32, u32); 2] = [(0b1010, 4), (0b00, 2)];

    /// Canonical Huffman codes (code, length) for symbols 0.. from the count per length.
    fn codes(bits: &[u8; 16]) -> Vec<(u32, u32)> {
        let (mut out, mut code) = (Vec::new(), 0u32);
        for (i, &n) in bits.iter().enumerate() {
            for _ in 0..n {
                out.push((code, i as u32 + 1));
                code += 1;
            }
            code <<= 1;
        }
        out
    }

    #[derive(Default)]
    struct Bits {
        out: Vec<u8>,
        acc: u32,
        n: u32,
    }

    impl Bits {
        fn put(&mut self, value: u32, len: u32) {
            for i in (0..len).rev() {
                self.acc = self.acc << 1 | (value >> i & 1);
                self.n += 1;
                if self.n == 8 {
                    let byte = self.acc as u8;
                    self.out.push(byte);
                    if byte == 0xFF {
                        self.out.push(0); // byte stuffing
                    }
                    (self.acc, self.n) = (0, 0);
                }
            }
        }
        fn finish(mut self) -> Vec<u8> {
            while self.n != 0 {
                self.put(1, 1);
            }
            self.out
        }
    }

    pub fn encode(palette: &[[u8; 3]; 8]) -> Vec<u8> {
        let dc = [codes(&DC_LUMA_BITS), codes(&DC_CHROMA_BITS)];
        let mut bits = Bits::default();
        let mut prev = [0i32; 3];
        for _ in 0..H / 8 {
            for bx in 0..W / 8 {
                for c in 0..3 {
                    // Flat block of value v: DC = 8 (v - 128) with unit quantisation.
                    let value = 8 * (i32::from(palette[band(bx * 8)][c]) - 128);
                    let diff = value - prev[c];
                    prev[c] = value;
                    let size = 32 - diff.unsigned_abs().leading_zeros();
                    let table = usize::from(c > 0);
                    let (code, len) = dc[table][size as usize];
                    bits.put(code, len);
                    let extra = if diff < 0 { diff - 1 } else { diff } as u32;
                    bits.put(extra & ((1 << size) - 1), size);
                    bits.put(EOB[table].0, EOB[table].1);
                }
            }
        }
        let mut out = vec![0xFF, 0xD8, 0xFF, 0xDB, 0, 67, 0];
        out.extend([1u8; 64]);
        out.extend([
            0xFF,
            0xC0,
            0,
            17,
            8,
            (H >> 8) as u8,
            H as u8,
            (W >> 8) as u8,
            W as u8,
            3,
        ]);
        out.extend([1, 0x11, 0, 2, 0x11, 0, 3, 0x11, 0]);
        out.extend([0xFF, 0xDA, 0, 12, 3, 1, 0x00, 2, 0x11, 3, 0x11, 0, 63, 0]);
        out.extend(bits.finish());
        out.extend([0xFF, 0xD9]);
        out
    }
}

// ---------------------------------------------------------------- comparing

fn max_difference(a: &RgbaImage, b: &RgbaImage) -> Result<u8, String> {
    if (a.width, a.height) != (b.width, b.height) {
        return Err(format!(
            "size {}x{} vs {}x{}",
            a.width, a.height, b.width, b.height
        ));
    }
    let mut worst = 0;
    for (p, q) in a.pixels.iter().zip(&b.pixels) {
        for c in 0..3 {
            worst = worst.max(p[c].abs_diff(q[c]));
        }
    }
    Ok(worst)
}

fn read_rgba(path: &Path) -> RgbaImage {
    let bytes = std::fs::read(path).unwrap();
    let pixels = bytes
        .as_chunks::<4>()
        .0
        .iter()
        .map(|p| [p[0], p[1], p[2], p[3]])
        .collect();
    RgbaImage {
        width: W,
        height: H,
        pixels,
        has_alpha: false,
    }
}

fn write_rgba(path: &Path, img: &RgbaImage) {
    std::fs::write(
        path,
        img.pixels.iter().flatten().copied().collect::<Vec<u8>>(),
    )
    .unwrap();
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("camera-tests")
        .join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

// ---------------------------------------------------------------- the stand-in device

fn fake_library() -> &'static Path {
    static LIB: OnceLock<PathBuf> = OnceLock::new();
    LIB.get_or_init(|| {
        let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("fake-v4l2");
        std::fs::create_dir_all(&dir).unwrap();
        common::fake_v4l2(&dir)
    })
}

/// A stand-in camera: a folder holding its device node and frame files.
struct FakeCamera {
    dir: PathBuf,
    env: Vec<(String, String)>,
}

impl FakeCamera {
    fn new(name: &str, format: &str) -> FakeCamera {
        let dir = temp_dir(name);
        let node = dir.join("video7");
        std::fs::write(&node, b"").unwrap(); // so that listing the folder finds it
        let env = vec![
            ("FAKE_V4L2_DEVICE".into(), node.display().to_string()),
            ("FAKE_V4L2_FORMAT".into(), format.into()),
            ("CONTRASTXR_V4L2_DIR".into(), dir.display().to_string()),
        ];
        FakeCamera { dir, env }
    }

    fn set(mut self, key: &str, value: &str) -> FakeCamera {
        self.env.push((key.into(), value.into()));
        self
    }

    /// Frames the device serves in turn, and the images they must decode to.
    fn frames(self, fourcc: &str, variants: &[u8]) -> FakeCamera {
        let (mut frames, mut expected) = (Vec::new(), Vec::new());
        for &v in variants {
            let (raw, img) = test_frame(fourcc, v);
            let (f, e) = (
                self.dir.join(format!("frame{v}.raw")),
                self.dir.join(format!("expect{v}.rgba")),
            );
            std::fs::write(&f, raw).unwrap();
            write_rgba(&e, &img);
            frames.push(f.display().to_string());
            expected.push(e.display().to_string());
        }
        self.set("FAKE_V4L2_FRAMES", &frames.join(":"))
            .set("EXPECT", &expected.join(":"))
    }

    /// Runs `case` in a child process with the stand-in preloaded; returns its output.
    fn run(&self, case: &str) -> String {
        let mut child = Command::new(std::env::current_exe().unwrap())
            .args([
                "child_dispatch",
                "--exact",
                "--nocapture",
                "--test-threads=1",
            ])
            .env(CHILD, case)
            .env("LD_PRELOAD", fake_library())
            .envs(self.env.iter().map(|(k, v)| (k, v)))
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .unwrap();
        let deadline = Instant::now() + Duration::from_secs(60);
        while child.try_wait().unwrap().is_none() {
            if Instant::now() > deadline {
                child.kill().unwrap();
                panic!("child case {case} hung (killed after 60 s)");
            }
            std::thread::sleep(Duration::from_millis(20));
        }
        let out = child.wait_with_output().unwrap();
        let text = String::from_utf8_lossy(&out.stdout).into_owned()
            + &String::from_utf8_lossy(&out.stderr);
        assert!(out.status.success(), "child case {case} failed:\n{text}");
        println!("--- child {case}:\n{text}");
        text
    }
}

// ---------------------------------------------------------------- V4L2 cases (parent side)

#[test]
fn each_pixel_format_negotiates_and_decodes() {
    for (fourcc, tolerance) in [
        ("YUYV", 1),
        ("NV12", 1),
        ("MJPG", 2),
        ("RGB3", 0),
        ("BGR3", 0),
        ("GREY", 0),
    ] {
        let out = FakeCamera::new(&format!("format-{fourcc}"), fourcc)
            .frames(fourcc, &[0])
            .set("TOLERANCE", &tolerance.to_string())
            .run("decode");
        assert!(out.contains(&format!("640x480 {fourcc}")), "{out}");
    }
}

#[test]
fn negotiation_prefers_the_smallest_good_size_and_raw_formats() {
    // 320x240 is too small, 1280x720 larger than needed; YUYV is chosen over MJPEG; of
    // 15/30/60 fps the lowest that reaches 30.
    let out = FakeCamera::new("negotiate", "MJPG,YUYV")
        .set("FAKE_V4L2_SIZE", "320x240,640x480,1280x720")
        .set("FAKE_V4L2_FPS", "15,30,60")
        .frames("YUYV", &[0])
        .set("TOLERANCE", "1")
        .run("decode");
    assert!(out.contains("640x480 YUYV at 30 fps"), "{out}");
}

#[test]
fn streaming_delivers_new_frames_with_growing_sequence() {
    // At 5 fps the capture thread's 100 ms polls time out between frames, which must not be
    // taken for a loss (the v4l crate would queue a buffer twice after a timeout).
    let out = FakeCamera::new("stream", "YUYV")
        .set("FAKE_V4L2_FPS", "5")
        .frames("YUYV", &[0, 3])
        .run("stream");
    assert!(out.contains("saw both frames"), "{out}");
}

#[test]
fn vanishing_device_goes_stale_then_lost_then_live_again() {
    let out = FakeCamera::new("vanish", "NV12")
        .frames("NV12", &[0, 1])
        .set("FAKE_V4L2_VANISH_AFTER", "6")
        .set("FAKE_V4L2_RETURN_AFTER_MS", "1200")
        .run("vanish");
    assert!(out.contains("recovered"), "{out}");
}

#[test]
fn stable_paths_are_listed_and_open_and_auto_says_why() {
    let cam = FakeCamera::new("stable", "YUYV").frames("YUYV", &[0]);
    let by_id = cam.dir.join("v4l/by-id");
    std::fs::create_dir_all(&by_id).unwrap();
    std::os::unix::fs::symlink(
        "../../video7",
        by_id.join("usb-Acme_World_Camera-video-index0"),
    )
    .unwrap();
    let out = cam.run("stable");
    assert!(out.contains("stable path opened"), "{out}");
    // A laptop's camera is still taken when it is the only one, and the log says so.
    let out = FakeCamera::new("stable-builtin", "YUYV")
        .frames("YUYV", &[0])
        .set("FAKE_V4L2_CARD", "Integrated Camera")
        .run("stable");
    assert!(
        out.contains("every usable capture device looks built in"),
        "{out}"
    );
}

/// A fake sysfs in which the stand-in's node hangs off `device` (a folder made under it).
fn fake_sysfs(cam: FakeCamera, device: &str) -> FakeCamera {
    let sys = cam.dir.join("sys");
    let target = sys.join("devices").join(device);
    std::fs::create_dir_all(&target).unwrap();
    let class = sys.join("class/video4linux/video7");
    std::fs::create_dir_all(&class).unwrap();
    std::os::unix::fs::symlink(&target, class.join("device")).unwrap();
    let root = sys.display().to_string();
    cam.set("CONTRASTXR_SYSFS_ROOT", &root)
}

fn with_by_id(cam: FakeCamera, name: &str) -> FakeCamera {
    let by_id = cam.dir.join("v4l/by-id");
    std::fs::create_dir_all(&by_id).unwrap();
    std::os::unix::fs::symlink("../../video7", by_id.join(name)).unwrap();
    cam
}

#[test]
fn auto_decides_built_in_by_the_bus_not_the_word_webcam() {
    // A USB camera called "Webcam" is the world-facing one.
    let cam = FakeCamera::new("auto-usb", "YUYV")
        .frames("YUYV", &[0])
        .set("FAKE_V4L2_CARD", "HD Pro Webcam C920");
    let cam = with_by_id(cam, "usb-046d_HD_Pro_Webcam_C920-video-index0");
    let out = fake_sysfs(cam, "pci0000:00/0000:00:14.0/usb1/1-2/1-2:1.0").run("stable");
    assert!(
        out.contains("usb-046d_HD_Pro_Webcam_C920-video-index0 (HD Pro Webcam C920): the only usable capture device, on USB"),
        "{out}"
    );
    // On the platform bus it is the machine's own, whatever its name.
    let cam = FakeCamera::new("auto-platform", "YUYV")
        .frames("YUYV", &[0])
        .set("FAKE_V4L2_CARD", "Acme World Camera");
    let out = fake_sysfs(cam, "platform/soc/camera0").run("stable");
    assert!(
        out.contains("every usable capture device looks built in"),
        "{out}"
    );
}

/// The headset's camera named by its device profile (`camera_usb_ids`): `v4l2:auto` says it
/// took it for that reason; with another id listed, it chooses as before.
#[test]
fn auto_takes_the_camera_the_profile_names_by_its_usb_id() {
    let with_ids = |name: &str, ids: &str| {
        let cam = FakeCamera::new(name, "YUYV")
            .frames("YUYV", &[0])
            .set("FAKE_V4L2_CARD", "VITURE Camera")
            .set("CONTRASTXR_CAMERA_USB_IDS", ids);
        let cam = fake_sysfs(cam, "pci0000:00/0000:00:14.0/usb1/1-2/1-2:1.0");
        let usb = cam.dir.join("sys/devices/pci0000:00/0000:00:14.0/usb1/1-2");
        std::fs::write(usb.join("idVendor"), "0c45\n").unwrap();
        std::fs::write(usb.join("idProduct"), "636b\n").unwrap();
        cam.run("stable")
    };
    let out = with_ids("auto-profile-camera", "0c45:6368,0c45:636b");
    assert!(
        out.contains("(VITURE Camera): USB 0c45:636b, the camera camera_usb_ids names"),
        "{out}"
    );
    let out = with_ids("auto-other-camera", "0c45:6368");
    assert!(
        out.contains("the only usable capture device, on USB"),
        "{out}"
    );
}

#[test]
fn auto_skips_a_node_without_a_colour_mode() {
    let out = FakeCamera::new("auto-depth", "Z16 ")
        .set("FAKE_V4L2_CARD", "Intel RealSense Depth")
        .run("auto_unusable");
    assert!(out.contains("with a usable mode (video* absent"), "{out}");
}

#[test]
fn auto_keeps_its_camera_by_stable_path_after_a_loss_and_says_it_once() {
    let cam = FakeCamera::new("auto-vanish", "YUYV")
        .frames("YUYV", &[0])
        .set("FAKE_V4L2_VANISH_AFTER", "4")
        .set("FAKE_V4L2_RETURN_AFTER_MS", "800");
    let out = with_by_id(cam, "usb-Acme_World_Camera-video-index0").run("auto_vanish");
    assert!(out.contains("auto kept its camera"), "{out}");
}

#[test]
fn fixed_exposure_white_balance_and_gain_are_set_and_reported() {
    let out = FakeCamera::new("controls", "YUYV")
        .frames("YUYV", &[0])
        .run("controls");
    assert!(out.contains("controls checked"), "{out}");
    let out = FakeCamera::new("no-controls", "YUYV")
        .frames("YUYV", &[0])
        .set("FAKE_V4L2_NO_CONTROLS", "1")
        .run("controls");
    assert!(
        out.contains("camera_exposure 10000us: the camera has no such control"),
        "{out}"
    );
}

#[test]
fn auto_turns_the_automatic_controls_back_on_and_close_restores_them() {
    let out = FakeCamera::new("controls-auto", "YUYV")
        .frames("YUYV", &[0])
        .run("controls_auto");
    assert!(out.contains("auto controls checked"), "{out}");
}

#[test]
fn a_busy_camera_is_retried_until_it_is_free() {
    let out = FakeCamera::new("in-use", "YUYV")
        .frames("YUYV", &[0])
        .set("FAKE_V4L2_BUSY_FOR_MS", "1500")
        .run("busy");
    assert!(out.contains("frame after busy"), "{out}");
}

#[test]
fn device_that_never_delivers_reports_it_without_hanging() {
    let out = FakeCamera::new("silent", "YUYV")
        .set("FAKE_V4L2_NO_FRAMES", "1")
        .run("silent");
    assert!(out.contains("no frame, as expected"), "{out}");
}

#[test]
fn camera_list_shows_the_fake_device_and_auto_finds_it() {
    let cam = FakeCamera::new("list", "YUYV,MJPG,H264")
        .set("FAKE_V4L2_SIZE", "320x240,640x480")
        .set("FAKE_V4L2_FPS", "15,30");
    std::fs::write(cam.dir.join("video3"), b"not a device").unwrap();
    let out = cam.run("list");
    assert!(out.contains("auto chose video7"), "{out}");
}

#[test]
fn camera_test_reports_rate_and_saves_frames() {
    let out = FakeCamera::new("cli-test", "YUYV")
        .frames("YUYV", &[0, 2])
        .set("TOLERANCE", "1")
        .run("cli_test");
    assert!(out.contains("saved frames match"), "{out}");
}

#[test]
fn camera_list_without_any_device_says_so() {
    let dir = temp_dir("no-device");
    let text = v4l2::listing(&dir);
    assert_eq!(
        text.trim(),
        format!(
            "no V4L2 capture device found ({}/video* absent)",
            dir.display()
        )
    );
}

#[test]
fn missing_device_is_a_clear_error() {
    let spec = parse_source("v4l2:/nonexistent/video9").unwrap();
    let err = Background::open(&spec, &CaptureConfig::default())
        .err()
        .expect("must fail");
    assert_eq!(err.to_string(), "/nonexistent/video9 does not exist");
}

// ---------------------------------------------------------------- V4L2 cases (child side)

#[test]
fn child_dispatch() {
    let Ok(case) = std::env::var(CHILD) else {
        return; // a normal run: the cases above start this in a child process
    };
    match case.as_str() {
        "decode" => child_decode(),
        "stream" => child_stream(),
        "vanish" => child_vanish(),
        "silent" => child_silent(),
        "busy" => child_busy(),
        "stable" => child_stable(),
        "controls" => child_controls(),
        "controls_auto" => child_controls_auto(),
        "auto_unusable" => child_auto_unusable(),
        "auto_vanish" => child_auto_vanish(),
        "list" => child_list(),
        "cli_test" => child_cli_test(),
        other => panic!("unknown child case {other}"),
    }
}

fn env(key: &str) -> String {
    std::env::var(key).unwrap_or_default()
}

fn expected_images() -> Vec<RgbaImage> {
    env("EXPECT")
        .split(':')
        .map(|p| read_rgba(Path::new(p)))
        .collect()
}

fn fake_spec() -> SourceSpec {
    SourceSpec::V4l2Device(env("FAKE_V4L2_DEVICE").into())
}

/// Index of the expected image `img` matches within the tolerance, or a description.
fn which_expected(img: &RgbaImage, expected: &[RgbaImage]) -> Result<usize, String> {
    let tolerance: u8 = env("TOLERANCE").parse().unwrap_or(1);
    let diffs: Vec<_> = expected.iter().map(|e| max_difference(img, e)).collect();
    diffs
        .iter()
        .position(|d| d.as_ref().is_ok_and(|d| *d <= tolerance))
        .ok_or(format!(
            "frame matches no expected image (max differences {diffs:?})"
        ))
}

fn wait_for_frame(
    bg: &Background,
    after: u64,
    within: Duration,
) -> Option<contrastxr::camera::Frame> {
    let deadline = Instant::now() + within;
    while Instant::now() < deadline {
        if let Some(f) = bg.latest().filter(|f| f.sequence > after) {
            return Some(f);
        }
        std::thread::sleep(Duration::from_millis(2));
    }
    None
}

/// `camera list` names a device's stable paths, `v4l2:` opens one, and `v4l2:auto` logs what
/// it took and why.
fn child_stable() {
    static LOG: std::sync::Mutex<Vec<String>> = std::sync::Mutex::new(Vec::new());
    contrastxr::camera::set_log_sink(Box::new(|m| LOG.lock().unwrap().push(m.to_string())));
    let dir = env("CONTRASTXR_V4L2_DIR");
    let link = format!("{dir}/v4l/by-id/usb-Acme_World_Camera-video-index0");
    let text = listed();
    if std::path::Path::new(&link).exists() {
        assert!(text.contains(&format!("  also {link}\n")), "{text}");
        let spec = parse_source(&format!("v4l2:{link}")).unwrap();
        let bg = Background::open(&spec, &CaptureConfig::default()).unwrap();
        wait_for_frame(&bg, 0, Duration::from_secs(10)).expect("a frame through the link");
        println!("stable path opened");
    }
    // The device profile's camera, as the layer passes it from camera_usb_ids.
    let ids = std::env::var("CONTRASTXR_CAMERA_USB_IDS").unwrap_or_default();
    let cfg = CaptureConfig {
        usb_ids: UsbId::parse_list(&ids).unwrap(),
        ..CaptureConfig::default()
    };
    let bg = Background::open(&SourceSpec::V4l2Auto, &cfg).unwrap();
    drop(bg);
    let log = LOG.lock().unwrap().join("\n");
    let took: Vec<_> = log
        .lines()
        .filter(|l| l.contains("v4l2:auto took"))
        .collect();
    assert_eq!(took.len(), 1, "{log}");
    println!("{}", took[0]);
}

/// Fixed controls: the log names the value the camera took (clamped to its range, rounded to
/// its step), and `camera list` shows the controls with their ranges and current values.
fn child_controls() {
    static LOG: std::sync::Mutex<Vec<String>> = std::sync::Mutex::new(Vec::new());
    contrastxr::camera::set_log_sink(Box::new(|m| LOG.lock().unwrap().push(m.to_string())));
    let cfg = CaptureConfig {
        controls: contrastxr::camera::CameraControls {
            exposure_us: Some(10_000),
            white_balance_k: Some(5_003),
            gain: Some(300),
        },
        ..CaptureConfig::default()
    };
    let bg = Background::open(&fake_spec(), &cfg).unwrap();
    wait_for_frame(&bg, 0, Duration::from_secs(10)).expect("a frame");
    let log = LOG.lock().unwrap().join("\n");
    println!("{log}");
    if env("FAKE_V4L2_NO_CONTROLS").is_empty() {
        for line in [
            "camera_exposure 10000us: the camera took 10000us",
            "camera_white_balance 5003K: the camera took 5000K",
            "camera_gain 300: refused, outside the camera's range 0..255",
        ] {
            assert!(log.contains(line), "{line} missing:\n{log}");
        }
        let text = listed();
        assert!(
            text.contains(
                "  control camera_white_balance 2800..6500K (default 4600, now 5000, fixed)"
            ),
            "{text}"
        );
        assert!(
            text.contains("  control camera_exposure 300..204700us"),
            "{text}"
        );
        bg.close();
        let text = listed();
        for line in [
            "  control camera_white_balance 2800..6500K (default 4600, now 4600, automatic)",
            "  control camera_exposure 300..204700us (default 15600, now 15600, automatic)",
            "  control camera_gain 0..255 (default 32, now 32)\n",
        ] {
            assert!(text.contains(line), "not restored at close: {line}\n{text}");
        }
        println!("controls checked");
    }
}

fn child_auto_unusable() {
    match Background::open(&SourceSpec::V4l2Auto, &CaptureConfig::default()) {
        Ok(bg) => panic!("took a node without a colour mode: {}", bg.description()),
        Err(e) => println!("{e}"),
    }
}

/// After a loss the capture thread reopens the camera it chose, by its stable path, without
/// choosing (or saying so) again.
fn child_auto_vanish() {
    static LOG: std::sync::Mutex<Vec<String>> = std::sync::Mutex::new(Vec::new());
    contrastxr::camera::set_log_sink(Box::new(|m| LOG.lock().unwrap().push(m.to_string())));
    let cfg = CaptureConfig {
        stall_timeout: Duration::from_millis(300),
        grace: Duration::from_millis(200),
        max_backoff: Duration::from_millis(100),
        ..CaptureConfig::default()
    };
    let bg = Background::open(&SourceSpec::V4l2Auto, &cfg).unwrap();
    let link = format!(
        "{}/v4l/by-id/usb-Acme_World_Camera-video-index0",
        env("CONTRASTXR_V4L2_DIR")
    );
    let deadline = Instant::now() + Duration::from_secs(20);
    while !LOG
        .lock()
        .unwrap()
        .iter()
        .any(|l| l.starts_with("reopened"))
    {
        assert!(Instant::now() < deadline, "{:#?}", LOG.lock().unwrap());
        std::thread::sleep(Duration::from_millis(20));
    }
    bg.close();
    let log = LOG.lock().unwrap().join("\n");
    let took = log.lines().filter(|l| l.contains("v4l2:auto took")).count();
    assert_eq!(took, 1, "{log}");
    assert!(log.contains(&format!("reopened {link} (")), "{log}");
    println!("{log}\nauto kept its camera");
}

/// What `contrastxr camera list` prints, read in this process (whose stand-in holds the
/// state the case set up).
fn listed() -> String {
    v4l2::listing(&v4l2::device_dir())
}

/// Another program left the camera fixed: `auto` turns the automatic controls back on while
/// the layer holds the camera, and close puts back what it found. A value of 2^31 (which
/// would wrap in the driver's 32-bit field) is refused with the range, and nothing changes.
fn child_controls_auto() {
    use v4l::control::{Control, Value};
    static LOG: std::sync::Mutex<Vec<String>> = std::sync::Mutex::new(Vec::new());
    contrastxr::camera::set_log_sink(Box::new(|m| LOG.lock().unwrap().push(m.to_string())));
    {
        let other = v4l::Device::with_path(env("FAKE_V4L2_DEVICE")).unwrap();
        for (id, value) in [
            (0x009a_0901, Value::Integer(1)),
            (0x009a_0902, Value::Integer(500)),
            (0x0098_090c, Value::Boolean(false)),
            (0x0098_091a, Value::Integer(3000)),
        ] {
            other.set_control(Control { id, value }).unwrap();
        }
    }
    let fixed_by_other = [
        "  control camera_exposure 300..204700us (default 15600, now 50000, fixed)",
        "  control camera_white_balance 2800..6500K (default 4600, now 3000, fixed)",
    ];
    let text = listed();
    for line in fixed_by_other {
        assert!(text.contains(line), "{line}\n{text}");
    }
    let cfg = CaptureConfig {
        controls: contrastxr::camera::CameraControls {
            gain: Some(1 << 31),
            ..Default::default()
        },
        ..CaptureConfig::default()
    };
    let bg = Background::open(&fake_spec(), &cfg).unwrap();
    wait_for_frame(&bg, 0, Duration::from_secs(10)).expect("a frame");
    let log = LOG.lock().unwrap().join("\n");
    for line in [
        "camera_exposure auto: the camera's automatic control is on again",
        "camera_white_balance auto: the camera's automatic control is on again",
        "camera_gain 2147483648: refused, outside the camera's range 0..255",
    ] {
        assert!(log.contains(line), "{line} missing:\n{log}");
    }
    let text = listed();
    for line in [
        "  control camera_exposure 300..204700us (default 15600, now 50000, automatic)",
        "  control camera_white_balance 2800..6500K (default 4600, now 3000, automatic)",
        "  control camera_gain 0..255 (default 32, now 32)\n",
    ] {
        assert!(text.contains(line), "{line}\n{text}");
    }
    bg.close();
    let text = listed();
    for line in fixed_by_other {
        assert!(text.contains(line), "not restored at close: {line}\n{text}");
    }
    println!("auto controls checked");
}

/// Busy at open (another program captures): the source opens all the same, says so once,
/// and delivers frames once the device is free.
fn child_busy() {
    static LOG: std::sync::Mutex<Vec<String>> = std::sync::Mutex::new(Vec::new());
    contrastxr::camera::set_log_sink(Box::new(|m| LOG.lock().unwrap().push(m.to_string())));
    let cfg = CaptureConfig {
        max_backoff: Duration::from_millis(400),
        ..CaptureConfig::default()
    };
    let bg = Background::open(&fake_spec(), &cfg).unwrap();
    assert!(bg.description().contains("is busy"), "{}", bg.description());
    let frame = wait_for_frame(&bg, 0, Duration::from_secs(20)).expect("a frame once free");
    which_expected(&frame.image, &expected_images()).unwrap();
    let log = LOG.lock().unwrap().clone();
    let busy: Vec<_> = log.iter().filter(|l| l.contains("busy")).collect();
    assert_eq!(busy.len(), 1, "{log:#?}");
    println!("frame after busy");
}

fn child_decode() {
    let bg = Background::open(&fake_spec(), &CaptureConfig::default()).unwrap();
    println!("opened {}", bg.description());
    let frame = wait_for_frame(&bg, 0, Duration::from_secs(10)).expect("a frame");
    which_expected(&frame.image, &expected_images()).unwrap();
    assert_eq!(bg.status(), SourceStatus::Live);
}

fn child_stream() {
    static LOG: std::sync::Mutex<Vec<String>> = std::sync::Mutex::new(Vec::new());
    contrastxr::camera::set_log_sink(Box::new(|m| LOG.lock().unwrap().push(m.to_string())));
    let bg = Background::open(&fake_spec(), &CaptureConfig::default()).unwrap();
    assert!(
        bg.description().ends_with("640x480 YUYV at 5 fps"),
        "{}",
        bg.description()
    );
    let expected = expected_images();
    let (mut last, mut seen) = (0, [false; 2]);
    for _ in 0..8 {
        let frame = wait_for_frame(&bg, last, Duration::from_secs(5)).expect("a new frame");
        assert!(frame.sequence > last);
        last = frame.sequence;
        seen[which_expected(&frame.image, &expected).unwrap()] = true;
    }
    assert_eq!(seen, [true, true], "both served frames should show up");
    let log = LOG.lock().unwrap().join("\n");
    assert!(
        !log.contains("lost"),
        "a slow camera is not a lost one:\n{log}"
    );
    println!("saw both frames");
}

fn child_vanish() {
    let cfg = CaptureConfig {
        stall_timeout: Duration::from_millis(400),
        grace: Duration::from_millis(300),
        max_backoff: Duration::from_millis(100),
        ..CaptureConfig::default()
    };
    let bg = Background::open(&fake_spec(), &cfg).unwrap();
    let expected = expected_images();
    let mut history: Vec<&str> = Vec::new();
    let mut before = 0;
    let deadline = Instant::now() + Duration::from_secs(20);
    while Instant::now() < deadline {
        // latest() must answer while the device is gone; this loop would stall otherwise.
        let frame = bg.latest();
        let state = match bg.status() {
            SourceStatus::Waiting { .. } => "waiting",
            SourceStatus::Live => "live",
            SourceStatus::Stale { .. } => {
                assert!(frame.is_some(), "the last good frame is kept while stale");
                "stale"
            }
            SourceStatus::Lost => {
                assert!(frame.is_none(), "no frame once lost");
                "lost"
            }
        };
        if let Some(f) = &frame {
            which_expected(&f.image, &expected).unwrap();
        }
        if history.last() != Some(&state) {
            history.push(state);
        }
        match (history.contains(&"lost"), &frame) {
            (false, Some(f)) => before = f.sequence,
            (true, Some(f)) if state == "live" => {
                assert!(f.sequence > before, "sequence continues after reopening");
                break;
            }
            _ => {}
        }
        std::thread::sleep(Duration::from_millis(2));
    }
    let joined = history.join(" -> ");
    let path: Vec<&str> = history.into_iter().filter(|s| *s != "waiting").collect();
    assert_eq!(path, ["live", "stale", "lost", "live"], "{joined}");
    println!("recovered: {joined}");
}

fn child_silent() {
    let cfg = CaptureConfig {
        stall_timeout: Duration::from_millis(200),
        grace: Duration::from_millis(200),
        ..CaptureConfig::default()
    };
    let bg = Background::open(&fake_spec(), &cfg).unwrap();
    assert!(
        matches!(bg.status(), SourceStatus::Waiting { .. }),
        "{:?}",
        bg.status()
    );
    let start = Instant::now();
    while start.elapsed() < Duration::from_millis(1200) {
        assert!(bg.latest().is_none());
        std::thread::sleep(Duration::from_millis(5));
    }
    assert_eq!(bg.status(), SourceStatus::Lost);
    drop(bg); // joins the capture thread: must not hang on the silent device
    println!("no frame, as expected");
}

fn child_list() {
    let text = listed();
    println!("{text}");
    let dir = env("CONTRASTXR_V4L2_DIR");
    assert!(
        text.contains(&format!("{dir}/video3: cannot open")),
        "{text}"
    );
    assert!(text.contains(&format!(
        "{dir}/video7: Fake V4L2 camera (fake_v4l2, fake:0)"
    )));
    assert!(text.contains("  YUYV\n    320x240 at 15, 30 fps\n    640x480 at 15, 30 fps\n"));
    assert!(text.contains("  MJPG\n"));
    assert!(text.contains("  H264 (not usable as a background)\n"));
    assert!(!text.contains("no V4L2 capture device"));
    let bg = Background::open(&SourceSpec::V4l2Auto, &CaptureConfig::default()).unwrap();
    assert!(
        bg.description().contains("/video7 "),
        "{}",
        bg.description()
    );
    println!("auto chose video7");
}

fn child_cli_test() {
    let dir = PathBuf::from(env("CONTRASTXR_V4L2_DIR")).join("saved");
    // The tool itself, in a process of its own (the stand-in is preloaded there too).
    let out = Command::new(env!("CARGO_BIN_EXE_contrastxr"))
        .args([
            "camera",
            "test",
            &env("FAKE_V4L2_DEVICE"),
            "--frames",
            "6",
            "-o",
        ])
        .arg(&dir)
        .output()
        .unwrap();
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(
        out.status.success(),
        "{text}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    println!("{text}");
    assert!(text.contains("6 frames of 640x480 at "), "{text}");
    assert!(
        text.contains("latency from capture to the reader: mean "),
        "{text}"
    );
    let expected = expected_images();
    for i in 0..6 {
        let saved = RgbaImage::load_png(&dir.join(format!("frame-{i:04}.png"))).unwrap();
        which_expected(&saved, &expected).unwrap();
    }
    println!("saved frames match");
}

// ---------------------------------------------------------------- file sources

#[test]
fn image_source_serves_the_png_unchanged_and_static() {
    let dir = temp_dir("image");
    let mut img = RgbaImage::new(5, 3, [0; 4]);
    img.has_alpha = false;
    for (i, p) in img.pixels.iter_mut().enumerate() {
        *p = [i as u8 * 10, 255 - i as u8, 7, 255];
    }
    let path = dir.join("bg.png");
    img.save_png(&path).unwrap();
    let spec = parse_source(&format!("image:{}", path.display())).unwrap();
    let bg = Background::open(&spec, &CaptureConfig::default()).unwrap();
    let (a, b) = (bg.latest().unwrap(), bg.latest().unwrap());
    assert_eq!(a.image.pixels, img.pixels);
    assert_eq!(a.sequence, b.sequence, "a static source keeps its sequence");
    assert_eq!(bg.status(), SourceStatus::Live);
    let missing = parse_source("image:/nonexistent.png").unwrap();
    assert!(Background::open(&missing, &CaptureConfig::default()).is_err());
}

/// A smooth image (gradients and soft colour fields): what a camera sees, and what JPEG keeps
/// well, so the decoded pixels can be held to a small tolerance.
fn smooth_scene(w: u32, h: u32) -> RgbaImage {
    let mut img = RgbaImage::new(w, h, [0, 0, 0, 255]);
    img.has_alpha = false;
    for y in 0..h {
        for x in 0..w {
            let (u, v) = (f64::from(x) / f64::from(w), f64::from(y) / f64::from(h));
            let r = 40.0 + 180.0 * u;
            let g = 200.0 - 120.0 * v;
            let b = 128.0 + 90.0 * (6.0 * u + 3.0 * v).sin();
            img.set(x, y, [r as u8, g as u8, b as u8, 255]);
        }
    }
    img
}

/// Writes `img` as a JPEG with an independent encoder (the jpeg-encoder crate: 4:2:0, standard
/// Huffman tables), under a name that does not end in .jpg: sources tell formats by content.
fn write_jpeg(path: &Path, img: &RgbaImage, quality: u8) {
    let rgb: Vec<u8> = img.pixels.iter().flat_map(|p| [p[0], p[1], p[2]]).collect();
    jpeg_encoder::Encoder::new_file(path, quality)
        .unwrap()
        .encode(
            &rgb,
            img.width as u16,
            img.height as u16,
            jpeg_encoder::ColorType::Rgb,
        )
        .unwrap();
}

fn differences(a: &RgbaImage, b: &RgbaImage) -> (u8, f64) {
    assert_eq!((a.width, a.height), (b.width, b.height));
    let diffs: Vec<u8> = a
        .pixels
        .iter()
        .zip(&b.pixels)
        .flat_map(|(p, q)| (0..3).map(move |c| p[c].abs_diff(q[c])))
        .collect();
    let mean = diffs.iter().map(|&d| f64::from(d)).sum::<f64>() / diffs.len() as f64;
    (*diffs.iter().max().unwrap(), mean)
}

#[test]
fn image_source_reads_a_jpeg() {
    let dir = temp_dir("image-jpeg");
    let scene = smooth_scene(96, 64);
    let path = dir.join("background.camera");
    write_jpeg(&path, &scene, 95);
    let spec = parse_source(&format!("image:{}", path.display())).unwrap();
    let bg = Background::open(&spec, &CaptureConfig::default()).unwrap();
    let frame = bg.latest().unwrap();
    let (max, mean) = differences(&frame.image, &scene);
    println!("JPEG q95 decoded: max difference {max}, mean {mean:.2} code values");
    assert!(max <= 12 && mean <= 2.0, "max {max}, mean {mean}");
    // A different image must not pass the same check (the comparison can fail).
    let mut other = scene.clone();
    other.pixels.iter_mut().for_each(|p| p[0] = 255 - p[0]);
    assert!(differences(&frame.image, &other).0 > 12);
    // Not a PNG nor a JPEG: one sentence naming both.
    let text = dir.join("notes.txt");
    std::fs::write(&text, "hello").unwrap();
    let spec = parse_source(&format!("image:{}", text.display())).unwrap();
    let err = Background::open(&spec, &CaptureConfig::default())
        .err()
        .expect("a text file is no image")
        .to_string();
    assert!(err.contains("not a readable PNG or JPEG"), "{err}");
}

#[test]
fn color_source_is_flat() {
    let bg = Background::open(
        &parse_source("color:#102030").unwrap(),
        &CaptureConfig::default(),
    )
    .unwrap();
    let f = bg.latest().unwrap();
    assert_eq!((f.image.width, f.image.height), (640, 480));
    assert!(f.image.pixels.iter().all(|p| *p == [0x10, 0x20, 0x30, 255]));
}

/// Watches a video source: every new frame must be `frames[(sequence - 1) % n]`.
fn check_video(bg: &Background, frames: &[RgbaImage], tolerance: u8) {
    let (mut last, mut shown) = (0, 0);
    let deadline = Instant::now() + Duration::from_millis(1500);
    while Instant::now() < deadline && shown < 6 {
        if let Some(f) = bg.latest().filter(|f| f.sequence > last) {
            let want = &frames[((f.sequence - 1) % frames.len() as u64) as usize];
            let diff = max_difference(&f.image, want).unwrap();
            assert!(diff <= tolerance, "frame {} differs by {diff}", f.sequence);
            (last, shown) = (f.sequence, shown + 1);
        }
        std::thread::sleep(Duration::from_millis(1));
    }
    assert!(shown >= 6, "only {shown} new frames in 1.5 s");
}

#[test]
fn video_folder_loops_numbered_frames_at_the_configured_rate() {
    let dir = temp_dir("video-folder");
    let colours = [[200, 0, 0, 255], [0, 200, 0, 255], [0, 0, 200, 255]];
    let frames: Vec<RgbaImage> = colours.iter().map(|c| RgbaImage::new(4, 4, *c)).collect();
    // Named so that text order (f1, f10, f2) differs from frame order (f1, f2, f10).
    for (img, name) in frames.iter().zip(["f1.png", "f2.png", "f10.png"]) {
        img.save_png(&dir.join(name)).unwrap();
    }
    let cfg = CaptureConfig {
        video_fps: 20.0,
        ..CaptureConfig::default()
    };
    let bg = Background::open(&SourceSpec::Video(dir.clone()), &cfg).unwrap();
    assert!(
        bg.description().contains("3 frames at 20.00 fps"),
        "{}",
        bg.description()
    );
    check_video(&bg, &frames, 0);
}

/// Writes a Y4M file of `frames` (each a list of per-pixel YCbCr at full resolution).
fn write_y4m(path: &Path, w: u32, h: u32, chroma: &str, frames: &[Vec<[u8; 3]>]) {
    let mut out = format!("YUV4MPEG2 W{w} H{h} F20:1 Ip A1:1 C{chroma}\n").into_bytes();
    let sub = if chroma == "444" { 1 } else { 2 };
    for f in frames {
        out.extend(b"FRAME\n");
        out.extend(f.iter().map(|p| p[0]));
        for c in [1, 2] {
            for y in (0..h).step_by(sub) {
                for x in (0..w).step_by(sub) {
                    out.push(f[(y * w + x) as usize][c]);
                }
            }
        }
    }
    std::fs::write(path, out).unwrap();
}

#[test]
fn y4m_420_and_444_play_with_bt601_colours() {
    let dir = temp_dir("y4m");
    let (w, h) = (4, 2);
    for chroma in ["420jpeg", "444"] {
        // 4:2:0 shares chroma per 2x2 block, so each 2x2 block gets one colour there.
        let frames: Vec<Vec<[u8; 3]>> = (0..3)
            .map(|k| {
                (0..w * h)
                    .map(|i| {
                        let x = i % w;
                        let block = if chroma == "444" {
                            (i + k) % 8
                        } else {
                            (x / 2 + k) % 8
                        };
                        PALETTE[block as usize]
                    })
                    .collect()
            })
            .collect();
        let path = dir.join(format!("clip-{chroma}.y4m"));
        write_y4m(&path, w, h, chroma, &frames);
        let expected: Vec<RgbaImage> = frames
            .iter()
            .map(|f| RgbaImage {
                width: w,
                height: h,
                pixels: f
                    .iter()
                    .map(|&[y, cb, cr]| ref_limited(y, cb, cr))
                    .collect(),
                has_alpha: false,
            })
            .collect();
        let bg = Background::open(&SourceSpec::Video(path), &CaptureConfig::default()).unwrap();
        assert!(
            bg.description().contains("3 frames at 20.00 fps"),
            "{}",
            bg.description()
        );
        check_video(&bg, &expected, 1);
    }
}

/// The nice value and name of each thread of this process (from /proc/self/task).
fn threads_nice() -> Vec<(String, i64)> {
    let mut out = Vec::new();
    for task in std::fs::read_dir("/proc/self/task").unwrap().flatten() {
        let dir = task.path();
        let (Ok(name), Ok(stat)) = (
            std::fs::read_to_string(dir.join("comm")),
            std::fs::read_to_string(dir.join("stat")),
        ) else {
            continue;
        };
        // Fields after the parenthesised name: state is field 3, nice field 19.
        let after = &stat[stat.rfind(')').unwrap() + 2..];
        let nice = after.split(' ').nth(16).unwrap().parse().unwrap();
        out.push((name.trim().to_string(), nice));
    }
    out
}

/// This thread's nice value.
fn own_nice() -> i32 {
    // SAFETY: getpriority of this thread only reads it.
    unsafe { libc::getpriority(libc::PRIO_PROCESS, libc::gettid() as libc::id_t) }
}

/// A live source's thread runs below the app's thread that opened it (5 more nice): where the
/// CPU is short, its decoding and blurring wait for the app's frame work. Relative, also under
/// an app started with `nice`: here the opening thread runs at 3 more than the test's start
/// (as this test does when the tests themselves run under `nice`), and the source at 8 more.
#[test]
fn a_live_sources_thread_yields_to_the_app() {
    let start = own_nice();
    let app = (start + 3).min(19);
    // SAFETY: setpriority on this test's own thread only changes its scheduling weight.
    unsafe { libc::setpriority(libc::PRIO_PROCESS, libc::gettid() as libc::id_t, app) };
    assert_eq!(own_nice(), app);
    let dir = temp_dir("nice-video");
    for k in 0..2u8 {
        let frame = RgbaImage::new(8, 6, [k, 9, 9, 255]);
        frame.save_png(&dir.join(format!("{k}.png"))).unwrap();
    }
    let bg = Background::open(&SourceSpec::Video(dir.clone()), &CaptureConfig::default()).unwrap();
    wait_for_frame(&bg, 0, Duration::from_secs(10)).expect("a frame of the video");
    let threads = threads_nice();
    let video: Vec<_> = threads
        .iter()
        .filter(|(n, _)| n == "contrastxr-vide")
        .collect();
    assert_eq!(video.len(), 1, "{threads:?}");
    assert_eq!(video[0].1, i64::from((app + 5).min(19)), "{threads:?}");
    assert_eq!(own_nice(), app, "the opening thread's own priority changed");
    drop(bg);
}

/// A frame rate far out of range (a hostile Y4M header, a folder's rate) is clamped to
/// 0.1-1000 fps: the player neither panics nor spins, and the video plays.
#[test]
fn out_of_range_frame_rates_are_clamped() {
    let dir = temp_dir("y4m-rates");
    let (w, h) = (4, 2);
    let frames: Vec<Vec<[u8; 3]>> = (0..3).map(|k| vec![PALETTE[k]; (w * h) as usize]).collect();
    let plain = dir.join("plain.y4m");
    write_y4m(&plain, w, h, "444", &frames);
    let bytes = std::fs::read(&plain).unwrap();
    for (rate, shown) in [
        ("F1e300:1", "1000.00 fps"),
        ("F1:1e300", "0.10 fps"),
        ("F0:1", "0.10 fps"),
    ] {
        let path = dir.join(format!("{rate}.y4m"));
        let at = bytes.windows(5).position(|w| w == b"F20:1").unwrap();
        let file = [&bytes[..at], rate.as_bytes(), &bytes[at + 5..]].concat();
        std::fs::write(&path, file).unwrap();
        let bg = Background::open(&SourceSpec::Video(path), &CaptureConfig::default())
            .unwrap_or_else(|e| panic!("{rate}: {e}"));
        assert!(bg.description().contains(shown), "{}", bg.description());
        let first = Instant::now();
        while bg.latest().is_none() && first.elapsed() < Duration::from_secs(2) {
            std::thread::sleep(Duration::from_millis(5));
        }
        assert!(bg.latest().is_some(), "{rate}: no frame");
        if rate == "F1e300:1" {
            // At 1000 fps the player keeps publishing new frames: its thread lives.
            let seen = bg.latest().unwrap().sequence;
            std::thread::sleep(Duration::from_millis(200));
            assert!(bg.latest().unwrap().sequence > seen + 50, "{rate}: stalled");
        }
    }
    for (fps, shown) in [(1e300, "1000.00 fps"), (0.0, "0.10 fps")] {
        let folder = dir.join(format!("folder-{fps:e}"));
        std::fs::create_dir_all(&folder).unwrap();
        RgbaImage::new(2, 2, [9, 9, 9, 255])
            .save_png(&folder.join("f1.png"))
            .unwrap();
        let cfg = CaptureConfig {
            video_fps: fps,
            ..CaptureConfig::default()
        };
        let bg = Background::open(&SourceSpec::Video(folder), &cfg)
            .unwrap_or_else(|e| panic!("folder at {fps}: {e}"));
        assert!(bg.description().contains(shown), "{}", bg.description());
    }
}

/// An `image:` background larger than the camera size is shrunk to it as it loads, and its
/// texels are prepared there with the blur the consumer asked for: no frame call blurs it.
#[test]
fn a_large_image_is_shrunk_to_the_camera_size_and_prepared_as_it_loads() {
    use contrastxr::algorithm::Params;
    use contrastxr::gpu::core::blurred_texels::BlurTaps;
    let dir = temp_dir("image-large");
    let path = dir.join("large.png");
    smooth_scene(1200, 900).save_png(&path).unwrap();
    let params = Params::default();
    let cfg = CaptureConfig {
        still_blur: Some(BlurTaps::of(&params)),
        ..CaptureConfig::default()
    };
    let spec = parse_source(&format!("image:{}", path.display())).unwrap();
    let frame = Background::open(&spec, &cfg).unwrap().latest().unwrap();
    assert_eq!((frame.image.width, frame.image.height), (640, 480));
    let prepared = frame.prepared.as_ref().expect("prepared as it loaded");
    assert!(prepared.made_for((640, 480), &params));
    // Without a blur asked for, the consumer prepares it; a small image keeps its size.
    let plain = Background::open(&spec, &CaptureConfig::default()).unwrap();
    assert!(plain.latest().unwrap().prepared.is_none());
}
