//! What a run may hold, checked at the door before anything touches the store: times parsed and
//! within a window of the server's clock, timings finite, non-negative and below a bound, names
//! from one character set and length. Every refusal names the field (`run.started_at`,
//! `scenarios.basic.results.native.passes.shade.samples_ms[3]`), so that a CI job can say what
//! to fix; the limits are documented in the crate README ("What an upload may hold").
//!
//! Why: a run with `started_at` "not a date" or in the year 9999 pinned itself to the top of the
//! runs list and made retention delete the real newest run; a timing of 1.7e308 or -5 ms flattened
//! every chart of its series (issue 22, item 3).
//!
//! Not for: schema versions, record shapes, run-id consistency and images (see
//! [`crate::bundle`]), or storing (see [`crate::store`]).

use chrono::{DateTime, Utc};
use tessera_results::{PassRecord, RunInfo, ScenarioResult, Summary, VariantResult};

/// Times may lie at most this many days before the server's clock...
pub const MAX_AGE_DAYS: i64 = 3650;
/// ...and at most this many hours after it (clock skew between a runner and the server).
pub const MAX_FUTURE_HOURS: i64 = 24;
/// Largest timing accepted, in milliseconds (a frame or pass time; one hour).
pub const MAX_TIMING_MS: f64 = 3_600_000.0;
/// Largest scenario wall time accepted, in milliseconds (one day).
pub const MAX_WALL_MS: f64 = 86_400_000.0;
/// Largest |metric value| accepted (`+inf` is allowed: the PSNR of identical frames).
pub const MAX_METRIC_ABS: f64 = 1e12;
/// Longest scenario, variant, technique, pass, metric, image kind, suite or branch name, in bytes.
pub const MAX_NAME_LEN: usize = 160;
/// Longest driver, driver info, adapter, host or harness version string, in bytes.
pub const MAX_TEXT_LEN: usize = 512;

/// A refused field: where it is and what is allowed.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{field}: {problem}")]
pub struct FieldError {
    /// Dotted path of the field in the upload (`run.started_at`, `scenarios.basic.wall_ms`).
    pub field: String,
    pub problem: String,
}

fn refuse(field: impl Into<String>, problem: impl Into<String>) -> FieldError {
    FieldError {
        field: field.into(),
        problem: problem.into(),
    }
}

/// Characters a name may hold: ASCII letters, digits and `. _ - = , [ ] + :` (a variant is
/// `technique[key=value,...]`). With `slash`, also `/` (branches such as `feature/x`, suites).
/// No spaces, pipes, backticks, quotes or angle brackets: names go into URLs, Markdown and CSV.
pub fn valid_name(s: &str, slash: bool) -> bool {
    !s.is_empty()
        && s.len() <= MAX_NAME_LEN
        && s.bytes().all(|b| {
            b.is_ascii_alphanumeric()
                || matches!(
                    b,
                    b'.' | b'_' | b'-' | b'=' | b',' | b'[' | b']' | b'+' | b':'
                )
                || (slash && b == b'/')
        })
}

const NAME_RULE: &str =
    "may only hold ASCII letters, digits and . _ - = , [ ] + : (1 to 160 bytes)";

fn name(field: &str, s: &str) -> Result<(), FieldError> {
    if valid_name(s, false) {
        Ok(())
    } else {
        Err(refuse(field, format!("{s:?} {NAME_RULE}")))
    }
}

fn text(field: &str, s: &str) -> Result<(), FieldError> {
    if s.len() > MAX_TEXT_LEN {
        Err(refuse(
            field,
            format!("is longer than {MAX_TEXT_LEN} bytes"),
        ))
    } else if s.chars().any(char::is_control) {
        Err(refuse(field, "holds control characters"))
    } else {
        Ok(())
    }
}

/// Parses an RFC 3339 time and checks it lies within [`MAX_AGE_DAYS`] before and
/// [`MAX_FUTURE_HOURS`] after `now`.
pub fn time(field: &str, s: &str, now: DateTime<Utc>) -> Result<DateTime<Utc>, FieldError> {
    let t = DateTime::parse_from_rfc3339(s)
        .map_err(|_| {
            refuse(
                field,
                format!("{s:?} is not an RFC 3339 time (like 2026-11-22T03:05:20Z)"),
            )
        })?
        .with_timezone(&Utc);
    let earliest = now - chrono::Duration::days(MAX_AGE_DAYS);
    let latest = now + chrono::Duration::hours(MAX_FUTURE_HOURS);
    if t < earliest || t > latest {
        return Err(refuse(
            field,
            format!(
                "{s:?} is outside the accepted window, {MAX_AGE_DAYS} days before to {MAX_FUTURE_HOURS} hours after the server's clock ({})",
                now.to_rfc3339_opts(chrono::SecondsFormat::Secs, true)
            ),
        ));
    }
    Ok(t)
}

