//! Conditions, sampling and pacing through the run loop on the default adapter (lavapipe in CI):
//! the "not available" path of a CPU adapter, `measured = "auto"` ending at its cap, pacing and its
//! CSV columns, and a fake vendor source whose throttled samples flag the result and fail a gate.

mod common;

use tessera::conditions::{ConditionSource, DeviceLimits, Sample, Sensors, ThrottleReason};
use tessera::run::{self, Options};
use tessera_results::conditions::{
    Conditions, DeviceConditions, EnergyMethod, SamplingMode, StopReason,
};
use tessera_results::{GateLevel, RunInfo, Status};

/// TINY with `frames` and gates replaced, native and checkerboard.
fn scenario_src(frames: &str, gates: &str) -> String {
    common::TINY.replace("warmup = 1\nmeasured = 2\n", frames)
        + "[[techniques]]\ntechnique = \"checkerboard\"\n"
        + gates
}

fn options(out: &std::path::Path, junit: bool) -> Options {
    Options {
        adapter: None,
        out: out.to_path_buf(),
        junit: junit.then(|| out.join("junit.xml")),
        progress: false,
        command_line: vec!["tessera".into(), "test".into()],
        suite: None,
        branch: None,
        timings: false,
        expectations: Default::default(),
        slow: false,
        adapter_class: None,
    }
}

fn run_json(run_dir: &std::path::Path) -> RunInfo {
    serde_json::from_str(&std::fs::read_to_string(run_dir.join("run.json")).unwrap()).unwrap()
}

#[test]
fn cpu_adapter_records_not_available_and_pacing() {
    let gpu = common::gpu();
    assert_eq!(gpu.info.device_type, "cpu", "these tests expect lavapipe");
    let s = common::scenario(&scenario_src("warmup = 1\nmeasured = 7\n", ""));
    let out = tempfile::tempdir().unwrap();
    let outcome = run::run_on(&gpu, &[s], &options(out.path(), false)).unwrap();

    let reason = match run_json(&outcome.run_dir).conditions {
        Some(DeviceConditions::NotAvailable { reason }) => reason,
        other => panic!("expected not-available, got {other:?}"),
    };
    assert!(
        reason.ends_with("is a CPU adapter: it has no GPU clocks, temperature or power sensors"),
        "{reason}"
    );
    let results = &outcome.scenarios[0].results;
    for r in results {
        assert_eq!(r.status, Status::Ok, "{}", r.variant);
        assert_eq!(
            r.conditions,
            Some(Conditions::NotAvailable {
                reason: reason.clone()
            })
        );
        let sampling = r.sampling.unwrap();
        assert_eq!(sampling.mode, SamplingMode::Fixed);
        assert_eq!((sampling.frames, sampling.ended_by), (7, StopReason::Count));
        assert!(sampling.precision.is_some(), "7 frames have an interval");
        let ci = r.gpu_frame_ms.unwrap().median_ci95.unwrap();
        assert!(ci[0] <= r.gpu_frame_ms.unwrap().median && r.gpu_frame_ms.unwrap().median <= ci[1]);
        let pacing = r.pacing.unwrap();
        assert!(pacing.p95_over_p50 >= 1.0);
        assert!(pacing.mean_abs_delta_ms >= 0.0);
    }
    // Checkerboard alternates parities: its pacing reports them apart; native's does not.
    assert!(results[0].pacing.unwrap().parity.is_none());
    let parity = results[1].pacing.unwrap().parity.unwrap();
    assert!(parity.even_median_ms > 0.0 && parity.odd_median_ms > 0.0);

    let csv = std::fs::read_to_string(outcome.run_dir.join("results.csv")).unwrap();
    let measures: Vec<(&str, &str)> = csv
        .lines()
        .filter(|l| l.contains(",checkerboard,"))
        .map(|l| {
            // From the end: the adapter's name may hold a quoted comma.
            let f: Vec<&str> = l.rsplitn(4, ',').collect();
            (f[2], f[0])
        })
        .collect();
    for (m, unit) in [
        ("measured_frames", "count"),
        ("gpu_ms.median_ci95.low", "ms"),
        ("gpu_ms.precision", "ratio"),
        ("pacing.p95_over_p50", "x"),
        ("pacing.mean_abs_delta_ms", "ms"),
        ("pacing.even_ms.median", "ms"),
        ("pacing.odd_ms.median", "ms"),
        ("pacing.even_over_odd", "x"),
    ] {
        assert!(measures.contains(&(m, unit)), "{m} missing: {csv}");
    }
    assert!(
        !csv.contains("energy_mj") && !csv.contains("throttled"),
        "{csv}"
    );
}

