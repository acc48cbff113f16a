//! Steam's pressure-vessel setting: without `PRESSURE_VESSEL_IMPORT_OPENXR_1_LAYERS=1` the Steam
//! Linux Runtime container does not import the host's OpenXR layers. Users set it per game, in
//! its launch options, which Steam keeps in each account's `localconfig.vdf`; doctor reads them
//! there, so a game set up that way gets no warning.

use super::finding::{doc, var, Finding};
use std::path::{Path, PathBuf};

const VAR: &str = "PRESSURE_VESSEL_IMPORT_OPENXR_1_LAYERS";
const OPTIONS: &str = "PRESSURE_VESSEL_IMPORT_OPENXR_1_LAYERS=1 CONTRASTXR=1 %command%";

/// localconfig.vdf holds every game's settings of one account: a few MiB at most.
const MAX_VDF_BYTES: u64 = 64 << 20;

/// Steam's own folders, as installed natively or as a Flatpak.
fn steam_roots() -> Vec<PathBuf> {
    let Some(home) = var("HOME").map(PathBuf::from) else {
        return Vec::new();
    };
    let data = var("XDG_DATA_HOME").map_or_else(|| home.join(".local/share"), PathBuf::from);
    let flatpak = home.join(".var/app/com.valvesoftware.Steam");
    vec![
        home.join(".steam/steam"),
        data.join("Steam"),
        flatpak.join(".local/share/Steam"),
        flatpak,
    ]
}

/// The tokens of Valve's KeyValues text: quoted strings (with `\"` and `\\` escapes) and braces.
fn tokens(text: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut chars = text.chars();
    while let Some(c) = chars.next() {
        match c {
            '{' | '}' => out.push(c.to_string()),
            '"' => {
                let mut s = String::new();
                while let Some(c) = chars.next() {
                    match c {
                        '"' => break,
                        '\\' => s.extend(chars.next()),
                        c => s.push(c),
                    }
                }
                out.push(s);
            }
            _ => {}
        }
    }
    out
}

/// Each game's launch options in a localconfig.vdf: (app id, options), from the
/// `LaunchOptions` values of the blocks under an `apps` block.
fn launch_options(text: &str) -> Vec<(String, String)> {
    let mut found = Vec::new();
    // The keys of the open blocks, outermost first.
    let mut path: Vec<String> = Vec::new();
    let mut key: Option<String> = None;
    for t in tokens(text) {
        match (t.as_str(), key.take()) {
            ("{", k) => path.push(k.unwrap_or_default()),
            ("}", _) => {
                path.pop();
            }
            (_, None) => key = Some(t),
            (_, Some(k)) => {
                let in_apps = path.len() >= 2 && path[path.len() - 2].eq_ignore_ascii_case("apps");
                if in_apps && k.eq_ignore_ascii_case("LaunchOptions") {
                    found.push((path[path.len() - 1].clone(), t));
                }
            }
        }
    }
    found
}

/// Whether a command line sets `name=1` as a word of its own.
fn sets(options: &str, name: &str) -> bool {
    options.split_whitespace().any(|w| w == format!("{name}=1"))
}

/// What the launch options of the games say, as a finding.
fn from_launch_options(games: &[(String, String)], files: usize) -> Finding {
    const NAME: &str = "steam";
    let ids = |pick: &dyn Fn(&str) -> bool| -> Vec<&str> {
        games
            .iter()
            .filter(|(_, o)| pick(o))
            .map(|(id, _)| id.as_str())
            .collect()
    };
    let lacking = ids(&|o| sets(o, "CONTRASTXR") && !sets(o, VAR));
    if !lacking.is_empty() {
        return Finding::warn(
            NAME,
            format!(
                "Steam game(s) {} start with CONTRASTXR=1, but their launch options lack {VAR}=1: \
                 the container does not import the host's OpenXR layers without it",
                lacking.join(", ")
            ),
            format!(
                "set each one's launch options to {OPTIONS} ({})",
                doc("steam-flatpak.md")
            ),
        );
    }
    let importing = ids(&|o| sets(o, VAR));
    if !importing.is_empty() {
        return Finding::ok(
            NAME,
            format!(
                "the launch options of Steam game(s) {} import the host's OpenXR layers",
                importing.join(", ")
            ),
        );
    }
    // Doctor cannot know whether any Steam game is meant to use the layer: a note, not a warning.
    Finding::ok(
        NAME,
        format!(
            "Steam is installed; no game's launch options import the host's OpenXR layers \
             ({files} localconfig.vdf read): for a Steam game with the layer, set its launch \
             options to {OPTIONS} ({})",
            doc("steam-flatpak.md")
        ),
    )
}

