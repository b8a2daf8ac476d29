//! Result record types shared by the harness (which writes them) and the dashboard (which reads
//! them), and their meaning: [`measure`] (every measure's name, unit, direction and label, the
//! baseline lookup by technique, the values that become series), [`folder`] (the one run-folder
//! reader, upgrading older schema versions), [`upload`] (the body of `POST /api/runs`), and
//! [`compare`] (the one comparison of two runs, its rules in `COMPARISON.md`) on [`stats`].
//!
//! No GPU, no HTTP, no writing. The file format built from these types is documented in
//! `results/README.md`; bump [`SCHEMA_VERSION`] on any change a reader could notice, and teach
//! [`folder::upgrade`] to read the previous version.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

pub mod adapter;
pub mod compare;
pub mod conditions;
pub mod csv_file;
pub mod digest;
pub mod expectation;
pub mod folder;
pub mod measure;
pub mod queue;
mod timed;
pub mod upload;

/// The run folder's layout (`results/README.md`): where each file of a run lives. Both the
/// dashboard's import and `tessera compare` read run folders through this.
pub mod layout {
    use std::path::{Path, PathBuf};

    pub const RUN_JSON: &str = "run.json";
    pub const SCENARIOS_DIR: &str = "scenarios";
    pub const RESULTS_CSV: &str = "results.csv";

    /// Every `scenarios/*.json` of a run folder, sorted by name; none when the run was interrupted
    /// before its first scenario (no `scenarios/` folder).
    pub fn scenario_files(run_dir: &Path) -> std::io::Result<Vec<PathBuf>> {
        let dir = run_dir.join(SCENARIOS_DIR);
        let mut files: Vec<PathBuf> = match std::fs::read_dir(&dir) {
            Ok(entries) => entries
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| p.extension().is_some_and(|x| x == "json"))
                .collect(),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => Vec::new(),
            Err(e) => return Err(e),
        };
        files.sort();
        Ok(files)
    }
}

pub mod stats;

/// Version of the result format written now. Readers refuse versions they do not know; versions 1
/// and 2 are read through [`folder::upgrade`] (`results/README.md`, "Compatibility").
pub const SCHEMA_VERSION: u32 = 3;

/// The oldest version [`folder`] still reads.
pub const OLDEST_SCHEMA_VERSION: u32 = 1;

/// `run.json`: one invocation over a suite on one adapter at one commit.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct RunInfo {
    pub schema_version: u32,
    pub run_id: String,
    /// `None` when the harness was not run from a git checkout.
    pub commit: Option<CommitInfo>,
    /// Committer date of `commit`, RFC 3339 UTC; `None` without a git checkout and in runs written
    /// before it was recorded. The dashboard orders a series by it (then by `started_at`), so that
    /// runs uploaded out of commit order are placed where their commit belongs.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub commit_time: Option<String>,
    /// RFC 3339, UTC.
    pub started_at: String,
    /// RFC 3339, UTC; `None` while the run is going on or when it was interrupted.
    pub finished_at: Option<String>,
    pub status: RunStatus,
    pub harness_version: String,
    pub adapter: AdapterInfo,
    pub host: HostInfo,
    pub command_line: Vec<String>,
    /// Scenario files of the suite, in the order they run.
    pub scenarios: Vec<String>,
    /// The adapter's sensors, or why there are none. Absent in files written before they were
    /// recorded.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub conditions: Option<conditions::DeviceConditions>,
    /// The suite: the name of each scenario folder given on the command line (a file's parent
    /// folder), in order, joined by `+`. `None` in files written before it existed.
    #[serde(default)]
    pub suite: Option<String>,
    /// The git branch of the checkout (or `--branch`); `None` on a detached head, outside git, or
    /// in files written before it existed.
    #[serde(default)]
    pub branch: Option<String>,
    /// The adapter class the run declares (`tessera run --adapter-class`, a runner's label):
    /// what approved frames are kept per. `None`: derived from the adapter
    /// ([`adapter::class`]); absent before version 3.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub adapter_class: Option<String>,
}

