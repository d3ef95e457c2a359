//! The one list a term family is written as: `family!` turns it into the family's enum,
//! whose discriminants are the codes both engines compare against (the CPU lanes' const
//! parameters and the kernel's `#define`s), its `ALL`, and the exhaustive tables from a
//! variant to its term file's [`Term`](super::term::Term). A term that is in the list but has no
//! file, or a file that says nothing the table reads, is a compile error; nothing is
//! numbered anywhere else.

/// Declares a term family: `pub enum Name { Variant = code => module, "GPU_MACRO", feature; … }`,
/// where `module` is the term's file under the family's folder (it defines `NAME` and
/// `CITATION`), `GPU_MACRO` the kernel's name for the code and `feature` its `FeatureSet`
/// bit and `HAS_*` macro (`None` for a term with no code).
macro_rules! family {
    (
        $(#[$meta:meta])*
        pub enum $family:ident {
            $(
                $(#[$vmeta:meta])*
                $variant:ident = $code:literal => $module:ident, $macro:literal, $feature:expr;
            )+
        }
    ) => {
        $(pub mod $module;)+

        $(#[$meta])*
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
        #[repr(u8)]
        pub enum $family {
            $(
                $(#[$vmeta])*
                $variant = $code,
            )+
        }

        impl $family {
            /// Every term of the family, in the order of its list (and of the materials help).
            pub const ALL: [$family; [$($code),+].len()] = [$($family::$variant),+];

            /// The term's name, citation, kernel code and feature.
            pub const fn term(self) -> $crate::terms::term::Term {
                match self {
                    $(
                        $family::$variant => $crate::terms::term::Term {
                            toml_name: $module::NAME,
                            citation: $module::CITATION,
                            gpu_code: ($macro, $code),
                            feature: $feature,
                        },
                    )+
                }
            }

            /// The code both engines compare against (the enum's discriminant).
            pub const fn code(self) -> u8 {
                self as u8
            }

            /// The term whose [`code`](Self::code) is `code`. For the lanes' const
            /// parameters, in a `const` block (an unknown code is then a compile error).
            pub const fn from_code(code: u8) -> $family {
                $(
                    if code == $code {
                        return $family::$variant;
                    }
                )+
                panic!("no term of the family has this code")
            }

            /// The spelling in a materials file.
            pub fn toml_name(self) -> &'static str {
                self.term().toml_name
            }

            /// The term a materials file names, if any.
            pub fn from_toml_name(name: &str) -> Option<$family> {
                $family::ALL.into_iter().find(|t| t.toml_name() == name)
            }
        }
    };
}

pub(crate) use family;
