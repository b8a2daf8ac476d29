//! Measures: every named quantity of a result, with its one name, its unit, which way is better and
//! the label a page shows. The harness (gates, `results.csv`, `tessera compare`) and the dashboard
//! (series, regression detection, pages) both read this table, so they cannot disagree on what
//! `speedup` or `gpu_ms` means (rustc-perf's `database/src/metric.rs` is the model).
//!
//! Names, as `results/README.md` ("Measures") lists them:
//!
//! - a measure's **name** is what a gate's `measure` key, a `results.csv` row, a stored series and a
//!   page call it: snake_case for the harness's own measures (`gpu_ms`, `non_finite_values`),
//!   the scenario's spelling for image metrics (`psnr-luma`, `max-abs-error`);
//! - a measure summarised over frames is written `<name>.<statistic>` in the CSV and the store
//!   (`gpu_ms.median`, `gpu_ms.p95`, `temperature_c.max`); a gate on `<name>` reads the median;
//! - a per-pass measure is written `pass.<pass>.<name>[.<statistic>]`;
//! - `speedup.<technique>` is the speedup against a technique's own baseline (`speedup` itself is
//!   against [`DEFAULT_BASELINE`]).
//!
//! Older spellings (a gate on `non-finite`, schema version 1) are read as aliases and written
//! with the canonical name. Also here: the baseline lookup by technique that `speedup` and
//! `energy_saving` divide by, and the values of a result that become series in the store.
//!
//! Not for: formatting the CSV (the harness's `run/output.rs`) or storing series (the dashboard).

use crate::{MetricRecord, Status, VariantResult};

/// Which way a measure is better. `Neither` for facts that are not goals (clocks, frame counts).
/// Written `lower-is-better`, `higher-is-better`, `neither` where a record carries it
/// ([`crate::Check`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Direction {
    LowerIsBetter,
    HigherIsBetter,
    Neither,
}

impl Direction {
    /// The store's `higher_is_better` flag (`Neither` is stored as lower-is-better; no series of
    /// such a measure is stored).
    pub fn higher_is_better(self) -> bool {
        self == Direction::HigherIsBetter
    }

    /// `"higher is better"`, `"lower is better"` or `""`.
    pub fn phrase(self) -> &'static str {
        match self {
            Direction::LowerIsBetter => "lower is better",
            Direction::HigherIsBetter => "higher is better",
            Direction::Neither => "",
        }
    }
}

/// The technique whose variant `speedup` and `energy_saving` divide by when a technique names no
/// baseline of its own.
pub const DEFAULT_BASELINE: &str = "native";

/// Statistics a summarised measure is written with in the CSV and the store.
pub const STATISTICS: [&str; 8] = [
    "median",
    "p5",
    "p95",
    "min",
    "max",
    "mean",
    "median_ci95.low",
    "median_ci95.high",
];

/// Where a measure comes from, which decides how [`value`] reads it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Source {
    /// A field of the result or its conditions, stability or pacing.
    Record,
    /// An image metric of the result (`VariantResult::metrics`), computed against the reference.
    /// A technique's own checks of its frames are metrics too, but not measures of this table:
    /// their records carry their unit and direction ([`MetricRecord::check`]).
    Metric,
    /// Per pass (`pass.<pass>.<name>`).
    Pass,
}

/// Everything the harness and the dashboard need to know about one measure.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Info {
    /// The one name: gate key, CSV row, store series, page.
    pub name: &'static str,
    /// Earlier spellings still read (gates in older scenario files, schema version 1 results).
    pub aliases: &'static [&'static str],
    /// The CSV `unit` column; empty for unitless ratios of the metrics.
    pub unit: &'static str,
    pub direction: Direction,
    /// The column or axis label on pages and in the console.
    pub label: &'static str,
    /// A gate may name it (metrics only when the scenario computes them).
    pub gate: bool,
    /// Summarised over frames: CSV and store write `<name>.<statistic>`, a gate reads the median.
    pub summarised: bool,
    /// The dashboard stores a series of it (under [`Measure::store_key`]) and detects regressions.
    pub stored: bool,
    pub source: Source,
    /// The change a comparison must see before it calls the measure better or worse, in its own
    /// unit (`compare::metrics::judge`); `None`: 0.1% of the larger magnitude
    /// (`compare::metrics::RELATIVE_TOLERANCE`).
    pub tolerance: Option<f64>,
}

