//! What a technique is to the harness: the [`Definition`] every technique folder implements once
//! (a type, with its options as a type), the object-safe [`Technique`] the registry and variants
//! hold (every `Definition` is one), [`Variant`], and the [`Shader`] modules it declares.
//!
//! A definition is static data plus pure functions of its options: its parameters and the one
//! reader of them (its `Options`, declared with [`options!`](crate::options)), the checks across them, what it needs of an adapter
//! ([`Requirements`]), the pass graph for an output size, construction on a device (with the scene
//! and the target: [`BuildContext`]), its WGSL, the technique its speed-up is read against and its
//! frame pattern, each per variant. It knows no other technique; the list of all of them is
//! `registry.rs`. How to write one: `harness/README.md`, "Adding a technique".

use std::collections::BTreeMap;
use std::fmt;

use crate::gpu::{Gpu, Requirements};
use crate::params::{FromParam, Param, ParamSpec, ParamValue};
use crate::render::graph::Plan;
use crate::render::renderer::{Renderer, Unsupported};
use crate::render::scene::SceneGpu;

/// Where a variant renders: the output size and what the scene does (techniques that need motion
/// add passes only when something moves by itself).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Target {
    pub width: u32,
    pub height: u32,
    /// Whether anything in the scene moves by itself (animated objects).
    pub dynamic_scene: bool,
}

impl Target {
    pub fn new(width: u32, height: u32, dynamic_scene: bool) -> Target {
        Target {
            width,
            height,
            dynamic_scene,
        }
    }
}

/// What [`Definition::build`] builds with: the device, the scene already on it (a pass that
/// draws the scene itself, e.g. outside wgpu, can fail here, before any frame is rendered) and
/// where the variant renders.
pub struct BuildContext<'a> {
    pub gpu: &'a Gpu,
    pub scene: &'a SceneGpu,
    pub target: Target,
}

impl<'a> BuildContext<'a> {
    pub fn new(gpu: &'a Gpu, scene: &'a SceneGpu, target: Target) -> BuildContext<'a> {
        BuildContext { gpu, scene, target }
    }
}

/// Whether consecutive frames do the same work or alternate between two kinds (checkerboarding
/// shades even and odd pixel sets on alternate frames, interlacing even and odd columns):
/// frame-time pacing then reports even and odd frames apart.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FramePattern {
    Same,
    Alternating,
}

/// A technique, written once per folder under `techniques/`, listed once in the registry.
///
/// `Options` is the variant's parameters as a type, declared and read by
/// [`options!`](crate::options) alone; every other method sees only the options.
pub trait Definition: Sync + 'static {
    /// Its parameters and their reading, declared once with [`options!`](crate::options) (`()`
    /// when it has none): the only place that reads parameter values ([`Variant::get`]).
    type Options: Clone + fmt::Debug + DeclaredOptions;

    /// The name scenarios and results use (`checkerboard-2x2`).
    fn name(&self) -> &'static str;

    /// One sentence for the parameter table of `scenarios/README.md` and `tessera validate`.
    fn summary(&self) -> &'static str;

    /// Checks across parameters (`blend_min < blend_max`): the reason, in words, when they do not
    /// fit together. Reported by validation with the variant's file and line.
    fn check(&self, _options: &Self::Options) -> Result<(), String> {
        Ok(())
    }

    /// What the variant needs of an adapter (features, MSAA per format, extensions): printed by
    /// `tessera validate` without a GPU, checked on the device before [`Definition::build`];
    /// a variant that lacks one is `skipped` with the reason.
    fn requirements(&self, _options: &Self::Options) -> Requirements {
        Requirements::none()
    }

    /// Whether the variant draws textured models (glTF materials, the city): the reason, in
    /// words, when it cannot. Printed by `tessera validate` for scenarios with textured models
    /// and checked before [`Definition::build`] on such a scene (the variant is then `skipped`).
    fn textured(&self, _options: &Self::Options) -> Result<(), String> {
        Ok(())
    }

    /// The pass graph at `target`, without a GPU: which passes run, which are culled, what is
    /// allocated. [`Definition::build`] allocates the same plan.
    fn plan(&self, options: &Self::Options, target: Target) -> Plan;

    /// The variant on the context's device, or why it cannot run there (reported as `skipped`).
    /// Called after its requirements were met.
    fn build(
        &self,
        options: &Self::Options,
        cx: &BuildContext<'_>,
    ) -> Result<Box<dyn Renderer>, Unsupported>;

    /// Every WGSL module it builds, composed as the GPU sees it (files in its own folder).
    fn shaders(&self) -> Vec<Shader>;

    /// The technique this variant's speed-up is read against besides `native` (its same-pipeline
    /// baseline, e.g. `native-deferred` for software adaptive shading, `native-vrs` for hardware);
    /// `None` when `native` is the only one. Recorded as the result's `baseline`.
    fn baseline(&self, _options: &Self::Options) -> Option<&'static str> {
        None
    }

    /// Whether the variant's frames alternate between two kinds of work.
    fn frames(&self, _options: &Self::Options) -> FramePattern {
        FramePattern::Same
    }

    /// Frames its history needs before its output is steady at an output `width` pixels wide
    /// (its declared convergence): a run's warm-up should be at least this long, with the camera
    /// already moving, and a result says whether it was (`Convergence`). By default 0 (no
    /// history), or 2 for alternating frames (both parities).
    fn convergence(&self, options: &Self::Options, _width: u32) -> u32 {
        match self.frames(options) {
            FramePattern::Same => 0,
            FramePattern::Alternating => 2,
        }
    }
}

