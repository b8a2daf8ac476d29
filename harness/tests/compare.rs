//! `tessera compare`: the Markdown from records built in code (whole expected strings), and the
//! command's exit codes on run folders written from those records. No GPU needed. The rules are
//! `results/COMPARISON.md`'s; the engine's own cases are in `results/tests/compare.rs`.

use std::path::Path;
use std::process::Command;

use tessera::compare::{self, Options, Run};
use tessera_results::conditions::{Conditions, Energy, EnergyMethod, RecordedConditions};
use tessera_results::{
    AdapterFeatures, AdapterInfo, CommitInfo, GateLevel, GateOutcome, HostInfo, MetricRecord,
    RunInfo, RunStatus, ScenarioResult, Status, VariantResult, SCHEMA_VERSION,
};

fn adapter(name: &str, device_type: &str, driver_info: &str) -> AdapterInfo {
    AdapterInfo {
        name: name.into(),
        vendor: 0x10de,
        device: 0x2330,
        device_type: device_type.into(),
        driver: "NVIDIA".into(),
        driver_info: driver_info.into(),
        backend: "vulkan".into(),
        features: AdapterFeatures::default(),
    }
}

fn gpu() -> AdapterInfo {
    adapter("NVIDIA H100", "discrete-gpu", "580.65")
}

fn run_info(run_id: &str, sha: &str, adapter: AdapterInfo) -> RunInfo {
    RunInfo {
        schema_version: SCHEMA_VERSION,
        run_id: run_id.into(),
        commit: Some(CommitInfo {
            sha: sha.into(),
            dirty: false,
        }),
        commit_time: None,
        started_at: "2026-11-22T03:00:00Z".into(),
        finished_at: Some("2026-11-22T03:01:00Z".into()),
        status: RunStatus::Complete,
        harness_version: "0.1.0".into(),
        adapter,
        host: HostInfo {
            hostname: "ci".into(),
            os: "linux".into(),
            arch: "x86_64".into(),
            cpu_cores: 16,
        },
        command_line: vec!["tessera".into(), "run".into()],
        scenarios: vec!["scenarios/a.toml".into(), "scenarios/b.toml".into()],
        conditions: None,
        suite: Some("scenarios".into()),
        branch: Some("main".into()),
        adapter_class: None,
    }
}

/// Ten frames: `start`, `start + 0.01`, ...
fn frames(start: f64) -> Vec<f64> {
    (0..10).map(|i| start + 0.01 * f64::from(i)).collect()
}

fn metric(name: &str, value: f64, higher_is_better: bool) -> MetricRecord {
    MetricRecord {
        name: name.into(),
        per_frame: vec![value],
        frames: vec![0],
        value,
        higher_is_better,
        frame_stats: None,
        metrics_device: None,
        check: None,
    }
}

/// A variant with one pass timed `samples` and PSNR, SSIM and FLIP as given.
fn variant(name: &str, samples: &[f64], quality: Option<(f64, f64, f64)>) -> VariantResult {
    let mut v = VariantResult::timed(name, samples);
    if let Some((psnr, ssim, flip)) = quality {
        v.reference = Some("native".into());
        v.metrics = vec![
            metric("psnr", psnr, true),
            metric("ssim", ssim, true),
            metric("flip", flip, false),
        ];
    }
    v
}

fn scenario(run_id: &str, name: &str, results: Vec<VariantResult>) -> ScenarioResult {
    ScenarioResult {
        schema_version: SCHEMA_VERSION,
        run_id: run_id.into(),
        scenario: name.into(),
        file: format!("scenarios/{name}.toml"),
        width: 64,
        height: 32,
        warmup_frames: 2,
        measured_frames: 10,
        time_step: 1.0 / 60.0,
        reference: "native".into(),
        results,
        wall_ms: 100.0,
        peak_rss_bytes: None,
        peak_heap_bytes: None,
        reference_digests: Vec::new(),
        reference_noise: None,
    }
}