macro_rules! measures {
    ($($variant:ident => $info:expr,)*) => {
        /// Every named quantity of a result; [`Measure::ALL`] lists them all.
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
        pub enum Measure { $($variant,)* }

        impl Measure {
            pub const ALL: &'static [Measure] = &[$(Measure::$variant,)*];

            pub fn info(self) -> &'static Info {
                match self { $(Measure::$variant => { const I: Info = $info; &I })* }
            }
        }
    };
}

const fn info(
    name: &'static str,
    unit: &'static str,
    direction: Direction,
    label: &'static str,
    source: Source,
) -> Info {
    Info {
        name,
        aliases: &[],
        unit,
        direction,
        label,
        gate: false,
        summarised: false,
        stored: false,
        source,
        tolerance: None,
    }
}

/// An image metric against the reference, gated and stored, that moves only beyond `tolerance`
/// (in its unit; `None`: relative).
const fn metric(
    name: &'static str,
    unit: &'static str,
    direction: Direction,
    label: &'static str,
    tolerance: Option<f64>,
) -> Info {
    Info {
        gate: true,
        stored: true,
        tolerance,
        ..info(name, unit, direction, label, Source::Metric)
    }
}

use Direction::{HigherIsBetter as Higher, LowerIsBetter as Lower, Neither};

