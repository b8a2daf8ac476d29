//! Windows of sensor samples as one result's record: min / median / max per sensor over the
//! measured frames, whether they were throttled, and the energy per frame over the energy window.
//! Pure functions of the samples.
//!
//! - **Energy per frame** (over the energy window, [`super::ENERGY_WINDOW_MS`] of frames that
//!   continue the measured ones): the device's total-energy counter moves in steps (on an H200
//!   about every 100 ms, by some 13 J under load), so the difference of its values at the window's
//!   ends is off by up to a step. The steps are located instead: the first sample showing each new
//!   counter value marks an update (to within one sampling period); the energy between the first
//!   and the last update over the time between them is the mean power, and the mean power times
//!   the window over its frames is the energy per frame. With fewer than two updates, or without
//!   a counter, the power samples are integrated over the window (trapezoids between consecutive
//!   samples).
//! - **Throttled**: a sample's graphics clock below [`THROTTLE_CLOCK_FRACTION`] of the device's
//!   maximum graphics clock (nvbench flags samples below 75% of the default clock), or a thermal
//!   or power limit among the reported clock-limiting reasons.

use tessera_results::conditions::{
    Energy, EnergyMethod, RecordedConditions, Spread, THROTTLE_CLOCK_FRACTION,
};

use super::{DeviceLimits, Sample, ThrottleReason};

/// The record of a result: `samples` over its measured frames, and the energy window's samples
/// and frame count where there was one.
pub fn summarise(
    samples: &[Sample],
    limits: &DeviceLimits,
    energy_window: Option<(&[Sample], u32)>,
) -> RecordedConditions {
    let spread = |f: fn(&Sample) -> Option<f64>| {
        let values: Vec<f64> = samples.iter().filter_map(f).collect();
        Spread::of(&values)
    };
    let mut reasons: Vec<ThrottleReason> = samples
        .iter()
        .flat_map(|s| s.throttle_reasons.iter().copied())
        .filter(|r| *r != ThrottleReason::GpuIdle)
        .collect();
    reasons.sort();
    reasons.dedup();
    let throttle_causes = throttle_causes(samples, limits, THROTTLE_CLOCK_FRACTION);
    RecordedConditions {
        source: limits.source.to_string(),
        samples: samples.len() as u32,
        window_ms: window_s(samples) * 1000.0,
        graphics_clock_mhz: spread(|s| s.graphics_clock_mhz),
        memory_clock_mhz: spread(|s| s.memory_clock_mhz),
        temperature_c: spread(|s| s.temperature_c),
        power_w: spread(|s| s.power_w),
        throttle_reasons: reasons.iter().map(|r| r.name().to_string()).collect(),
        energy: energy_window.and_then(|(s, frames)| energy(s, frames)),
        throttled: !throttle_causes.is_empty(),
        throttle_causes,
        clock_warmup_ms: None,
    }
}

fn window_s(samples: &[Sample]) -> f64 {
    match (samples.first(), samples.last()) {
        (Some(a), Some(b)) => (b.at_s - a.at_s).max(0.0),
        _ => 0.0,
    }
}

/// Energy per frame of a window of `frames` frames; `None` without frames, or with neither two
/// counter updates nor two power samples spanning some time.
pub fn energy(samples: &[Sample], frames: u32) -> Option<Energy> {
    if frames == 0 {
        return None;
    }
    let window_s = window_s(samples);
    let per_frame = |joules: f64, method| Energy {
        mj_per_frame: joules * 1000.0 / f64::from(frames),
        method,
        frames,
        window_ms: window_s * 1000.0,
    };
    // Counter updates: the first sample showing each new value.
    let mut updates: Vec<(f64, f64)> = Vec::new();
    let mut previous: Option<f64> = None;
    for s in samples {
        if let Some(e) = s.energy_mj {
            if previous.is_some_and(|p| p != e) {
                updates.push((s.at_s, e));
            }
            previous = Some(e);
        }
    }
    if let (Some(a), Some(b)) = (updates.first(), updates.last()) {
        if b.0 > a.0 {
            let watts = (b.1 - a.1) / 1000.0 / (b.0 - a.0);
            return Some(per_frame(watts * window_s, EnergyMethod::Counter));
        }
    }
    let power: Vec<(f64, f64)> = samples
        .iter()
        .filter_map(|s| Some((s.at_s, s.power_w?)))
        .collect();
    let joules: f64 = power
        .windows(2)
        .map(|p| (p[1].0 - p[0].0) * (p[0].1 + p[1].1) / 2.0)
        .sum();
    let span = power.last()?.0 - power.first()?.0;
    (span > 0.0).then(|| per_frame(joules, EnergyMethod::PowerTimesTime))
}