/// Base run: scenario `a` with native (1.045 ms) and upscale (0.545 ms).
fn base() -> Run {
    Run {
        info: run_info("20261122T030000Z-aaaaaaa", "aaaaaaa000", gpu()),
        scenarios: vec![scenario(
            "20261122T030000Z-aaaaaaa",
            "a",
            vec![
                variant("native", &frames(1.0), Some((f64::INFINITY, 1.0, 0.0))),
                variant("upscale", &frames(0.5), Some((30.0, 0.9, 0.1))),
            ],
        )],
    }
}

const B_ID: &str = "20261122T040000Z-bbbbbbb";

/// `v` with sensors that recorded `mj` millijoules per frame, throttled or not.
fn with_energy(mut v: VariantResult, mj: f64, throttled: bool) -> VariantResult {
    v.conditions = Some(Conditions::Recorded(Box::new(RecordedConditions {
        source: "nvml".into(),
        samples: 3,
        window_ms: 40.0,
        graphics_clock_mhz: None,
        memory_clock_mhz: None,
        temperature_c: None,
        power_w: None,
        throttle_reasons: vec![],
        energy: Some(Energy {
            mj_per_frame: mj,
            method: EnergyMethod::Counter,
            frames: 10,
            window_ms: 1000.0,
        }),
        throttled,
        throttle_causes: if throttled {
            vec!["the device reported sw-thermal-slowdown in 2 of 3 samples".into()]
        } else {
            vec![]
        },
        clock_warmup_ms: None,
    })));
    v
}

#[test]
fn energy_per_frame_and_throttled_results_are_reported() {
    let mut a = base();
    let r = &mut a.scenarios[0].results;
    r[0] = with_energy(r[0].clone(), 4.0, false);
    r[1] = with_energy(r[1].clone(), 2.0, false);
    let b = Run {
        info: run_info(B_ID, "bbbbbbb000", gpu()),
        scenarios: vec![scenario(
            B_ID,
            "a",
            vec![
                with_energy(
                    variant("native", &frames(1.0), Some((f64::INFINITY, 1.0, 0.0))),
                    4.0,
                    false,
                ),
                with_energy(
                    variant("upscale", &frames(0.5), Some((30.0, 0.9, 0.1))),
                    2.5,
                    true,
                ),
            ],
        )],
    };
    let c = compare::compare(&a, &b, &Options::default());
    let upscale = &c.scenarios[0].variants[1];
    assert_eq!(
        (upscale.energy_saving.a, upscale.energy_saving.b),
        (Some(2.0), Some(1.6))
    );
    assert_eq!(
        (upscale.throttled.a, upscale.throttled.b),
        (Some(false), Some(true))
    );
    // Energy is reported, not judged.
    assert!(!c.regressed());
    let md = compare::markdown::render(&c);
    assert!(md.contains("> **Warning:** throttled during measured frames in run B (their times read lowered clocks): `a` / `upscale`.\n"), "{md}");
    assert!(!md.contains("in run A"), "{md}");
    assert!(
        md.contains(
            "### Energy per frame\n\n| scenario | variant | mJ/frame | change | saving vs baseline |\n|---|---|---:|---:|---:|\n| a | native | 4.000 | +0.0% | - |\n| a | upscale | 2.000 → 2.500 | +25.0% | 2.00x → 1.60x |\n"
        ),
        "{md}"
    );
}

