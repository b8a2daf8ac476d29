//! Scenarios: the TOML format, parsed and validated into domain types.
//!
//! `load` reads one file; `collect` expands files and folders into a sorted list of scenario files.
//! Parsing rejects unknown keys (`raw.rs`), validation checks values (`validate.rs`), and every error
//! names the file, line:column and dotted key, and says what is allowed. Nothing here touches a GPU:
//! limits that depend on the adapter are checked when a scenario runs.

pub mod pattern;
mod raw;
pub mod span;
pub mod sweep;
mod validate;

use std::fmt;
use std::path::{Path, PathBuf};

use tessera_results::measure::Measure;

use crate::metric::MetricKind;
use crate::techniques::Variant;
pub use crate::world::scene::{
    Animation, CameraPose, CameraTrack, City, Ground, GroundFilter, Inject, Interpolation,
    Keyframe, Light, Object, Scene, Shape, Stage,
};
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
    /// The energy window after the timed frames where sensors exist, in milliseconds (0: none);
    /// `None` is [`crate::conditions::ENERGY_WINDOW_MS`].
    pub energy_window_ms: Option<f64>,
    /// `frames.energy_steps`: the energy counter's steps that end the energy window; `None` is
    /// [`crate::conditions::ENERGY_STEPS`].
    pub energy_steps: Option<u32>,
    pub measured_frames: u32,
    /// `frames.measured = "auto"`: timed frames go on past `measured_frames` (then the rule's
    /// `min`) until the median GPU frame time is precise enough or the cap is reached; metrics
    /// still use `measured_frames`. `None` for a fixed count.
    pub auto: Option<crate::timing::stop::AutoRule>,
    /// Measured-frame indices to save as PNG.
    pub save_frames: Vec<u32>,
    /// `frames.save_worst`: also save, for each variant, the worst frame of each of its metrics
    /// (with its heat map and the reference's frame), beside `save_frames`.
    pub save_worst: bool,
    pub time_step: f64,
    pub reference: Reference,
    /// `reference.noise_samples`: the samples per pixel of the denser reference the converged
    /// reference is measured against on its first compared frame, to state its own error
    /// (`run/reference_noise.rs`); `None` when not measured.
    pub reference_noise: Option<u32>,
    /// `reference.motion_blur`: every compared frame (the reference's and each variant's) is
    /// filtered by a box of its pixels' motion along that motion before the metrics
    /// (`run/motion_blur.rs`).
    pub motion_blur: bool,
    pub metrics: Vec<MetricKind>,
    /// The display ColorVideoVDP (`cvvdp`) sees the frames on.
    pub display: tessera_metrics::DisplaySpec,
    /// `metrics_device`: where the metrics run; `None` picks by adapter
    /// (`metrics_device::default_backend`).
    pub metrics_device: Option<tessera_metrics_gpu::Backend>,
    pub scene: Scene,
    pub camera: CameraTrack,
    pub variants: Vec<Variant>,
    pub gates: Vec<Gate>,
    /// The values of a `[sweep]` this scenario was expanded with (label, value), in the file's
    /// order; empty for a file without one. They are also in the name.
    pub sweep: Vec<(String, String)>,
}

impl From<&Scenario> for Stage {
    fn from(s: &Scenario) -> Stage {
        Stage {
            width: s.width,
            height: s.height,
            scene: s.scene.clone(),
            camera: s.camera.clone(),
        }
    }
}

impl Scenario {
    /// Where a variant stands in the scenario's declaration (results are reported in this
    /// order); a name the scenario does not declare sorts last.
    pub fn declared_position(&self, variant: &str) -> usize {
        self.variants
            .iter()
            .position(|v| v.name == variant)
            .unwrap_or(usize::MAX)
    }

    /// Whether a reference is rendered at all: only when there are metrics to compute against it.
    pub fn needs_reference(&self) -> bool {
        self.reference != Reference::None && !self.metrics.is_empty()
    }

    /// Whether the reference needs a render of its own: not when it is the scenario's own
    /// `native` variant (that render serves as both).
    pub fn needs_separate_reference(&self) -> bool {
        self.needs_reference()
            && !(self.reference == Reference::Native
                && self.variants.iter().any(crate::techniques::is_reference))
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
    /// The converged reference: `samples` renders per frame at the output resolution, each
    /// jittered by a point of a low-discrepancy sequence in the pixel, averaged
    /// (`techniques/native/converged.rs`); also `kind = "ground-truth"`.
    Converged { samples: u32 },
}

impl Reference {
    pub fn name(self) -> &'static str {
        match self {
            Reference::None => "none",
            Reference::Native => "native",
            Reference::GroundTruth { .. } | Reference::Converged { .. } => "ground-truth",
        }
    }
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

/// Reads one scenario file and expands its `[sweep]` (`sweep.rs`): one scenario per combination
/// of the swept values, each named `name[key=value,...]`; the file's one scenario without one.
pub fn load_all(path: &Path) -> Result<Vec<Scenario>, ScenarioErrors> {
    let source = std::fs::read_to_string(path).map_err(|e| {
        ScenarioErrors(vec![ScenarioError {
            file: path.to_path_buf(),
            line: 0,
            column: 0,
            key: String::new(),
            message: format!("cannot read the file: {e}"),
        }])
    })?;
    let mut scenarios = Vec::new();
    let mut errors = Vec::new();
    for e in sweep::expand(path, &source)? {
        match parse(path, &e.source) {
            Ok(mut s) if !e.values.is_empty() => {
                let values: Vec<String> =
                    e.values.iter().map(|(k, v)| format!("{k}={v}")).collect();
                s.name = format!("{}[{}]", s.name, values.join(","));
                s.sweep = e.values;
                scenarios.push(s);
            }
            Ok(s) => scenarios.push(s),
            Err(ScenarioErrors(found)) => {
                for mut f in found {
                    // A fault in a swept value says which one; others are the file's own.
                    let swept = e.keys.iter().zip(&e.values).find(|(k, _)| {
                        f.key == **k
                            || f.key.starts_with(&format!("{k}["))
                            || f.key.starts_with(&format!("{k}."))
                    });
                    if let Some((k, (_, v))) = swept {
                        f.message = format!("{} (with sweep {k} = {v})", f.message);
                    }
                    // One report per fault, not one per combination that meets it.
                    if !errors.contains(&f) {
                        errors.push(f);
                    }
                }
            }
        }
    }
    if errors.is_empty() {
        Ok(scenarios)
    } else {
        Err(ScenarioErrors(errors))
    }
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

/// A suite's expectations file, beside its scenarios (read by `crate::expect`).
pub const EXPECTATIONS_FILE: &str = "expectations.toml";

/// Files and folders of a suite that are not scenarios: its expectations
/// ([`EXPECTATIONS_FILE`]) and its approved frame digests (`digests/`).
fn not_a_scenario(path: &Path) -> bool {
    let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("");
    if path.is_dir() {
        name == "digests"
    } else {
        name == EXPECTATIONS_FILE
    }
}

fn find_toml(dir: &Path, out: &mut Vec<PathBuf>) -> std::io::Result<()> {
    for entry in std::fs::read_dir(dir)? {
        let path = entry?.path();
        if not_a_scenario(&path) {
            continue;
        }
        if path.is_dir() {
            find_toml(&path, out)?;
        } else if path.extension().is_some_and(|x| x == "toml") {
            out.push(path);
        }
    }
    Ok(())
}