#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum RunStatus {
    Running,
    Complete,
    /// The process ended before the last scenario; the scenario files present are complete.
    Interrupted,
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq, Eq)]
pub struct CommitInfo {
    pub sha: String,
    /// Uncommitted changes to tracked files when the run started.
    pub dirty: bool,
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq, Eq)]
pub struct HostInfo {
    pub hostname: String,
    pub os: String,
    pub arch: String,
    pub cpu_cores: usize,
}

/// GPU plus driver as wgpu reports it, and the features that matter to Tessera.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct AdapterInfo {
    pub name: String,
    pub vendor: u32,
    pub device: u32,
    /// `discrete-gpu`, `integrated-gpu`, `virtual-gpu`, `cpu` or `other`.
    pub device_type: String,
    pub driver: String,
    pub driver_info: String,
    /// `vulkan`, `metal`, `dx12`, `gl`, ...
    pub backend: String,
    pub features: AdapterFeatures,
}

#[derive(Clone, Debug, Default, Serialize, Deserialize, PartialEq)]
pub struct AdapterFeatures {
    /// Timestamp queries at pass boundaries (`TIMESTAMP_QUERY`).
    pub timestamps: bool,
    /// Timestamp writes inside passes (`TIMESTAMP_QUERY_INSIDE_PASSES`).
    pub timestamps_inside_passes: bool,
    /// Nanoseconds per timestamp tick; `None` without timestamps.
    pub timestamp_period_ns: Option<f32>,
    pub pipeline_statistics: bool,
    pub shader_f16: bool,
    /// Supported MSAA sample counts per texture format (e.g. `"rgba16float": [1, 4]`).
    pub msaa: BTreeMap<String, Vec<u32>>,
    pub max_texture_dimension_2d: u32,
}

/// One scenario's results: `scenarios/<scenario>.json` in a run folder.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct ScenarioResult {
    pub schema_version: u32,
    pub run_id: String,
    pub scenario: String,
    /// The scenario file as given on the command line.
    pub file: String,
    pub width: u32,
    pub height: u32,
    pub warmup_frames: u32,
    pub measured_frames: u32,
    /// Seconds of scene time per frame.
    pub time_step: f64,
    /// `native`, `ground-truth` or `none`.
    pub reference: String,
    pub results: Vec<VariantResult>,
    /// CPU wall time of the whole scenario, including readback and metrics.
    pub wall_ms: f64,
    /// Peak resident memory of the harness process during the scenario (Linux `VmHWM`, reset at
    /// its start): host memory, the driver's host-side allocations included; absent where the
    /// system does not report it and in files written before it was recorded.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub peak_rss_bytes: Option<u64>,
    /// Peak bytes the harness's own heap held during the scenario (its counting allocator, reset
    /// at the start): frames, images, metric and wgpu objects on the host; the driver's
    /// allocations are not in it. Absent where not counted and in older files.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub peak_heap_bytes: Option<u64>,
    /// The digests of the separately rendered reference's frames ([`digest::frame_digest`], one
    /// per measured frame); empty when the reference is the scenario's own `native` variant (its
    /// `frame_digests` are the reference's), without a reference, and before version 3.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub reference_digests: Vec<String>,
    /// The reference's own error (a ground-truth scenario with `samples`): on the first compared
    /// frame, the reference against one of more samples, on the scenario's metrics. Differences
    /// between variants smaller than it are ties. Absent without it and in older files.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reference_noise: Option<ReferenceNoise>,
}

