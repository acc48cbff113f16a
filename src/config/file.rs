//! The config file's TOML, read into entries that remember their line. Knows the file's shape
//! (top-level keys, `[device."SYSTEM"]` and `[app."NAME"]` tables) but not the keys: those are
//! checked by `resolve`.

use toml_edit::{Document, Item, TableLike};

/// One `key = value` line.
#[derive(Clone, Debug)]
pub struct Entry {
    pub key: String,
    /// 1-based.
    pub line: usize,
    /// The TOML value, or the type name of what stood there instead (e.g. a table).
    pub value: Result<toml_edit::Value, &'static str>,
}

#[derive(Clone, Debug, Default)]
pub struct ParsedFile {
    /// Top-level keys: the defaults for every app.
    pub defaults: Vec<Entry>,
    /// `[device."SYSTEM"]` tables, in file order.
    pub devices: Vec<(String, Vec<Entry>)>,
    /// `[app."NAME"]` tables, in file order.
    pub apps: Vec<(String, Vec<Entry>)>,
    /// Shape problems (unknown tables), with their line.
    pub problems: Vec<(usize, String)>,
}

/// A syntax error: the line and the parser's message.
#[derive(Clone, Debug, PartialEq)]
pub struct SyntaxError {
    pub line: usize,
    pub message: String,
}

/// The 1-based line of byte `offset` in `text`.
pub fn line_of(text: &str, offset: usize) -> usize {
    let end = offset.min(text.len());
    text.as_bytes()[..end]
        .iter()
        .filter(|&&b| b == b'\n')
        .count()
        + 1
}

fn key_line(text: &str, table: &dyn TableLike, key: &str) -> usize {
    table
        .key(key)
        .and_then(|k| k.span())
        .map_or(0, |span| line_of(text, span.start))
}

fn entry(text: &str, table: &dyn TableLike, key: &str, item: &Item) -> Entry {
    Entry {
        key: key.to_string(),
        line: key_line(text, table, key),
        value: match item {
            Item::Value(v) => Ok(v.clone()),
            other => Err(other.type_name()),
        },
    }
}

fn entries(text: &str, table: &dyn TableLike) -> Vec<Entry> {
    table
        .iter()
        .map(|(key, item)| entry(text, table, key, item))
        .collect()
}

/// The `[KIND."NAME"]` tables (KIND is `app` or `device`).
fn named_tables(
    text: &str,
    root: &dyn TableLike,
    kind: &str,
    problems: &mut Vec<(usize, String)>,
) -> Vec<(String, Vec<Entry>)> {
    let line = key_line(text, root, kind);
    let Some(tables) = root.get(kind).and_then(Item::as_table_like) else {
        let problem = format!("`{kind}` must hold tables: write [{kind}.\"NAME\"]");
        problems.push((line, problem));
        return Vec::new();
    };
    let mut out = Vec::new();
    for (name, item) in tables.iter() {
        let line = key_line(text, tables, name);
        match item.as_table_like() {
            Some(table) => out.push((name.to_string(), entries(text, table))),
            None => problems.push((
                line,
                format!("{kind}.{name:?} must be a table: write [{kind}.{name:?}]"),
            )),
        }
    }
    out
}

/// Reads `text` as a config file.
pub fn parse(text: &str) -> Result<ParsedFile, SyntaxError> {
    let doc = Document::parse(text).map_err(|e| SyntaxError {
        line: e.span().map_or(0, |s| line_of(text, s.start)),
        message: e.message().trim().to_string(),
    })?;
    let root = doc.as_table();
    let mut out = ParsedFile::default();
    for (key, item) in root.iter() {
        if key == "app" {
            out.apps = named_tables(text, root, "app", &mut out.problems);
        } else if key == "device" {
            out.devices = named_tables(text, root, "device", &mut out.problems);
        } else if item.is_table_like() && !item.is_inline_table() {
            out.problems.push((
                key_line(text, root, key),
                format!("unknown table [{key}]: settings go at the top, in [device.\"SYSTEM\"] or in [app.\"NAME\"]"),
            ));
        } else {
            out.defaults.push(entry(text, root, key, item));
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn entries_know_their_lines() {
        let text = "# c\nlambda_e = 0.6\n\n[app.\"hello_xr\"]\nmode = \"split\"\n";
        let f = parse(text).unwrap();
        assert_eq!(f.defaults.len(), 1);
        assert_eq!(
            (f.defaults[0].key.as_str(), f.defaults[0].line),
            ("lambda_e", 2)
        );
        assert_eq!(f.apps[0].0, "hello_xr");
        assert_eq!(f.apps[0].1[0].line, 5);
    }

    #[test]
    fn syntax_errors_have_a_line() {
        let e = parse("lambda_e = 0.6\nmode = \n").unwrap_err();
        assert_eq!(e.line, 2, "{e:?}");
    }

    #[test]
    fn device_tables_are_read_like_app_tables() {
        let text = "[device.\"Monado: Simulated HMD\"]\ncamera_fov = [90, 70]\n";
        let f = parse(text).unwrap();
        assert_eq!(f.devices.len(), 1, "{f:?}");
        assert_eq!(f.devices[0].0, "Monado: Simulated HMD");
        assert_eq!(
            (f.devices[0].1[0].key.as_str(), f.devices[0].1[0].line),
            ("camera_fov", 2)
        );
        let f = parse("device = 3\n").unwrap();
        assert!(f.problems[0].1.contains("[device.\"NAME\"]"), "{f:?}");
    }

    #[test]
    fn unknown_tables_are_problems() {
        let f = parse("[display]\nx = 1\n[app]\nfoo = 3\n").unwrap();
        assert_eq!(f.problems.len(), 2, "{:?}", f.problems);
        assert_eq!(f.problems[0].0, 1);
    }
}