#[test]
fn slower_variant_and_worse_psnr_are_regressions_on_one_adapter() {
    let b = Run {
        info: run_info(B_ID, "bbbbbbb000", gpu()),
        scenarios: vec![scenario(
            B_ID,
            "a",
            vec![
                variant("native", &frames(1.0), Some((f64::INFINITY, 1.0, 0.0))),
                // +18% with no overlap, PSNR -0.5 dB, SSIM and FLIP within tolerance.
                variant("upscale", &frames(0.6), Some((29.5, 0.9005, 0.1005))),
            ],
        )],
    };
    let c = compare::compare(&base(), &b, &Options::default());
    assert!(c.regressed());
    assert_eq!(
        compare::markdown::render(&c),
        "\
## Tessera comparison: `20261122T030000Z-aaaaaaa` → `20261122T040000Z-bbbbbbb`

| | A (base) | B (new) |
|---|---|---|
| run | `20261122T030000Z-aaaaaaa` | `20261122T040000Z-bbbbbbb` |
| commit | `aaaaaaa` | `bbbbbbb` |
| adapter | NVIDIA H100, vulkan | NVIDIA H100, vulkan |
| driver | NVIDIA, 580.65 | NVIDIA, 580.65 |
| status | complete | complete |

### a

| variant | GPU ms | change [99% interval] | time | speedup | PSNR dB | SSIM | FLIP | status |
|---|---:|---:|---|---:|---:|---:|---:|---|
| native | 1.045 | +0.0% [-3.8%, +3.8%] | within noise (p=1.000) | - | inf | 1.0000 | 0.0000 | ok |
| upscale | 0.545 → 0.645 | +18.3% [+11.0%, +25.7%] | **slower (p<0.001)** | 1.92x → 1.62x | 30.00 → 29.50 **worse** | 0.9000 → 0.9005 | 0.1000 → 0.1005 | ok |

**Regressions**

- `a` / `upscale`: GPU time +18.3% [+11.0%, +25.7%] (p<0.001)
- `a` / `upscale`: PSNR dB 30.00 → 29.50

**Verdict: regressed** (2 regressions, 0 improvements; time: Mann-Whitney U p < 0.01 and a Hodges-Lehmann shift of at least 5%; too few frames below 5 per side)
"
    );
    // Below the threshold the same separation is real but not marked, and the PSNR loss remains.
    let c = compare::compare(
        &base(),
        &b,
        &Options {
            threshold_pct: 20.0,
            ..Default::default()
        },
    );
    let md = compare::markdown::render(&c);
    assert!(
        md.contains(
            "| upscale | 0.545 → 0.645 | +18.3% [+11.0%, +25.7%] | below threshold (p<0.001) |"
        ),
        "{md}"
    );
    assert!(md.ends_with("**Verdict: regressed** (1 regression, 0 improvements; time: Mann-Whitney U p < 0.01 and a Hodges-Lehmann shift of at least 20%; too few frames below 5 per side)\n"), "{md}");
}

#[test]
fn other_adapter_is_compared_by_speedup_and_its_skips_are_not_regressions() {
    let id = B_ID;
    let mut skipped = variant("checkerboard", &[], None);
    skipped.status = Status::Skipped {
        reason: "needs MULTISAMPLE_X2 for Rgba16Float".into(),
    };
    let b = Run {
        info: run_info(
            id,
            "bbbbbbb000",
            adapter("AMD Radeon RX 7900", "discrete-gpu", "Mesa 24"),
        ),
        scenarios: vec![scenario(
            id,
            "a",
            vec![
                // Everything twice as fast: the speedup against native is unchanged.
                variant("native", &frames(0.5), Some((f64::INFINITY, 1.0, 0.0))),
                variant("upscale", &frames(0.25), Some((30.0, 0.9, 0.1))),
                skipped,
            ],
        )],
    };
    let mut a = base();
    a.scenarios[0].results.push(variant(
        "checkerboard",
        &frames(0.7),
        Some((35.0, 0.95, 0.05)),
    ));
    let c = compare::compare(&a, &b, &Options::default());
    assert!(!c.regressed());
    assert_eq!(
        compare::markdown::render(&c),
        "\
## Tessera comparison: `20261122T030000Z-aaaaaaa` → `20261122T040000Z-bbbbbbb`

| | A (base) | B (new) |
|---|---|---|
| run | `20261122T030000Z-aaaaaaa` | `20261122T040000Z-bbbbbbb` |
| commit | `aaaaaaa` | `bbbbbbb` |
| adapter | NVIDIA H100, vulkan | AMD Radeon RX 7900, vulkan |
| driver | NVIDIA, 580.65 | NVIDIA, Mesa 24 |
| status | complete | complete |

> **Warning:** the adapters or drivers differ: GPU times are compared relative to each variant's baseline on each adapter (its speedup), not in milliseconds.

### a

| variant | GPU ms | change [99% interval] | time | speedup | PSNR dB | SSIM | FLIP | status |
|---|---:|---:|---|---:|---:|---:|---:|---|
| native | 1.045 → 0.545 | - | baseline | - | inf | 1.0000 | 0.0000 | ok |
| upscale | 0.545 → 0.295 | +3.8% [-7.9%, +15.5%] | within noise (p=0.481) | 1.92x → 1.85x | 30.00 | 0.9000 | 0.1000 | ok |
| checkerboard | 0.745 → - | - | not ok in both | 1.40x → - | 35.00 → - | 0.9500 → - | 0.0500 → - | ok → skipped: needs MULTISAMPLE_X2 for Rgba16Float |

**Verdict: no regression** (0 regressions, 0 improvements; time: Mann-Whitney U p < 0.01 and a Hodges-Lehmann shift of at least 5%; too few frames below 5 per side)
"
    );
}