/// How far the scenario's reference is from a reference of more samples, on its first compared
/// frame: the floor under which two variants' metric values cannot be told apart.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct ReferenceNoise {
    /// Jittered samples per pixel of the scenario's reference.
    pub reference_samples: u32,
    /// Samples per pixel of the reference it was measured against.
    pub samples: u32,
    /// Measured-frame index compared.
    pub frame: u32,
    /// Per metric name (as in the variants' `metrics`), the reference's value against the
    /// denser one: PSNR in dB, FLIP, JOD, ... Infinite values are left out.
    pub metrics: std::collections::BTreeMap<String, f64>,
    /// Why a metric could not be measured, when one could not.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub error: Option<String>,
}

impl ReferenceNoise {
    /// Whether values `a` and `b` of metric `name` differ by less than the reference's own error
    /// (a tie). The margin is the reference's distance from perfect in the metric's units: its
    /// FLIP (or any error) itself, `10 - JOD` for `cvvdp`, `1 - SSIM`; for PSNR, what the
    /// reference's noise power adds to the better value's error power,
    /// `10 log10(1 + 10^((max(a, b) - noise) / 10))` dB. A metric without a recorded noise ties
    /// nothing, and an infinite value ties only an infinite one.
    pub fn tied(&self, name: &str, a: f64, b: f64) -> bool {
        let Some(&n) = self.metrics.get(name) else {
            return false;
        };
        if !a.is_finite() || !b.is_finite() {
            return a == b;
        }
        let margin = match name {
            "psnr" | "psnr-luma" => 10.0 * (1.0 + 10f64.powf((a.max(b) - n) / 10.0)).log10(),
            "cvvdp" | "cvvdp-flicker" => 10.0 - n,
            "ssim" | "ssim-luma" => 1.0 - n,
            _ => n,
        };
        (a - b).abs() < margin
    }
}

/// One (run, scenario, variant) record.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct VariantResult {
    /// `technique` or `technique[key=value,...]` for swept parameters.
    pub variant: String,
    pub technique: String,
    /// The technique this variant's speed-up is also read against besides `native` (its
    /// same-pipeline baseline, chosen per variant: `native-deferred` for `adaptive-shading` in
    /// software, `native-vrs` for it in hardware); `speedup.<baseline>` is computed against the
    /// first ok result of that technique in the scenario. `None` when `native` is the only one,
    /// and in files written before it was recorded (readers may then fall back on the
    /// technique's).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub baseline: Option<String>,
    /// Concrete parameter values of this variant.
    pub params: BTreeMap<String, serde_json::Value>,
    pub status: Status,
    /// What the metrics were computed against (`native`, `ground-truth`); `None` without metrics.
    pub reference: Option<String>,
    /// Passes recorded per frame, in submission order. Culled passes are absent.
    pub passes: Vec<PassRecord>,
    /// Passes the technique declares but that nothing read, so they were not recorded.
    pub culled_passes: Vec<String>,
    /// Sum of the pass times of each measured frame; `None` without timestamps.
    pub gpu_frame_ms: Option<Summary>,
    /// CPU wall time from the start of encoding to the frame's completion on the GPU.
    pub cpu_frame_ms: Summary,
    /// Every GPU resource the technique allocated.
    pub resources: Vec<ResourceRecord>,
    pub allocated_bytes: u64,
    pub metrics: Vec<MetricRecord>,
    /// Non-finite channel values in the variant's output, summed over measured frames.
    pub non_finite_values: u64,
    /// Numerical-stability checks of this result: non-finite pixels and their spread, determinism,
    /// recovery after camera cuts. Absent in files written before they existed.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stability: Option<Stability>,
    /// Saved frames (paths relative to the run folder).
    pub images: Vec<ImageRecord>,
    pub gates: Vec<GateOutcome>,
    /// Clocks, temperature, power, energy and throttling during the measured frames. Absent in
    /// files written before they were recorded and for variants that did not render.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub conditions: Option<conditions::Conditions>,
    /// How the number of timed frames was decided (fixed, or `measured = "auto"`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sampling: Option<conditions::Sampling>,
    /// Frame-time stability of the per-frame GPU times; `None` with fewer than 2 of them.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pacing: Option<conditions::Pacing>,
    /// The digest of every compared frame's 8-bit display output ([`digest::frame_digest`]), one
    /// per measured frame in order (index = measured-frame index); empty for a variant that did
    /// not render and in files written before version 3.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub frame_digests: Vec<String>,
    /// The suite's expectation that applied to this result and what came of it; absent where
    /// none applied and in files written before version 3.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub expectation: Option<expectation::ExpectationRecord>,
    /// The frames the variant's history needs against the warm-up it had. Absent for variants
    /// that did not render and in files written before it was recorded.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub convergence: Option<Convergence>,
}

