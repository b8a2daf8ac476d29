//! The conditions a timing was taken in, and what the timings say beyond their median: the device's
//! clocks, temperature, power and energy per frame during a result's measured frames, whether it
//! was throttled, how the number of measured frames was chosen (`measured = "auto"`), and the
//! frame-time stability (pacing) of its per-frame samples.
//!
//! Record types and their meaning only (`results/README.md`, "Conditions", "Sampling",
//! "Pacing"); sampling the sensors and computing the figures is the harness's job.

use serde::{Deserialize, Serialize};

/// Fraction of the device's maximum graphics clock below which a sample counts as throttled
/// (nvbench flags samples below 75% of the default clock).
pub const THROTTLE_CLOCK_FRACTION: f64 = 0.75;

/// The device's sensors as the run saw them (`run.json`, `conditions`).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(tag = "state", rename_all = "kebab-case")]
pub enum DeviceConditions {
    /// A vendor library or sysfs exposed the adapter's sensors.
    Available(DeviceSensors),
    /// Nothing to read on this adapter or platform, and why (a CPU adapter, no vendor library,
    /// no readable hwmon folder, no PCI ids to match a sensor device with).
    NotAvailable { reason: String },
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct DeviceSensors {
    /// `nvml` or `hwmon`.
    pub source: String,
    /// The sensor device's own name (NVML's name, or the sysfs card folder).
    pub device: String,
    /// Highest graphics (SM) clock the device can run at; `None` when the source cannot say.
    pub max_graphics_clock_mhz: Option<f64>,
    pub max_memory_clock_mhz: Option<f64>,
    /// The device has a total-energy counter (NVML on Volta and later, `energy1_input` on hwmon):
    /// energy per frame is a difference of that counter, otherwise power integrated over time.
    pub energy_counter: bool,
    /// Period of the sampling thread, in milliseconds.
    pub sample_interval_ms: f64,
    /// [`THROTTLE_CLOCK_FRACTION`] as used by this run.
    pub throttle_clock_fraction: f64,
}

/// One result's conditions during its measured frames (`VariantResult::conditions`).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(tag = "state", rename_all = "kebab-case")]
pub enum Conditions {
    Recorded(Box<RecordedConditions>),
    NotAvailable { reason: String },
}

impl Conditions {
    pub fn recorded(&self) -> Option<&RecordedConditions> {
        match self {
            Conditions::Recorded(r) => Some(r.as_ref()),
            Conditions::NotAvailable { .. } => None,
        }
    }
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct RecordedConditions {
    pub source: String,
    /// Sensor samples taken from the first to the last measured frame (one at each end, then
    /// one per sampling period in between).
    pub samples: u32,
    /// Wall time from the completion of the last warm-up frame to the completion of the last
    /// measured frame: the window the samples and the energy cover.
    pub window_ms: f64,
    /// Each `None` when the source cannot read it.
    pub graphics_clock_mhz: Option<Spread>,
    pub memory_clock_mhz: Option<Spread>,
    pub temperature_c: Option<Spread>,
    pub power_w: Option<Spread>,
    /// Every clock-limiting reason the device reported in any sample, kebab-case
    /// (`sw-power-cap`, `hw-thermal-slowdown`, ...), sorted, without `gpu-idle`.
    pub throttle_reasons: Vec<String>,
    pub energy: Option<Energy>,
    /// A sample's graphics clock fell below `throttle_clock_fraction` of the maximum, or a
    /// thermal or power limit was reported.
    pub throttled: bool,
    /// Why `throttled` is true, one sentence each; empty otherwise.
    pub throttle_causes: Vec<String>,
    /// How long the clock warm-up before the timed frames lasted, in milliseconds: `warmup_ms`,
    /// or less where the sensors saw the top graphics clock sooner. Absent in older results.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub clock_warmup_ms: Option<f64>,
}

/// Minimum, median and maximum of one sensor over a result's samples.
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq)]
pub struct Spread {
    pub min: f64,
    pub median: f64,
    pub max: f64,
}

impl Spread {
    /// `None` without values.
    pub fn of(values: &[f64]) -> Option<Spread> {
        let s = crate::Summary::of(values)?;
        Some(Spread {
            min: s.min,
            median: s.median,
            max: s.max,
        })
    }
}

#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq)]
pub struct Energy {
    /// Energy of the energy window (frames that continue the measured ones, 500 ms by default)
    /// divided by its frames, in millijoules.
    pub mj_per_frame: f64,
    pub method: EnergyMethod,
    /// Frames the window holds.
    pub frames: u32,
    /// Length of the energy window, in milliseconds.
    pub window_ms: f64,
}

#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum EnergyMethod {
    /// The device's total-energy counter: the mean power between its first and last updates in
    /// the window, times the window.
    Counter,
    /// Power samples integrated over the window (trapezoids between consecutive samples).
    PowerTimesTime,
}

