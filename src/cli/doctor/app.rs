//! The config file and its problems, and what the last app that loaded the layer logged about
//! it.

use super::finding::{doc, Finding};
use contrastxr::config::{self, Env, Source};
use contrastxr::layer::{log, log_file};
use std::path::{Path, PathBuf};

/// A problem sentence without the list of known keys that follows an unknown one.
fn short(problem: &str) -> &str {
    problem
        .split_once(" (known keys:")
        .map_or(problem, |(head, _)| head)
}

/// The line a `config PATH:LINE: ...` problem names.
fn line_of(problem: &str, path: &Path) -> Option<usize> {
    let rest = problem.strip_prefix(&format!("config {}:", path.display()))?;
    rest.split(':').next()?.parse().ok()
}

/// The config file the layer reads, every problem in it (all its tables), and the problems of
/// this shell's `CONTRASTXR_*` variables.
pub fn config(env: &Env) -> Finding {
    const NAME: &str = "config";
    let Some(path) = config::path::find(env) else {
        let user = config::path::user_path(env)
            .map_or("~/.config/contrastxr/config.toml".into(), |p| {
                p.display().to_string()
            });
        return Finding::ok(
            NAME,
            format!("no config file: defaults apply (`contrastxr set` writes {user})"),
        );
    };
    let mut problems = match contrastxr::user_file::read_text(&path) {
        Ok(text) => config::check(Source {
            path: &path,
            text: &text,
        }),
        Err(why) => vec![format!("config {} {why}", path.display())],
    };
    let from_env = config::load("", env).problems.into_iter();
    problems.extend(from_env.filter(|p| p.starts_with("environment variable")));
    let Some(first) = problems.first() else {
        return Finding::ok(NAME, format!("{}: no problems", path.display()));
    };
    let fix = match line_of(first, &path) {
        Some(line) => format!(
            "edit {} line {line}; `contrastxr config check` lists every problem",
            path.display()
        ),
        None => "correct the value named above; `contrastxr config check` lists every problem \
                 in the file"
            .into(),
    };
    Finding::problem(
        NAME,
        format!("{} problem(s): {}", problems.len(), short(first)),
        fix,
    )
}

/// The graphics APIs the layer enhances, in short (the report's header).
pub const ENHANCED_APIS: &str = "Vulkan, OpenGL";

/// The same, with the bindings: what a passed-through session's finding tells the user.
const ENHANCED_APIS_IN_FULL: &str = "Vulkan sessions, and OpenGL sessions through \
    XR_KHR_opengl_enable with the Xlib binding (GLX), or with EGL where the runtime offers \
    XR_MNDX_egl_enable";

/// The APIs, as the layer's [`log::GRAPHICS_API`] line names them, of sessions it enhances
/// (those of `layer::graphics`' bindings that enhance).
const ENHANCED_SESSION_APIS: [&str; 3] = contrastxr::layer::graphics::ENHANCED_APIS;

/// The layer's reason for passing a session of `api` through, from its `session (API): WHY`
/// line, without the `: passing ... through untouched` every such line ends with.
fn pass_through_reason<'a>(text: &'a str, api: &str) -> Option<&'a str> {
    let why = text
        .strip_prefix("session (")?
        .strip_prefix(api)?
        .strip_prefix("): ")?;
    let why = why.split_once(": passing").map_or(why, |(head, _)| head);
    (!why.is_empty()).then_some(why)
}

/// A session's graphics API and whether the layer enhanced it, from its log line.
#[derive(Debug, PartialEq, Eq)]
pub struct Session<'a> {
    /// As the layer names it: `Vulkan`, `OpenGL (Xlib)`, `OpenGL (EGL)`, ...
    pub api: &'a str,
    pub enhanced: bool,
}

/// `graphics API of this session: API, enhanced` (or `, passed through`); None for any other
/// line, and for one whose ending is neither.
fn session(text: &str) -> Option<Session<'_>> {
    let (api, state) = text
        .strip_prefix(log::GRAPHICS_API)?
        .trim_end()
        .rsplit_once(", ")?;
    let enhanced = match state {
        "enhanced" => true,
        "passed through" => false,
        _ => return None,
    };
    (!api.is_empty()).then_some(Session { api, enhanced })
}

/// The log lines of the last app that loaded the layer (`contrastxr log`'s reading).
pub struct LastApp {
    path: Option<PathBuf>,
    lines: Vec<String>,
}