measures! {
    GpuMs => Info { gate: true, summarised: true, stored: true,
        ..info("gpu_ms", "ms", Lower, "GPU ms", Source::Record) },
    CpuMs => Info { gate: true, summarised: true, stored: true,
        ..info("cpu_ms", "ms", Lower, "CPU ms", Source::Record) },
    Speedup => Info { gate: true, stored: true,
        ..info("speedup", "x", Higher, "speedup", Source::Record) },
    GpuMsPrecision => info("gpu_ms.precision", "ratio", Lower, "GPU ms precision", Source::Record),
    MeasuredFrames => info("measured_frames", "count", Neither, "measured frames", Source::Record),
    PacingP95OverP50 => Info { gate: true,
        ..info("pacing.p95_over_p50", "x", Lower, "pacing p95/p50", Source::Record) },
    PacingMeanAbsDeltaMs => Info { gate: true,
        ..info("pacing.mean_abs_delta_ms", "ms", Lower, "pacing mean |Δ| ms", Source::Record) },
    PacingEvenMs => Info { summarised: true,
        ..info("pacing.even_ms", "ms", Neither, "even-frame ms", Source::Record) },
    PacingOddMs => Info { summarised: true,
        ..info("pacing.odd_ms", "ms", Neither, "odd-frame ms", Source::Record) },
    PacingEvenOverOdd => info("pacing.even_over_odd", "x", Neither, "even/odd", Source::Record),
    GraphicsClockMhz => Info { summarised: true,
        ..info("graphics_clock_mhz", "MHz", Neither, "graphics clock MHz", Source::Record) },
    MemoryClockMhz => Info { summarised: true,
        ..info("memory_clock_mhz", "MHz", Neither, "memory clock MHz", Source::Record) },
    TemperatureC => Info { summarised: true,
        ..info("temperature_c", "C", Neither, "temperature °C", Source::Record) },
    PowerW => Info { summarised: true,
        ..info("power_w", "W", Neither, "power W", Source::Record) },
    EnergyMj => Info { gate: true, stored: true,
        ..info("energy_mj", "mJ", Lower, "energy mJ/frame", Source::Record) },
    EnergySaving => Info { gate: true,
        ..info("energy_saving", "x", Higher, "energy saving", Source::Record) },
    Throttled => Info { gate: true,
        ..info("throttled", "bool", Lower, "throttled", Source::Record) },
    // One measure for fragment-shader invocations, per pass: hardware VRS's raw pass is counted
    // as `pass.scene_vrs.fragment_invocations` like any other; `fragment-invocations`, its
    // per-frame metric before issue 21, is read as this one.
    FragmentInvocations => Info { aliases: &["fragment-invocations"],
        ..info("fragment_invocations", "count", Lower, "fragment invocations", Source::Pass) },
    AllocatedBytes => Info { stored: true,
        ..info("allocated_bytes", "bytes", Lower, "allocated bytes", Source::Record) },
    NonFiniteValues => Info { gate: true, aliases: &["non-finite"],
        ..info("non_finite_values", "count", Lower, "non-finite values", Source::Record) },
    SpreadNonFinite => Info { gate: true, aliases: &["spread-non-finite"],
        ..info("spread_non_finite", "count", Lower, "spread non-finite pixels", Source::Record) },
    Nondeterministic => Info { gate: true,
        ..info("nondeterministic", "bool", Lower, "nondeterministic", Source::Record) },
    UnrecoveredCuts => Info { gate: true, aliases: &["unrecovered-cuts"],
        ..info("unrecovered_cuts", "count", Lower, "unrecovered cuts", Source::Record) },
    // Tolerances: 0.1 dB of PSNR, 0.001 of SSIM and FLIP, 0.05 JOD (1/20 of the step at which
    // 75% of viewers prefer one video), 0.01 of the transient share; the rest relative.
    Psnr => metric("psnr", "dB", Higher, "PSNR dB", Some(0.1)),
    PsnrLuma => metric("psnr-luma", "dB", Higher, "PSNR luma dB", Some(0.1)),
    MaxAbsError => metric("max-abs-error", "", Lower, "max abs error", None),
    Ssim => metric("ssim", "", Higher, "SSIM", Some(0.001)),
    SsimLuma => metric("ssim-luma", "", Higher, "SSIM luma", Some(0.001)),
    Flip => metric("flip", "", Lower, "FLIP", Some(0.001)),
    FlipHdr => metric("flip-hdr", "", Lower, "HDR-FLIP", Some(0.001)),
    FlipMax => metric("flip-max", "", Lower, "FLIP max", Some(0.01)),
    Flicker => metric("flicker", "", Lower, "flicker", None),
    Tde => metric("tde", "", Lower, "TDE", None),
    Cvvdp => metric("cvvdp", "JOD", Higher, "ColorVideoVDP JOD", Some(0.05)),
    CvvdpFlicker => metric("cvvdp-flicker", "JOD", Higher, "ColorVideoVDP flicker JOD", Some(0.05)),
    CvvdpTransientShare => metric("cvvdp-transient-share", "", Lower, "ColorVideoVDP transient share", Some(0.01)),
}

impl Measure {
    pub fn name(self) -> &'static str {
        self.info().name
    }
    pub fn unit(self) -> &'static str {
        self.info().unit
    }
    pub fn direction(self) -> Direction {
        self.info().direction
    }
    pub fn label(self) -> &'static str {
        self.info().label
    }

    /// The measure called `name` (or one of its older spellings), exactly; `None` for anything
    /// else, including CSV keys with a statistic or a pass (see [`Key::parse`]).
    pub fn from_name(name: &str) -> Option<Measure> {
        Measure::ALL
            .iter()
            .copied()
            .find(|m| m.name() == name || m.info().aliases.contains(&name))
    }

    /// The measures a gate may name, metrics included (a scenario allows a metric only when it
    /// computes it).
    pub fn gateable() -> impl Iterator<Item = Measure> {
        Measure::ALL.iter().copied().filter(|m| m.info().gate)
    }

    /// Whether this is an image metric against the reference.
    pub fn is_metric(self) -> bool {
        self.info().source == Source::Metric
    }

    /// The key of its series in the store and its row in the CSV when only one is kept: the median
    /// of a summarised measure, else the name.
    pub fn store_key(self) -> String {
        if self.info().summarised {
            format!("{}.median", self.name())
        } else {
            self.name().to_string()
        }
    }
}