/// How a result's number of measured frames was decided (`VariantResult::sampling`).
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq)]
pub struct Sampling {
    /// `fixed` (`frames.measured = N`) or `auto`.
    pub mode: SamplingMode,
    /// Timed measured frames (for `auto` between `min` and `max`).
    pub frames: u32,
    /// `auto` only: the bounds and the target relative half-width of the median's 95% interval.
    pub min: Option<u32>,
    pub max: Option<u32>,
    pub target_precision: Option<f64>,
    /// `auto` only: the wall-time cap in seconds.
    pub timeout_s: Option<f64>,
    /// Relative half-width of the median's 95% confidence interval of the GPU frame time when
    /// sampling stopped; `None` with too few frames for an interval (fewer than 6).
    pub precision: Option<f64>,
    pub ended_by: StopReason,
}

#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum SamplingMode {
    Fixed,
    Auto,
}

#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum StopReason {
    /// The fixed count was rendered.
    Count,
    /// `auto`: the target precision was met (after at least `min` frames).
    Precision,
    /// `auto`: `max` frames were rendered before the target was met.
    Cap,
    /// `auto`: the measured frames took `timeout_s` before the target was met.
    Timeout,
}

/// Frame-time stability of a result's per-frame GPU times (`VariantResult::pacing`).
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq)]
pub struct Pacing {
    /// 95th percentile over median: 1 for perfectly even frames.
    pub p95_over_p50: f64,
    /// Mean of |t[i] - t[i-1]| over consecutive measured frames, in milliseconds.
    pub mean_abs_delta_ms: f64,
    /// `mean_abs_delta_ms` over the median.
    pub mean_abs_delta_rel: f64,
    /// Techniques that alternate frame parities (checkerboarding): the figures of even and odd
    /// frames (scenario frame index) apart; `None` for the others.
    pub parity: Option<ParityPacing>,
}

#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq)]
pub struct ParityPacing {
    pub even_median_ms: f64,
    pub odd_median_ms: f64,
    /// Median of the even frames over that of the odd frames.
    pub even_over_odd: f64,
    pub even_p95_over_p50: f64,
    pub odd_p95_over_p50: f64,
}

/// The distribution-free 95% confidence interval of the median of `samples` (order statistics
/// of ranks n/2 ± 1.96·√n/2, the normal approximation of the binomial): `(low, high)`. `None`
/// with fewer than 6 samples, where those ranks fall outside the sample.
pub fn median_ci95(samples: &[f64]) -> Option<(f64, f64)> {
    let n = samples.len();
    let half = 1.959_964 * (n as f64).sqrt() / 2.0;
    let lo = (n as f64 / 2.0 - half).round();
    let hi = (1.0 + n as f64 / 2.0 + half).round();
    if lo < 1.0 || hi > n as f64 {
        return None;
    }
    let mut sorted = samples.to_vec();
    sorted.sort_by(|a, b| a.total_cmp(b));
    Some((sorted[lo as usize - 1], sorted[hi as usize - 1]))
}

/// Half the width of [`median_ci95`] over the median: the relative precision of the median.
/// `None` without an interval or with a median of zero.
pub fn median_precision(samples: &[f64]) -> Option<f64> {
    let (lo, hi) = median_ci95(samples)?;
    let median = crate::Summary::of(samples)?.median;
    (median > 0.0).then(|| (hi - lo) / 2.0 / median)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn median_interval_ranks() {
        // n = 10: ranks round(5 - 3.099) = 2 and round(6 + 3.099) = 9.
        let s: Vec<f64> = (1..=10).map(f64::from).collect();
        assert_eq!(median_ci95(&s), Some((2.0, 9.0)));
        // n = 100: ranks 40 and 61 (Conover's table for 95%).
        let s: Vec<f64> = (1..=100).map(f64::from).collect();
        assert_eq!(median_ci95(&s), Some((40.0, 61.0)));
        assert_eq!(median_ci95(&[1.0, 2.0, 3.0, 4.0, 5.0]), None);
        assert!(median_ci95(&[1.0; 6]).is_some());
        let p = median_precision(&s).unwrap();
        assert!((p - 10.5 / 50.5).abs() < 1e-12, "{p}");
    }

    #[test]
    fn tagged_records_round_trip() {
        let c = Conditions::NotAvailable {
            reason: "a CPU adapter".into(),
        };
        let json = serde_json::to_string(&c).unwrap();
        assert_eq!(
            json,
            r#"{"state":"not-available","reason":"a CPU adapter"}"#
        );
        let r = Conditions::Recorded(Box::new(RecordedConditions {
            source: "nvml".into(),
            samples: 3,
            window_ms: 40.0,
            graphics_clock_mhz: Spread::of(&[1980.0, 1900.0, 1980.0]),
            memory_clock_mhz: None,
            temperature_c: None,
            power_w: None,
            throttle_reasons: vec!["sw-power-cap".into()],
            energy: Some(Energy {
                mj_per_frame: 2.5,
                method: EnergyMethod::PowerTimesTime,
                frames: 10,
                window_ms: 1000.0,
            }),
            throttled: true,
            throttle_causes: vec!["power cap".into()],
            clock_warmup_ms: None,
        }));
        let json = serde_json::to_string(&r).unwrap();
        assert!(
            json.starts_with(r#"{"state":"recorded","source":"nvml""#),
            "{json}"
        );
        assert!(json.contains(r#""method":"power-times-time""#), "{json}");
        assert_eq!(serde_json::from_str::<Conditions>(&json).unwrap(), r);
    }
}