/// A line saying the layer is on, or why it is not, and the fix for the latter.
fn verdict(text: &str) -> Option<(bool, &'static str)> {
    const LOG: &str = "`contrastxr log` shows the whole log of that app";
    if text.contains("enhancement began")
        || text.contains("processing frames")
        || text.starts_with(log::ENHANCING_AGAIN)
        || text.ends_with(": enhancing")
    {
        return Some((true, ""));
    }
    if text.contains(log::TRIES_AGAIN) {
        return Some((
            false,
            "the app's OpenGL context was current on another thread when it called xrEndFrame \
             (or xrReleaseSwapchainImage): the layer can enhance only frames whose thread can \
             make it current; if it never could, report it to the app's developers",
        ));
    }
    if text.contains(" off (CONTRASTXR is 0") {
        return Some((false, "start the app with CONTRASTXR=1"));
    }
    if !text.contains("passing") || !text.contains("through") {
        return None;
    }
    Some((
        false,
        if text.contains("blend mode") {
            "if the headset is see-through but its runtime reports another blend mode, set \
             environment_blend_mode = \"additive\" in its [device.\"...\"] table (or \
             CONTRASTXR_ENVIRONMENT_BLEND_MODE=additive): apps then render black around their \
             content; not force = true, which acts on opaque frames as they are and recolours \
             the whole background of an app that believes the display is opaque"
        } else if text.contains("background") {
            "check the camera finding and the background setting (`contrastxr camera list`)"
        } else if text.contains("not a Vulkan session") {
            "choose the app's Vulkan renderer, or its OpenGL one (GLX, or EGL where the \
             runtime offers XR_MNDX_egl_enable): the layer enhances those sessions"
        } else {
            LOG
        },
    ))
}

impl LastApp {
    pub fn read() -> LastApp {
        let path = log::path();
        // The layer caps each file at log_file::MAX_BYTES; anything else there is not read whole.
        let read = |p: &Path| {
            contrastxr::user_file::read(p, 2 * log_file::MAX_BYTES)
                .map(|b| String::from_utf8_lossy(&b).into_owned())
                .unwrap_or_default()
        };
        let text = path
            .as_deref()
            .map_or(String::new(), |p| read(&log_file::rotated(p)) + &read(p));
        let lines = log::last_app(&text)
            .into_iter()
            .map(str::to_string)
            .collect();
        LastApp { path, lines }
    }

    /// The headset's system name, from the layer's `system "NAME": ...` line.
    pub fn system(&self) -> Option<&str> {
        self.lines.iter().rev().find_map(|l| {
            let text = log::parse_line(l)?.text;
            let rest = text.strip_prefix("system \"")?;
            Some(&rest[..rest.find("\": settings")?])
        })
    }

    /// The text of the last line the app logged that starts with `prefix`.
    pub fn last_line(&self, prefix: &str) -> Option<&str> {
        self.lines.iter().rev().find_map(|l| {
            let text = log::parse_line(l)?.text;
            text.starts_with(prefix).then_some(text)
        })
    }

