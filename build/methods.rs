//! The method table (src/algorithm/method/table.rs) as build.rs sees it: each entry's name,
//! code, space and WGSL file.

// Dependency-free, so included here as in the library.
include!("../src/algorithm/method/table.rs");

/// A method as build.rs sees its entry.
pub struct BuildMethod {
    pub name: &'static str,
    pub code: u32,
    /// `Scaled`, `Linear` or `Perceptual` (the entry's reference).
    pub space: &'static str,
    pub wgsl: &'static str,
}

macro_rules! build_methods {
    ($($variant:ident {
        name: $name:literal,
        code: $code:literal,
        doc: $doc:literal,
        comparison: $comparison:literal,
        reference: $space:ident($f:ident),
        wgsl: $wgsl:literal,
        $($rest:tt)*
    }),* $(,)?) => {
        &[$(BuildMethod {
            name: $name,
            code: $code,
            space: stringify!($space),
            wgsl: $wgsl,
        }),*]
    };
}

/// Every method of the table.
pub const METHODS: &[BuildMethod] = with_methods!(build_methods);

/// The code of the perceptual method, whose own `classify` variants skip the tiles it leaves
/// alone.
pub fn perceptual_code() -> u32 {
    METHODS
        .iter()
        .find(|m| m.space == "Perceptual")
        .expect("perceptual")
        .code
}

/// The code of the method the single passes and the background mode are built with (their
/// METHOD is never read; `paper`'s).
pub fn paper_code() -> u32 {
    METHODS
        .iter()
        .find(|m| m.name == "paper")
        .expect("paper")
        .code
}

/// The entry of a method's code.
pub fn by_code(code: u32) -> &'static BuildMethod {
    METHODS
        .iter()
        .find(|m| m.code == code)
        .expect("a method's code")
}