fn timing(field: &str, v: f64, max: f64) -> Result<(), FieldError> {
    if !v.is_finite() || v < 0.0 || v > max {
        Err(refuse(
            field,
            format!("{v} ms is not a timing: it must be finite, at least 0 and at most {max} ms"),
        ))
    } else {
        Ok(())
    }
}

fn summary(field: &str, s: &Summary) -> Result<(), FieldError> {
    for (k, v) in [
        ("median", s.median),
        ("p5", s.p5),
        ("p95", s.p95),
        ("min", s.min),
        ("max", s.max),
        ("mean", s.mean),
    ] {
        timing(&format!("{field}.{k}"), v, MAX_TIMING_MS)?;
    }
    if let Some([lo, hi]) = s.median_ci95 {
        timing(&format!("{field}.median_ci95[0]"), lo, MAX_TIMING_MS)?;
        timing(&format!("{field}.median_ci95[1]"), hi, MAX_TIMING_MS)?;
    }
    Ok(())
}

fn metric_value(field: &str, v: f64) -> Result<(), FieldError> {
    if v.is_nan() || v == f64::NEG_INFINITY || (v.is_finite() && v.abs() > MAX_METRIC_ABS) {
        Err(refuse(
            field,
            format!("{v} is not a metric value: it must be a number of magnitude at most {MAX_METRIC_ABS:e} (or +infinity, written null)"),
        ))
    } else {
        Ok(())
    }
}

fn pass(field: &str, p: &PassRecord) -> Result<(), FieldError> {
    name(&format!("{field}.name"), &p.name)?;
    if let Some(s) = &p.gpu_ms {
        summary(&format!("{field}.gpu_ms"), s)?;
    }
    for (i, v) in p.samples_ms.iter().enumerate() {
        timing(&format!("{field}.samples_ms[{i}]"), *v, MAX_TIMING_MS)?;
    }
    Ok(())
}

fn variant(field: &str, v: &VariantResult) -> Result<(), FieldError> {
    name(&format!("{field}.technique"), &v.technique)?;
    for (i, p) in v.passes.iter().enumerate() {
        let at = if valid_name(&p.name, false) {
            format!("{field}.passes.{}", p.name)
        } else {
            format!("{field}.passes[{i}]")
        };
        pass(&at, p)?;
    }
    if let Some(s) = &v.gpu_frame_ms {
        summary(&format!("{field}.gpu_frame_ms"), s)?;
    }
    summary(&format!("{field}.cpu_frame_ms"), &v.cpu_frame_ms)?;
    for (i, m) in v.metrics.iter().enumerate() {
        name(&format!("{field}.metrics[{i}].name"), &m.name)?;
        let at = format!("{field}.metrics.{}", m.name);
        metric_value(&format!("{at}.value"), m.value)?;
        for (j, x) in m.per_frame.iter().enumerate() {
            metric_value(&format!("{at}.per_frame[{j}]"), *x)?;
        }
    }
    for (i, img) in v.images.iter().enumerate() {
        name(&format!("{field}.images[{i}].kind"), &img.kind)?;
    }
    Ok(())
}

