//! The stored schema-version-1 run folder (`fixtures/v1/`, written by `tessera run` before the
//! measure table) read through the shared reader: it upgrades to the current version without
//! losing a value, and its `results.csv` agrees with the measure table (names, units) and with
//! the series the dashboard stores (names, values, directions).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use tessera_results::folder;
use tessera_results::measure::{self, Direction, Key, Measure, DEFAULT_BASELINE};
use tessera_results::{MetricRecord, ScenarioResult, SCHEMA_VERSION};

fn fixture() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/v1/20261201T103009Z")
}

fn raw_v1(rel: &str) -> serde_json::Value {
    serde_json::from_slice(&std::fs::read(fixture().join(rel)).unwrap()).unwrap()
}

/// `results.csv` rows as (variant, measure) → (value, unit); RFC 4180 quoting.
fn csv_rows() -> BTreeMap<(String, String), (String, String)> {
    let text = std::fs::read_to_string(fixture().join("results.csv")).unwrap();
    let mut lines = text.lines();
    assert_eq!(
        lines.next().unwrap(),
        tessera_results::CSV_COLUMNS.join(",")
    );
    let mut out = BTreeMap::new();
    for line in lines {
        let mut fields = Vec::new();
        let mut cur = String::new();
        let mut quoted = false;
        let mut chars = line.chars().peekable();
        while let Some(c) = chars.next() {
            match c {
                '"' if quoted && chars.peek() == Some(&'"') => {
                    cur.push('"');
                    chars.next();
                }
                '"' => quoted = !quoted,
                ',' if !quoted => fields.push(std::mem::take(&mut cur)),
                c => cur.push(c),
            }
        }
        fields.push(cur);
        assert_eq!(fields.len(), 10, "{line}");
        let prev = out.insert(
            (fields[2].clone(), fields[7].clone()),
            (fields[8].clone(), fields[9].clone()),
        );
        assert!(prev.is_none(), "row twice: {line}");
    }
    out
}

fn scenario(run: &folder::Run) -> &ScenarioResult {
    assert_eq!(run.scenarios.len(), 1);
    &run.scenarios[0]
}

#[test]
fn version_1_reads_as_the_current_version_without_losing_values() {
    let run = folder::read(&fixture()).unwrap();
    assert_eq!(run.info.schema_version, SCHEMA_VERSION);
    let s = scenario(&run);
    assert_eq!(s.schema_version, SCHEMA_VERSION);
    let variants: Vec<&str> = s.results.iter().map(|r| r.variant.as_str()).collect();
    assert_eq!(
        variants,
        [
            "native",
            "native-deferred",
            "adaptive-shading",
            "upscale",
            "checkerboard"
        ]
    );

    // Every metric's per-frame statistics, written as `series` in version 1, are `frame_stats`.
    let v1 = raw_v1("scenarios/mini.json");
    let mut stats = 0;
    for (r, r1) in s.results.iter().zip(v1["results"].as_array().unwrap()) {
        for (m, m1) in r.metrics.iter().zip(r1["metrics"].as_array().unwrap()) {
            assert_eq!(m.name, m1["name"].as_str().unwrap());
            assert_eq!(
                m.value,
                m1["value"].as_f64().unwrap_or(f64::INFINITY),
                "{} {}",
                r.variant,
                m.name
            );
            let fs = serde_json::to_value(m.frame_stats).unwrap();
            assert_eq!(fs, m1["series"], "{} {}", r.variant, m.name);
            stats += m.frame_stats.is_some() as usize;
        }
        // Gates under older spellings are written with the canonical names, values kept.
        for (g, g1) in r.gates.iter().zip(r1["gates"].as_array().unwrap()) {
            let old = g1["measure"].as_str().unwrap();
            assert_eq!(Measure::from_name(old).unwrap().name(), g.measure);
            assert_eq!(g.message, g1["message"].as_str().unwrap());
        }
    }
    assert!(
        stats > 10,
        "the fixture has per-frame statistics to carry over"
    );
    let gates: Vec<&str> = s.results[1]
        .gates
        .iter()
        .map(|g| g.measure.as_str())
        .collect();
    assert_eq!(gates, ["non_finite_values", "spread_non_finite", "gpu_ms"]);

    // Written in the current format and read back, nothing changes.
    let dir = std::env::temp_dir().join(format!("tessera-fixture-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(dir.join("scenarios")).unwrap();
    std::fs::write(dir.join("run.json"), serde_json::to_vec(&run.info).unwrap()).unwrap();
    std::fs::write(
        dir.join("scenarios/mini.json"),
        serde_json::to_vec(s).unwrap(),
    )
    .unwrap();
    let again = folder::read(&dir).unwrap();
    std::fs::remove_dir_all(&dir).unwrap();
    assert_eq!(again, run);
    let written = serde_json::to_string(s).unwrap();
    assert!(written.contains("\"frame_stats\"") && !written.contains("\"series\""));
}

#[test]
fn the_raw_reader_upgrades_and_lists_the_images_the_folder_holds() {
    let raw = folder::read_raw(&fixture()).unwrap();
    assert_eq!(raw.run["schema_version"], SCHEMA_VERSION);
    let images = raw.read_images().unwrap();
    assert_eq!(images.len(), 11);
    assert!(images.values().all(|b| b.starts_with(b"\x89PNG\r\n\x1a\n")));
    let body = tessera_results::upload::UploadBody::from_folder(&raw).unwrap();
    assert_eq!(body.decode_images().unwrap(), images);
    assert_eq!(body.scenarios[0]["schema_version"], SCHEMA_VERSION);
}

/// The metric record `name` of `variant`, if the scenario has one.
fn metric<'a>(s: &'a ScenarioResult, variant: &str, name: &str) -> Option<&'a MetricRecord> {
    s.results
        .iter()
        .find(|r| r.variant == variant)?
        .metrics
        .iter()
        .find(|m| m.name == name)
}