#[test]
fn auto_sampling_stops_at_its_cap_and_metrics_keep_min_frames() {
    let gpu = common::gpu();
    // A precision no real timing meets: the cap ends every variant.
    let s = common::scenario(&scenario_src(
        "warmup = 1\nmeasured = { min = 6, max = 11, precision = 1e-12 }\n",
        "",
    ));
    assert_eq!(s.measured_frames, 6);
    let out = tempfile::tempdir().unwrap();
    let outcome = run::run_on(&gpu, &[s], &options(out.path(), false)).unwrap();
    let scenario = &outcome.scenarios[0];
    assert_eq!(scenario.measured_frames, 6);
    for r in &scenario.results {
        let sampling = r.sampling.unwrap();
        assert_eq!(sampling.mode, SamplingMode::Auto);
        assert_eq!((sampling.frames, sampling.ended_by), (11, StopReason::Cap));
        assert_eq!((sampling.min, sampling.max), (Some(6), Some(11)));
        assert!(sampling.precision.unwrap() > 1e-12);
        assert_eq!(r.gpu_frame_ms.unwrap().count, 11, "{}", r.variant);
        assert!(r.passes.iter().all(|p| p.samples_ms.len() == 11));
        let psnr = r.metrics.iter().find(|m| m.name == "psnr").unwrap();
        assert_eq!(psnr.per_frame.len(), 6, "metrics use the first min frames");
        // The timed phase's frame 6 was copied aside and equals the capture's.
        assert_eq!(r.stability.as_ref().unwrap().deterministic, Some(true));
    }
}

/// A throttled fake GPU (half its maximum clock, a thermal limit on every other read) whose
/// energy counter reads 5 W and, like an H200's, steps every 100 ms: 500 mJ per 100 ms since it
/// was made, whatever the sampling period.
struct Throttled {
    reads: u32,
    since: std::time::Instant,
}

impl ConditionSource for Throttled {
    fn limits(&self) -> DeviceLimits {
        DeviceLimits {
            source: "fake",
            device: "fake vendor GPU".into(),
            max_graphics_clock_mhz: Some(2000.0),
            max_memory_clock_mhz: Some(2600.0),
            energy_counter: true,
        }
    }

    fn sample(&mut self) -> Sample {
        self.reads += 1;
        Sample {
            at_s: 0.0,
            graphics_clock_mhz: Some(1000.0),
            memory_clock_mhz: Some(2600.0),
            temperature_c: Some(87.0),
            power_w: Some(350.0),
            energy_mj: Some(500.0 * (self.since.elapsed().as_secs_f64() * 10.0).floor()),
            throttle_reasons: if self.reads & 1 == 0 {
                vec![ThrottleReason::SwThermalSlowdown]
            } else {
                vec![]
            },
        }
    }
}