/// Checks a typed run and its scenario results against the limits above, `now` being the
/// server's clock. The first refused field is returned.
pub fn check(
    run: &RunInfo,
    scenarios: &[ScenarioResult],
    now: DateTime<Utc>,
) -> Result<(), FieldError> {
    let started = time("run.started_at", &run.started_at, now)?;
    if let Some(f) = &run.finished_at {
        let finished = time("run.finished_at", f, now)?;
        if finished < started {
            return Err(refuse(
                "run.finished_at",
                format!("{f:?} is before run.started_at {:?}", run.started_at),
            ));
        }
    }
    if let Some(c) = &run.commit_time {
        time("run.commit_time", c, now)?;
    }
    if let Some(c) = &run.commit {
        if c.sha.is_empty() || c.sha.len() > 64 || !c.sha.bytes().all(|b| b.is_ascii_alphanumeric())
        {
            return Err(refuse(
                "run.commit.sha",
                format!("{:?} must be 1 to 64 ASCII letters and digits", c.sha),
            ));
        }
    }
    for (field, v) in [("run.suite", &run.suite), ("run.branch", &run.branch)] {
        if let Some(s) = v {
            if !valid_name(s, true) {
                return Err(refuse(
                    field,
                    format!("{s:?} may only hold ASCII letters, digits and . _ - = , [ ] + : / (1 to 160 bytes)"),
                ));
            }
        }
    }
    let a = &run.adapter;
    for (field, v) in [
        ("run.adapter.name", &a.name),
        ("run.adapter.driver", &a.driver),
        ("run.adapter.driver_info", &a.driver_info),
        ("run.adapter.backend", &a.backend),
        ("run.adapter.device_type", &a.device_type),
        ("run.host.hostname", &run.host.hostname),
        ("run.harness_version", &run.harness_version),
    ] {
        text(field, v)?;
    }
    for (i, s) in scenarios.iter().enumerate() {
        name(&format!("scenarios[{i}].scenario"), &s.scenario)?;
        let at = format!("scenarios.{}", s.scenario);
        timing(&format!("{at}.wall_ms"), s.wall_ms, MAX_WALL_MS)?;
        for (j, v) in s.results.iter().enumerate() {
            name(&format!("{at}.results[{j}].variant"), &v.variant)?;
            variant(&format!("{at}.results.{}", v.variant), v)?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn now() -> DateTime<Utc> {
        DateTime::parse_from_rfc3339("2026-12-01T12:00:00Z")
            .unwrap()
            .with_timezone(&Utc)
    }

    #[test]
    fn times_must_parse_and_lie_in_the_window() {
        assert!(time("t", "2026-11-22T03:05:20Z", now()).is_ok());
        assert!(time("t", "2026-11-22T03:05:20+02:00", now()).is_ok());
        let e = time("run.started_at", "not a date", now()).unwrap_err();
        assert_eq!(e.field, "run.started_at");
        assert!(e.problem.contains("not an RFC 3339 time"), "{e}");
        let e = time("run.started_at", "9999-01-01T00:00:00Z", now()).unwrap_err();
        assert!(e.problem.contains("outside the accepted window"), "{e}");
        assert!(time("t", "2026-12-02T11:00:00Z", now()).is_ok());
        assert!(time("t", "2026-12-02T13:00:00Z", now()).is_err());
        assert!(time("t", "1970-01-01T00:00:00Z", now()).is_err());
    }

    #[test]
    fn timings_are_finite_non_negative_and_bounded() {
        assert!(timing("x", 0.0, MAX_TIMING_MS).is_ok());
        assert!(timing("x", 12.5, MAX_TIMING_MS).is_ok());
        for bad in [-1.0, 1.7e308, f64::INFINITY, f64::NAN, MAX_TIMING_MS * 2.0] {
            assert!(timing("x", bad, MAX_TIMING_MS).is_err(), "{bad}");
        }
    }

    #[test]
    fn names_have_one_character_set() {
        for ok in [
            "native",
            "checkerboard[sampling=two-pass]",
            "upscale[scale=0.75]",
            "adaptive-shading[threshold=0.15,vrs=hardware]",
            "gbuf_position",
            "psnr-luma",
        ] {
            assert!(valid_name(ok, false), "{ok}");
        }
        for bad in [
            "",
            "a|b",
            "`x`",
            "a b",
            "<script>",
            "=HYPERLINK(1)\"",
            "feature/x",
        ] {
            assert!(!valid_name(bad, false), "{bad}");
        }
        assert!(valid_name("feature/x", true));
        assert!(!valid_name(&"a".repeat(MAX_NAME_LEN + 1), false));
    }

    #[test]
    fn metric_values_allow_identical_frames() {
        assert!(metric_value("m", f64::INFINITY).is_ok());
        assert!(metric_value("m", 42.0).is_ok());
        assert!(metric_value("m", -0.5).is_ok());
        for bad in [f64::NAN, f64::NEG_INFINITY, 1.7e308] {
            assert!(metric_value("m", bad).is_err(), "{bad}");
        }
    }
}
