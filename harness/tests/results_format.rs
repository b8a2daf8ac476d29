//! The result files against the shared measure table and the stored schema-version-1 run folder
//! (`results/tests/fixtures/v1/`): the CSV writer, reading that folder through the shared reader,
//! gives byte for byte the `results.csv` the harness wrote then; gates name measures by the
//! table, older spellings included. No GPU needed.

use std::path::{Path, PathBuf};

use tessera::metric::MetricKind;
use tessera::scenario;
use tessera_results::measure::{Key, Measure};

fn fixture() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../results/tests/fixtures/v1/20261201T103009Z")
}

#[test]
fn the_csv_of_a_version_1_folder_is_unchanged() {
    let run = tessera::compare::load_run(&fixture()).unwrap();
    let csv = tessera::run::output::results_csv(&run.info, &run.scenarios);
    let expected = std::fs::read_to_string(fixture().join("results.csv")).unwrap();
    let csv = String::from_utf8(csv).unwrap();
    for (i, (got, want)) in csv.lines().zip(expected.lines()).enumerate() {
        assert_eq!(got, want, "line {}", i + 1);
    }
    assert_eq!(csv.lines().count(), expected.lines().count());
    assert_eq!(csv, expected);
}

#[test]
fn results_csv_reads_back_through_the_shared_reader() {
    use tessera_results::csv_file;
    let mut run = tessera::compare::load_run(&fixture()).unwrap();
    let plain = tessera::run::output::results_csv(&run.info, &run.scenarios);
    let plain_rows = String::from_utf8(plain).unwrap().lines().count() - 1;
    // A name with what CSV must quote, and one a spreadsheet would run: kept as written.
    run.scenarios[0].results[0].variant = "say \"hi\",\r\n=1+1".into();
    let bytes = tessera::run::output::results_csv(&run.info, &run.scenarios);
    let table = csv_file::read(&bytes, Some(&tessera_results::CSV_COLUMNS)).unwrap();
    let rows = &table.rows;
    assert_eq!(rows.len(), plain_rows);
    assert_eq!(rows[0][2], "say \"hi\",\r\n=1+1");
    assert!(rows.iter().all(|r| r[0] == run.info.run_id));
}

#[test]
fn metric_kinds_are_measures_of_the_table() {
    for m in MetricKind::ALL {
        let measure = Measure::from_name(m.name()).unwrap();
        assert_eq!(measure, m.measure());
        assert!(measure.is_metric() && measure.info().gate, "{}", m.name());
        assert_eq!(m.higher_is_better(), measure.direction().higher_is_better());
    }
}

const BASE: &str = r#"
resolution = [64, 32]
metrics = ["psnr"]

[frames]
warmup = 1
measured = 3

[camera]
[[camera.keyframes]]
time = 0.0
position = [0, 1, 5]
target = [0, 0, 0]

[[techniques]]
technique = "native"
"#;

fn gate_measures(names: &[&str]) -> Result<Vec<String>, String> {
    let mut src = BASE.to_string();
    for n in names {
        src.push_str(&format!("\n[[gates]]\nmeasure = \"{n}\"\nfail_above = 0\n"));
    }
    scenario::parse(Path::new("s.toml"), &src)
        .map(|s| s.gates.into_iter().map(|g| g.measure).collect())
        .map_err(|e| e.to_string())
}

#[test]
fn gates_take_canonical_names_older_spellings_and_medians() {
    assert_eq!(
        gate_measures(&[
            "non-finite",
            "non_finite_values",
            "spread-non-finite",
            "unrecovered-cuts",
            "gpu_ms.median",
            "psnr"
        ])
        .unwrap(),
        [
            "non_finite_values",
            "non_finite_values",
            "spread_non_finite",
            "unrecovered_cuts",
            "gpu_ms",
            "psnr"
        ]
    );
    // Every gateable measure that is not a metric is accepted under its name.
    let names: Vec<&str> = Measure::gateable()
        .filter(|m| !m.is_metric())
        .map(Measure::name)
        .collect();
    assert_eq!(gate_measures(&names).unwrap(), names);
    // A per-pass time or another statistic is not a gate's measure.
    for bad in [
        "pass.scene.gpu_ms.median",
        "gpu_ms.p95",
        "speedup.native-deferred",
    ] {
        let e = gate_measures(&[bad]).unwrap_err();
        assert!(e.contains(&format!("unknown measure \"{bad}\"")), "{e}");
        assert!(Key::parse(bad).is_some(), "{bad} is a CSV key");
    }
}
