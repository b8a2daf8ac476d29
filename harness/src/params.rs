//! Technique parameters as the scenario format sees them: their kinds, ranges and defaults
//! ([`ParamSpec`]), typed handles a technique reads its options through ([`Param`]), concrete
//! values. Variants (a technique with values) are `techniques/definition.rs`'s.
//!
//! Which techniques exist and which parameters each takes is the registry's (`techniques/`); this
//! module knows no technique and names no other module of the harness.

use std::fmt;
use std::marker::PhantomData;

/// One parameter of a technique.
#[derive(Debug)]
pub struct ParamSpec {
    pub name: &'static str,
    pub kind: ParamKind,
    pub default: DefaultValue,
    pub doc: &'static str,
}

#[derive(Debug)]
pub enum ParamKind {
    /// A finite float in `(min, max]` or `[min, max]`.
    Float {
        min: f64,
        min_inclusive: bool,
        max: f64,
    },
    Int {
        min: i64,
        max: i64,
    },
    Choice(&'static [&'static str]),
    Bool,
}

/// A parameter's default value.
#[derive(Debug)]
pub enum DefaultValue {
    Float(f64),
    Int(i64),
    Str(&'static str),
    Bool(bool),
}

impl DefaultValue {
    pub fn value(&self) -> ParamValue {
        match self {
            DefaultValue::Float(v) => ParamValue::Float(*v),
            DefaultValue::Int(v) => ParamValue::Int(*v),
            DefaultValue::Str(v) => ParamValue::Str((*v).to_string()),
            DefaultValue::Bool(v) => ParamValue::Bool(*v),
        }
    }
}

impl ParamKind {
    /// What values are allowed, in words, for error messages.
    pub fn allowed(&self) -> String {
        match self {
            ParamKind::Float {
                min,
                min_inclusive,
                max,
            } => {
                let open = if *min_inclusive { "[" } else { "(" };
                format!("a number in {open}{min}, {max}]")
            }
            ParamKind::Int { min, max } => format!("an integer from {min} to {max}"),
            ParamKind::Choice(options) => format!("one of {}", quoted_list(options)),
            ParamKind::Bool => "true or false".to_string(),
        }
    }

    /// Checks one TOML value against this kind.
    pub fn check(&self, value: &toml::Value) -> Result<ParamValue, String> {
        let fail = || Err(format!("expected {}", self.allowed()));
        match (self, value) {
            (
                ParamKind::Float {
                    min,
                    min_inclusive,
                    max,
                },
                v,
            ) => {
                let x = match v {
                    toml::Value::Float(x) => *x,
                    toml::Value::Integer(i) => *i as f64,
                    _ => return fail(),
                };
                let above_min = if *min_inclusive { x >= *min } else { x > *min };
                if !x.is_finite() || !above_min || x > *max {
                    return Err(format!("{x} is out of range: expected {}", self.allowed()));
                }
                Ok(ParamValue::Float(x))
            }
            (ParamKind::Int { min, max }, toml::Value::Integer(i)) => {
                if i < min || i > max {
                    return Err(format!("{i} is out of range: expected {}", self.allowed()));
                }
                Ok(ParamValue::Int(*i))
            }
            (ParamKind::Choice(options), toml::Value::String(s)) => {
                if options.contains(&s.as_str()) {
                    Ok(ParamValue::Str(s.clone()))
                } else {
                    Err(format!(
                        "unknown value \"{s}\": expected {}",
                        self.allowed()
                    ))
                }
            }
            (ParamKind::Bool, toml::Value::Boolean(b)) => Ok(ParamValue::Bool(*b)),
            _ => fail(),
        }
    }
}

/// A concrete parameter value of a variant.
#[derive(Clone, Debug, PartialEq)]
pub enum ParamValue {
    Float(f64),
    Int(i64),
    Str(String),
    Bool(bool),
}

impl ParamValue {
    pub fn as_f64(&self) -> Option<f64> {
        match self {
            ParamValue::Float(x) => Some(*x),
            ParamValue::Int(i) => Some(*i as f64),
            _ => None,
        }
    }

    pub fn as_str(&self) -> Option<&str> {
        match self {
            ParamValue::Str(s) => Some(s),
            _ => None,
        }
    }

    pub fn to_json(&self) -> serde_json::Value {
        match self {
            ParamValue::Float(x) => serde_json::json!(x),
            ParamValue::Int(i) => serde_json::json!(i),
            ParamValue::Str(s) => serde_json::json!(s),
            ParamValue::Bool(b) => serde_json::json!(b),
        }
    }
}

impl fmt::Display for ParamValue {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ParamValue::Float(x) => write!(f, "{x}"),
            ParamValue::Int(i) => write!(f, "{i}"),
            ParamValue::Str(s) => f.write_str(s),
            ParamValue::Bool(b) => write!(f, "{b}"),
        }
    }
}