#[test]
fn a_throttled_sample_is_flagged_and_fails_its_gate() {
    let gpu = common::gpu();
    let gates = "[[gates]]\nmeasure = \"throttled\"\nfail_above = 0.5\n";
    let s = common::scenario(&scenario_src("warmup = 1\nmeasured = 4\n", gates));
    let out = tempfile::tempdir().unwrap();
    let sensors = Sensors::from_source(Ok(Box::new(Throttled {
        reads: 0,
        since: std::time::Instant::now(),
    })));
    let outcome = run::run_with_sensors(&gpu, &[s], &options(out.path(), true), &sensors).unwrap();

    match run_json(&outcome.run_dir).conditions {
        Some(DeviceConditions::Available(d)) => {
            assert_eq!(d.source, "fake");
            assert_eq!(d.max_graphics_clock_mhz, Some(2000.0));
            assert_eq!(d.throttle_clock_fraction, 0.75);
        }
        other => panic!("expected available, got {other:?}"),
    }
    let results = &outcome.scenarios[0].results;
    for r in results {
        let c = r.conditions.as_ref().unwrap().recorded().unwrap();
        assert!(c.samples >= 2, "one sample at each end of the window");
        assert_eq!(c.graphics_clock_mhz.unwrap().max, 1000.0);
        assert!(c.throttled);
        assert!(c.throttle_causes[0]
            .starts_with("graphics clock fell to 1000 MHz, below 75% of the maximum 2000 MHz, in"));
        assert_eq!(c.throttle_reasons, vec!["sw-thermal-slowdown"]);
        // Energy over the window that follows the measured frames (sampled every millisecond):
        // it ends at the first frame after the counter's third step (200 ms at the least), and
        // at the latest when the frames still in flight at the 500 ms cap have drained (up to
        // MAX_PENDING_FRAMES of them, plus a sampler tick: a frame on a loaded CPU adapter can
        // take 200 ms, so the bound is in frames, not milliseconds; CI once read 519.6 ms at
        // 9.6 ms a frame); the counter reads 5 W.
        let e = c.energy.unwrap();
        assert_eq!(e.method, EnergyMethod::Counter);
        assert!(e.frames > 0, "{e:?}");
        let frame_ms = e.window_ms / f64::from(e.frames);
        assert!(
            e.window_ms >= 190.0 && e.window_ms <= 500.0 + 4.0 * frame_ms + 10.0,
            "{e:?}"
        );
        let watts = e.mj_per_frame * f64::from(e.frames) / e.window_ms;
        assert!((3.0..8.0).contains(&watts), "{watts} W from {e:?}");
    }
    // The gate applies to checkerboard (native is the reference) and fails on the flag.
    let cb = &results[1];
    assert_eq!(cb.gates.len(), 1);
    assert_eq!(cb.gates[0].level, GateLevel::Fail);
    assert_eq!(
        cb.gates[0].message,
        "throttled = 1.0000 is above 0.5: fails"
    );

    let junit = std::fs::read_to_string(out.path().join("junit.xml")).unwrap();
    assert!(
        junit.contains("<failure message=\"throttled = 1.0000 is above 0.5: fails\"/>"),
        "{junit}"
    );
    assert!(
        junit.contains("<system-out>throttled: graphics clock fell to 1000 MHz"),
        "{junit}"
    );
    let csv = std::fs::read_to_string(outcome.run_dir.join("results.csv")).unwrap();
    assert!(csv.contains(",checkerboard,checkerboard,"), "{csv}");
    assert!(
        csv.lines()
            .any(|l| l.contains(",checkerboard,") && l.ends_with(",throttled,1,bool")),
        "{csv}"
    );
    assert!(csv.lines().any(|l| l.contains(",energy_saving,")), "{csv}");
    assert!(
        csv.lines()
            .any(|l| l.contains(",graphics_clock_mhz.min,1000,MHz")),
        "{csv}"
    );
    let table = tessera::run::console::scenario_table(&outcome.scenarios[0]);
    assert!(
        table.contains(
            "  conditions: checkerboard: clock 1000 MHz (min 1000), 87-87 C, 350 W median"
        ),
        "{table}"
    );
    assert!(table.contains("THROTTLED"), "{table}");
    let hints = tessera::run::console::throttle_hints(&outcome.scenarios[0]);
    assert_eq!(hints.len(), 2);
    assert!(
        hints[0].contains("was throttled during its measured frames"),
        "{}",
        hints[0]
    );
}
