//! The per-pixel methods as one table (src/algorithm/method/table.rs, one entry each): each
//! method's entry (its CPU reference, shader file, settings and passes), and the names derived
//! from them for the settings, the command line and their help. The `Method` type itself is
//! src/algorithm/method/kind.rs; the type of an entry's CPU reference, `Reference`, is
//! src/algorithm/reference_fn.rs.

use super::kind::Method;
use crate::algorithm::reference_fn::Reference;

include!("table.rs");

/// A GPU pass of a method. The backends run an entry's passes as the steps src/gpu/core/plan.rs
/// makes of them, which holds each pass to the one it needs before it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Pass {
    /// Lists the tiles with a foreground pixel (`classify`).
    Classify,
    /// Turns the tile count into the indirect dispatch (`finish_tiles`).
    FinishTiles,
    /// The per-pixel method over the listed tiles (`enhance`, the entry's variant).
    Enhance,
}

/// The per-pixel passes: classify lists the tiles with content, finish_tiles makes the
/// dispatch of enhance over them.
pub const PER_PIXEL_PASSES: [Pass; 3] = [Pass::Classify, Pass::FinishTiles, Pass::Enhance];

/// One method, as its entry in method/table.rs says.
#[derive(Debug)]
pub struct MethodEntry {
    pub method: Method,
    pub name: &'static str,
    pub code: u32,
    pub doc: &'static str,
    pub comparison: bool,
    pub reference: Reference,
    pub wgsl: &'static str,
    pub settings: &'static [&'static str],
    pub push: &'static [&'static str],
    pub passes: &'static [Pass],
}

macro_rules! define_methods {
    ($($variant:ident {
        name: $name:literal,
        code: $code:literal,
        doc: $doc:literal,
        comparison: $comparison:literal,
        reference: $space:ident($f:ident),
        wgsl: $wgsl:literal,
        settings: [$($setting:literal),* $(,)?],
        push: [$($push:literal),* $(,)?],
        passes: [$($pass:ident),* $(,)?],
    }),* $(,)?) => {
        /// Every method's entry, in `Method` order.
        pub static ENTRIES: [MethodEntry; Method::ALL.len()] = [$(MethodEntry {
            method: Method::$variant,
            name: $name,
            code: $code,
            doc: $doc,
            comparison: $comparison,
            reference: Reference::$space(reference::$f),
            wgsl: $wgsl,
            settings: &[$($setting),*],
            push: &[$($push),*],
            passes: &[$(Pass::$pass),*],
        }),*];

        /// Every method's name, in `Method` order (for the derived texts below).
        const NAMES: [&str; Method::ALL.len()] = [$($name),*];
        const COMPARISON: [bool; Method::ALL.len()] = [$($comparison),*];
    };
}

/// The functions the entries name (`reference: Scaled(f)` or `Linear(f)`).
mod reference {
    pub(super) use crate::algorithm::perception::perceptual_pixel::perceptual_step;
    pub(super) use crate::algorithm::pixel::*;
    pub(super) use crate::algorithm::scaled::*;
}

with_methods!(define_methods);

impl Method {
    /// Its entry in method/table.rs.
    pub fn entry(self) -> &'static MethodEntry {
        &ENTRIES[self as usize]
    }
}

/// How many methods are comparison methods (selectable as a `mode`).
pub const COMPARISONS: usize = {
    let mut n = 0;
    let mut i = 0;
    while i < COMPARISON.len() {
        if COMPARISON[i] {
            n += 1;
        }
        i += 1;
    }
    n
};

/// The comparison methods' names, in `Method` order.
pub const COMPARISON_NAMES: [&str; COMPARISONS] = {
    let mut out = [""; COMPARISONS];
    let (mut i, mut k) = (0, 0);
    while i < NAMES.len() {
        if COMPARISON[i] {
            out[k] = NAMES[i];
            k += 1;
        }
        i += 1;
    }
    out
};

/// Room for the derived texts below.
const TEXT: usize = 1024;

/// `prefix`, the names joined by `sep` (the last by `last`), then `suffix`, as bytes and a
/// length (a const fn cannot allocate).
const fn join(
    prefix: &str,
    names: &[&str],
    sep: &str,
    last: &str,
    suffix: &str,
) -> ([u8; TEXT], usize) {
    const fn put(buf: &mut [u8; TEXT], at: usize, s: &str) -> usize {
        let b = s.as_bytes();
        let mut i = 0;
        while i < b.len() {
            buf[at + i] = b[i];
            i += 1;
        }
        at + b.len()
    }
    let mut buf = [0u8; TEXT];
    let mut at = put(&mut buf, 0, prefix);
    let mut i = 0;
    while i < names.len() {
        if i > 0 {
            at = put(&mut buf, at, if i + 1 == names.len() { last } else { sep });
        }
        at = put(&mut buf, at, names[i]);
        i += 1;
    }
    at = put(&mut buf, at, suffix);
    (buf, at)
}

