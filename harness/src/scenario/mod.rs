//! Scenarios: the TOML format, parsed and validated into domain types.
//!
//! `load` reads one file; `collect` expands files and folders into a sorted list of scenario files.
//! Parsing rejects unknown keys (`raw.rs`), validation checks values (`validate.rs`), and every error
//! names the file, line:column and dotted key, and says what is allowed. Nothing here touches a GPU:
//! limits that depend on the adapter are checked when a scenario runs.

mod raw;
pub mod span;
mod validate;

use std::fmt;
use std::path::{Path, PathBuf};

use glam::{DMat4, DVec3, Vec3};
use tessera_results::measure::Measure;

use crate::params::Variant;
pub use span::KeyPath;

/// Largest width or height accepted without an adapter (wgpu's largest texture limit on any
/// backend). The adapter's own limit is checked at run time.
pub const MAX_DIMENSION: u32 = 16384;

/// A validated scenario.
#[derive(Clone, Debug)]
pub struct Scenario {
    pub name: String,
    pub file: PathBuf,
    pub description: String,
    pub width: u32,
    pub height: u32,
    pub warmup_frames: u32,
    /// Minimum GPU-busy time before the timed frames (frame 0 repeated), in milliseconds; `None`
    /// picks by adapter (see [`Scenario::clock_warmup_ms`]).
    pub warmup_ms: Option<f64>,
    pub measured_frames: u32,
    /// `frames.measured = "auto"`: timed frames go on past `measured_frames` (then the rule's
    /// `min`) until the median GPU frame time is precise enough or the cap is reached; metrics
    /// still use `measured_frames`. `None` for a fixed count.
    pub auto: Option<crate::timing::stop::AutoRule>,
    /// Measured-frame indices to save as PNG.
    pub save_frames: Vec<u32>,
    pub time_step: f64,
    pub reference: Reference,
    pub metrics: Vec<MetricKind>,
    /// The display ColorVideoVDP (`cvvdp`) sees the frames on.
    pub display: tessera_metrics::DisplaySpec,
    pub scene: Scene,
    pub camera: CameraTrack,
    pub variants: Vec<Variant>,
    pub gates: Vec<Gate>,
}

impl Scenario {
    /// Whether a reference is rendered at all: only when there are metrics to compute against it.
    pub fn needs_reference(&self) -> bool {
        self.reference != Reference::None && !self.metrics.is_empty()
    }

    /// Whether the reference needs a render of its own: not when it is the scenario's own
    /// `native` variant (that render serves as both).
    pub fn needs_separate_reference(&self) -> bool {
        self.needs_reference()
            && !(self.reference == Reference::Native
                && self
                    .variants
                    .iter()
                    .any(|v| v.technique.name() == crate::techniques::native::NAME))
    }

    /// Clock warm-up for an adapter of `device_type`: as set, or 1000 ms on GPUs (an H200 took
    /// several hundred milliseconds of load to reach its top clock) and 20 ms on CPU adapters.
    pub fn clock_warmup_ms(&self, device_type: &str) -> f64 {
        self.warmup_ms
            .unwrap_or(if device_type == "cpu" { 20.0 } else { 1000.0 })
    }

    pub fn total_frames(&self) -> u32 {
        self.warmup_frames + self.measured_frames
    }