    /// The graphics API of the app's last session, from the layer's [`log::GRAPHICS_API`] line.
    pub fn session(&self) -> Option<Session<'_>> {
        self.lines
            .iter()
            .rev()
            .find_map(|l| session(log::parse_line(l)?.text))
    }

    pub fn finding(&self) -> Finding {
        const NAME: &str = "last-app";
        let where_ = self
            .path
            .as_ref()
            .map_or("(no log path: HOME unset)".into(), |p| {
                p.display().to_string()
            });
        let Some(first) = self.lines.first().and_then(|l| log::parse_line(l)) else {
            return Finding::warn(
                NAME,
                format!("no app has loaded the layer yet (no start of an app in {where_})"),
                format!(
                    "start an OpenXR app with CONTRASTXR=1 (for Steam games see {}), then run \
                     doctor again",
                    doc("steam-flatpak.md")
                ),
            );
        };
        let exe = first.text.strip_prefix(log::LOADED).unwrap_or(first.text);
        let app = format!("last app {exe} (pid {}, {})", first.pid, first.time);
        let mut session = None;
        match self.session() {
            Some(Session {
                api,
                enhanced: true,
            }) => session = Some(format!("{api} session, enhanced")),
            Some(Session {
                api,
                enhanced: false,
            }) => {
                let why = self
                    .lines
                    .iter()
                    .rev()
                    .find_map(|l| pass_through_reason(log::parse_line(l)?.text, api));
                // An API the layer enhances was passed through for another reason: its log says
                // which.
                let fix: String = if ENHANCED_SESSION_APIS.contains(&api) {
                    "`contrastxr log` shows the whole log of that app".into()
                } else {
                    "choose the app's Vulkan renderer, or its OpenGL one (GLX, or EGL where the \
                     runtime offers XR_MNDX_egl_enable)"
                        .into()
                };
                return Finding::warn(
                    NAME,
                    format!(
                        "{app}, {api} session, passed through untouched{}; the layer enhances \
                         {ENHANCED_APIS_IN_FULL}",
                        why.map_or(String::new(), |w| format!(" ({w})"))
                    ),
                    fix,
                );
            }
            None => {}
        }
        let last = self.lines.iter().rev().find_map(|l| {
            let text = log::parse_line(l)?.text;
            verdict(text).map(|v| (text, v))
        });
        let named = session
            .as_ref()
            .map_or(app.clone(), |s| format!("{app}, {s}"));
        match last {
            Some((text, (true, _))) => Finding::ok(NAME, format!("{named}: {text}")),
            Some((text, (false, fix))) => Finding::warn(NAME, format!("{named}: {text}"), fix),
            None => Finding::warn(
                NAME,
                format!(
                    "{app} loaded the layer but logged no enhanced frame{}",
                    session.map_or(String::new(), |s| format!(" ({s})"))
                ),
                "let the app run until it shows frames; `contrastxr log` shows what it logged",
            ),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::finding::Status;
    use super::*;

    /// The last app's lines as the layer writes them to its file.
    fn last_app(lines: &[&str]) -> LastApp {
        LastApp {
            path: None,
            lines: lines.iter().map(|l| l.to_string()).collect(),
        }
    }

    #[test]
    fn reads_the_sessions_graphics_api_line() {
        assert_eq!(
            session("graphics API of this session: OpenGL (Xlib), enhanced"),
            Some(Session {
                api: "OpenGL (Xlib)",
                enhanced: true
            })
        );
        assert_eq!(
            session("graphics API of this session: OpenGL (Wayland), passed through"),
            Some(Session {
                api: "OpenGL (Wayland)",
                enhanced: false
            })
        );
        assert_eq!(
            session("graphics API of this session: Vulkan, enhanced\n"),
            Some(Session {
                api: "Vulkan",
                enhanced: true
            })
        );
        // Another ending, no API, or another line: nothing.
        assert_eq!(session("graphics API of this session: Vulkan, maybe"), None);
        assert_eq!(session("graphics API of this session: , enhanced"), None);
        assert_eq!(session("graphics API of this session: Vulkan"), None);
        assert_eq!(
            session("enhancement began 0.2 s after the session started"),
            None
        );
    }

    #[test]
    fn the_last_session_of_the_last_app_counts() {
        let app = last_app(&[
            "2026-01-01T00:00:00.000Z [pid 9] layer loaded into /usr/bin/hello_xr",
            "2026-01-01T00:00:00.100Z [pid 9] graphics API of this session: Vulkan, enhanced",
            "2026-01-01T00:00:02.100Z [pid 9] graphics API of this session: OpenGL (Xlib), enhanced",
            "2026-01-01T00:00:02.400Z [pid 9] enhancement began 0.300 s after the session started",
        ]);
        assert_eq!(
            app.session(),
            Some(Session {
                api: "OpenGL (Xlib)",
                enhanced: true
            })
        );
        let f = app.finding();
        assert_eq!(f.status, Status::Ok);
        assert_eq!(
            f.detail,
            "last app /usr/bin/hello_xr (pid 9, 2026-01-01T00:00:00.000Z), OpenGL (Xlib) \
             session, enhanced: enhancement began 0.300 s after the session started"
        );
    }

    /// Frames passed through while the app's OpenGL context was current on another thread:
    /// a warning while it lasts, fine again once the layer enhances again.
    #[test]
    fn frames_passed_for_a_context_busy_elsewhere_are_a_warning_until_enhanced_again() {
        let busy = format!(
            "2026-01-01T00:00:00.300Z [pid 5] the app's OpenGL context could not be made current on the thread calling the layer (is it current on another thread?): {} at the next frame, then after 2, 4, 8 ... frames (at most 64)",
            log::TRIES_AGAIN
        );
        let mut lines = vec![
            "2026-01-01T00:00:00.000Z [pid 5] layer loaded into /usr/bin/app".to_string(),
            "2026-01-01T00:00:00.100Z [pid 5] graphics API of this session: OpenGL (Xlib), enhanced".into(),
            "2026-01-01T00:00:00.110Z [pid 5] session on the app's OpenGL (Xlib) context, background color:#e0d020: enhancing".into(),
            busy,
        ];
        let read = |lines: &[String]| {
            last_app(&lines.iter().map(String::as_str).collect::<Vec<_>>()).finding()
        };
        let f = read(&lines);
        assert_eq!(f.status, Status::Warn, "{}", f.detail);
        assert!(
            f.detail.contains("could not be made current"),
            "{}",
            f.detail
        );
        let fix = f.fix.unwrap_or_default();
        assert!(fix.contains("current on another thread"), "{fix}");
        lines.push(format!(
            "2026-01-01T00:00:01.000Z [pid 5] {} 3 frames passed through (the app's OpenGL context could not be made current ...)",
            log::ENHANCING_AGAIN
        ));
        assert_eq!(read(&lines).status, Status::Ok);
    }

    #[test]
    fn an_enhanced_session_without_frames_yet_is_named() {
        let f = last_app(&[
            "2026-01-01T00:00:00.000Z [pid 4] layer loaded into /usr/bin/hello_xr",
            "2026-01-01T00:00:00.100Z [pid 4] graphics API of this session: Vulkan, enhanced",
        ])
        .finding();
        assert_eq!(f.status, Status::Warn);
        assert_eq!(
            f.detail,
            "last app /usr/bin/hello_xr (pid 4, 2026-01-01T00:00:00.000Z) loaded the layer but \
             logged no enhanced frame (Vulkan session, enhanced)"
        );
    }

    #[test]
    fn a_passed_through_api_gets_the_enhanced_ones() {
        let f = last_app(&[
            "2026-01-01T00:00:00.000Z [pid 5] layer loaded into /usr/bin/game",
            "2026-01-01T00:00:00.100Z [pid 5] graphics API of this session: OpenGL (XCB), passed through",
        ])
        .finding();
        assert_eq!(f.status, Status::Warn);
        assert_eq!(
            f.detail,
            "last app /usr/bin/game (pid 5, 2026-01-01T00:00:00.000Z), OpenGL (XCB) session, \
             passed through untouched; the layer enhances Vulkan sessions, and OpenGL sessions \
             through XR_KHR_opengl_enable with the Xlib binding (GLX), or with EGL where the \
             runtime offers XR_MNDX_egl_enable"
        );
        assert_eq!(
            f.fix.as_deref(),
            Some(
                "choose the app's Vulkan renderer, or its OpenGL one (GLX, or EGL where the \
                 runtime offers XR_MNDX_egl_enable)"
            )
        );
        // The layer's reason, when it logged one, in the detail.
        let f = last_app(&[
            "2026-01-01T00:00:00.000Z [pid 6] layer loaded into /usr/bin/game",
            "2026-01-01T00:00:00.090Z [pid 6] session (Direct3D): contrastxr enhances Vulkan and OpenGL sessions, not Direct3D: passing its frames through untouched",
            "2026-01-01T00:00:00.100Z [pid 6] graphics API of this session: Direct3D, passed through",
        ])
        .finding();
        assert!(
            f.detail.starts_with(
                "last app /usr/bin/game (pid 6, 2026-01-01T00:00:00.000Z), Direct3D session, \
                 passed through untouched (contrastxr enhances Vulkan and OpenGL sessions, not \
                 Direct3D); the layer enhances Vulkan"
            ),
            "{}",
            f.detail
        );
        // An API the layer enhances, passed through all the same: the log says why.
        let f = last_app(&[
            "2026-01-01T00:00:00.000Z [pid 7] layer loaded into /usr/bin/game",
            "2026-01-01T00:00:00.090Z [pid 7] session (OpenGL (Xlib)): no current context: passing its frames through untouched",
            "2026-01-01T00:00:00.100Z [pid 7] graphics API of this session: OpenGL (Xlib), passed through",
        ])
        .finding();
        assert_eq!(f.status, Status::Warn);
        assert!(
            f.detail.contains(
                ", OpenGL (Xlib) session, passed through untouched (no current context); "
            ),
            "{}",
            f.detail
        );
        assert_eq!(
            f.fix.as_deref(),
            Some("`contrastxr log` shows the whole log of that app")
        );
    }

    #[test]
    fn reads_the_layers_reason_for_passing_a_session_through() {
        let line = "session (OpenGL (Xlib)): GLX_ARB_create_context missing: passing its frames \
                    through untouched";
        assert_eq!(
            pass_through_reason(line, "OpenGL (Xlib)"),
            Some("GLX_ARB_create_context missing")
        );
        assert_eq!(pass_through_reason(line, "Vulkan"), None);
        assert_eq!(
            pass_through_reason("session (Vulkan): GPU set-up failed (lost)", "Vulkan"),
            Some("GPU set-up failed (lost)")
        );
        assert_eq!(
            pass_through_reason("enhancement began 0.2 s", "Vulkan"),
            None
        );
    }

    #[test]
    fn an_app_without_the_line_reads_as_before() {
        let f = last_app(&[
            "2026-01-01T00:00:00.000Z [pid 3] layer loaded into /usr/bin/a",
            "2026-01-01T00:00:00.500Z [pid 3] enhancement began 0.200 s after the session started",
        ])
        .finding();
        assert_eq!(f.status, Status::Ok);
        assert_eq!(
            f.detail,
            "last app /usr/bin/a (pid 3, 2026-01-01T00:00:00.000Z): enhancement began 0.200 s \
             after the session started"
        );
    }
}