/// A variant's declared convergence against its run's warm-up (`results/README.md`,
/// "Convergence").
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq, Eq)]
pub struct Convergence {
    /// Frames the technique's history needs before its output is steady, as it declares them
    /// (`taau`: its jitter phases; `adaptive-shading`: its previous frame and, with hysteresis,
    /// the previous rates; `checkerboard`, `interlace`: both frame parities; 0: no history).
    pub frames: u32,
    /// Warm-up frames rendered before the first measured one.
    pub warmup_frames: u32,
    /// Whether the camera moved during the warm-up.
    pub camera_moving_in_warmup: bool,
    /// Whether the camera moved during the measured frames.
    pub camera_moving_in_measured: bool,
    /// The measured frames saw a steady history: at least `frames` warm-up frames, moving
    /// through the warm-up wherever the camera moves while measured. False: the result was
    /// measured before its history was steady, and says so.
    pub converged: bool,
}

/// Stability checks of one variant (`results/README.md`, "Stability").
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Stability {
    /// Output pixels with a non-finite channel, summed over measured frames.
    pub non_finite_pixels: u64,
    /// Of those, pixels whose reference pixel is finite: non-finite values the technique made or
    /// spread beyond what the scene injected. `None` without a reference render.
    pub spread_pixels: Option<u64>,
    /// Whether the capture render's last frame equals the timed render's last frame bit for bit:
    /// the same sequence rendered twice on one adapter, histories included. `None` when the
    /// scenario measures no frames.
    pub deterministic: Option<bool>,
    /// Camera cuts inside the measured frames, and how fast the error came back.
    pub cuts: Vec<CutRecovery>,
}

/// The error around one camera cut, as mean squared error against the reference (8-bit sRGB
/// units, the MSE behind PSNR).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct CutRecovery {
    /// Measured-frame index of the first frame of the new shot.
    pub frame: u32,
    /// MSE of the cut frame and the frames after it, up to 2 (fewer at the end of the sequence).
    pub mse: Vec<f64>,
    /// Median MSE of the new shot from 3 frames after the cut to the next cut; `None` when the
    /// shot is shorter.
    pub steady_mse: Option<f64>,
    /// The frame 2 after the cut is within `tolerance_db` of the steady PSNR; `None` when there
    /// is no steady level or no such frame.
    pub recovered: Option<bool>,
    pub tolerance_db: f64,
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq, Eq)]
#[serde(tag = "state", rename_all = "kebab-case")]
pub enum Status {
    Ok,
    Skipped { reason: String },
    Failed { error: String },
}

impl Status {
    pub fn label(&self) -> &'static str {
        match self {
            Status::Ok => "ok",
            Status::Skipped { .. } => "skipped",
            Status::Failed { .. } => "failed",
        }
    }
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct PassRecord {
    pub name: String,
    /// `render`, `compute` or `copy`.
    pub kind: String,
    pub reads: Vec<String>,
    pub writes: Vec<String>,
    /// `None` when the adapter cannot time this pass (absent, never zero).
    pub gpu_ms: Option<Summary>,
    /// Raw per-frame GPU times of the measured frames, in milliseconds.
    pub samples_ms: Vec<f64>,
    /// Fragment shader invocations of one frame (median over measured frames), where the adapter
    /// has pipeline statistics and the pass is a render pass.
    pub fragment_invocations: Option<u64>,
}