/// A technique as the registry and a [`Variant`] hold it: a [`Definition`] with its options
/// read from the variant on each call. Implemented for every `Definition`; never by hand.
pub trait Technique: Sync + 'static {
    fn name(&self) -> &'static str;
    fn summary(&self) -> &'static str;
    fn params(&self) -> &'static [&'static ParamSpec];
    fn check(&self, variant: &Variant) -> Result<(), String>;
    fn requirements(&self, variant: &Variant) -> Requirements;
    fn textured(&self, variant: &Variant) -> Result<(), String>;
    fn plan(&self, variant: &Variant, target: Target) -> Plan;
    fn build(
        &self,
        variant: &Variant,
        cx: &BuildContext<'_>,
    ) -> Result<Box<dyn Renderer>, Unsupported>;
    fn shaders(&self) -> Vec<Shader>;
    fn baseline(&self, variant: &Variant) -> Option<&'static str>;
    fn frames(&self, variant: &Variant) -> FramePattern;
    fn convergence(&self, variant: &Variant, width: u32) -> u32;
}

impl<D: Definition> Technique for D {
    fn name(&self) -> &'static str {
        Definition::name(self)
    }
    fn summary(&self) -> &'static str {
        Definition::summary(self)
    }
    fn params(&self) -> &'static [&'static ParamSpec] {
        D::Options::params()
    }
    fn check(&self, variant: &Variant) -> Result<(), String> {
        Definition::check(self, &D::Options::from_variant(variant))
    }
    fn requirements(&self, variant: &Variant) -> Requirements {
        Definition::requirements(self, &D::Options::from_variant(variant))
    }
    fn textured(&self, variant: &Variant) -> Result<(), String> {
        Definition::textured(self, &D::Options::from_variant(variant))
    }
    fn plan(&self, variant: &Variant, target: Target) -> Plan {
        Definition::plan(self, &D::Options::from_variant(variant), target)
    }
    fn build(
        &self,
        variant: &Variant,
        cx: &BuildContext<'_>,
    ) -> Result<Box<dyn Renderer>, Unsupported> {
        Definition::build(self, &D::Options::from_variant(variant), cx)
    }
    fn shaders(&self) -> Vec<Shader> {
        Definition::shaders(self)
    }
    fn baseline(&self, variant: &Variant) -> Option<&'static str> {
        Definition::baseline(self, &D::Options::from_variant(variant))
    }
    fn frames(&self, variant: &Variant) -> FramePattern {
        Definition::frames(self, &D::Options::from_variant(variant))
    }
    fn convergence(&self, variant: &Variant, width: u32) -> u32 {
        Definition::convergence(self, &D::Options::from_variant(variant), width)
    }
}

/// One WGSL module as the GPU sees it, and the files it is made of (`scene.wgsl` in `shaders/`, a technique's own as `<folder>/<file>.wgsl`, in its folder).
pub struct Shader {
    pub name: String,
    pub source: String,
    pub files: Vec<&'static str>,
}

impl Shader {
    /// A module made of one file.
    pub fn file(path: &'static str, source: &str) -> Shader {
        Shader {
            name: path.to_string(),
            source: source.to_string(),
            files: vec![path],
        }
    }
}

impl fmt::Debug for dyn Technique {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl fmt::Display for dyn Technique {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// Techniques are singletons: two are the same when their names are.
impl PartialEq for dyn Technique {
    fn eq(&self, other: &Self) -> bool {
        self.name() == other.name()
    }
}

/// A technique with concrete parameter values.
#[derive(Clone, Debug, PartialEq)]
pub struct Variant {
    pub name: String,
    pub technique: &'static dyn Technique,
    /// Every parameter of the technique, defaults filled in.
    pub params: BTreeMap<String, ParamValue>,
}

impl Variant {
    /// The value of `param`. Validation checked every value against its technique's
    /// [`ParamSpec`]s, so a missing or mistyped value is a bug in the technique (its options read
    /// a parameter it does not declare): the registry's tests read every technique's defaults.
    pub fn get<T: FromParam>(&self, param: &Param<T>) -> T {
        self.params
            .get(param.spec.name)
            .and_then(T::from_param)
            .unwrap_or_else(|| {
                panic!(
                    "variant {} of {} lacks a valid parameter {}",
                    self.name,
                    self.technique.name(),
                    param.spec.name
                )
            })
    }

    /// A variant of `technique` with every parameter at its default.
    pub fn with_defaults(technique: &'static dyn Technique) -> Variant {
        Variant {
            name: technique.name().to_string(),
            technique,
            params: technique
                .params()
                .iter()
                .map(|p| (p.name.to_string(), p.default.value()))
                .collect(),
        }
    }
}

/// `technique` or `technique[a=1,b=x]` listing the parameters the scenario set explicitly.
pub fn variant_name(technique: &dyn Technique, explicit: &[(String, ParamValue)]) -> String {
    if explicit.is_empty() {
        return technique.name().to_string();
    }
    let parts: Vec<String> = explicit.iter().map(|(k, v)| format!("{k}={v}")).collect();
    format!("{}[{}]", technique.name(), parts.join(","))
}

/// Options read from a variant's parameters: the parameters declared, in docs order, and the
/// reading of values that each passed their own [`ParamSpec`]. Written by
/// [`options!`](crate::options) (`options.rs`) (or for `()`, a technique without parameters).
pub trait DeclaredOptions: Sized {
    /// The parameters, in the order the docs list them.
    fn params() -> &'static [&'static ParamSpec];

    /// The options of `variant` (validated against [`DeclaredOptions::params`]).
    fn from_variant(variant: &Variant) -> Self;
}

impl DeclaredOptions for () {
    fn params() -> &'static [&'static ParamSpec] {
        &[]
    }

    fn from_variant(_variant: &Variant) {}
}
