//! What a technique is to the harness: the [`Technique`] definition every technique folder
//! implements once, and the [`Shader`] modules it declares.
//!
//! A definition is static data plus pure functions: its parameters, the checks across them, the
//! pass graph for an output size, construction on a device, its WGSL, and the technique its
//! speedup is also read against. It knows no other technique; the list of all of them is
//! `registry.rs`.

use std::fmt;

use crate::gpu::Gpu;
use crate::params::{ParamSpec, Variant};
use crate::render::graph::Plan;
use crate::render::renderer::{Renderer, Unsupported};

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

/// A technique: one implementation per folder under `techniques/`, one line in the registry.
pub trait Technique: Sync + 'static {
    /// The name scenarios and results use (`checkerboard-2x2`).
    fn name(&self) -> &'static str;

    /// One sentence for the parameter table of `scenarios/README.md` and `tessera validate`.
    fn summary(&self) -> &'static str;

    /// Its parameters, in the order the docs list them.
    fn params(&self) -> &'static [&'static ParamSpec] {
        &[]
    }

    /// Checks across parameters of a variant whose values each passed their own spec
    /// (`blend_min < blend_max`): the reason, in words, when they do not fit together.
    fn check(&self, _variant: &Variant) -> Result<(), String> {
        Ok(())
    }

    /// The pass graph `variant` runs at `target`, without a GPU: which passes run, which are
    /// culled, what is allocated. [`Technique::build`] allocates the same plan.
    fn plan(&self, variant: &Variant, target: Target) -> Plan;

    /// The variant on `gpu`, or why this adapter cannot run it (reported as `skipped`).
    fn build(
        &self,
        gpu: &Gpu,
        variant: &Variant,
        target: Target,
    ) -> Result<Box<dyn Renderer>, Unsupported>;

    /// Every WGSL module it builds, composed as the GPU sees it.
    fn shaders(&self) -> Vec<Shader>;

    /// The technique its speedup is read against besides `native` (its own cheaper path, e.g.
    /// `native-deferred` for `adaptive-shading`); `None` when `native` is the only one.
    fn baseline(&self) -> Option<&'static str> {
        None
    }

    /// Whether consecutive frames alternate between two kinds of work (checkerboarding shades
    /// even and odd pixel sets on alternate frames): frame-time pacing then reports even and odd
    /// frames apart.
    fn alternates_frames(&self) -> bool {
        false
    }

    /// Why it cannot draw textured materials (glTF `materials = "file"`, the city), when it
    /// shades through passes of its own instead of the scene's forward pipelines: such variants
    /// are skipped on textured scenes with this reason. `None` (it can) by default.
    fn materials_unsupported(&self) -> Option<&'static str> {
        None
    }
}

/// One WGSL module as the GPU sees it, and the files under `shaders/` it is made of.
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