/// A measure name with what the CSV and the store add to it: a pass, a statistic, a baseline.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Key {
    pub measure: Measure,
    /// `pass.<pass>.…`
    pub pass: Option<String>,
    /// `….median`, `….p95`, …
    pub statistic: Option<&'static str>,
    /// `speedup.<technique>`: the technique whose variant was divided by; `None` for
    /// [`DEFAULT_BASELINE`].
    pub baseline: Option<String>,
}

impl Key {
    pub fn of(measure: Measure) -> Key {
        Key {
            measure,
            pass: None,
            statistic: None,
            baseline: None,
        }
    }

    pub fn statistic(mut self, statistic: &'static str) -> Key {
        self.statistic = Some(statistic);
        self
    }

    pub fn pass(mut self, pass: &str) -> Key {
        self.pass = Some(pass.to_string());
        self
    }

    /// `speedup.<baseline>`.
    pub fn speedup_over(baseline: &str) -> Key {
        Key {
            baseline: Some(baseline.to_string()),
            ..Key::of(Measure::Speedup)
        }
    }

    /// Reads a CSV or store key (`gpu_ms.median`, `pass.scene.gpu_ms.median`, `speedup.native-deferred`,
    /// `psnr`); older spellings are read as their measure. `None` for a name that is not a measure.
    pub fn parse(key: &str) -> Option<Key> {
        if let Some(m) = Measure::from_name(key) {
            return Some(Key::of(m));
        }
        if let Some(rest) = key.strip_prefix("pass.") {
            for m in Measure::ALL
                .iter()
                .filter(|m| m.info().source == Source::Pass || **m == Measure::GpuMs)
            {
                for stat in std::iter::once(None).chain(STATISTICS.iter().map(Some)) {
                    let suffix = match stat {
                        Some(s) => format!(".{}.{s}", m.name()),
                        None => format!(".{}", m.name()),
                    };
                    if let Some(pass) = rest.strip_suffix(&suffix).filter(|p| !p.is_empty()) {
                        return Some(Key {
                            measure: *m,
                            pass: Some(pass.to_string()),
                            statistic: stat.copied(),
                            baseline: None,
                        });
                    }
                }
            }
            return None;
        }
        for stat in STATISTICS {
            if let Some(name) = key.strip_suffix(stat).and_then(|k| k.strip_suffix('.')) {
                if let Some(m) = Measure::from_name(name).filter(|m| m.info().summarised) {
                    return Some(Key::of(m).statistic(stat));
                }
            }
        }
        let baseline = key.strip_prefix("speedup.")?;
        (!baseline.is_empty()).then(|| Key::speedup_over(baseline))
    }

    /// The key as the CSV and the store write it.
    pub fn render(&self) -> String {
        let mut s = String::new();
        if let Some(p) = &self.pass {
            s.push_str("pass.");
            s.push_str(p);
            s.push('.');
        }
        s.push_str(self.measure.name());
        if let Some(b) = &self.baseline {
            s.push('.');
            s.push_str(b);
        }
        if let Some(st) = self.statistic {
            s.push('.');
            s.push_str(st);
        }
        s
    }

