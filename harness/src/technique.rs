//! The catalogue of techniques and their parameters, as the scenario format sees them.
//!
//! This is what `tessera validate` checks against without a GPU. How a technique renders lives in
//! `render/`; this module only names techniques, declares their parameters (type, range, default)
//! and turns concrete values into variant names.

use std::collections::BTreeMap;
use std::fmt;

/// A technique the harness can run.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum TechniqueKind {
    /// Full-resolution forward rendering: the reference and the baseline.
    Native,
    /// Render at a scale factor, then upscale: what a user would pick instead of a technique.
    Upscale,
    /// Checkerboard rendering: Intel CBR with mosaiikki's refinements.
    Checkerboard,
    /// Depth-based 2x2 checkerboarding (the depth-based report, seeds/depth-based-checkerboarding.txt).
    Checkerboard2x2,
    /// NVIDIA content and motion adaptive shading (Yang et al. 2019) on software variable-rate
    /// shading: a G-buffer, a per-16x16-tile rate pass, a compute shading pass.
    AdaptiveShading,
    /// The deferred path of `adaptive-shading` with every tile at rate 1x1: its baseline.
    NativeDeferred,
}

impl TechniqueKind {
    pub const ALL: [TechniqueKind; 6] = [
        TechniqueKind::Native,
        TechniqueKind::Upscale,
        TechniqueKind::Checkerboard,
        TechniqueKind::Checkerboard2x2,
        TechniqueKind::AdaptiveShading,
        TechniqueKind::NativeDeferred,
    ];

    pub fn name(self) -> &'static str {
        match self {
            TechniqueKind::Native => "native",
            TechniqueKind::Upscale => "upscale",
            TechniqueKind::Checkerboard => "checkerboard",
            TechniqueKind::AdaptiveShading => "adaptive-shading",
            TechniqueKind::NativeDeferred => "native-deferred",
            TechniqueKind::Checkerboard2x2 => "checkerboard-2x2",
        }
    }

    pub fn from_name(name: &str) -> Option<TechniqueKind> {
        Self::ALL.into_iter().find(|t| t.name() == name)
    }

    /// Names of every known technique, for error messages.
    pub fn known_names() -> Vec<&'static str> {
        Self::ALL.iter().map(|t| t.name()).collect()
    }

    pub fn params(self) -> &'static [ParamSpec] {
        match self {
            TechniqueKind::Native => &[],
            TechniqueKind::Upscale => &UPSCALE_PARAMS,
            TechniqueKind::Checkerboard => &CHECKERBOARD_PARAMS,
            TechniqueKind::AdaptiveShading => &ADAPTIVE_SHADING_PARAMS,
            TechniqueKind::NativeDeferred => &[],
            TechniqueKind::Checkerboard2x2 => &CHECKERBOARD_2X2_PARAMS,
        }
    }
}

impl fmt::Display for TechniqueKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

static UPSCALE_PARAMS: [ParamSpec; 2] = [
    ParamSpec {
        name: "scale",
        kind: ParamKind::Float {
            min: 0.0,
            min_inclusive: false,
            max: 1.0,
        },
        default: Default::Float(0.5),
        doc: "render width and height as a fraction of the output resolution",
    },
    ParamSpec {
        name: "filter",
        kind: ParamKind::Choice(&["bilinear", "nearest"]),
        default: Default::Str("bilinear"),
        doc: "upscaling filter",
    },
];

/// Defaults trace to the sources: sampling portable; gradients as Intel's code (DDXY_BIAS 0.5);
/// CSO with mosaiikki's tolerance (view units); mosaiikki's differential fill; Intel's unclamped
/// history (mosaiikki's clamps are options); mosaiikki's velocity buffer.
static CHECKERBOARD_PARAMS: [ParamSpec; 7] = [
    ParamSpec {
        name: "sampling",
        kind: ParamKind::Choice(&["two-pass", "msaa2x"]),
        default: Default::Str("two-pass"),
        doc: "msaa2x: 2x MSAA quarter-res targets shaded per sample (needs MULTISAMPLE_X2 and standard sample positions); two-pass: two jittered single-sample quarter-res renders, any adapter",
    },
    ParamSpec {
        name: "gradient_scale",
        kind: ParamKind::Float { min: 0.0, min_inclusive: false, max: 1.0 },
        default: Default::Float(0.5),
        doc: "multiplies screen-space derivatives at quarter resolution: 0.5 as Intel's code (-1 LOD), 0.7071 as mosaiikki's -0.5 LOD bias, 1 uncorrected",
    },
    ParamSpec {
        name: "occlusion",
        kind: ParamKind::Choice(&["cso", "aso"]),
        default: Default::Str("cso"),
        doc: "cso: a pixel that moved to another 2x2 block is occluded when its old view depth differs from the mean of its neighbours by depth_tolerance or more; aso: it always is",
    },
    ParamSpec {
        name: "depth_tolerance",
        kind: ParamKind::Float { min: 0.0, min_inclusive: false, max: 1.0e9 },
        default: Default::Float(0.01),
        doc: "CSO tolerance in view-space units (mosaiikki's depthTolerance)",
    },
    ParamSpec {
        name: "fill",
        kind: ParamKind::Choice(&["plain", "tonemapped", "differential"]),
        default: Default::Str("differential"),
        doc: "how a missing pixel is filled from its 4 neighbours: plain mean, mean in reversible-tonemapped space, or mosaiikki's differential blend (tonemapped)",
    },
    ParamSpec {
        name: "clamp",
        kind: ParamKind::Choice(&["none", "min-max", "min-max-confidence"]),
        default: Default::Str("none"),
        doc: "history clamp to the neighbours' min/max (mosaiikki), optionally blended back by depth confidence; none as Intel",
    },
    ParamSpec {
        name: "velocity",
        kind: ParamKind::Bool,
        default: Default::Bool(true),
        doc: "full-resolution velocity pass for dynamic objects (recorded only when the scene has some)",
    },
];