#[test]
fn failures_gates_and_missing_scenarios() {
    let mut failed = variant("upscale", &[], None);
    failed.status = Status::Failed {
        error: "the GPU device was lost | twice".into(),
    };
    let mut gated = variant("native", &frames(1.0), Some((f64::INFINITY, 1.0, 0.0)));
    gated.gates.push(GateOutcome {
        measure: "gpu_ms".into(),
        value: 1.045,
        level: GateLevel::Fail,
        message: "gpu_ms = 1.045 is above 1: fails".into(),
    });
    let b = Run {
        info: run_info(
            B_ID,
            "bbbbbbb000",
            adapter("llvmpipe (LLVM 15.0.6, 256 bits)", "cpu", "Mesa 22.3.6"),
        ),
        scenarios: vec![scenario(
            B_ID,
            "b",
            vec![gated, failed, variant("native-2", &frames(1.0), None)],
        )],
    };
    let mut a = base();
    a.info.adapter = b.info.adapter.clone();
    a.scenarios.push(scenario(
        "20261122T030000Z-aaaaaaa",
        "b",
        vec![
            variant("native", &frames(1.0), Some((f64::INFINITY, 1.0, 0.0))),
            variant("upscale", &frames(0.5), Some((30.0, 0.9, 0.1))),
        ],
    ));
    let c = compare::compare(&a, &b, &Options::default());
    assert!(c.regressed());
    assert_eq!(
        compare::markdown::render(&c),
        "\
## Tessera comparison: `20261122T030000Z-aaaaaaa` → `20261122T040000Z-bbbbbbb`

| | A (base) | B (new) |
|---|---|---|
| run | `20261122T030000Z-aaaaaaa` | `20261122T040000Z-bbbbbbb` |
| commit | `aaaaaaa` | `bbbbbbb` |
| adapter | llvmpipe (LLVM 15.0.6, 256 bits), vulkan | llvmpipe (LLVM 15.0.6, 256 bits), vulkan |
| driver | NVIDIA, Mesa 22.3.6 | NVIDIA, Mesa 22.3.6 |
| status | complete | complete |

> **Note:** a run is on a CPU adapter (lavapipe): its timings measure CPU work and depend on other load on the machine, so time verdicts are shown but never count as regressions.

### a (only in A)

| variant | GPU ms | change [99% interval] | time | speedup | PSNR dB | SSIM | FLIP | status |
|---|---:|---:|---|---:|---:|---:|---:|---|
| native (only in A) | 1.045 → - | - | not in both | - | inf → - | 1.0000 → - | 0.0000 → - | ok → - |
| upscale (only in A) | 0.545 → - | - | not in both | 1.92x → - | 30.00 → - | 0.9000 → - | 0.1000 → - | ok → - |

### b

| variant | GPU ms | change [99% interval] | time | speedup | PSNR dB | SSIM | FLIP | status |
|---|---:|---:|---|---:|---:|---:|---:|---|
| native | 1.045 | +0.0% [-3.8%, +3.8%] | within noise (p=1.000) | - | inf | 1.0000 | 0.0000 | **ok → gate failed** |
| upscale | 0.545 → - | - | not ok in both | 1.92x → - | 30.00 → - | 0.9000 → - | 0.1000 → - | **ok → failed: the GPU device was lost \\| twice** |
| native-2 (only in B) | - → 1.045 | - | not in both | - → 1.00x | - | - | - | - → ok |

**Regressions**

- `b` / `native`: status ok → gate failed
- `b` / `upscale`: status ok → failed: the GPU device was lost \\| twice

**Verdict: regressed** (2 regressions, 0 improvements; time: Mann-Whitney U p < 0.01 and a Hodges-Lehmann shift of at least 5%; too few frames below 5 per side)
"
    );
}