    /// What a page shows for this key: the pass name for per-pass GPU time, the measure's label
    /// with the statistic where it is not the median, and the baseline of a speedup.
    pub fn label(&self) -> String {
        let mut l = match &self.pass {
            Some(p) if self.measure == Measure::GpuMs => p.clone(),
            Some(p) => format!("{p} {}", self.measure.label()),
            None => self.measure.label().to_string(),
        };
        if let Some(b) = &self.baseline {
            l = format!("{l} over {b}");
        }
        match self.statistic {
            None | Some("median") => {}
            Some(st) => l = format!("{l} {st}"),
        }
        l
    }
}

impl std::fmt::Display for Key {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.render())
    }
}

/// The unit of a metric record: its measure's, else the one its technique's check carries
/// ([`MetricRecord::check`]), else none.
pub fn metric_unit(m: &MetricRecord) -> &str {
    match (Measure::from_name(&m.name), &m.check) {
        (Some(known), _) => known.unit(),
        (None, Some(c)) => &c.unit,
        (None, None) => "",
    }
}

/// Which way a metric record is better: its measure's, else its check's, else the record's
/// `higher_is_better` (a metric of a newer harness).
pub fn metric_direction(m: &MetricRecord) -> Direction {
    match (Measure::from_name(&m.name), &m.check) {
        (Some(known), _) => known.direction(),
        (None, Some(c)) => c.direction,
        (None, None) if m.higher_is_better => Direction::HigherIsBetter,
        (None, None) => Direction::LowerIsBetter,
    }
}

/// Which way `key` (a CSV or store key) is better; `None` for a name that is not a measure.
pub fn direction_of(key: &str) -> Option<Direction> {
    Key::parse(key).map(|k| k.measure.direction())
}

/// The first ok variant of technique `baseline` among `results` (one scenario on one adapter).
/// Found by technique, so a `label` on the baseline changes nothing; a baseline that names a
/// variant (`native[motion_pass=true]`, checkerboard-2x2's) is found by that name first, as the
/// comparison engine finds it (`compare::baseline`).
pub fn baseline_of<'a>(results: &'a [VariantResult], baseline: &str) -> Option<&'a VariantResult> {
    let ok = |v: &&VariantResult| v.status == Status::Ok;
    results
        .iter()
        .filter(ok)
        .find(|v| v.variant == baseline)
        .or_else(|| results.iter().filter(ok).find(|v| v.technique == baseline))
}

/// Median GPU frame time; `None` without timestamps.
pub fn gpu_ms(r: &VariantResult) -> Option<f64> {
    r.gpu_frame_ms.map(|s| s.median)
}

/// Energy per measured frame in millijoules; `None` without sensors.
pub fn energy_mj(r: &VariantResult) -> Option<f64> {
    r.conditions
        .as_ref()?
        .recorded()?
        .energy
        .map(|e| e.mj_per_frame)
}

/// The baseline's median GPU time over `r`'s: `speedup` (with [`DEFAULT_BASELINE`]) or
/// `speedup.<baseline>`. `None` when either is not ok or has no timings.
pub fn speedup(results: &[VariantResult], r: &VariantResult, baseline: &str) -> Option<f64> {
    ratio(results, r, baseline, gpu_ms)
}

/// The baseline's energy per frame over `r`'s (2 = half the energy per frame).
pub fn energy_saving(results: &[VariantResult], r: &VariantResult, baseline: &str) -> Option<f64> {
    ratio(results, r, baseline, energy_mj)
}

fn ratio(
    results: &[VariantResult],
    r: &VariantResult,
    baseline: &str,
    of: fn(&VariantResult) -> Option<f64>,
) -> Option<f64> {
    let base = baseline_of(results, baseline)?;
    if r.status != Status::Ok {
        return None;
    }
    let (b, v) = (of(base)?, of(r)?);
    (v > 0.0 && b > 0.0).then(|| b / v)
}