/// Defaults are the paper's (seeds/nvidia-adaptive-shading.txt): t = 0.15 and l = 0.05 (section
/// 6), k = 2.13 (Eq. 14), e = 0.1 (section 4.2's example), 4x4 off (section 3.4), the 2x neighbour
/// filter on (section 5.4). The paper gives no value for the hysteresis epsilon nor for the
/// depth-rejection tolerance (section 5.1 cites Nehab et al.): those defaults are ours.
static ADAPTIVE_SHADING_PARAMS: [ParamSpec; 10] = [
    ParamSpec {
        name: "threshold",
        kind: ParamKind::Float { min: 0.0, min_inclusive: false, max: 100.0 },
        default: Default::Float(0.15),
        doc: "sensitivity threshold t of the JND threshold t * (I_avg + l) (Eq. 15); the paper uses 0.15",
    },
    ParamSpec {
        name: "env_luma",
        kind: ParamKind::Float { min: 0.0, min_inclusive: true, max: 100.0 },
        default: Default::Float(0.05),
        doc: "environment luminance l of the JND threshold (Eq. 15); the paper uses 0.05",
    },
    ParamSpec {
        name: "k",
        kind: ParamKind::Float { min: 0.0, min_inclusive: false, max: 100.0 },
        default: Default::Float(2.13),
        doc: "quarter-rate error over half-rate error (Eq. 14), also the scale of b_Q (Eq. 21); 2.13 in the paper",
    },
    ParamSpec {
        name: "mode",
        kind: ParamKind::Choice(&["content-motion", "content", "motion"]),
        default: Default::Str("content-motion"),
        doc: "content-motion: Eq. 22 with the motion factors of Eq. 20 and 21; content: Eq. 16 (b_H = 1, b_Q = k); motion: standalone motion-adaptive shading (Eq. 24), the relative error taken as max_error",
    },
    ParamSpec {
        name: "max_error",
        kind: ParamKind::Float { min: 0.0, min_inclusive: false, max: 100.0 },
        default: Default::Float(0.1),
        doc: "mode motion only: the bound e on the relative error E / (I_avg + l) (Eq. 24); 0.1 as the paper's example in section 4.2",
    },
    ParamSpec {
        name: "hysteresis",
        kind: ParamKind::Float { min: 0.0, min_inclusive: true, max: 0.99 },
        default: Default::Float(0.2),
        doc: "epsilon of the hysteresis thresholds (section 5.4; no value in the paper; 0.2 is the least that stopped rate oscillation on scenarios/adaptive/detailed.toml, where coarse output raises the next estimate by about sqrt 2; 0 turns it off): against the tile's previous rate per axis, a rise of the predicted error to a finer rate must pass t(1 + epsilon), a fall to a coarser rate t(1 - epsilon)",
    },
    ParamSpec {
        name: "neighbour_filter",
        kind: ParamKind::Bool,
        default: Default::Bool(true),
        doc: "a filter pass limiting neighbouring tiles to a 2x rate difference per axis, quarter raised to half (section 5.4)",
    },
    ParamSpec {
        name: "allow_4x4",
        kind: ParamKind::Bool,
        default: Default::Bool(false),
        doc: "allow quarter rate on both axes at once; off in the paper (section 3.4), which then keeps quarter rate on the axis with the smaller error",
    },
    ParamSpec {
        name: "disocclusion_tolerance",
        kind: ParamKind::Float { min: 0.0, min_inclusive: false, max: 1.0e9 },
        default: Default::Float(0.05),
        doc: "depth-based rejection (section 5.1): a pixel whose previous-frame view depth differs from its reprojected surface's by more than this fraction is disoccluded, and its tile is shaded at full rate",
    },
    ParamSpec {
        name: "coarse_sample",
        kind: ParamKind::Choice(&["centre", "pixel"]),
        default: Default::Str("centre"),
        doc: "where software VRS shades a coarse pixel: centre, as hardware VRS (the paper's setting), at the mean of the object's G-buffer attributes in it with derivatives across it; pixel, at one of its pixels' own sample, replicated",
    },
];