/// A parameter with the Rust type its technique reads it as: the spec the scenario format checks
/// and the typed reading come from one declaration, so a technique cannot read a parameter under
/// a name or type it does not declare.
#[derive(Debug)]
pub struct Param<T> {
    pub spec: ParamSpec,
    _type: PhantomData<fn() -> T>,
}

/// The Rust types a float parameter reads as (`f64`, or `f32` as the shaders take it).
pub trait FloatParam: FromParam {}
impl FloatParam for f64 {}
impl FloatParam for f32 {}

impl<T: FloatParam> Param<T> {
    /// A finite number in `(min, max]`, or `[min, max]` when `min_inclusive`, read as `T`.
    pub const fn float(
        name: &'static str,
        (min, min_inclusive, max): (f64, bool, f64),
        default: f64,
        doc: &'static str,
    ) -> Param<T> {
        Param::new(ParamSpec {
            name,
            kind: ParamKind::Float {
                min,
                min_inclusive,
                max,
            },
            default: DefaultValue::Float(default),
            doc,
        })
    }
}

impl Param<bool> {
    pub const fn flag(name: &'static str, default: bool, doc: &'static str) -> Param<bool> {
        Param::new(ParamSpec {
            name,
            kind: ParamKind::Bool,
            default: DefaultValue::Bool(default),
            doc,
        })
    }
}

impl<T> Param<T> {
    /// A typed handle on `spec` (choices: see [`choice!`](crate::choice)).
    pub const fn new(spec: ParamSpec) -> Param<T> {
        Param {
            spec,
            _type: PhantomData,
        }
    }
}

/// A Rust type a parameter value reads as.
pub trait FromParam: Sized {
    fn from_param(value: &ParamValue) -> Option<Self>;
}

impl FromParam for f64 {
    fn from_param(value: &ParamValue) -> Option<f64> {
        value.as_f64()
    }
}

/// Narrowed as the shaders take it (`v as f32`).
impl FromParam for f32 {
    fn from_param(value: &ParamValue) -> Option<f32> {
        value.as_f64().map(|x| x as f32)
    }
}

impl FromParam for bool {
    fn from_param(value: &ParamValue) -> Option<bool> {
        match value {
            ParamValue::Bool(b) => Some(*b),
            _ => None,
        }
    }
}

/// An enum of a choice parameter's options, each with its name in scenarios:
/// `choice! { pub enum Fill { Plain = "plain", Tonemapped = "tonemapped" } }` gives `Fill::NAMES`,
/// `Fill::from_name`, `Fill::name` and `Fill::param(name, default, doc)`, the typed [`Param`].
#[macro_export]
macro_rules! choice {
    ($(#[$meta:meta])* $vis:vis enum $name:ident {
        $($(#[$vmeta:meta])* $option:ident = $text:literal),+ $(,)?
    }) => {
        $(#[$meta])*
        #[derive(Clone, Copy, Debug, PartialEq, Eq)]
        $vis enum $name {
            $($(#[$vmeta])* $option),+
        }

        impl $name {
            /// Every option's name, in declaration order.
            pub const NAMES: &'static [&'static str] = &[$($text),+];

            pub const fn name(self) -> &'static str {
                match self {
                    $($name::$option => $text),+
                }
            }

            pub fn from_name(name: &str) -> Option<$name> {
                match name {
                    $($text => Some($name::$option),)+
                    _ => None,
                }
            }

            /// The parameter `name` taking one of these options, `default` when not given.
            pub const fn param(
                name: &'static str,
                default: $name,
                doc: &'static str,
            ) -> $crate::params::Param<$name> {
                $crate::params::Param::new($crate::params::ParamSpec {
                    name,
                    kind: $crate::params::ParamKind::Choice($name::NAMES),
                    default: $crate::params::DefaultValue::Str(default.name()),
                    doc,
                })
            }
        }

        impl $crate::params::FromParam for $name {
            fn from_param(value: &$crate::params::ParamValue) -> Option<$name> {
                value.as_str().and_then($name::from_name)
            }
        }
    };
}

/// The closest known name to `unknown`, if any is close enough to be a likely typo.
pub fn closest<'a>(unknown: &str, known: &[&'a str]) -> Option<&'a str> {
    known
        .iter()
        .map(|k| (strsim::damerau_levenshtein(unknown, k), *k))
        .filter(|(d, k)| *d <= 3.max(k.len() / 3) && *d < k.len())
        .min_by_key(|(d, _)| *d)
        .map(|(_, k)| k)
}

pub fn quoted_list(items: &[&str]) -> String {
    items
        .iter()
        .map(|s| format!("\"{s}\""))
        .collect::<Vec<_>>()
        .join(", ")
}