    /// Scene time of frame `index` (warm-up frames first). Fixed step: runs are deterministic.
    pub fn frame_time(&self, index: u32) -> f64 {
        index as f64 * self.time_step
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Reference {
    /// No reference render: no metrics.
    None,
    /// The `native` technique in the same run on the same adapter.
    Native,
    /// NxN supersampled native render, box-downsampled.
    GroundTruth { supersample: u32 },
}

impl Reference {
    pub fn name(self) -> &'static str {
        match self {
            Reference::None => "none",
            Reference::Native => "native",
            Reference::GroundTruth { .. } => "ground-truth",
        }
    }
}

/// The measures `cvvdp` records besides `cvvdp` (JOD): the transient channel's own JOD (higher is
/// better) and its share of the visible difference (lower is better).
pub const CVVDP_MEASURES: [Measure; 2] = [Measure::CvvdpFlicker, Measure::CvvdpTransientShare];

/// Image metrics a scenario can ask for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MetricKind {
    Psnr,
    PsnrLuma,
    MaxAbsError,
    Ssim,
    SsimLuma,
    Flip,
    /// Static-scene flicker: mean absolute change between consecutive output frames.
    Flicker,
    /// HDR-FLIP on the linear output, exposures from the reference frame.
    FlipHdr,
    /// Temporal difference error with the renderer's exact motion (notes/metrics.md 3.3).
    Tde,
    /// ColorVideoVDP in JOD on the scenario's `display`, plus its perceptual-flicker measures.
    Cvvdp,
}

impl MetricKind {
    pub const ALL: [MetricKind; 10] = [
        MetricKind::Psnr,
        MetricKind::PsnrLuma,
        MetricKind::MaxAbsError,
        MetricKind::Ssim,
        MetricKind::SsimLuma,
        MetricKind::Flip,
        MetricKind::Flicker,
        MetricKind::FlipHdr,
        MetricKind::Tde,
        MetricKind::Cvvdp,
    ];
    pub const DEFAULT: [MetricKind; 3] = [
        MetricKind::Psnr,
        MetricKind::PsnrLuma,
        MetricKind::MaxAbsError,
    ];

    /// The measure this metric records (its name, unit and direction are defined there).
    pub fn measure(self) -> Measure {
        match self {
            MetricKind::Psnr => Measure::Psnr,
            MetricKind::PsnrLuma => Measure::PsnrLuma,
            MetricKind::MaxAbsError => Measure::MaxAbsError,
            MetricKind::Ssim => Measure::Ssim,
            MetricKind::SsimLuma => Measure::SsimLuma,
            MetricKind::Flip => Measure::Flip,
            MetricKind::Flicker => Measure::Flicker,
            MetricKind::FlipHdr => Measure::FlipHdr,
            MetricKind::Tde => Measure::Tde,
            MetricKind::Cvvdp => Measure::Cvvdp,
        }
    }

    /// The name in `metrics = [...]`, gates, the CSV and the store: the measure's.
    pub fn name(self) -> &'static str {
        self.measure().name()
    }

    pub fn higher_is_better(self) -> bool {
        self.measure().direction().higher_is_better()
    }
}

/// What is drawn.
#[derive(Clone, Debug)]
pub struct Scene {
    pub background: Vec3,
    pub ambient: f32,
    pub shading_cost: u32,
    pub ground: Option<Ground>,
    pub lights: Vec<Light>,
    pub objects: Vec<Object>,
    /// Maximum anisotropy of texture samplers whose filters are all linear (1: none).
    pub anisotropy: u16,
    /// A generated city (`[scene.city]`).
    pub city: Option<City>,
}

impl Scene {
    /// Whether anything moves by itself (not counting the camera).
    pub fn has_dynamic_objects(&self) -> bool {
        self.objects.iter().any(|o| o.animation.is_some())
            || self.city.as_ref().is_some_and(|c| c.moving > 0)
    }
}

/// `[scene.city]`: a generated city, deterministic from its seed (`render/city.rs`).
#[derive(Clone, Debug, PartialEq)]
pub struct City {
    pub seed: u64,
    /// Blocks per side of the square grid.
    pub blocks: u32,
    /// Side of one block in metres (streets of 12 m between blocks).
    pub block_size: f32,
    /// Buildings per block (object count).
    pub buildings: u32,
    /// Texels per side of each generated texture (before its mip chain).
    pub texture_size: u32,
    /// Frequency of the finest texture detail as a fraction of level 0's Nyquist frequency.
    pub texture_detail: f32,
    /// Trees per block, each of `tree_cards` alpha-tested foliage cards (overdraw).
    pub trees: u32,
    pub tree_cards: u32,
    /// Poles per block side, joined by wires (thin geometry).
    pub poles: u32,
    /// Parked vehicles per block.
    pub parked: u32,
    /// Moving vehicles in the whole city, driving along the streets at `speed` m/s.
    pub moving: u32,
    pub speed: f32,
}

