//! A technique's options declared once: [`options!`](crate::options) writes the options struct,
//! its parameters (the [`ParamSpec`]s the scenario format checks and the docs table lists) and the
//! one reader of a variant's values from a single list of fields, so a parameter cannot be
//! declared without being read, or read under another name, type or default than it is declared
//! with. [`DeclaredOptions`] is what the definition seam (`definition.rs`) asks of them.
//!
//! Not for checks across parameters (those are `Definition::check`) nor for what a technique
//! derives from its options (methods on the struct, in the technique's folder).

// The trait lives with the seam that asks for it (`definition.rs`), so the two do not import
// each other; the macro's paths name it here.
pub use super::definition::DeclaredOptions;

/// Declares a technique's options struct, its parameters and their reading, once:
///
/// ```ignore
/// tessera::options! {
///     /// A variant's options, typed.
///     #[derive(Clone, Copy, Debug, PartialEq)]
///     pub struct Options {
///         /// How strongly to sharpen.
///         strength: f32 = float((0.0, true, 1.0), 0.2, "how much"),
///         filter: Filter = choice(Filter::Bilinear, "upscaling filter"),
///         velocity: bool = flag(true, "a velocity pass for animated objects"),
///     }
/// }
/// ```
///
/// Each field is a parameter of the same name (`float` reads as `f64` or `f32`; `choice` takes a
/// [`choice!`](crate::choice) enum; `flag` a `bool`), listed in field order. The struct gets
/// public fields, [`DeclaredOptions`], an inherent `from_variant` and `params`, and `Default` (every
/// parameter at its declared default). What a technique derives from its options (a render size,
/// an automatic value) is a method on the struct.
#[macro_export]
macro_rules! options {
    ($(#[$meta:meta])* $vis:vis struct $name:ident {
        $($(#[$fmeta:meta])* $field:ident : $ty:ty = $kind:ident ( $($arg:expr),* $(,)? )),* $(,)?
    }) => {
        $(#[$meta])*
        $vis struct $name {
            $($(#[$fmeta])* pub $field: $ty),*
        }

        const _: () = {
            $(
                #[allow(non_upper_case_globals)]
                static $field: $crate::params::Param<$ty> =
                    $crate::options!(@param $ty, $field, $kind($($arg),*));
            )*
            static PARAMS: &[&$crate::params::ParamSpec] = &[$(&$field.spec),*];

            impl $crate::techniques::options::DeclaredOptions for $name {
                fn params() -> &'static [&'static $crate::params::ParamSpec] {
                    PARAMS
                }

                fn from_variant(variant: &$crate::techniques::Variant) -> $name {
                    $name {
                        $($field: variant.get(&$field)),*
                    }
                }
            }
        };

        impl $name {
            /// The options of `variant` (see [`DeclaredOptions`](
            /// $crate::techniques::options::DeclaredOptions)).
            pub fn from_variant(variant: &$crate::techniques::Variant) -> $name {
                <$name as $crate::techniques::options::DeclaredOptions>::from_variant(variant)
            }

            /// Its parameters, in docs order.
            pub fn params() -> &'static [&'static $crate::params::ParamSpec] {
                <$name as $crate::techniques::options::DeclaredOptions>::params()
            }
        }

        /// Every parameter at its declared default, read as a variant's values are.
        impl ::core::default::Default for $name {
            fn default() -> $name {
                let params = <$name as $crate::techniques::options::DeclaredOptions>::params();
                let mut fields = params.iter();
                $name {
                    $($field: {
                        let spec = fields.next().expect("one spec per field");
                        <$ty as $crate::params::FromParam>::from_param(&spec.default.value())
                            .expect("a declared default reads as its field's type")
                    }),*
                }
            }
        }
    };
    (@param $ty:ty, $field:ident, float($range:expr, $default:expr, $doc:expr)) => {
        $crate::params::Param::float(stringify!($field), $range, $default, $doc)
    };
    (@param $ty:ty, $field:ident, flag($default:expr, $doc:expr)) => {
        $crate::params::Param::flag(stringify!($field), $default, $doc)
    };
    (@param $ty:ty, $field:ident, choice($default:expr, $doc:expr)) => {
        <$ty>::param(stringify!($field), $default, $doc)
    };
}

#[cfg(test)]
mod tests {
    use super::DeclaredOptions;
    use crate::params::{ParamKind, ParamValue};
    use crate::techniques::{registry, Variant};

    crate::choice! {
        enum Filter { Bilinear = "bilinear", Nearest = "nearest" }
    }

    crate::options! {
        #[derive(Clone, Copy, Debug, PartialEq)]
        struct Example {
            strength: f32 = float((0.0, true, 1.0), 0.25, "how much"),
            filter: Filter = choice(Filter::Nearest, "which filter"),
            velocity: bool = flag(true, "a velocity pass"),
        }
    }

    #[test]
    fn fields_are_parameters_in_order_with_their_kinds() {
        let names: Vec<&str> = Example::params().iter().map(|p| p.name).collect();
        assert_eq!(names, ["strength", "filter", "velocity"]);
        assert!(matches!(
            Example::params()[0].kind,
            ParamKind::Float { min_inclusive: true, max, .. } if max == 1.0
        ));
        assert!(matches!(Example::params()[1].kind, ParamKind::Choice(c) if c == Filter::NAMES));
        assert!(matches!(Example::params()[2].kind, ParamKind::Bool));
    }

    #[test]
    fn reads_a_variant_with_its_defaults_and_values() {
        let mut v = Variant::with_defaults(registry::ALL[0]);
        v.params = Example::params()
            .iter()
            .map(|p| (p.name.to_string(), p.default.value()))
            .collect();
        let d = Example::from_variant(&v);
        assert_eq!(
            d,
            Example {
                strength: 0.25,
                filter: Filter::Nearest,
                velocity: true
            }
        );
        v.params
            .insert("filter".into(), ParamValue::Str("bilinear".into()));
        v.params.insert("strength".into(), ParamValue::Float(0.5));
        let e = <Example as DeclaredOptions>::from_variant(&v);
        assert_eq!((e.filter, e.strength), (Filter::Bilinear, 0.5));
        assert_eq!(Example::default(), d);
    }
}
