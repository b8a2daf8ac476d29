//! The converged reference states its own noise (issue 33, item 6): a tiny ground-truth scenario
//! on lavapipe records it, the result file carries it, and `tessera report` prints it as the
//! line under which differences are ties.

mod common;

use tessera::run::{self, Options};

fn options(out: &std::path::Path) -> Options {
    Options {
        adapter: None,
        out: out.to_path_buf(),
        junit: None,
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

/// TINY against the converged reference of `samples`, with `extra` in its `[reference]`.
fn source(samples: u32, extra: &str) -> String {
    format!(
        "metrics = [\"psnr\", \"flip\"]\n{}[reference]\nkind = \"ground-truth\"\nsamples = {samples}\n{extra}\
         [[techniques]]\ntechnique = \"upscale\"\nscale = 0.5\n",
        common::TINY
    )
}

#[test]
fn a_ground_truth_scenario_records_its_reference_noise() {
    let gpu = common::gpu();
    let s = common::scenario(&source(8, ""));
    // On by default: four times the reference's samples.
    assert_eq!(s.reference_noise, Some(32));
    let out = tempfile::tempdir().unwrap();
    let outcome = run::run_on(&gpu, &[s], &options(out.path())).unwrap();
    let result = &outcome.scenarios[0];
    let noise = result.reference_noise.as_ref().expect("reference_noise");
    assert_eq!(noise.error, None);
    assert_eq!((noise.reference_samples, noise.samples), (8, 32));
    let psnr = noise.metrics["psnr"];
    let flip = noise.metrics["flip"];
    assert!(psnr.is_finite() && psnr > 0.0, "psnr {psnr}");
    assert!(flip.is_finite() && flip > 0.0, "flip {flip}");
    // The 8-sample reference is nearer the 32-sample one than a half-resolution stretch is to it.
    let upscale = result
        .results
        .iter()
        .find(|r| r.variant.starts_with("upscale"))
        .unwrap();
    let value = |name: &str| {
        upscale
            .metrics
            .iter()
            .find(|m| m.name == name)
            .unwrap()
            .value
    };
    assert!(psnr > value("psnr"), "{psnr} against {}", value("psnr"));
    assert!(flip < value("flip"), "{flip} against {}", value("flip"));

    // The result file keeps it, and the report says what it means.
    let run = tessera_results::folder::read(&outcome.run_dir).unwrap();
    assert_eq!(run.scenarios[0].reference_noise.as_ref(), Some(noise));
    let tables = tessera::tables::tables(&[run]);
    let text = tessera::tables::render(&tables, tessera::tables::Format::Text);
    assert!(
        text.contains("reference noise (8 samples against 32, measured frame 0): flip ")
            && text.contains("; differences below it are ties"),
        "{text}"
    );
}

#[test]
fn noise_samples_zero_turns_it_off_and_fewer_are_refused() {
    let s = common::scenario(&source(32, "noise_samples = 0\n"));
    assert_eq!(s.reference_noise, None);
    let s = common::scenario(&source(32, "noise_samples = 256\n"));
    assert_eq!(s.reference_noise, Some(256));
    let e = tessera::scenario::parse(
        std::path::Path::new("test.toml"),
        &source(32, "noise_samples = 16\n"),
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("reference.noise_samples")
            && e.contains("more samples than its own 32: give more than 32, or 0 to turn it off"),
        "{e}"
    );
    let e = tessera::scenario::parse(
        std::path::Path::new("test.toml"),
        &common::TINY.replace("[camera]", "[reference]\nnoise_samples = 64\n[camera]"),
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("`noise_samples` applies only to kind = \"ground-truth\""),
        "{e}"
    );
}