#[test]
fn every_csv_measure_is_in_the_table_with_its_unit() {
    let run = folder::read(&fixture()).unwrap();
    let s = scenario(&run);
    let rows = csv_rows();
    assert!(rows.len() > 100);
    let mut own = 0;
    for ((variant, name), (_, unit)) in &rows {
        if name == "status" {
            continue;
        }
        match Key::parse(name) {
            Some(key) => {
                assert_eq!(&key.render(), name, "{name} round-trips");
                assert_eq!(key.measure.unit(), unit, "{name}: the CSV's unit");
            }
            // A technique's own check (`shading-rate`): not a measure of the table; its unit is
            // its record's.
            None => {
                let m = metric(s, variant, name).unwrap_or_else(|| {
                    panic!("{variant}: {name} is neither a measure nor a metric")
                });
                assert_eq!(measure::metric_unit(m), unit, "{name}: the CSV's unit");
                own += 1;
            }
        }
    }
    assert!(own > 0, "the fixture has adaptive shading's own check");
}

#[test]
fn stored_series_are_csv_rows_with_the_same_value_and_the_tables_direction() {
    let run = folder::read(&fixture()).unwrap();
    let s = scenario(&run);
    let rows = csv_rows();
    let mut n = 0;
    for r in &s.results {
        let points = measure::points(&s.results, r);
        assert!(!points.is_empty());
        for p in points {
            let (value, _) = rows
                .get(&(r.variant.clone(), p.key.clone()))
                .unwrap_or_else(|| panic!("{} {}: stored but not in the CSV", r.variant, p.key));
            let csv: f64 = value.parse().unwrap();
            assert!(
                (csv - p.value).abs() <= 1e-12 * csv.abs().max(1.0),
                "{} {}: {csv} in the CSV, {} stored",
                r.variant,
                p.key,
                p.value
            );
            let direction = match Key::parse(&p.key) {
                Some(key) => {
                    assert!(key.measure.info().stored, "{}", p.key);
                    key.measure.direction()
                }
                // A technique's own check is stored under its name, with its record's direction.
                None => measure::metric_direction(
                    metric(s, &r.variant, &p.key)
                        .unwrap_or_else(|| panic!("{}: stored, not a metric", p.key)),
                ),
            };
            assert_eq!(
                p.higher_is_better,
                direction == Direction::HigherIsBetter,
                "{}: detection's direction is the table's (or the check's)",
                p.key
            );
            n += 1;
        }
        // The harness wrote each metric's direction into the record; the table (or, for a
        // technique's own check, the record's reading) agrees.
        for m in &r.metrics {
            let dir = measure::metric_direction(m);
            assert_eq!(m.higher_is_better, dir.higher_is_better(), "{}", m.name);
        }
    }
    assert!(n > 40);
}

#[test]
fn speedups_are_found_by_technique() {
    let run = folder::read(&fixture()).unwrap();
    let s = scenario(&run);
    let rows = csv_rows();
    let csv = |variant: &str, key: &str| -> Option<f64> {
        rows.get(&(variant.to_string(), key.to_string()))
            .map(|(v, _)| v.parse().unwrap())
    };
    for r in &s.results {
        let sp = measure::speedup(&s.results, r, DEFAULT_BASELINE);
        assert_eq!(sp, csv(&r.variant, "speedup"), "{}", r.variant);
        assert_eq!(
            sp,
            measure::value(&s.results, r, Measure::Speedup),
            "{}",
            r.variant
        );
    }
    let adaptive = &s.results[2];
    let own = measure::speedup(&s.results, adaptive, "native-deferred").unwrap();
    assert_eq!(
        Some(own),
        csv("adaptive-shading", "speedup.native-deferred")
    );

    // A label on the baseline changes nothing: it is found by technique.
    let mut relabelled = s.results.clone();
    relabelled[0].variant = "native[label=full]".into();
    assert_eq!(
        measure::speedup(&relabelled, &relabelled[3], DEFAULT_BASELINE),
        measure::speedup(&s.results, &s.results[3], DEFAULT_BASELINE)
    );
}