/// The value of a measure for `r` among the results of its scenario, as a gate reads it (a
/// summarised measure's median; booleans as 0 and 1); `None` when not measured. Per-pass measures
/// have no single value: `None`.
pub fn value(results: &[VariantResult], r: &VariantResult, m: Measure) -> Option<f64> {
    use Measure::*;
    let stability = r.stability.as_ref();
    let recorded = r.conditions.as_ref().and_then(|c| c.recorded());
    let flag = |b: bool| if b { 1.0 } else { 0.0 };
    match m {
        GpuMs => gpu_ms(r),
        CpuMs => (r.cpu_frame_ms.count > 0).then_some(r.cpu_frame_ms.median),
        Speedup => speedup(results, r, DEFAULT_BASELINE),
        GpuMsPrecision => r.sampling.as_ref()?.precision,
        MeasuredFrames => r.sampling.as_ref().map(|s| s.frames as f64),
        PacingP95OverP50 => r.pacing.map(|p| p.p95_over_p50),
        PacingMeanAbsDeltaMs => r.pacing.map(|p| p.mean_abs_delta_ms),
        PacingEvenMs => r.pacing?.parity.map(|p| p.even_median_ms),
        PacingOddMs => r.pacing?.parity.map(|p| p.odd_median_ms),
        PacingEvenOverOdd => r.pacing?.parity.map(|p| p.even_over_odd),
        GraphicsClockMhz => recorded?.graphics_clock_mhz.map(|s| s.median),
        MemoryClockMhz => recorded?.memory_clock_mhz.map(|s| s.median),
        TemperatureC => recorded?.temperature_c.map(|s| s.median),
        PowerW => recorded?.power_w.map(|s| s.median),
        EnergyMj => energy_mj(r),
        EnergySaving => energy_saving(results, r, DEFAULT_BASELINE),
        Throttled => recorded.map(|c| flag(c.throttled)),
        FragmentInvocations => None,
        AllocatedBytes => Some(r.allocated_bytes as f64),
        NonFiniteValues => Some(r.non_finite_values as f64),
        SpreadNonFinite => stability?.spread_pixels.map(|v| v as f64),
        Nondeterministic => stability?.deterministic.map(|d| flag(!d)),
        UnrecoveredCuts => stability.map(|s| unrecovered_cuts(s) as f64),
        _ => r
            .metrics
            .iter()
            .find(|x| x.name == m.name())
            .map(|x| x.value),
    }
}

/// Camera cuts whose error did not come back within 2 frames (`recovered == Some(false)`).
pub fn unrecovered_cuts(s: &crate::Stability) -> usize {
    s.cuts.iter().filter(|c| c.recovered == Some(false)).count()
}

/// One value of a result that becomes a point of a series in the store.
#[derive(Clone, Debug, PartialEq)]
pub struct Point {
    /// The store key ([`Key::render`]).
    pub key: String,
    pub value: f64,
    /// The direction regression detection reads: the measure's, or for a metric this table does
    /// not know, the record's own `higher_is_better`.
    pub higher_is_better: bool,
}

fn push_named(out: &mut Vec<Point>, key: String, value: Option<f64>, higher_is_better: bool) {
    if let Some(value) = value.filter(|v| v.is_finite()) {
        out.push(Point {
            key,
            value,
            higher_is_better,
        });
    }
}

/// The series values of one result among its scenario's: the measures marked `stored`, per pass
/// for GPU time, `speedup` for every technique but the baseline. Skipped and failed results have
/// none; non-finite values (infinite PSNR of identical frames) are left out. A result whose
/// expectation is `no-perf` has no timing series (GPU and CPU time, per pass, speed-up, energy):
/// its timings are not measurements.
pub fn points(results: &[VariantResult], r: &VariantResult) -> Vec<Point> {
    if r.status != Status::Ok {
        return Vec::new();
    }
    let mut out = points_of_ok(results, r);
    if r.expectation.as_ref().is_some_and(|e| !e.timings_count()) {
        out.retain(|p| !is_timing_key(&p.key));
    }
    out
}

