//! Which per-pixel method runs: the `Method` type, one variant per entry of the method table
//! (src/algorithm/method/table.rs), with its name on the command line and in config and JSON.
//! Its entry (CPU reference, shader, settings, passes) is `Method::entry`
//! (src/algorithm/method/method_entry.rs).

include!("table.rs");

macro_rules! define_method {
    ($($variant:ident {
        name: $name:literal,
        code: $code:literal,
        doc: $doc:literal,
        $($rest:tt)*
    }),* $(,)?) => {
        /// Which per-pixel method runs (docs/algorithm.md, Per-pixel optimisation and
        /// Comparison methods); one variant per entry of method/table.rs.
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
        pub enum Method {
            $(#[doc = $doc] $variant,)*
        }

        impl Method {
            pub const ALL: [Method; [$($code),*].len()] = [$(Method::$variant),*];

            /// The name used on the command line and in config/JSON.
            pub fn name(self) -> &'static str {
                [$($name),*][self as usize]
            }
        }
    };
}

with_methods!(define_method);

impl Method {
    pub fn parse(name: &str) -> Option<Method> {
        Method::ALL.into_iter().find(|m| m.name() == name)
    }
}
