//! The comparison engine on records built in code: the cases `COMPARISON.md` promises, each
//! checked through the Markdown as a whole expected string (the summary `tessera compare` prints
//! and the dashboard exports) and through the values the page and the API read.

use std::collections::BTreeMap;

use tessera_results::compare::{self, markdown, Comparison, Options, RunRef, Verdict};
use tessera_results::stats::TimeVerdict;
use tessera_results::{
    AdapterFeatures, AdapterInfo, CommitInfo, HostInfo, MetricRecord, RunInfo, RunStatus,
    ScenarioResult, VariantResult, SCHEMA_VERSION,
};

fn h200() -> AdapterInfo {
    AdapterInfo {
        name: "NVIDIA H200".into(),
        vendor: 0x10de,
        device: 0x2335,
        device_type: "discrete-gpu".into(),
        driver: "NVIDIA".into(),
        driver_info: "580.159.04".into(),
        backend: "vulkan".into(),
        features: AdapterFeatures::default(),
    }
}

fn info(run_id: &str, sha: &str) -> RunInfo {
    RunInfo {
        schema_version: SCHEMA_VERSION,
        run_id: run_id.into(),
        commit: Some(CommitInfo {
            sha: sha.into(),
            dirty: false,
        }),
        commit_time: None,
        started_at: "2026-12-01T03:00:00Z".into(),
        finished_at: Some("2026-12-01T03:01:00Z".into()),
        status: RunStatus::Complete,
        harness_version: "0.1.0".into(),
        adapter: h200(),
        host: HostInfo {
            hostname: "ci".into(),
            os: "linux".into(),
            arch: "x86_64".into(),
            cpu_cores: 16,
        },
        command_line: vec!["tessera".into(), "run".into()],
        scenarios: vec!["scenarios/smoke/basic.toml".into()],
        conditions: None,
        suite: Some("smoke".into()),
        branch: Some("main".into()),
        adapter_class: None,
    }
}

/// An ok variant of technique `name` (up to a `[`) with one pass timed `samples` and a PSNR.
fn variant(name: &str, samples: &[f64], psnr: f64) -> VariantResult {
    let mut v = VariantResult::timed(name, samples);
    v.reference = Some("native".into());
    v.metrics = vec![MetricRecord {
        name: "psnr".into(),
        per_frame: vec![psnr; samples.len()],
        frames: (0..samples.len() as u32).collect(),
        value: psnr,
        higher_is_better: true,
        frame_stats: None,
        metrics_device: None,
        check: None,
    }];
    v
}