/// Order statistics of a set of samples, in the unit the field name gives.
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq)]
pub struct Summary {
    pub count: usize,
    pub median: f64,
    pub p5: f64,
    pub p95: f64,
    pub min: f64,
    pub max: f64,
    pub mean: f64,
    /// The distribution-free 95% confidence interval of the median, `[low, high]`
    /// ([`conditions::median_ci95`]); absent below 6 samples and in files written before it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub median_ci95: Option<[f64; 2]>,
}

impl Summary {
    /// Summary of `samples`; `None` when there are none. Percentiles interpolate linearly between
    /// order statistics (the "linear" method of numpy).
    pub fn of(samples: &[f64]) -> Option<Summary> {
        if samples.is_empty() {
            return None;
        }
        let mut sorted: Vec<f64> = samples.to_vec();
        sorted.sort_by(|a, b| a.total_cmp(b));
        let q = |p: f64| {
            let pos = p * (sorted.len() - 1) as f64;
            let lo = pos.floor() as usize;
            let hi = pos.ceil() as usize;
            sorted[lo] + (sorted[hi] - sorted[lo]) * (pos - lo as f64)
        };
        Some(Summary {
            count: sorted.len(),
            median: q(0.5),
            p5: q(0.05),
            p95: q(0.95),
            min: sorted[0],
            max: sorted[sorted.len() - 1],
            mean: sorted.iter().sum::<f64>() / sorted.len() as f64,
            median_ci95: conditions::median_ci95(&sorted).map(|(lo, hi)| [lo, hi]),
        })
    }
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq, Eq)]
pub struct ResourceRecord {
    pub name: String,
    /// `texture` or `buffer`.
    pub kind: String,
    /// wgpu texture format in kebab case, empty for buffers.
    pub format: String,
    pub width: u32,
    pub height: u32,
    pub samples: u32,
    pub bytes: u64,
}

/// A metric of a variant against its reference: per measured frame, and aggregated.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct MetricRecord {
    /// `psnr`, `psnr-luma`, `max-abs-error`, ...
    pub name: String,
    /// Per compared frame. Infinite PSNR (identical frames) is written as `null` in JSON.
    #[serde(with = "opt_f64_vec")]
    pub per_frame: Vec<f64>,
    /// Frame indices (measured-frame numbering) that `per_frame` refers to.
    pub frames: Vec<u32>,
    /// Aggregate over frames: mean, or for PSNR the PSNR of the mean MSE. `None` in JSON when infinite.
    #[serde(with = "opt_f64")]
    pub value: f64,
    /// Whether larger values are better (PSNR, SSIM) or worse (errors): the direction of its
    /// [`measure::Measure`] (written so that a reader without this crate can tell).
    pub higher_is_better: bool,
    /// Temporal behaviour of `per_frame`: mean, p95, max and population standard deviation over
    /// frames (a proxy for quality "pumping"); absent when a frame's value is infinite. Called
    /// `series` in schema version 1 (a series is one measure over commits, in the store); that
    /// key is still read.
    #[serde(default, alias = "series", skip_serializing_if = "Option::is_none")]
    pub frame_stats: Option<FrameStats>,
    /// Where it was computed: `"gpu"` (WGSL passes on the rendering device) or `"cpu"` (the
    /// reference implementations); absent in results written before the GPU back end (CPU).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub metrics_device: Option<String>,
    /// A technique's own check of its frames (`shading-rate`, hardware VRS's `model-shades`), not
    /// compared with the reference: its unit and direction, carried here because the shared
    /// measure table ([`measure`]) names no technique's checks. Absent for the metrics against
    /// the reference, whose unit and direction are their measure's
    /// ([`measure::metric_unit`], [`measure::metric_direction`] read either).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub check: Option<Check>,
}