/// Defaults are the depth-based report's final implementation (seeds/depth-based-checkerboarding.txt,
/// sections 5.3.4 to 5.3.8): blended clamping with motion coherency, its small-motion constant and
/// its blend limits. Motion is in pixels per frame; depth differences are in linear depth
/// normalised to [0, 1] between the camera's near and far planes (section 5.3.7).
static CHECKERBOARD_2X2_PARAMS: [ParamSpec; 5] = [
    ParamSpec {
        name: "clamp",
        kind: ParamKind::Choice(&["none", "uniform", "conditional", "blended"]),
        default: Default::Str("blended"),
        doc: "reprojected colour against the two shaded direct neighbours' min/max: none (5.3.3), always (uniform, 5.3.4), only where motion exceeds motion_threshold (conditional, 5.3.5), or conditional with the clamp blended back by depth difference (blended, 5.3.7; the report's final version)",
    },
    ParamSpec {
        name: "motion_threshold",
        kind: ParamKind::Float { min: 0.0, min_inclusive: true, max: 1.0e9 },
        default: Default::Float(1.0e-7),
        doc: "conditional and blended: pixels moving less than this (pixels per frame) are not clamped; 0.0000001 as the report (5.3.5)",
    },
    ParamSpec {
        name: "blend_min",
        kind: ParamKind::Float { min: 0.0, min_inclusive: true, max: 1.0 },
        default: Default::Float(0.005),
        doc: "blended: linear depth difference below which the reprojected colour is kept unclamped (the report's minimum blend difference, 5.3.7)",
    },
    ParamSpec {
        name: "blend_max",
        kind: ParamKind::Float { min: 0.0, min_inclusive: false, max: 1.0 },
        default: Default::Float(0.1),
        doc: "blended: linear depth difference at which the clamped colour is used in full; the clamp weight is difference / blend_max (the report's maximum blend difference, 5.3.7)",
    },
    ParamSpec {
        name: "motion_coherency",
        kind: ParamKind::Bool,
        default: Default::Bool(true),
        doc: "conditional and blended: also clamp when a shaded neighbour's previous motion differs from this pixel's motion by more than motion_threshold (5.3.8; keeps the motion history)",
    },
];

/// One parameter of a technique.
#[derive(Debug)]
pub struct ParamSpec {
    pub name: &'static str,
    pub kind: ParamKind,
    pub default: Default,
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

#[derive(Debug)]
pub enum Default {
    Float(f64),
    Int(i64),
    Str(&'static str),
    Bool(bool),
}

impl Default {
    pub fn value(&self) -> ParamValue {
        match self {
            Default::Float(v) => ParamValue::Float(*v),
            Default::Int(v) => ParamValue::Int(*v),
            Default::Str(v) => ParamValue::Str((*v).to_string()),
            Default::Bool(v) => ParamValue::Bool(*v),
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

/// A technique with concrete parameter values.
#[derive(Clone, Debug, PartialEq)]
pub struct Variant {
    pub name: String,
    pub technique: TechniqueKind,
    /// Every parameter of the technique, defaults filled in.
    pub params: BTreeMap<String, ParamValue>,
}

impl Variant {
    pub fn float(&self, name: &str) -> f64 {
        self.params
            .get(name)
            .and_then(ParamValue::as_f64)
            .unwrap_or_else(|| {
                panic!(
                    "validated variant {} lacks float parameter {name}",
                    self.name
                )
            })
    }

    pub fn flag(&self, name: &str) -> bool {
        match self.params.get(name) {
            Some(ParamValue::Bool(b)) => *b,
            _ => panic!(
                "validated variant {} lacks bool parameter {name}",
                self.name
            ),
        }
    }

    pub fn choice(&self, name: &str) -> &str {
        self.params
            .get(name)
            .and_then(ParamValue::as_str)
            .unwrap_or_else(|| {
                panic!(
                    "validated variant {} lacks choice parameter {name}",
                    self.name
                )
            })
    }
}

/// `technique` or `technique[a=1,b=x]` listing the parameters the scenario set explicitly.
pub fn variant_name(technique: TechniqueKind, explicit: &[(String, ParamValue)]) -> String {
    if explicit.is_empty() {
        return technique.name().to_string();
    }
    let parts: Vec<String> = explicit.iter().map(|(k, v)| format!("{k}={v}")).collect();
    format!("{}[{}]", technique.name(), parts.join(","))
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