/// Whether a window of load ran at the device's top graphics clock throughout: at least one
/// clock reading, every reading at least [`TOP_CLOCK_FRACTION`] of `max_mhz`. What ends the clock
/// warm-up early (`run/frames.rs`). NVML's `gpu-idle` reason is no sign of a cold GPU here: the
/// warm-up's chunks drain the queue, and the sample at a chunk's start reads idle (an H200 at
/// 1980 MHz did in every chunk, so the warm-up never ended early).
pub fn at_top_clock(samples: &[Sample], max_mhz: f64) -> bool {
    let clocks: Vec<f64> = samples
        .iter()
        .filter_map(|s| s.graphics_clock_mhz)
        .collect();
    !clocks.is_empty() && clocks.iter().all(|c| *c >= TOP_CLOCK_FRACTION * max_mhz)
}

/// A clock within 1% of the maximum is the top clock (boost bins are 15 MHz apart).
pub const TOP_CLOCK_FRACTION: f64 = 0.99;

/// Why the window counts as throttled, one sentence per cause; empty when it does not.
pub fn throttle_causes(samples: &[Sample], limits: &DeviceLimits, fraction: f64) -> Vec<String> {
    let mut causes = Vec::new();
    let n = samples.len();
    if let Some(max) = limits.max_graphics_clock_mhz {
        let floor = fraction * max;
        let low: Vec<f64> = samples
            .iter()
            .filter_map(|s| s.graphics_clock_mhz)
            .filter(|c| *c < floor)
            .collect();
        if let Some(lowest) = low.iter().copied().reduce(f64::min) {
            causes.push(format!(
                "graphics clock fell to {lowest:.0} MHz, below {:.0}% of the maximum {max:.0} MHz, in {} of {n} samples",
                fraction * 100.0,
                low.len()
            ));
        }
    }
    let mut limited: Vec<ThrottleReason> = samples
        .iter()
        .flat_map(|s| s.throttle_reasons.iter().copied())
        .filter(|r| r.is_thermal_or_power())
        .collect();
    limited.sort();
    limited.dedup();
    for r in limited {
        let count = samples
            .iter()
            .filter(|s| s.throttle_reasons.contains(&r))
            .count();
        causes.push(format!(
            "the device reported {} in {count} of {n} samples",
            r.name()
        ));
    }
    causes
}

#[cfg(test)]
mod tests {
    use super::*;

    fn limits() -> DeviceLimits {
        DeviceLimits {
            source: "fake",
            device: "fake gpu".into(),
            max_graphics_clock_mhz: Some(2000.0),
            max_memory_clock_mhz: Some(2600.0),
            energy_counter: true,
        }
    }

    fn sample(at_s: f64, clock: f64, power: f64, energy: Option<f64>) -> Sample {
        Sample {
            at_s,
            graphics_clock_mhz: Some(clock),
            memory_clock_mhz: Some(2600.0),
            temperature_c: Some(60.0 + at_s),
            power_w: Some(power),
            energy_mj: energy,
            throttle_reasons: Vec::new(),
        }
    }

    #[test]
    fn the_top_clock_is_every_reading_within_a_percent_of_the_maximum() {
        let at = |clocks: &[f64]| -> Vec<Sample> {
            clocks
                .iter()
                .enumerate()
                .map(|(i, c)| sample(i as f64 * 0.01, *c, 300.0, None))
                .collect()
        };
        assert!(at_top_clock(&at(&[1980.0, 1995.0, 2000.0]), 2000.0));
        // One reading still ramping: not yet.
        assert!(!at_top_clock(&at(&[1410.0, 1980.0, 2000.0]), 2000.0));
        // No clock sensor read: never settled (the warm-up runs its full length).
        let mut none = at(&[2000.0]);
        none[0].graphics_clock_mhz = None;
        assert!(!at_top_clock(&none, 2000.0));
        assert!(!at_top_clock(&[], 2000.0));
        let mut idle = at(&[2000.0, 2000.0]);
        idle[0].throttle_reasons.push(ThrottleReason::GpuIdle);
        assert!(
            at_top_clock(&idle, 2000.0),
            "idle between chunks at the top clock"
        );
    }