fn scenario(run_id: &str, results: Vec<VariantResult>) -> ScenarioResult {
    ScenarioResult {
        schema_version: SCHEMA_VERSION,
        run_id: run_id.into(),
        scenario: "basic".into(),
        file: "scenarios/smoke/basic.toml".into(),
        width: 64,
        height: 32,
        warmup_frames: 2,
        measured_frames: results[0].passes[0].samples_ms.len() as u32,
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

const A: &str = "20261201T030000Z-aaaaaaa";
const B: &str = "20261201T040000Z-bbbbbbb";

fn run(a: Vec<VariantResult>, b: Vec<VariantResult>, opts: &Options) -> (Comparison, String) {
    let (ia, ib) = (info(A, "aaaaaaa000"), info(B, "bbbbbbb000"));
    let (sa, sb) = ([scenario(A, a)], [scenario(B, b)]);
    let c = compare::compare(
        RunRef {
            info: &ia,
            scenarios: &sa,
        },
        RunRef {
            info: &ib,
            scenarios: &sb,
        },
        opts,
    );
    let md = markdown::render(&c);
    (c, md)
}

/// `n` frames around `median`, `step` apart, symmetric so the median is exact.
fn frames(n: usize, median: f64, step: f64) -> Vec<f64> {
    (0..n)
        .map(|i| median + step * (i as f64 - (n as f64 - 1.0) / 2.0))
        .collect()
}

/// `n` frames of GPU-like noise around `median`: a fixed pseudo-random sequence (an LCG), about
/// ±2% uniform, so the test sees real spread and overlapping sets.
fn noisy(n: usize, median: f64, seed: u64) -> Vec<f64> {
    let mut x = seed;
    (0..n)
        .map(|_| {
            x = x
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            let u = (x >> 11) as f64 / (1u64 << 53) as f64;
            median * (1.0 + 0.04 * (u - 0.5))
        })
        .collect()
}

const HEADER: &str = "\
## Tessera comparison: `20261201T030000Z-aaaaaaa` → `20261201T040000Z-bbbbbbb`

| | A (base) | B (new) |
|---|---|---|
| run | `20261201T030000Z-aaaaaaa` | `20261201T040000Z-bbbbbbb` |
| commit | `aaaaaaa` | `bbbbbbb` |
| adapter | NVIDIA H200, vulkan | NVIDIA H200, vulkan |
| driver | NVIDIA, 580.159.04 | NVIDIA, 580.159.04 |
| status | complete | complete |

";

#[test]
fn four_frames_cannot_tell_even_a_1531_percent_slowdown() {
    // The smoke suite's 4 measured frames: native 0.1 ms → 1.631 ms.
    let (c, md) = run(
        vec![
            variant("native", &frames(4, 0.1, 0.001), f64::INFINITY),
            variant("upscale", &frames(4, 0.05, 0.001), 30.0),
        ],
        vec![
            variant("native", &frames(4, 1.631, 0.001), f64::INFINITY),
            variant("upscale", &frames(4, 0.05, 0.001), 30.0),
        ],
        &Options::default(),
    );
    assert_eq!(c.count_time(TimeVerdict::TooFewFrames), 2);
    assert!(!c.regressed());
    assert_eq!(
        md,
        format!(
            "{HEADER}\
### basic

| variant | GPU ms | change [99% interval] | time | speedup | PSNR dB | SSIM | FLIP | status |
|---|---:|---:|---|---:|---:|---:|---:|---|
| native | 0.100 → 1.631 | +1531.0% | too few frames (4 vs 4; 5 per side needed) | - | inf | - | - | ok |
| upscale | 0.050 | +0.0% | too few frames (4 vs 4; 5 per side needed) | 2.00x → 32.62x | 30.00 | - | - | ok |

**Too few frames**

The time test cannot reach p < 0.01 with so few measured frames, whatever the change: `basic` / `native` (4 vs 4), `basic` / `upscale` (4 vs 4). It takes 5 frames per side (`frames.measured`).

**Verdict: inconclusive**: too few frames in 2 of 2 timed variants (5 per side needed) (0 regressions, 0 improvements, 2 too few frames; time: Mann-Whitney U p < 0.01 and a Hodges-Lehmann shift of at least 5%; too few frames below 5 per side)
"
        )
    );
    // The API's JSON carries the same words.
    let json = serde_json::to_value(&c).unwrap();
    let time = &json["scenarios"][0]["variants"][0]["time"];
    assert_eq!(time["verdict"], "too few frames", "{time}");
    assert_eq!(time["frames"], serde_json::json!([4, 4]));
    assert_eq!(json["rule"]["frames_needed"], 5);
}

#[test]
fn a_real_change_in_many_frames_is_flagged_and_noise_is_not() {
    let n = 2000;
    let (c, _) = run(
        vec![
            variant("native", &noisy(n, 1.0, 1), 40.0),
            variant("upscale", &noisy(n, 0.5, 2), 30.0),
            variant("interlace", &noisy(n, 0.6, 3), 30.0),
        ],
        vec![
            // Same distribution, other noise.
            variant("native", &noisy(n, 1.0, 4), 40.0),
            // +8%: slower.
            variant("upscale", &noisy(n, 0.54, 5), 30.0),
            // +1%: real, and resolved with 2000 frames, but below the 5% threshold.
            variant("interlace", &noisy(n, 0.606, 6), 30.0),
        ],
        &Options::default(),
    );
    let v = &c.scenarios[0].variants;
    let t: Vec<_> = v.iter().map(|v| *v.time.tested().unwrap()).collect();
    assert_eq!(t[0].verdict, TimeVerdict::WithinNoise, "{:?}", t[0]);
    assert_eq!(t[1].verdict, TimeVerdict::Slower, "{:?}", t[1]);
    let [lo, hi] = t[1].interval.unwrap();
    assert!(lo < 0.08 && 0.08 < hi && hi - lo < 0.01, "{:?}", t[1]);
    assert!(t[1].p < 1e-6);
    assert_eq!(t[2].verdict, TimeVerdict::BelowThreshold, "{:?}", t[2]);
    assert!(t[2].interval.unwrap()[0] > 0.0);
    assert!(c.regressed());
    let worse: Vec<_> = c.findings_of(Verdict::Worse).collect();
    assert_eq!(worse.len(), 1);
    assert_eq!(
        (worse[0].variant.as_str(), worse[0].what.as_str()),
        ("upscale", "GPU time")
    );
}

#[test]
fn an_improvement_is_an_improvement() {
    let (c, md) = run(
        vec![
            variant("native", &frames(10, 1.0, 0.01), f64::INFINITY),
            variant("upscale", &frames(10, 0.5, 0.01), 30.0),
        ],
        vec![
            variant("native", &frames(10, 1.0, 0.01), f64::INFINITY),
            // 20% faster and 0.5 dB better.
            variant("upscale", &frames(10, 0.4, 0.01), 30.5),
        ],
        &Options::default(),
    );
    assert!(!c.regressed());
    assert_eq!(
        md,
        format!(
            "{HEADER}\
### basic

| variant | GPU ms | change [99% interval] | time | speedup | PSNR dB | SSIM | FLIP | status |
|---|---:|---:|---|---:|---:|---:|---:|---|
| native | 1.000 | +0.0% [-4.0%, +4.0%] | within noise (p=1.000) | - | inf | - | - | ok |
| upscale | 0.500 → 0.400 | -20.0% [-28.0%, -12.0%] | faster (p<0.001) | 2.00x → 2.50x | 30.00 → 30.50 better | - | - | ok |

**Improvements**

- `basic` / `upscale`: GPU time -20.0% [-28.0%, -12.0%] (p<0.001)
- `basic` / `upscale`: PSNR dB 30.00 → 30.50

**Verdict: no regression** (0 regressions, 2 improvements; time: Mann-Whitney U p < 0.01 and a Hodges-Lehmann shift of at least 5%; too few frames below 5 per side)
"
        )
    );
}

#[test]
fn a_slower_baseline_is_one_regression_not_better_speedups() {
    let (c, md) = run(
        vec![
            variant("native", &frames(10, 1.0, 0.01), f64::INFINITY),
            variant("upscale", &frames(10, 0.5, 0.01), 30.0),
            variant("checkerboard", &frames(10, 0.6, 0.01), 35.0),
        ],
        vec![
            // native 30% slower; the others' times unchanged, so their speedups rise.
            variant("native", &frames(10, 1.3, 0.01), f64::INFINITY),
            variant("upscale", &frames(10, 0.5, 0.01), 30.0),
            variant("checkerboard", &frames(10, 0.6, 0.01), 35.0),
        ],
        &Options::default(),
    );
    assert_eq!(c.findings.len(), 1, "{:?}", c.findings);
    assert_eq!(
        c.findings[0].moves_speedups_of,
        vec!["upscale".to_string(), "checkerboard".to_string()]
    );
    assert_eq!(
        md,
        format!(
            "{HEADER}\
### basic

| variant | GPU ms | change [99% interval] | time | speedup | PSNR dB | SSIM | FLIP | status |
|---|---:|---:|---|---:|---:|---:|---:|---|
| native | 1.000 → 1.300 | +30.0% [+26.0%, +34.0%] | **slower (p<0.001)** | - | inf | - | - | ok |
| upscale | 0.500 | +0.0% [-8.0%, +8.0%] | within noise (p=1.000) | 2.00x → 2.60x (moved with native) | 30.00 | - | - | ok |
| checkerboard | 0.600 | +0.0% [-6.7%, +6.7%] | within noise (p=1.000) | 1.67x → 2.17x (moved with native) | 35.00 | - | - | ok |

**Regressions**

- `basic` / `native`: GPU time +30.0% [+26.0%, +34.0%] (p<0.001); the speedups of `upscale`, `checkerboard` moved with it (counted here once)

**Verdict: regressed** (1 regression, 0 improvements; time: Mann-Whitney U p < 0.01 and a Hodges-Lehmann shift of at least 5%; too few frames below 5 per side)
"
        )
    );
}

#[test]
fn baselines_are_per_variant() {
    // adaptive-shading declares native-deferred: its slowdown moves adaptive-shading's speedup,
    // not upscale's, which is measured against native.
    let adaptive = |samples: &[f64]| {
        let mut v = variant("adaptive-shading", samples, 33.0);
        v.baseline = Some("native-deferred".into());
        v
    };
    let (c, md) = run(
        vec![
            variant("native", &frames(10, 1.0, 0.01), f64::INFINITY),
            variant("native-deferred", &frames(10, 1.2, 0.01), f64::INFINITY),
            adaptive(&frames(10, 0.8, 0.01)),
            variant("upscale", &frames(10, 0.5, 0.01), 30.0),
        ],
        vec![
            variant("native", &frames(10, 1.0, 0.01), f64::INFINITY),
            variant("native-deferred", &frames(10, 1.5, 0.01), f64::INFINITY),
            adaptive(&frames(10, 0.8, 0.01)),
            variant("upscale", &frames(10, 0.5, 0.01), 30.0),
        ],
        &Options::default(),
    );
    assert_eq!(
        md,
        format!(
            "{HEADER}\
### basic

| variant | GPU ms | change [99% interval] | time | speedup | PSNR dB | SSIM | FLIP | status |
|---|---:|---:|---|---:|---:|---:|---:|---|
| native | 1.000 | +0.0% [-4.0%, +4.0%] | within noise (p=1.000) | - | inf | - | - | ok |
| native-deferred | 1.200 → 1.500 | +25.0% [+21.7%, +28.3%] | **slower (p<0.001)** | 0.83x → 0.67x | inf | - | - | ok |
| adaptive-shading | 0.800 | +0.0% [-5.0%, +5.0%] | within noise (p=1.000) | 1.50x → 1.88x (moved with native-deferred) | 33.00 | - | - | ok |
| upscale | 0.500 | +0.0% [-8.0%, +8.0%] | within noise (p=1.000) | 2.00x | 30.00 | - | - | ok |

**Regressions**

- `basic` / `native-deferred`: GPU time +25.0% [+21.7%, +28.3%] (p<0.001); the speedups of `adaptive-shading` moved with it (counted here once)

**Verdict: regressed** (1 regression, 0 improvements; time: Mann-Whitney U p < 0.01 and a Hodges-Lehmann shift of at least 5%; too few frames below 5 per side)
"
        )
    );
    let v = &c.scenarios[0].variants[2];
    assert_eq!(v.baseline.b.as_deref(), Some("native-deferred"));
}

#[test]
fn names_with_pipes_and_backticks_stay_inside_their_cells() {
    let (_, md) = run(
        vec![variant("native", &frames(4, 1.0, 0.01), 40.0)],
        vec![
            variant("native", &frames(4, 1.0, 0.01), 40.0),
            variant("x|`y`", &frames(4, 1.0, 0.01), 40.0),
        ],
        &Options::default(),
    );
    assert!(
        md.contains("| x\\|`y` (only in B) | - → 1.000 | - | not in both |"),
        "{md}"
    );
}

#[test]
fn a_change_many_sigma_outside_its_series_noise_is_called_below_the_fixed_threshold() {
    // 30 frames per side, +3%: significant, below the fixed 5%.
    let a = vec![variant("native", &frames(30, 1.0, 0.0005), f64::INFINITY)];
    let b = vec![variant("native", &frames(30, 1.03, 0.0005), f64::INFINITY)];
    let (c, _) = run(a.clone(), b.clone(), &Options::default());
    assert_eq!(c.count_time(TimeVerdict::BelowThreshold), 1);
    assert_eq!(c.decision(), compare::Decision::NoRegression);
    // The series' nightly noise is 0.1%: 5σ is 0.5%, floored at 1%; +3% is slower.
    let mut opts = Options::default();
    opts.noise.insert(
        "basic".into(),
        BTreeMap::from([("native".to_string(), 0.001)]),
    );
    assert_eq!(opts.threshold_for("basic", "native"), (1.0, Some(0.001)));
    // A noisy series keeps the fixed threshold.
    assert_eq!(opts.threshold_for("basic", "other"), (5.0, None));
    let (c, md) = run(a, b, &opts);
    assert_eq!(c.count_time(TimeVerdict::Slower), 1, "{md}");
    assert_eq!(c.decision(), compare::Decision::Regressed);
    let v = &c.scenarios[0].variants[0];
    assert_eq!((v.threshold_pct, v.noise), (1.0, Some(0.001)));
    assert!(
        md.contains("(or 5σ of the series' nightly noise, at least 1%, where a history gives it)"),
        "{md}"
    );
    let mut loud = Options::default();
    loud.noise.insert(
        "basic".into(),
        BTreeMap::from([("native".to_string(), 0.02)]),
    );
    assert_eq!(loud.threshold_for("basic", "native"), (5.0, Some(0.02)));
}
