//! Command-line flags. They are a stable interface: the runtime and layer tests drive the client
//! with them.

use crate::gl_binding::GlBinding;
use crate::pattern::Content;
use crate::swapchain_format::{SwapchainFormat, FORMATS};

pub const USAGE: &str = "\
usage: contrastxr-xr-client [options]
  --format NAME           swapchain format: auto (the runtime's first) or one of
                          R8G8B8A8_SRGB B8G8R8A8_SRGB R8G8B8A8_UNORM B8G8R8A8_UNORM
                          R16G16B16A16_UNORM R16G16B16A16_SFLOAT A2B10G10R10_UNORM
  --graphics vulkan|opengl
                          the session's graphics API: Vulkan (XR_KHR_vulkan_enable2, default)
                          or OpenGL (XR_KHR_opengl_enable, Xlib binding on a GLX 4.5 core
                          context on $DISPLAY; the same layouts, quads and scripts, the
                          pattern's rows and image rects bottom first; GL formats by the Vulkan name of their layout: R8G8B8A8_SRGB
                          is GL_SRGB8_ALPHA8, R8G8B8A8_UNORM GL_RGBA8, R16G16B16A16_SFLOAT
                          GL_RGBA16F, R16G16B16A16_UNORM GL_RGBA16, A2B10G10R10_UNORM
                          GL_RGB10_A2)
  --gl-binding xlib|egl   with --graphics opengl: how the session gets the app's context: the
                          Xlib binding of XR_KHR_opengl_enable on GLX (default), or the EGL
                          binding of XR_MNDX_egl_enable (the runtime must offer it) on an EGL
                          4.5 core context of Mesa's surfaceless platform (libEGL.so.1) current
                          on a 16x16 pbuffer (--check-gl-state's drawables are then EGL
                          pbuffer surfaces)
  --egl-bind-es           with --gl-binding egl: before every xrEndFrame the client binds
                          EGL_OPENGL_ES_API on its thread (its OpenGL context stays current:
                          eglBindAPI changes only which API's context eglGetCurrent* name), and
                          after it checks that eglQueryAPI still answers that
                          (`egl_api_checked`, and `egl_api_changed`: the frames it did not)
  --layout array|side-by-side
                          one swapchain with arraySize 2, or one wide swapchain (default array)
  --frames N              frames to submit before ending the session (default 60)
  --stop-file PATH        end the session before --frames once PATH exists (looked for
                          before each frame): a test's run lasts as long as it needs
  --until-modified N      with --check-untouched: end the session before --frames once N of
                          its frames were found changed after the client wrote them (a run
                          lasts until the layer has enhanced that many, however long its
                          shaders take to build)
  --quad                  also submit a quad layer with its own swapchain
  --quad-strips N         with --quad: submit the quad's image as N quad layers, one per
                          horizontal strip (N regions of one swapchain in one frame; default 1)
  --size WxH              per-view size (default: the runtime's recommended size)
  --content panels|typical|image:PATH
                          what the images show: coloured panels and a ramp (default, 37 %
                          of each view), a typical mixed-reality frame (17 %: two UI
                          panels and a shaded disc, as `contrastxr bench --content typical`),
                          or the PNG at PATH stretched over each view (nearest texel; with
                          --size of the PNG's size, texel for texel), as an app's frame
  --validation            enable VK_LAYER_KHRONOS_validation; any error fails the run
  --list-formats          print the formats the runtime offers and exit
  --json                  print the final report as one JSON line on stdout
  --timing                report the time spent in xrEndFrame and, after it, waiting for the
                          queue to drain (a layer's GPU work), per frame (median, p95, after
                          10 warm-up frames); each frame-loop call's time over every frame
                          (xrWaitFrame, xrBeginFrame, xrAcquire/Wait/ReleaseSwapchainImage,
                          xrEndFrame: median, p95, max; `calls`); when the first 30 frames'
                          xrEndFrame returned, in s after xrCreateSession (`first_frames_s`);
                          frames per second from xrCreateSession to the last frame; and the
                          client's whole run time (`run_s`)
  --provoke-xr-validation-error, --provoke-vk-validation-error
                          make one invalid call on purpose (to test that validation is seen)
  --provoke-vk-sync-hazard
                          record two unsynchronised writes (to test that sync validation is on)
  --provoke-vk-leak       leave one buffer undestroyed (to test that leaks are reported)
  --sessions N            create, run (--frames each) and destroy N sessions in turn (default 1)
  --pipelined             acquire and wait for the next frame's image before xrEndFrame of the
                          current one, as engines with a render thread running ahead do
  --churn-swapchains      create and destroy swapchains on a second thread while frames run
                          (with --graphics opengl: on the frame thread, one before each frame)
  --churn-formats         with --churn-swapchains: cycle through every format the runtime
                          offers (colour and depth), up to 1920x1080, from the moment the
                          session exists
  --script OPS            instead of frames, run one scripted sequence of raw swapchain and
                          frame calls (comma-separated: acquire wait release begin end
                          end-empty destroy create) and report each call's XrResult (`script`)
  --idle-ms N             after the frames, keep each session N ms without ending a frame
                          before xrDestroySession (an app paused or idle)
  --after-device-ms N     after the last session, destroy the Vulkan device and wait N ms
                          before xrDestroyInstance (a layer must not touch the device's memory
                          after xrDestroySession)
  --instances N           create, run (--sessions each) and destroy N instances in turn
                          (default 1)
  --linger-ms N           after the last xrDestroyInstance, run on N ms, then report the
                          layer's threads still running and whether its library is mapped
                          (`after_instances`)
  --exit-marker           at the end, register an exit handler that writes
                          `contrastxr-xr-client: exit handler ran` on stderr: it runs before
                          every handler registered earlier, and after none registered later
  --stderr-full           run the frame loop with stderr a full pipe nobody reads: a layer
                          that writes to it must not block the app's calls
  --check-untouched       read each swapchain image back when it is acquired again and report
                          the frames whose pixels changed after the client wrote them
  --check-gl-state        with --graphics opengl: before every xrEndFrame set non-default
                          values of the GL state a layer could touch (current context and
                          drawables: every second frame the read drawable is the draw
                          drawable, the others another pbuffer; program and pipeline, active texture, textures, samplers
                          and image units on units 0 to the layer's highest binding number,
                          generic and indexed buffer bindings, pixel store, framebuffers,
                          GL_FRAMEBUFFER_SRGB and other enables, viewport, scissor box) and
                          leave GL_INVALID_ENUM pending; after it read all back with glGet*
                          and report the frames checked (`gl_state_checked`) and every item
                          that changed (`gl_state_changed`: frame, what, before, after)
  --disturb-gl-state ITEMS
                          with --check-gl-state: change these items (comma-separated) after
                          setting them, as a layer that forgets to restore them would (to test
                          that the check sees it): glXGetCurrentDrawable (with EGL: the
                          draw surface) glGetError
                          GL_ACTIVE_TEXTURE GL_CURRENT_PROGRAM GL_TEXTURE_BINDING_2D
                          GL_IMAGE_BINDING_NAME GL_PIXEL_UNPACK_BUFFER_BINDING
                          GL_UNPACK_ALIGNMENT GL_DRAW_FRAMEBUFFER_BINDING GL_FRAMEBUFFER_SRGB
  --x-errors-elsewhere    with --graphics opengl (Xlib): count the X errors a thread of the
                          client keeps making on a second X connection with an X error handler
                          of the client's, and call xrEndFrame with the context released (a
                          layer then switches contexts around every frame); report both counts
                          (`x_errors_made`, `x_errors_seen`)
  The JSON report holds resident memory and open file descriptors every 50 frames
  (`memory`) and after each session (`sessions`).";

/// The session's graphics API.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Graphics {
    Vulkan,
    OpenGl,
}

impl Graphics {
    pub fn name(self) -> &'static str {
        match self {
            Graphics::Vulkan => "vulkan",
            Graphics::OpenGl => "opengl",
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Layout {
    /// One swapchain with arraySize 2; view i is at imageArrayIndex i.
    Array,
    /// One swapchain twice as wide as a view; view i is the i-th half (imageRect).
    SideBySide,
}

impl Layout {
    pub fn name(self) -> &'static str {
        match self {
            Layout::Array => "array",
            Layout::SideBySide => "side-by-side",
        }
    }
}

#[derive(Clone, Debug, PartialEq)]
pub struct Options {
    pub graphics: Graphics,
    /// With --graphics opengl: the session's binding.
    pub gl_binding: GlBinding,
    /// None: the first format the runtime offers that the client knows.
    pub format: Option<SwapchainFormat>,
    pub layout: Layout,
    pub frames: u32,
    /// End the session early once this file exists (--stop-file).
    pub stop_file: Option<std::path::PathBuf>,
    /// End the session early once this many frames were found changed (--until-modified).
    pub until_modified: Option<u32>,
    pub quad: bool,
    /// Quad layers the quad's image is split into (horizontal strips).
    pub quad_strips: u32,
    pub size: Option<(u32, u32)>,
    pub validation: bool,
    pub list_formats: bool,
    pub json: bool,
    pub timing: bool,
    pub provoke_xr_error: bool,
    pub provoke_vk_error: bool,
    pub provoke_sync_hazard: bool,
    pub provoke_leak: bool,
    pub sessions: u32,
    pub check_untouched: bool,
    pub pipelined: bool,
    pub churn_swapchains: bool,
    /// The churn thread cycles through every offered format at growing sizes.
    pub churn_formats: bool,
    pub script: Option<Vec<crate::script::Op>>,
    pub content: Content,
    /// Milliseconds between destroying the Vulkan device and xrDestroyInstance.
    pub after_device_ms: u64,
    pub idle_ms: u64,
    pub stderr_full: bool,
    /// Register a late exit handler that says when it runs (--exit-marker).
    pub exit_marker: bool,
    pub instances: u32,
    /// Milliseconds to run on after the last xrDestroyInstance (None: report nothing).
    pub linger_ms: Option<u64>,
    /// With --graphics opengl: set, and check after, the GL state around every xrEndFrame.
    pub check_gl_state: bool,
    /// Items of gl_state::DISTURBABLE the client changes before xrEndFrame (a test of the check).
    pub disturb_gl_state: Vec<String>,
    /// With --gl-binding egl: EGL_OPENGL_ES_API bound on the client's thread, checked after
    /// every xrEndFrame.
    pub egl_bind_es: bool,
    /// With --graphics opengl (Xlib): X errors made on a second connection, counted by the
    /// client's handler, and xrEndFrame called with the context released.
    pub x_errors_elsewhere: bool,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            graphics: Graphics::Vulkan,
            gl_binding: GlBinding::Xlib,
            format: None,
            layout: Layout::Array,
            frames: 60,
            stop_file: None,
            until_modified: None,
            quad: false,
            quad_strips: 1,
            size: None,
            validation: false,
            list_formats: false,
            json: false,
            timing: false,
            provoke_xr_error: false,
            provoke_vk_error: false,
            provoke_sync_hazard: false,
            provoke_leak: false,
            sessions: 1,
            check_untouched: false,
            pipelined: false,
            churn_swapchains: false,
            churn_formats: false,
            script: None,
            content: Content::Panels,
            after_device_ms: 0,
            idle_ms: 0,
            stderr_full: false,
            exit_marker: false,
            instances: 1,
            linger_ms: None,
            check_gl_state: false,
            disturb_gl_state: Vec::new(),
            egl_bind_es: false,
            x_errors_elsewhere: false,
        }
    }
}

pub fn parse(args: impl IntoIterator<Item = String>) -> Result<Options, String> {
    let mut options = Options::default();
    let mut args = args.into_iter();
    while let Some(arg) = args.next() {
        let mut value = || args.next().ok_or(format!("{arg} needs a value"));
        match arg.as_str() {
            "--format" => options.format = parse_format(&value()?)?,
            "--layout" => options.layout = parse_layout(&value()?)?,
            "--frames" => {
                options.frames = value()?.parse().map_err(|_| "--frames needs a count")?
            }
            "--stop-file" => options.stop_file = Some(value()?.into()),
            "--until-modified" => {
                let n = value()?
                    .parse()
                    .map_err(|_| "--until-modified needs a count")?;
                options.until_modified = Some(n)
            }
            "--size" => options.size = Some(parse_size(&value()?)?),
            "--content" => options.content = parse_content(&value()?)?,
            "--quad" => options.quad = true,
            "--quad-strips" => {
                options.quad_strips = value()?
                    .parse()
                    .ok()
                    .filter(|&n| n > 0)
                    .ok_or("--quad-strips needs a count above 0")?
            }
            "--graphics" => {
                options.graphics = match value()?.as_str() {
                    "vulkan" => Graphics::Vulkan,
                    "opengl" => Graphics::OpenGl,
                    _ => return Err("--graphics needs vulkan or opengl".into()),
                }
            }
            "--gl-binding" => {
                options.gl_binding = match value()?.as_str() {
                    "xlib" => GlBinding::Xlib,
                    "egl" => GlBinding::Egl,
                    _ => return Err("--gl-binding needs xlib or egl".into()),
                }
            }
            "--validation" => options.validation = true,
            "--list-formats" => options.list_formats = true,
            "--json" => options.json = true,
            "--timing" => options.timing = true,
            "--provoke-xr-validation-error" => options.provoke_xr_error = true,
            "--provoke-vk-validation-error" => options.provoke_vk_error = true,
            "--provoke-vk-sync-hazard" => options.provoke_sync_hazard = true,
            "--provoke-vk-leak" => options.provoke_leak = true,
            "--instances" => {
                options.instances = value()?.parse().map_err(|_| "--instances needs a count")?
            }
            "--linger-ms" => {
                options.linger_ms = Some(
                    value()?
                        .parse()
                        .map_err(|_| "--linger-ms needs milliseconds")?,
                )
            }
            "--stderr-full" => options.stderr_full = true,
            "--exit-marker" => options.exit_marker = true,
            "--check-untouched" => options.check_untouched = true,
            "--check-gl-state" => options.check_gl_state = true,
            "--x-errors-elsewhere" => options.x_errors_elsewhere = true,
            "--egl-bind-es" => options.egl_bind_es = true,
            "--disturb-gl-state" => {
                for item in value()?.split(',') {
                    if !crate::gl_state::DISTURBABLE.contains(&item) {
                        return Err(format!("--disturb-gl-state: unknown item {item}\n{USAGE}"));
                    }
                    options.disturb_gl_state.push(item.to_string());
                }
            }
            "--pipelined" => options.pipelined = true,
            "--churn-swapchains" => options.churn_swapchains = true,
            "--churn-formats" => {
                options.churn_swapchains = true;
                options.churn_formats = true;
            }
            "--script" => options.script = Some(crate::script::parse(&value()?)?),
            "--sessions" => {
                options.sessions = value()?.parse().map_err(|_| "--sessions needs a count")?
            }
            "--idle-ms" => {
                options.idle_ms = value()?
                    .parse()
                    .map_err(|_| "--idle-ms needs milliseconds")?
            }
            "--after-device-ms" => {
                options.after_device_ms = value()?
                    .parse()
                    .map_err(|_| "--after-device-ms needs milliseconds")?
            }
            "-h" | "--help" => return Err(USAGE.to_string()),
            other => return Err(format!("unknown argument {other}\n{USAGE}")),
        }
    }
    if options.check_gl_state && options.graphics != Graphics::OpenGl {
        return Err("--check-gl-state needs --graphics opengl".into());
    }
    if options.gl_binding == GlBinding::Egl && options.graphics != Graphics::OpenGl {
        return Err("--gl-binding needs --graphics opengl".into());
    }
    let egl = options.graphics == Graphics::OpenGl && options.gl_binding == GlBinding::Egl;
    if options.egl_bind_es && !egl {
        return Err("--egl-bind-es needs --graphics opengl --gl-binding egl".into());
    }
    let xlib = options.graphics == Graphics::OpenGl && options.gl_binding == GlBinding::Xlib;
    if options.x_errors_elsewhere && !xlib {
        return Err("--x-errors-elsewhere needs --graphics opengl with the Xlib binding".into());
    }
    if !options.disturb_gl_state.is_empty() && !options.check_gl_state {
        return Err("--disturb-gl-state needs --check-gl-state".into());
    }
    if options.until_modified.is_some() && !options.check_untouched {
        return Err("--until-modified needs --check-untouched".into());
    }
    Ok(options)
}

fn parse_format(name: &str) -> Result<Option<SwapchainFormat>, String> {
    if name == "auto" {
        return Ok(None);
    }
    let known = FORMATS.map(|f| f.name).join(" ");
    SwapchainFormat::by_name(name)
        .map(Some)
        .ok_or(format!("unknown format {name}: use auto or one of {known}"))
}

fn parse_layout(name: &str) -> Result<Layout, String> {
    match name {
        "array" => Ok(Layout::Array),
        "side-by-side" => Ok(Layout::SideBySide),
        _ => Err(format!("unknown layout {name}: use array or side-by-side")),
    }
}

fn parse_content(name: &str) -> Result<Content, String> {
    match name {
        "panels" => Ok(Content::Panels),
        "typical" => Ok(Content::Typical),
        _ => match name.strip_prefix("image:") {
            Some("") => Err("--content image: needs a PNG's path".into()),
            Some(path) => Ok(Content::Image(path.into())),
            None => Err(format!(
                "unknown content {name}: use panels, typical or image:PATH"
            )),
        },
    }
}

fn parse_size(text: &str) -> Result<(u32, u32), String> {
    let bad = || format!("bad size {text}: use WxH, e.g. 640x480");
    let (w, h) = text.split_once('x').ok_or_else(bad)?;
    let (w, h) = (w.parse().map_err(|_| bad())?, h.parse().map_err(|_| bad())?);
    if w == 0 || h == 0 {
        return Err(bad());
    }
    Ok((w, h))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse_str(s: &str) -> Result<Options, String> {
        parse(s.split_whitespace().map(String::from))
    }

    #[test]
    fn parses_every_flag() {
        let o = parse_str("--format b8g8r8a8_srgb --layout side-by-side --frames 7 --quad --size 64x48 --validation --json").unwrap();
        assert_eq!(o.format.unwrap().name, "B8G8R8A8_SRGB");
        assert_eq!(
            (o.layout, o.frames, o.quad, o.size),
            (Layout::SideBySide, 7, true, Some((64, 48)))
        );
        assert!(o.validation && o.json && !o.list_formats);
        assert_eq!(o.stop_file, None);
        let o = parse_str("--frames 900 --stop-file /tmp/x/stop").unwrap();
        assert_eq!(
            o.stop_file.as_deref(),
            Some(std::path::Path::new("/tmp/x/stop"))
        );
        let o = parse_str("--check-untouched --until-modified 40").unwrap();
        assert_eq!(o.until_modified, Some(40));
        assert!(parse_str("--check-untouched --until-modified many").is_err());
        assert!(parse_str("--until-modified 40").is_err());
        let o = parse_str("--pipelined --script acquire,wait,release,end-empty").unwrap();
        assert!(o.pipelined);
        assert_eq!(o.script.unwrap().len(), 4);
        assert_eq!(o.content, Content::Panels);
        let o = parse_str("--content typical").unwrap();
        assert_eq!(o.content, Content::Typical);
        let o = parse_str("--content image:samples/display-text-swatches.png").unwrap();
        assert_eq!(
            o.content,
            Content::Image("samples/display-text-swatches.png".into())
        );
        let o = parse_str("--instances 3 --linger-ms 1000 --after-device-ms 5 --stderr-full");
        let o = o.unwrap();
        assert_eq!(
            (o.instances, o.linger_ms, o.after_device_ms),
            (3, Some(1000), 5)
        );
        assert!(o.stderr_full);
        let o = parse_str(
            "--graphics opengl --check-gl-state --disturb-gl-state glGetError,GL_ACTIVE_TEXTURE",
        );
        let o = o.unwrap();
        assert!(o.check_gl_state);
        assert_eq!(o.disturb_gl_state, ["glGetError", "GL_ACTIVE_TEXTURE"]);
        assert_eq!(o.gl_binding, GlBinding::Xlib);
        let o = parse_str("--graphics opengl --gl-binding egl").unwrap();
        assert_eq!(o.gl_binding, GlBinding::Egl);
        assert!(!o.egl_bind_es);
        let o = parse_str("--graphics opengl --gl-binding egl --egl-bind-es").unwrap();
        assert!(o.egl_bind_es);
    }

    #[test]
    fn rejects_bad_values() {
        for bad in [
            "--format RGB",
            "--layout grid",
            "--frames x",
            "--size 10",
            "--size 0x5",
            "--content full",
            "--content image:",
            "--frames",
            "--bogus",
            "--script acquire,jump",
            "--instances x",
            "--linger-ms -1",
            "--after-device-ms",
            "--check-gl-state",
            "--graphics opengl --disturb-gl-state glGetError",
            "--graphics opengl --check-gl-state --disturb-gl-state GL_VIEWPORT",
            "--gl-binding egl",
            "--graphics opengl --gl-binding glx",
            "--graphics opengl --egl-bind-es",
        ] {
            assert!(parse_str(bad).is_err(), "{bad}");
        }
    }
}