    #[test]
    fn spreads_of_the_measured_window() {
        let s = [
            sample(0.0, 1980.0, 300.0, None),
            sample(0.02, 1965.0, 320.0, None),
            sample(0.04, 1980.0, 310.0, None),
        ];
        let r = summarise(&s, &limits(), None);
        assert_eq!(r.samples, 3);
        assert!((r.window_ms - 40.0).abs() < 1e-9);
        let clock = r.graphics_clock_mhz.unwrap();
        assert_eq!(
            (clock.min, clock.median, clock.max),
            (1965.0, 1980.0, 1980.0)
        );
        assert_eq!(r.power_w.unwrap().median, 310.0);
        assert_eq!(r.energy, None, "no energy window");
        assert!(!r.throttled);
        assert!(r.throttle_causes.is_empty());
    }

    #[test]
    fn counter_steps_are_located_not_differenced() {
        // A counter that steps by 20 J every 0.1 s (200 W), read every 0.02 s for 1 s; the steps
        // land at 0.05, 0.15, ... 0.95 s. The ends' difference would read 10 steps (200 J); the
        // located steps give 200 W over the window: 200 J, whatever the phase of the steps.
        let s: Vec<Sample> = (0..=50)
            .map(|i| {
                let t = f64::from(i) * 0.02;
                let steps = ((t + 0.05) / 0.1).floor();
                sample(t, 1980.0, 0.0, Some(20_000.0 * steps))
            })
            .collect();
        let e = energy(&s, 100).unwrap();
        assert_eq!(e.method, EnergyMethod::Counter);
        assert!((e.window_ms - 1000.0).abs() < 1e-9);
        // 200 W x 1 s over 100 frames, to within one sampling period over the steps' span.
        assert!(
            (e.mj_per_frame - 2000.0).abs() < 2000.0 * 0.03,
            "{}",
            e.mj_per_frame
        );
        let r = summarise(&s[..3], &limits(), Some((&s, 100)));
        assert_eq!(r.energy, Some(e));
    }

    #[test]
    fn power_times_time_without_two_counter_steps() {
        // The counter stepped once in the window: 0.1 s at 300 then 400 W instead.
        let s = [
            sample(0.0, 1980.0, 300.0, Some(5.0)),
            sample(0.05, 1980.0, 350.0, Some(9.0)),
            sample(0.1, 1980.0, 400.0, Some(9.0)),
        ];
        let e = energy(&s, 7).unwrap();
        assert_eq!(e.method, EnergyMethod::PowerTimesTime);
        // 35 J over 7 frames.
        assert!((e.mj_per_frame - 5000.0).abs() < 1e-9, "{}", e.mj_per_frame);
        let no_counter: Vec<Sample> = s
            .iter()
            .map(|x| Sample {
                energy_mj: None,
                ..x.clone()
            })
            .collect();
        assert_eq!(energy(&no_counter, 7), Some(e));
        assert_eq!(energy(&s[..1], 7), None, "one sample spans no time");
        assert_eq!(energy(&s, 0), None);
    }

    #[test]
    fn a_low_clock_or_a_thermal_limit_flags_the_window() {
        let mut s = vec![
            sample(0.0, 1980.0, 300.0, None),
            sample(0.02, 1400.0, 300.0, None),
            sample(0.04, 1980.0, 300.0, None),
        ];
        let r = summarise(&s, &limits(), None);
        assert!(r.throttled);
        assert_eq!(
            r.throttle_causes,
            vec!["graphics clock fell to 1400 MHz, below 75% of the maximum 2000 MHz, in 1 of 3 samples"]
        );
        // At 1500 MHz, exactly 75%: not below.
        s[1].graphics_clock_mhz = Some(1500.0);
        assert!(!summarise(&s, &limits(), None).throttled);
        // Idle and application-clock reasons are recorded but flag nothing; a thermal limit does.
        s[0].throttle_reasons = vec![
            ThrottleReason::GpuIdle,
            ThrottleReason::ApplicationsClocksSetting,
        ];
        let r = summarise(&s, &limits(), None);
        assert!(!r.throttled);
        assert_eq!(r.throttle_reasons, vec!["applications-clocks-setting"]);
        s[2].throttle_reasons = vec![ThrottleReason::SwThermalSlowdown];
        let r = summarise(&s, &limits(), None);
        assert!(r.throttled);
        assert_eq!(
            r.throttle_causes,
            vec!["the device reported sw-thermal-slowdown in 1 of 3 samples"]
        );
    }
}