pub fn steam() -> Finding {
    const NAME: &str = "steam";
    if std::env::var(VAR).is_ok_and(|v| v == "1") {
        return Finding::ok(
            NAME,
            format!(
                "{VAR}=1 here: Steam games started from this environment import the host's \
                 OpenXR layers (each still needs CONTRASTXR=1)"
            ),
        );
    }
    let roots: Vec<PathBuf> = steam_roots().into_iter().filter(|p| p.exists()).collect();
    if roots.is_empty() {
        return Finding::ok(
            NAME,
            format!(
                "Steam not found; for Steam games the launch options need {OPTIONS} ({})",
                doc("steam-flatpak.md")
            ),
        );
    }
    let mut files: Vec<PathBuf> = roots
        .iter()
        .filter_map(|r| std::fs::read_dir(r.join("userdata")).ok())
        .flatten()
        .flatten()
        .map(|account| account.path().join("config/localconfig.vdf"))
        .filter_map(|f| f.canonicalize().ok())
        .collect();
    files.sort();
    files.dedup();
    let games: Vec<(String, String)> = files
        .iter()
        .filter_map(|f| read_vdf(f))
        .flat_map(|text| launch_options(&text))
        .collect();
    from_launch_options(&games, files.len())
}

fn read_vdf(file: &Path) -> Option<String> {
    let bytes = contrastxr::user_file::read(file, MAX_VDF_BYTES).ok()?;
    Some(String::from_utf8_lossy(&bytes).into_owned())
}

#[cfg(test)]
mod tests {
    use super::super::finding::Status;
    use super::*;

    const VDF: &str = r#""UserLocalConfigStore"
{
	"Software"
	{
		"Valve"
		{
			"Steam"
			{
				"apps"
				{
					"620"
					{
						"LastPlayed"		"1700000000"
						"LaunchOptions"		"PRESSURE_VESSEL_IMPORT_OPENXR_1_LAYERS=1 CONTRASTXR=1 %command%"
					}
					"570"
					{
						"LaunchOptions"		"CONTRASTXR=1 %command% -title \"a b\""
					}
					"440"
					{
						"cloud"	{ "last_sync_state"	"synchronized" }
					}
				}
			}
		}
	}
}
"#;

    #[test]
    fn reads_each_games_launch_options() {
        assert_eq!(
            launch_options(VDF),
            [
                (
                    "620".to_string(),
                    "PRESSURE_VESSEL_IMPORT_OPENXR_1_LAYERS=1 CONTRASTXR=1 %command%".to_string()
                ),
                (
                    "570".to_string(),
                    "CONTRASTXR=1 %command% -title \"a b\"".to_string()
                ),
            ]
        );
        // A LaunchOptions key outside an apps block is not a game's.
        assert!(launch_options(r#""a" { "LaunchOptions" "x" }"#).is_empty());
    }

    #[test]
    fn a_game_set_up_per_game_is_no_warning() {
        let games = launch_options(VDF);
        // 570 has CONTRASTXR=1 without the import: that one is wrong.
        let f = from_launch_options(&games, 1);
        assert_eq!(f.status, Status::Warn);
        assert!(
            f.detail.starts_with("Steam game(s) 570 start"),
            "{}",
            f.detail
        );
        assert!(f.fix.as_deref().unwrap().contains(OPTIONS));
        // With only the game set up right: ok, naming it.
        let f = from_launch_options(&games[..1], 1);
        assert_eq!(f.status, Status::Ok);
        assert!(
            f.detail.contains("Steam game(s) 620 import"),
            "{}",
            f.detail
        );
        // No game asks for the layer: a note, not a warning.
        let f = from_launch_options(&[], 1);
        assert_eq!(f.status, Status::Ok);
        assert!(f.detail.contains(OPTIONS), "{}", f.detail);
    }
}
