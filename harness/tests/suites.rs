//! The suites under `scenarios/` as shipped: every file validates, and every scene runs only what
//! it needs (issue 8, "leave out what a scene does not need"): passes no output reads are culled
//! with their memory, and no reference is rendered that no metric reads. GPU-free: the plans are
//! the graphs `tessera run` builds, without allocating them.

use std::path::{Path, PathBuf};

use tessera::scenario::{self, Reference, Scenario};
use tessera::techniques::{plan, Target};

const SUITES: [&str; 6] = [
    "smoke",
    "quality",
    "perf",
    "stress",
    "checkerboard-2x2",
    "adaptive",
];

fn suite(name: &str) -> Vec<Scenario> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../scenarios")
        .join(name);
    let files: Vec<PathBuf> = scenario::collect(&[dir]).expect("suite folder");
    assert!(!files.is_empty(), "suite {name} is empty");
    files
        .iter()
        .map(|f| scenario::load(f).unwrap_or_else(|e| panic!("{}: {e}", f.display())))
        .collect()
}

fn bytes_of(p: &tessera::render::graph::Plan, resource: &str) -> u64 {
    p.records()
        .iter()
        .filter(|r| r.name == resource)
        .map(|r| r.bytes)
        .sum()
}

fn total(p: &tessera::render::graph::Plan) -> u64 {
    p.records().iter().map(|r| r.bytes).sum()
}

/// Velocity runs only for scenes with dynamic objects; without them the pass is culled and its
/// two full-resolution targets are not allocated: the plan is smaller by exactly their bytes.
#[test]
fn velocity_runs_only_where_objects_move() {
    for name in SUITES {
        let (mut culled, mut kept) = (0, 0);
        for s in suite(name) {
            let dynamic = s.scene.has_dynamic_objects();
            for v in s
                .variants
                .iter()
                .filter(|v| v.technique.name() == "checkerboard")
            {
                let p = plan(v, Target::new(s.width, s.height, dynamic));
                let wanted =
                    dynamic && tessera::techniques::checkerboard::Options::from_variant(v).velocity;
                let ran = p.passes.iter().any(|x| x.name == "velocity");
                assert_eq!(ran, wanted, "{}: {}", s.name, v.name);
                assert_eq!(p.culled.contains(&"velocity"), !wanted, "{}", s.name);
                if wanted {
                    kept += 1;
                    assert!(bytes_of(&p, "velocity") > 0);
                } else {
                    culled += 1;
                    assert_eq!(bytes_of(&p, "velocity") + bytes_of(&p, "velocity_depth"), 0);
                    // What the same variant would allocate with something moving.
                    let moving = plan(v, Target::new(s.width, s.height, true));
                    if tessera::techniques::checkerboard::Options::from_variant(v).velocity {
                        let velocity =
                            bytes_of(&moving, "velocity") + bytes_of(&moving, "velocity_depth");
                        assert_eq!(total(&moving) - total(&p), velocity, "{}", s.name);
                        // Rgba16Float + Depth32Float at full resolution: 12 bytes a pixel.
                        assert_eq!(velocity, 12 * s.width as u64 * s.height as u64);
                    }
                }
            }
        }
        println!("{name}: checkerboard variants with velocity culled {culled}, kept {kept}");
    }
}

/// The quality suite shows both sides: static scenes cull velocity, moving objects keep it.
#[test]
fn the_quality_suite_has_scenes_with_and_without_moving_objects() {
    let q = suite("quality");
    assert!(q.iter().any(|s| s.scene.has_dynamic_objects()));
    assert!(q.iter().any(|s| !s.scene.has_dynamic_objects()));
}

/// A reference is rendered only for metrics, and only once: the scenario's own `native` variant
/// serves when the reference is native.
#[test]
fn references_are_rendered_only_when_a_metric_reads_them() {
    for name in SUITES {
        for s in suite(name) {
            let lists_native = s.variants.iter().any(|v| v.technique.name() == "native");
            assert_eq!(
                s.needs_reference(),
                !s.metrics.is_empty() && s.reference != Reference::None,
                "{}",
                s.name
            );
            let separate = s.needs_separate_reference();
            match s.reference {
                Reference::GroundTruth { .. } | Reference::Converged { .. } => {
                    assert_eq!(separate, s.needs_reference())
                }
                Reference::Native => assert_eq!(separate, s.needs_reference() && !lists_native),
                Reference::None => assert!(!separate),
            }
        }
    }
}

/// What dropping the metrics does to a scenario: no reference render at all.
#[test]
fn a_scenario_without_metrics_renders_no_reference() {
    let src = r#"
resolution = [32, 24]
metrics = []
[[scene.objects]]
shape = "sphere"
[camera]
[[camera.keyframes]]
time = 0
position = [0, 1, 4]
target = [0, 0, 0]
[[techniques]]
technique = "upscale"
"#;
    let dir = tempfile::tempdir().unwrap();
    let f = dir.path().join("s.toml");
    std::fs::write(&f, src).unwrap();
    let s = scenario::load(&f).unwrap();
    assert!(!s.needs_reference());
    std::fs::write(&f, src.replace("metrics = []", "metrics = [\"psnr\"]")).unwrap();
    let s = scenario::load(&f).unwrap();
    assert!(s.needs_reference() && s.needs_separate_reference());
}

/// Every stress scenario gates on determinism and on non-finite output, so the nightly run fails
/// on either.
#[test]
fn the_stress_suite_gates_stability() {
    for s in suite("stress") {
        let measures: Vec<&str> = s.gates.iter().map(|g| g.measure.as_str()).collect();
        assert!(measures.contains(&"nondeterministic"), "{}", s.name);
        assert!(
            measures.contains(&"non_finite_values") || measures.contains(&"spread_non_finite"),
            "{}",
            s.name
        );
    }
}