/// What a technique declares of one of its own per-frame checks ([`MetricRecord::check`]).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq, Eq)]
pub struct Check {
    /// The CSV unit (`count`, `x`; empty for a plain ratio).
    pub unit: String,
    /// `lower-is-better`, `higher-is-better` or `neither` (a fact, never judged).
    pub direction: measure::Direction,
}

/// Statistics of a metric's per-frame values.
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq)]
pub struct FrameStats {
    pub mean: f64,
    pub p95: f64,
    pub max: f64,
    pub std_dev: f64,
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq, Eq)]
pub struct ImageRecord {
    /// Measured-frame index.
    pub frame: u32,
    /// `output` (this variant), `reference`, `heatmap` (FLIP error map in magma against the
    /// reference), `heatmap-hdr` (HDR-FLIP's), or a technique's own image such as `rate`.
    pub kind: String,
    pub path: String,
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct GateOutcome {
    /// What was gated: a [`measure::Measure`] name (`gpu_ms`, `speedup`, `psnr`,
    /// `non_finite_values`, ...). Version 1 files may hold an older spelling (`non-finite`).
    pub measure: String,
    #[serde(with = "opt_f64")]
    pub value: f64,
    pub level: GateLevel,
    pub message: String,
}

#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq, Eq, PartialOrd, Ord)]
#[serde(rename_all = "kebab-case")]
pub enum GateLevel {
    Pass,
    Warn,
    Fail,
}

/// Non-finite values (infinite PSNR) are not valid JSON numbers: they are written as `null` and
/// read back as `+inf`, the only non-finite value a metric aggregate can take.
mod opt_f64 {
    use serde::{Deserialize, Deserializer, Serializer};

    pub fn serialize<S: Serializer>(v: &f64, s: S) -> Result<S::Ok, S::Error> {
        if v.is_finite() {
            s.serialize_f64(*v)
        } else {
            s.serialize_none()
        }
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
        Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::INFINITY))
    }
}

mod opt_f64_vec {
    use serde::{Deserialize, Deserializer, Serialize, Serializer};

    pub fn serialize<S: Serializer>(v: &[f64], s: S) -> Result<S::Ok, S::Error> {
        let opts: Vec<Option<f64>> = v.iter().map(|x| x.is_finite().then_some(*x)).collect();
        opts.serialize(s)
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<f64>, D::Error> {
        let opts = Vec::<Option<f64>>::deserialize(d)?;
        Ok(opts
            .into_iter()
            .map(|x| x.unwrap_or(f64::INFINITY))
            .collect())
    }
}

/// Columns of `results.csv`, in order. One row per (scenario, variant, measure).
pub const CSV_COLUMNS: [&str; 10] = [
    "run_id",
    "scenario",
    "variant",
    "technique",
    "adapter",
    "backend",
    "status",
    "measure",
    "value",
    "unit",
];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn summary_percentiles_interpolate() {
        let s = Summary::of(&[4.0, 1.0, 3.0, 2.0, 5.0]).unwrap();
        assert_eq!(s.median, 3.0);
        assert_eq!(s.min, 1.0);
        assert_eq!(s.max, 5.0);
        assert!((s.p5 - 1.2).abs() < 1e-12);
        assert!((s.p95 - 4.8).abs() < 1e-12);
        assert!(Summary::of(&[]).is_none());
    }

    #[test]
    fn infinite_metric_round_trips_as_null() {
        let m = MetricRecord {
            name: "psnr".into(),
            per_frame: vec![f64::INFINITY, 42.0],
            frames: vec![0, 1],
            value: f64::INFINITY,
            higher_is_better: true,
            frame_stats: None,
            metrics_device: None,
            check: None,
        };
        let json = serde_json::to_string(&m).unwrap();
        assert!(json.contains("\"per_frame\":[null,42.0]"), "{json}");
        assert!(!json.contains("check"), "{json}");
        let back: MetricRecord = serde_json::from_str(&json).unwrap();
        assert_eq!(back, m);
    }
}
