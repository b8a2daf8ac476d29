//! A window of sensor samples as one result's record: min / median / max per sensor, the energy
//! per frame, and whether the result was throttled. Pure functions of the samples.
//!
//! - **Energy per frame**: the difference of the device's total-energy counter between the
//!   window's first and last samples, over the window's frames. Without a counter, or when it did
//!   not move during the window (short windows: the counter updates less often than the sampling
//!   thread reads it), the power samples are integrated over time instead (trapezoids between
//!   consecutive samples, [`super::SAMPLE_INTERVAL_MS`] apart, plus the two samples at the
//!   window's ends).
//! - **Throttled**: a sample's graphics clock below [`THROTTLE_CLOCK_FRACTION`] of the device's
//!   maximum graphics clock (nvbench flags samples below 75% of the default clock), or a thermal
//!   or power limit among the reported clock-limiting reasons.

use tessera_results::conditions::{
    Energy, EnergyMethod, RecordedConditions, Spread, THROTTLE_CLOCK_FRACTION,
};

use super::{DeviceLimits, Sample, ThrottleReason};

/// The record of one window of `frames` frames.
pub fn summarise(samples: &[Sample], limits: &DeviceLimits, frames: u32) -> RecordedConditions {
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
        energy: energy(samples, frames),
        throttled: !throttle_causes.is_empty(),
        throttle_causes,
    }
}

fn window_s(samples: &[Sample]) -> f64 {
    match (samples.first(), samples.last()) {
        (Some(a), Some(b)) => (b.at_s - a.at_s).max(0.0),
        _ => 0.0,
    }
}

/// Energy per frame of the window; `None` without frames, or without a moving counter and at
/// least two power samples spanning some time.
pub fn energy(samples: &[Sample], frames: u32) -> Option<Energy> {
    if frames == 0 {
        return None;
    }
    let counter = samples.first().and_then(|a| {
        let b = samples.last()?;
        Some(b.energy_mj? - a.energy_mj?)
    });
    if let Some(mj) = counter.filter(|mj| *mj > 0.0) {
        return Some(Energy {
            mj_per_frame: mj / f64::from(frames),
            method: EnergyMethod::Counter,
            frames,
        });
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
    (span > 0.0).then(|| Energy {
        mj_per_frame: joules * 1000.0 / f64::from(frames),
        method: EnergyMethod::PowerTimesTime,
        frames,
    })
}

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
    fn spreads_and_counter_energy() {
        let s = [
            sample(0.0, 1980.0, 300.0, Some(1_000.0)),
            sample(0.02, 1965.0, 320.0, Some(1_006.0)),
            sample(0.04, 1980.0, 310.0, Some(1_012.0)),
        ];
        let r = summarise(&s, &limits(), 10);
        assert_eq!(r.samples, 3);
        assert!((r.window_ms - 40.0).abs() < 1e-9);
        let clock = r.graphics_clock_mhz.unwrap();
        assert_eq!(
            (clock.min, clock.median, clock.max),
            (1965.0, 1980.0, 1980.0)
        );
        assert_eq!(r.power_w.unwrap().median, 310.0);
        let e = r.energy.unwrap();
        assert_eq!(e.method, EnergyMethod::Counter);
        assert!((e.mj_per_frame - 1.2).abs() < 1e-12);
        assert!(!r.throttled);
        assert!(r.throttle_causes.is_empty());
    }

    #[test]
    fn power_times_time_without_a_moving_counter() {
        // The counter did not update within the window: 0.1 s at 300 then 400 W.
        let s = [
            sample(0.0, 1980.0, 300.0, Some(5.0)),
            sample(0.1, 1980.0, 400.0, Some(5.0)),
        ];
        let e = energy(&s, 7).unwrap();
        assert_eq!(e.method, EnergyMethod::PowerTimesTime);
        // 35 J over 7 frames.
        assert!((e.mj_per_frame - 5000.0).abs() < 1e-9, "{}", e.mj_per_frame);
        let no_counter = [sample(0.0, 1.0, 300.0, None), sample(0.1, 1.0, 400.0, None)];
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
        let r = summarise(&s, &limits(), 3);
        assert!(r.throttled);
        assert_eq!(
            r.throttle_causes,
            vec!["graphics clock fell to 1400 MHz, below 75% of the maximum 2000 MHz, in 1 of 3 samples"]
        );
        // At 1500 MHz, exactly 75%: not below.
        s[1].graphics_clock_mhz = Some(1500.0);
        assert!(!summarise(&s, &limits(), 3).throttled);
        // Idle and application-clock reasons are recorded but flag nothing; a thermal limit does.
        s[0].throttle_reasons = vec![
            ThrottleReason::GpuIdle,
            ThrottleReason::ApplicationsClocksSetting,
        ];
        let r = summarise(&s, &limits(), 3);
        assert!(!r.throttled);
        assert_eq!(r.throttle_reasons, vec!["applications-clocks-setting"]);
        s[2].throttle_reasons = vec![ThrottleReason::SwThermalSlowdown];
        let r = summarise(&s, &limits(), 3);
        assert!(r.throttled);
        assert_eq!(
            r.throttle_causes,
            vec!["the device reported sw-thermal-slowdown in 1 of 3 samples"]
        );
    }
}
