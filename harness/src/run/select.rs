//! `tessera run --variants PATTERN`: run only the named variants, with what their numbers need
//! and nothing more, so that an A/B or bisection step costs what it measures.
//!
//! `PATTERN` is a comma-separated list of variant names, each with `*` as a wildcard (the gates'
//! [`crate::scenario::pattern::matches`]): `taau*`, `fsr1[scale=0.5],upscale*`. A matching variant keeps
//! `native` (its speed-up's baseline, and the reference where the scenario's reference is
//! `native`) and its own same-pipeline baseline (`native-deferred`, `native-vrs`, a named
//! variant such as `native[motion_pass=true]`). A scenario with no matching variant is left out
//! of the run; a pattern that matches nothing anywhere is an error naming the variants there are.
//!
//! Not for: choosing scenarios (paths do that) or skipping by adapter (expectations).

use crate::scenario::Scenario;

use crate::scenario::pattern::matches;

/// What [`select`] left in and out.
#[derive(Debug, Default, PartialEq)]
pub struct Selection {
    /// Scenarios left out because no variant of theirs matched.
    pub dropped_scenarios: Vec<String>,
    /// Variants run only as a kept variant's baseline or reference.
    pub kept_as_baselines: usize,
}

/// Keeps, in every scenario, the variants that match `pattern` and their baselines; drops the
/// scenarios left without a match. `Err` with the message to print when nothing matches.
pub fn select(scenarios: &mut Vec<Scenario>, pattern: &str) -> Result<Selection, String> {
    let patterns: Vec<&str> = pattern
        .split(',')
        .map(str::trim)
        .filter(|p| !p.is_empty())
        .collect();
    if patterns.is_empty() {
        return Err(
            "--variants: give at least one variant name or pattern (e.g. \"taau*\")".into(),
        );
    }
    let hit = |name: &str| patterns.iter().any(|p| matches(p, name));
    if !scenarios
        .iter()
        .any(|s| s.variants.iter().any(|v| hit(&v.name)))
    {
        let mut names: Vec<&str> = scenarios
            .iter()
            .flat_map(|s| s.variants.iter().map(|v| v.name.as_str()))
            .collect();
        names.sort();
        names.dedup();
        return Err(format!(
            "--variants {pattern:?} matches no variant of these scenarios; they have: {}",
            names.join(", ")
        ));
    }
    let mut out = Selection::default();
    scenarios.retain(|s| {
        let keep = s.variants.iter().any(|v| hit(&v.name));
        if !keep {
            out.dropped_scenarios.push(s.name.clone());
        }
        keep
    });
    for s in scenarios.iter_mut() {
        // The speed-up's baseline (and the reference where it is `native`): the measure table's.
        let mut needed: Vec<String> = vec![tessera_results::measure::DEFAULT_BASELINE.to_string()];
        for v in s.variants.iter().filter(|v| hit(&v.name)) {
            if let Some(b) = v.technique.baseline(v) {
                needed.push(b.to_string());
            }
        }
        let before = s.variants.len();
        s.variants.retain(|v| {
            hit(&v.name)
                || needed
                    .iter()
                    .any(|b| *b == v.name || *b == v.technique.name())
        });
        let matched = s.variants.iter().filter(|v| hit(&v.name)).count();
        out.kept_as_baselines += s.variants.len() - matched;
        debug_assert!(s.variants.len() <= before);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scenario(src: &str) -> Scenario {
        crate::scenario::parse(std::path::Path::new("sel.toml"), src).unwrap()
    }

    const SRC: &str = r#"
resolution = [32, 16]
[camera]
[[camera.keyframes]]
time = 0
position = [0, 1, 4]
target = [0, 0, 0]
[[techniques]]
technique = "native"
[[techniques]]
technique = "upscale"
scale = [0.5, 0.75]
[[techniques]]
technique = "adaptive-shading"
[[techniques]]
technique = "native-deferred"
[[techniques]]
technique = "taau"
"#;

    fn names(s: &Scenario) -> Vec<&str> {
        s.variants.iter().map(|v| v.name.as_str()).collect()
    }

    #[test]
    fn keeps_matches_native_and_their_own_baseline() {
        let mut all = vec![scenario(SRC)];
        let sel = select(&mut all, "upscale[scale=0.5]").unwrap();
        assert_eq!(names(&all[0]), ["native", "upscale[scale=0.5]"]);
        assert_eq!(sel.kept_as_baselines, 1);

        let mut all = vec![scenario(SRC)];
        select(&mut all, "adaptive*, taau").unwrap();
        assert_eq!(
            names(&all[0]),
            ["native", "adaptive-shading", "native-deferred", "taau"]
        );
    }

    #[test]
    fn nothing_matched_names_what_there_is() {
        let mut all = vec![scenario(SRC)];
        let e = select(&mut all, "fsr2*").unwrap_err();
        assert!(e.contains("matches no variant"), "{e}");
        assert!(e.contains("upscale[scale=0.75]"), "{e}");
        assert_eq!(all[0].variants.len(), 6, "nothing is changed");
        assert!(select(&mut all, " , ").is_err());
    }
}