#[derive(Clone, Debug)]
pub struct Ground {
    pub size: f32,
    pub height: f32,
    pub checker_size: f32,
    pub colors: [Vec3; 2],
    pub filter: GroundFilter,
    pub filter_epsilon: f32,
}

/// How the ground's checkerboard is filtered (`seeds/iq-filtered-checkerboard.txt`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GroundFilter {
    /// Point-sampled: aliases at a distance.
    None,
    /// IQ's analytic box filter over the pixel footprint from screen-space gradients.
    Box,
}

#[derive(Clone, Debug)]
pub enum Light {
    Directional {
        direction: Vec3,
        color: Vec3,
        intensity: f32,
    },
    Point {
        position: Vec3,
        color: Vec3,
        intensity: f32,
    },
}

#[derive(Clone, Debug)]
pub struct Object {
    pub shape: Shape,
    /// f64: a scene far from the origin keeps its precision (stress suite).
    pub position: DVec3,
    pub yaw_degrees: f32,
    pub color: Vec3,
    pub emissive: Vec3,
    pub specular: f32,
    pub animation: Option<Animation>,
    /// Stress suite: the object's pixels are written non-finite, to check that a technique does
    /// not spread them (issue 8).
    pub inject: Option<Inject>,
}

/// A non-finite value an object's shader writes instead of its colour.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Inject {
    Nan,
    Inf,
}

impl Inject {
    /// The value the scene shader reads (`Object.flags.x`).
    pub fn code(self) -> f32 {
        match self {
            Inject::Nan => 1.0,
            Inject::Inf => 2.0,
        }
    }
}

#[derive(Clone, Debug)]
pub enum Shape {
    /// Full extents.
    Box {
        size: Vec3,
    },
    Sphere {
        radius: f32,
    },
    /// A thin vertical cylinder standing on `position`.
    Pole {
        radius: f32,
        height: f32,
    },
    /// Posts from `position` to `end` with horizontal rails.
    Fence {
        end: Vec3,
        height: f32,
        posts: u32,
        rails: u32,
        thickness: f32,
    },
    /// A glTF 2.0 file, resolved against the scenario's folder.
    Mesh {
        path: PathBuf,
        scale: f32,
        /// `materials = "file"`: the file's textured PBR materials; otherwise the object's
        /// `color` (untextured Blinn-Phong, as procedural shapes).
        textured: bool,
    },
}

impl Shape {
    pub fn name(&self) -> &'static str {
        match self {
            Shape::Box { .. } => "box",
            Shape::Sphere { .. } => "sphere",
            Shape::Pole { .. } => "pole",
            Shape::Fence { .. } => "fence",
            Shape::Mesh { .. } => "mesh",
        }
    }
}

#[derive(Clone, Debug)]
pub enum Animation {
    Rotate { axis: Vec3, degrees_per_second: f32 },
    Translate { velocity: Vec3 },
    Oscillate { amplitude: Vec3, period: f32 },
}

impl Object {
    /// World-space model matrix at scene time `t` (seconds), in f64 so that objects far from the
    /// origin keep their precision once made camera-relative.
    pub fn model_at(&self, t: f64) -> DMat4 {
        let base = DMat4::from_translation(self.position)
            * DMat4::from_rotation_y((self.yaw_degrees as f64).to_radians());
        match &self.animation {
            None => base,
            Some(Animation::Rotate {
                axis,
                degrees_per_second,
            }) => {
                let angle = (*degrees_per_second as f64 * t).to_radians();
                base * DMat4::from_axis_angle(axis.as_dvec3().normalize(), angle)
            }
            Some(Animation::Translate { velocity }) => {
                DMat4::from_translation(velocity.as_dvec3() * t) * base
            }
            Some(Animation::Oscillate { amplitude, period }) => {
                let phase = (std::f64::consts::TAU * t / *period as f64).sin();
                DMat4::from_translation(amplitude.as_dvec3() * phase) * base
            }
        }
    }
}