// The command on run folders.

fn tessera(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_tessera"))
        .args(args)
        .output()
        .unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into(),
        String::from_utf8_lossy(&out.stderr).into(),
    )
}

fn write_run(dir: &Path, run: &Run) -> String {
    let d = dir.join(&run.info.run_id);
    std::fs::create_dir_all(d.join("scenarios")).unwrap();
    std::fs::write(d.join("run.json"), serde_json::to_vec(&run.info).unwrap()).unwrap();
    for s in &run.scenarios {
        std::fs::write(
            d.join("scenarios").join(format!("{}.json", s.scenario)),
            serde_json::to_vec(s).unwrap(),
        )
        .unwrap();
    }
    d.to_string_lossy().into_owned()
}

#[test]
fn exit_codes_of_the_command() {
    let dir = tempfile::tempdir().unwrap();
    let a = write_run(dir.path(), &base());
    let mut same = base();
    same.info.run_id = B_ID.into();
    let same = write_run(dir.path(), &same);
    let (code, out, _) = tessera(&["compare", &a, &same]);
    assert_eq!(code, 0, "{out}");
    assert!(out.ends_with("**Verdict: no regression** (0 regressions, 0 improvements; time: Mann-Whitney U p < 0.01 and a Hodges-Lehmann shift of at least 5%; too few frames below 5 per side)\n"), "{out}");

    let mut slower = base();
    slower.info.run_id = "slower".into();
    slower.scenarios[0].results[1] = variant("upscale", &frames(0.6), Some((30.0, 0.9, 0.1)));
    let slower = write_run(dir.path(), &slower);
    let (code, out, _) = tessera(&["compare", &a, &slower]);
    assert_eq!(code, 1, "{out}");
    let (code, out, _) = tessera(&["compare", &a, &slower, "--threshold-pct", "25"]);
    assert_eq!(code, 0, "{out}");

    let (code, _, err) = tessera(&["compare", &a, "/no/such/run"]);
    assert_eq!(code, 2);
    assert_eq!(
        err,
        "error: /no/such/run: no such run folder (expected <run-id>/run.json as written by `tessera run`)\n"
    );

    let newer = dir.path().join("newer");
    std::fs::create_dir_all(&newer).unwrap();
    std::fs::write(newer.join("run.json"), r#"{"schema_version": 4}"#).unwrap();
    let (code, _, err) = tessera(&["compare", &a, newer.to_str().unwrap()]);
    assert_eq!(code, 2);
    assert_eq!(
        err,
        format!(
            "error: {}/run.json has schema_version 4; this reader knows versions 1 to 3: read it with the newer tessera or tessera-dashboard that wrote it\n",
            newer.display()
        )
    );
}