const fn text(joined: &'static ([u8; TEXT], usize)) -> &'static str {
    match std::str::from_utf8(joined.0.split_at(joined.1).0) {
        Ok(s) => s,
        Err(_) => panic!("not UTF-8"),
    }
}

const METHOD_DOC_BYTES: ([u8; TEXT], usize) = join("", &NAMES, ", ", " or ", "");
/// The `method` key's description: every method's name.
pub const METHOD_DOC: &str = text(&METHOD_DOC_BYTES);

/// The view modes' names (ViewMode::name, held equal by a test), first values of `mode`.
pub const VIEW_MODE_NAMES: [&str; 5] = ["enhance", "off", "split", "heatmap", "background"];

const MODE_DOC_BYTES: ([u8; TEXT], usize) = join(
    "enhance, off, split, heatmap, background, or a comparison method (",
    &COMPARISON_NAMES,
    ", ",
    ", ",
    ")",
);
/// The `mode` key's description: the view modes and the comparison methods.
pub const MODE_DOC: &str = text(&MODE_DOC_BYTES);

/// The values of `mode`: the view modes, then the comparison methods (shown in mode enhance).
pub const MODES: [&str; VIEW_MODE_NAMES.len() + COMPARISONS] = {
    let mut out = [""; VIEW_MODE_NAMES.len() + COMPARISONS];
    let mut i = 0;
    while i < out.len() {
        out[i] = if i < VIEW_MODE_NAMES.len() {
            VIEW_MODE_NAMES[i]
        } else {
            COMPARISON_NAMES[i - VIEW_MODE_NAMES.len()]
        };
        i += 1;
    }
    out
};

#[cfg(test)]
mod tests {
    use super::*;
    use crate::algorithm::ViewMode;

    #[test]
    fn entries_are_in_method_order_with_distinct_names_and_codes() {
        for (i, e) in ENTRIES.iter().enumerate() {
            assert_eq!(e.method as usize, i, "{}", e.name);
            assert_eq!(e.method.entry().name, e.name);
        }
        for (i, a) in ENTRIES.iter().enumerate() {
            for b in &ENTRIES[i + 1..] {
                assert_ne!(a.name, b.name);
                assert_ne!(a.code, b.code, "{} and {}", a.name, b.name);
            }
        }
    }

    #[test]
    fn the_derived_texts_name_every_method() {
        let names: Vec<&str> = ENTRIES.iter().map(|e| e.name).collect();
        let (last, rest) = names.split_last().unwrap();
        assert_eq!(METHOD_DOC, format!("{} or {last}", rest.join(", ")));
        for e in &ENTRIES {
            assert!(METHOD_DOC.contains(e.name));
            assert_eq!(MODE_DOC.contains(e.name), e.comparison, "{}", e.name);
            assert_eq!(MODES.contains(&e.name), e.comparison, "{}", e.name);
        }
        let views: Vec<&str> = ViewMode::ALL.iter().map(|m| m.name()).collect();
        assert_eq!(views, VIEW_MODE_NAMES);
        assert_eq!(&MODES[..VIEW_MODE_NAMES.len()], VIEW_MODE_NAMES);
    }

    /// An entry's settings are keys of the one key table, its push-constant fields are
    /// PARAMS', and its WGSL reads no push-constant field it does not declare.
    #[test]
    fn every_entry_names_real_settings_and_push_constants() {
        let fields: Vec<&str> = crate::gpu::core::interface::PARAMS
            .iter()
            .map(|p| p.0)
            .collect();
        for e in &ENTRIES {
            for k in e.settings {
                assert!(
                    crate::config::key(k).is_some(),
                    "{}: {k} is not a key",
                    e.name
                );
            }
            for p in e.push {
                assert!(fields.contains(p), "{}: {p} is not in PARAMS", e.name);
            }
            let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(e.wgsl);
            let wgsl =
                std::fs::read_to_string(&path).unwrap_or_else(|err| panic!("{}: {err}", e.wgsl));
            let wanted = match e.reference {
                Reference::Scaled(_) => "fn method_scaled(s: Step) -> Colours",
                Reference::Linear(_) => {
                    "fn method_linear(display: Colours, bg: Background) -> Colours"
                }
                Reference::Perceptual(_) => {
                    "fn method_perceptual(display: Colours, d: Colours, bg: Background) -> Perceived"
                }
            };
            assert!(wgsl.contains(wanted), "{} lacks `{wanted}`", e.wgsl);
            for used in wgsl.split("pc.").skip(1) {
                let name: String = used
                    .chars()
                    .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
                    .collect();
                assert!(
                    e.push.contains(&name.as_str()),
                    "{} reads pc.{name}: add it to `push`",
                    e.wgsl
                );
            }
        }
    }
}
