//! A result recorded from timings alone: one pass timed, nothing measured against a reference.
//! What a timing-only variant looks like, and the starting point the comparison tests (here, in
//! the harness and in the dashboard) build their cases from, so the record's every field is
//! written in one place.

use std::collections::BTreeMap;

use crate::{PassRecord, Status, Summary, VariantResult};

impl VariantResult {
    /// An ok result of technique `name` (the name up to a `[`), one render pass `scene` timed
    /// `samples` (ms) and the frame timed the same; no metrics, images, gates or conditions.
    pub fn timed(name: &str, samples: &[f64]) -> VariantResult {
        VariantResult {
            variant: name.into(),
            technique: name.split('[').next().unwrap_or(name).into(),
            baseline: None,
            params: BTreeMap::new(),
            status: Status::Ok,
            reference: None,
            passes: vec![PassRecord {
                name: "scene".into(),
                kind: "render".into(),
                reads: vec![],
                writes: vec!["color".into()],
                gpu_ms: Summary::of(samples),
                samples_ms: samples.to_vec(),
                fragment_invocations: None,
            }],
            culled_passes: vec![],
            gpu_frame_ms: Summary::of(samples),
            cpu_frame_ms: Summary::of(samples)
                .or(Summary::of(&[0.0]))
                .expect("a summary of one value exists"),
            resources: vec![],
            allocated_bytes: 0,
            metrics: vec![],
            non_finite_values: 0,
            stability: None,
            images: vec![],
            gates: vec![],
            conditions: None,
            sampling: None,
            pacing: None,
            convergence: None,
            frame_digests: Vec::new(),
            expectation: None,
        }
    }
}