/// Whether a stored key is a timing (what `no-perf` leaves out).
pub fn is_timing_key(key: &str) -> bool {
    let base = key.rsplit('.').nth(1).unwrap_or(key);
    key == Measure::Speedup.store_key()
        || key == Measure::EnergyMj.store_key()
        || base == Measure::GpuMs.name()
        || base == Measure::CpuMs.name()
}

fn points_of_ok(results: &[VariantResult], r: &VariantResult) -> Vec<Point> {
    let mut out = Vec::new();
    let hib = |m: Measure| m.direction().higher_is_better();
    push_named(
        &mut out,
        Key::of(Measure::GpuMs).statistic("median").render(),
        gpu_ms(r),
        hib(Measure::GpuMs),
    );
    push_named(
        &mut out,
        Key::of(Measure::CpuMs).statistic("median").render(),
        Some(r.cpu_frame_ms.median),
        hib(Measure::CpuMs),
    );
    for p in &r.passes {
        push_named(
            &mut out,
            Key::of(Measure::GpuMs)
                .pass(&p.name)
                .statistic("median")
                .render(),
            p.gpu_ms.map(|g| g.median),
            hib(Measure::GpuMs),
        );
    }
    push_named(
        &mut out,
        Measure::AllocatedBytes.store_key(),
        Some(r.allocated_bytes as f64),
        hib(Measure::AllocatedBytes),
    );
    if r.technique != DEFAULT_BASELINE {
        push_named(
            &mut out,
            Measure::Speedup.store_key(),
            speedup(results, r, DEFAULT_BASELINE),
            hib(Measure::Speedup),
        );
    }
    for m in &r.metrics {
        let measure = Measure::from_name(&m.name).filter(|x| x.is_metric());
        let dir = measure.map_or(m.higher_is_better, hib);
        // A metric this table does not know yet is stored under its own name.
        let key = measure.map_or_else(|| m.name.clone(), |x| x.name().to_string());
        push_named(&mut out, key, Some(m.value), dir);
    }
    push_named(
        &mut out,
        Measure::EnergyMj.store_key(),
        energy_mj(r),
        hib(Measure::EnergyMj),
    );
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_baseline_naming_a_variant_is_found_by_name_else_by_technique() {
        let result = VariantResult::timed;
        let (plain, motion, twox2) = (
            result("native", &[2.0]),
            result("native[motion_pass=true]", &[2.5]),
            result("checkerboard-2x2", &[2.0]),
        );
        let results = vec![twox2, plain, motion];
        let by_name = baseline_of(&results, "native[motion_pass=true]").unwrap();
        assert_eq!(by_name.variant, "native[motion_pass=true]");
        assert_eq!(baseline_of(&results, "native").unwrap().variant, "native");
        // Without that variant the named baseline is missing, not silently plain native.
        assert!(baseline_of(&results[..2], "native[motion_pass=true]").is_none());
    }

    #[test]
    fn names_are_unique_and_round_trip() {
        let mut seen = std::collections::BTreeSet::new();
        for &m in Measure::ALL {
            assert!(seen.insert(m.name()), "{} twice", m.name());
            for a in m.info().aliases {
                assert!(seen.insert(a), "alias {a} twice");
                assert_eq!(Measure::from_name(a), Some(m));
            }
            assert_eq!(Measure::from_name(m.name()), Some(m));
            assert_eq!(Key::parse(m.name()), Some(Key::of(m)));
            assert_eq!(Key::parse(&m.store_key()).unwrap().measure, m);
            assert!(!m.label().is_empty());
        }
    }

    #[test]
    fn keys_with_passes_statistics_and_baselines_round_trip() {
        for key in [
            "gpu_ms.median",
            "gpu_ms.p5",
            "gpu_ms.median_ci95.low",
            "pass.scene.gpu_ms.median",
            "pass.reconstruct.fragment_invocations",
            "pass.a.b.gpu_ms.median",
            "speedup.native-deferred",
            "temperature_c.max",
            "pacing.even_ms.median",
            "gpu_ms.precision",
        ] {
            let k = Key::parse(key).unwrap_or_else(|| panic!("{key} does not parse"));
            assert_eq!(k.render(), key);
        }
        let k = Key::parse("pass.reconstruct.gpu_ms.median").unwrap();
        assert_eq!(k.measure, Measure::GpuMs);
        assert_eq!(k.pass.as_deref(), Some("reconstruct"));
        assert_eq!(k.label(), "reconstruct");
        assert_eq!(Key::parse("gpu_ms.median").unwrap().label(), "GPU ms");
        assert_eq!(Key::parse("gpu_ms.p95").unwrap().label(), "GPU ms p95");
        assert_eq!(
            Key::parse("speedup.native-deferred").unwrap().label(),
            "speedup over native-deferred"
        );
        assert_eq!(
            Key::parse("non-finite").unwrap().render(),
            "non_finite_values"
        );
        for bad in [
            "",
            "gpu",
            "pass.",
            "pass.x",
            "psnr.median",
            "speedup.",
            "cpu_ms.p7",
        ] {
            assert_eq!(Key::parse(bad), None, "{bad}");
        }
    }

    #[test]
    fn technique_checks_carry_their_unit_and_direction() {
        let record = |name: &str, check: Option<crate::Check>| MetricRecord {
            name: name.into(),
            per_frame: vec![1.0],
            frames: vec![0],
            value: 1.0,
            higher_is_better: false,
            frame_stats: None,
            metrics_device: None,
            check,
        };
        // No technique's check is a measure of the table.
        assert_eq!(Measure::from_name("shading-rate"), None);
        let own = record(
            "invocations-over-model",
            Some(crate::Check {
                unit: "x".into(),
                direction: Direction::Neither,
            }),
        );
        assert_eq!(metric_unit(&own), "x");
        assert_eq!(metric_direction(&own), Direction::Neither);
        let psnr = record("psnr", None);
        assert_eq!(metric_unit(&psnr), "dB");
        assert_eq!(metric_direction(&psnr), Direction::HigherIsBetter);
        assert_eq!(metric_unit(&record("a-new-metric", None)), "");
        let json = serde_json::to_string(&own).unwrap();
        assert!(
            json.contains(r#""check":{"unit":"x","direction":"neither"}"#),
            "{json}"
        );
        assert_eq!(serde_json::from_str::<MetricRecord>(&json).unwrap(), own);
    }

    #[test]
    fn directions_are_the_ones_the_pages_promise() {
        use Direction::*;
        for (name, dir) in [
            ("gpu_ms", LowerIsBetter),
            ("speedup", HigherIsBetter),
            ("psnr", HigherIsBetter),
            ("ssim", HigherIsBetter),
            ("flip", LowerIsBetter),
            ("tde", LowerIsBetter),
            ("cvvdp", HigherIsBetter),
            ("cvvdp-transient-share", LowerIsBetter),
            ("energy_mj", LowerIsBetter),
            ("energy_saving", HigherIsBetter),
            ("allocated_bytes", LowerIsBetter),
        ] {
            assert_eq!(direction_of(name), Some(dir), "{name}");
        }
        assert_eq!(
            direction_of("pass.scene.gpu_ms.median"),
            Some(LowerIsBetter)
        );
        assert_eq!(
            direction_of("speedup.native-deferred"),
            Some(HigherIsBetter)
        );
    }

    #[test]
    fn no_perf_results_have_no_timing_series() {
        assert!(is_timing_key("gpu_ms.median"));
        assert!(is_timing_key("pass.reconstruct.gpu_ms.median"));
        assert!(is_timing_key("cpu_ms.median"));
        assert!(is_timing_key("speedup"));
        assert!(!is_timing_key("psnr"));
        assert!(!is_timing_key("allocated_bytes"));
        assert!(!is_timing_key("pass.gpu_ms_like.psnr"));
    }
}