/// Timed keyframes of the camera, with cuts.
#[derive(Clone, Debug)]
pub struct CameraTrack {
    pub near: f32,
    pub far: f32,
    pub interpolation: Interpolation,
    pub keyframes: Vec<Keyframe>,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Interpolation {
    Linear,
    /// Catmull-Rom through the keyframe positions and targets.
    Smooth,
}

#[derive(Clone, Debug)]
pub struct Keyframe {
    pub time: f64,
    pub position: DVec3,
    pub target: DVec3,
    pub fov_degrees: f32,
    pub cut: bool,
}

/// The camera at one instant.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraPose {
    /// f64 and interpolated in f64: in f32 a camera 1e6 units from the origin moves in 1/16-unit
    /// steps (found by scenarios/stress/far-from-origin.toml).
    pub position: DVec3,
    pub target: DVec3,
    pub fov_degrees: f32,
    /// Index of the segment (between cuts) the pose belongs to: history is invalid across a change.
    pub segment: usize,
}

impl CameraTrack {
    /// The pose at scene time `t`. Before the first keyframe the camera holds it; after the last, too.
    /// A cut keyframe is not interpolated towards: the camera holds the previous pose until the cut.
    pub fn pose_at(&self, t: f64) -> CameraPose {
        let k = &self.keyframes;
        let segment_of = |i: usize| k[..=i].iter().filter(|f| f.cut).count();
        let hold = |i: usize| CameraPose {
            position: k[i].position,
            target: k[i].target,
            fov_degrees: k[i].fov_degrees,
            segment: segment_of(i),
        };
        if t <= k[0].time {
            return hold(0);
        }
        let Some(next) = k.iter().position(|f| f.time > t) else {
            return hold(k.len() - 1);
        };
        let prev = next - 1;
        if k[next].cut {
            return hold(prev);
        }
        let span = k[next].time - k[prev].time;
        let s = (t - k[prev].time) / span;
        let (position, target) = match self.interpolation {
            Interpolation::Linear => (
                k[prev].position.lerp(k[next].position, s),
                k[prev].target.lerp(k[next].target, s),
            ),
            Interpolation::Smooth => {
                // Neighbours across a cut do not shape the curve.
                let before = if prev > 0 && !k[prev].cut {
                    prev - 1
                } else {
                    prev
                };
                let after = if next + 1 < k.len() && !k[next + 1].cut {
                    next + 1
                } else {
                    next
                };
                (
                    catmull_rom(
                        k[before].position,
                        k[prev].position,
                        k[next].position,
                        k[after].position,
                        s,
                    ),
                    catmull_rom(
                        k[before].target,
                        k[prev].target,
                        k[next].target,
                        k[after].target,
                        s,
                    ),
                )
            }
        };
        CameraPose {
            position,
            target,
            fov_degrees: k[prev].fov_degrees
                + (k[next].fov_degrees - k[prev].fov_degrees) * s as f32,
            segment: segment_of(prev),
        }
    }
}

fn catmull_rom(p0: DVec3, p1: DVec3, p2: DVec3, p3: DVec3, t: f64) -> DVec3 {
    let t2 = t * t;
    let t3 = t2 * t;
    0.5 * ((2.0 * p1)
        + (-p0 + p2) * t
        + (2.0 * p0 - 5.0 * p1 + 4.0 * p2 - p3) * t2
        + (-p0 + 3.0 * p1 - 3.0 * p2 + p3) * t3)
}

/// A threshold on a metric or timing.
#[derive(Clone, Debug, PartialEq)]
pub struct Gate {
    /// A metric name, or `gpu_ms`, `cpu_ms`, `speedup`.
    pub measure: String,
    /// Variant name pattern; `None` means every variant but the reference.
    pub variants: Option<String>,
    pub warn_below: Option<f64>,
    pub fail_below: Option<f64>,
    pub warn_above: Option<f64>,
    pub fail_above: Option<f64>,
}

/// Measures a gate can name besides the metrics the scenario computes: every gateable measure of
/// `tessera_results::measure` that is not a metric (`gpu_ms`, `cpu_ms`, `speedup`, the conditions,
/// pacing and stability measures), by canonical name. Older spellings (`non-finite`) are still
/// accepted by validation and written with the canonical name.
pub fn record_gate_measures() -> Vec<&'static str> {
    Measure::gateable()
        .filter(|m| !m.is_metric())
        .map(Measure::name)
        .collect()
}

/// A problem in a scenario file, at a place in it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ScenarioError {
    pub file: PathBuf,
    /// 1-based; 0 when the problem has no position (unreadable file).
    pub line: usize,
    pub column: usize,
    /// Dotted key path; empty for syntax errors.
    pub key: String,
    pub message: String,
}

impl fmt::Display for ScenarioError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.file.display())?;
        if self.line > 0 {
            write!(f, ":{}:{}", self.line, self.column)?;
        }
        if !self.key.is_empty() {
            write!(f, ": `{}`", self.key)?;
        }
        write!(f, ": {}", self.message)
    }
}

impl std::error::Error for ScenarioError {}

/// Every problem found in one file (validation reports all of them, not only the first).
#[derive(Clone, Debug)]
pub struct ScenarioErrors(pub Vec<ScenarioError>);

impl fmt::Display for ScenarioErrors {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (i, e) in self.0.iter().enumerate() {
            if i > 0 {
                writeln!(f)?;
            }
            write!(f, "{e}")?;
        }
        Ok(())
    }
}

impl std::error::Error for ScenarioErrors {}

/// Reads, parses and validates one scenario file.
pub fn load(path: &Path) -> Result<Scenario, ScenarioErrors> {
    let source = std::fs::read_to_string(path).map_err(|e| {
        ScenarioErrors(vec![ScenarioError {
            file: path.to_path_buf(),
            line: 0,
            column: 0,
            key: String::new(),
            message: format!("cannot read the file: {e}"),
        }])
    })?;
    parse(path, &source)
}

/// Parses and validates scenario `source` as if read from `path`.
pub fn parse(path: &Path, source: &str) -> Result<Scenario, ScenarioErrors> {
    validate::parse_and_validate(path, source)
}

/// Expands files and folders into scenario files: folders are searched recursively for `*.toml`,
/// sorted by path so that runs are reproducible.
pub fn collect(inputs: &[PathBuf]) -> Result<Vec<PathBuf>, ScenarioError> {
    let mut files = Vec::new();
    for input in inputs {
        let err = |message: String| ScenarioError {
            file: input.clone(),
            line: 0,
            column: 0,
            key: String::new(),
            message,
        };
        let meta = std::fs::metadata(input).map_err(|e| err(format!("cannot read: {e}")))?;
        if meta.is_dir() {
            let mut found = Vec::new();
            find_toml(input, &mut found)
                .map_err(|e| err(format!("cannot list the folder: {e}")))?;
            if found.is_empty() {
                return Err(err(
                    "the folder holds no scenario (*.toml) files".to_string()
                ));
            }
            found.sort();
            files.extend(found);
        } else {
            files.push(input.clone());
        }
    }
    Ok(files)
}

fn find_toml(dir: &Path, out: &mut Vec<PathBuf>) -> std::io::Result<()> {
    for entry in std::fs::read_dir(dir)? {
        let path = entry?.path();
        if path.is_dir() {
            find_toml(&path, out)?;
        } else if path.extension().is_some_and(|x| x == "toml") {
            out.push(path);
        }
    }
    Ok(())
}
