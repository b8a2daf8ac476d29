//! A replayed nightly history with one injected step, made from a real run: the history the
//! pages a team reads the morning after are judged on (issue 38). One run per night on one
//! adapter profile (an H200 with 0.1% night-to-night noise, or lavapipe with 2%), each pass's
//! per-frame samples drawn around the template's with small within-run jitter, and from
//! `step_night` on one variant's every pass `factor` times slower or faster: the nights before,
//! the step's own night (one night cannot confirm it), and the nights after.
//!
//! On the GPU profile each result carries recorded conditions (clocks, temperature, power,
//! energy per frame, throttling); `clock_from` lowers the graphics clock from that night on, so a
//! comparison across it has conditions that differ.
//!
//! Not for: the detection benchmark with many injected changes (see [`crate::replay`]).

use tessera_results::conditions::{Conditions, Energy, EnergyMethod, RecordedConditions, Spread};
use tessera_results::Summary;

use crate::bundle::RunBundle;
use crate::detect::Rng;
use crate::synth::time_after;

/// What to replay.
#[derive(Clone, Debug)]
pub struct StepHistory {
    /// Run id prefix (`<name>-0007`).
    pub name: String,
    pub nights: usize,
    /// First night with the step.
    pub step_night: usize,
    /// The variant that steps (every pass of it).
    pub variant: String,
    /// Multiplies the variant's times from `step_night` on (`1.05`: 5% slower).
    pub factor: f64,
    /// Measured frames per result.
    pub frames: usize,
    /// An H200 (GPU, 0.1% noise, recorded conditions) or lavapipe (CPU, 2% noise).
    pub gpu: bool,
    /// From this night on the graphics clock reads lower (GPU profile only).
    pub clock_from: Option<usize>,
    pub seed: u64,
}

impl StepHistory {
    /// An H200 history of `nights` with `variant` `factor` times slower from `step_night`.
    pub fn h200(nights: usize, step_night: usize, variant: &str, factor: f64) -> StepHistory {
        StepHistory {
            name: "h200".into(),
            nights,
            step_night,
            variant: variant.into(),
            factor,
            frames: 30,
            gpu: true,
            clock_from: None,
            seed: 38,
        }
    }

    /// Night-to-night noise σ as a fraction of the level.
    pub fn cv(&self) -> f64 {
        if self.gpu {
            0.001
        } else {
            0.02
        }
    }

    /// The run id of `night`.
    pub fn run_id(&self, night: usize) -> String {
        format!("{}-{night:04}", self.name)
    }

    /// Every night's run, oldest first.
    pub fn runs(&self, template: &RunBundle) -> Vec<RunBundle> {
        let mut rng = Rng::new(self.seed);
        (0..self.nights)
            .map(|n| self.night(template, n, &mut rng))
            .collect()
    }

    fn night(&self, template: &RunBundle, night: usize, rng: &mut Rng) -> RunBundle {
        let mut b = template.clone();
        let id = self.run_id(night);
        b.run.run_id = id.clone();
        b.run.commit_time = Some(time_after(night as u64 * 1440));
        b.run.started_at = time_after(night as u64 * 1440 + 120);
        b.run.finished_at = Some(b.run.started_at.clone());
        b.run.commit = Some(tessera_results::CommitInfo {
            sha: sha(night),
            dirty: false,
        });
        if self.gpu {
            b.run.adapter.name = "NVIDIA H200 (replay)".into();
            b.run.adapter.device_type = "discrete-gpu".into();
            b.run.adapter.driver = "NVIDIA".into();
            b.run.adapter.driver_info = "580.159.04".into();
            b.run.adapter.vendor = 0x10de;
        } else {
            b.run.adapter.name = format!("{} (replay)", b.run.adapter.name);
        }
        let slow_clock = self.gpu && self.clock_from.is_some_and(|c| night >= c);
        let frames = self.frames.max(1);
        for s in &mut b.scenarios {
            s.run_id = id.clone();
            s.measured_frames = frames as u32;
            for v in &mut s.results {
                let step = if v.variant == self.variant && night >= self.step_night {
                    self.factor
                } else {
                    1.0
                };
                let f = step * (1.0 + self.cv() * rng.normal());
                let mut sums = vec![0.0; frames];
                for p in &mut v.passes {
                    if p.samples_ms.is_empty() {
                        continue;
                    }
                    let base = p.samples_ms.clone();
                    p.samples_ms = (0..frames)
                        .map(|i| base[i % base.len()] * f * (1.0 + 0.002 * rng.normal()))
                        .collect();
                    for (sum, x) in sums.iter_mut().zip(&p.samples_ms) {
                        *sum += x;
                    }
                    p.gpu_ms = Summary::of(&p.samples_ms);
                }
                if v.gpu_frame_ms.is_some() {
                    v.gpu_frame_ms = Summary::of(&sums);
                }
                if self.gpu {
                    let ms = v.gpu_frame_ms.map_or(1.0, |g| g.median);
                    v.conditions = Some(conditions(ms, slow_clock));
                }
            }
        }
        b
    }
}

/// The commit of `night`: 40 hex digits whose first ones differ from night to night, as real
/// commits' do (pages show the first 10).
pub fn sha(night: usize) -> String {
    let n = night as u64 + 1;
    format!("{:016x}{n:024x}", n.wrapping_mul(0x9E37_79B9_7F4A_7C15))
}

/// Sensor readings of an H200 result whose frames take `frame_ms` (about 300 W at full clock).
fn conditions(frame_ms: f64, slow_clock: bool) -> Conditions {
    let clock = if slow_clock { 1410.0 } else { 1980.0 };
    let spread = |m: f64, d: f64| {
        Some(Spread {
            min: m - d,
            median: m,
            max: m + d,
        })
    };
    let power = if slow_clock { 240.0 } else { 310.0 };
    Conditions::Recorded(Box::new(RecordedConditions {
        source: "nvml".into(),
        samples: 12,
        window_ms: 520.0,
        graphics_clock_mhz: spread(clock, 15.0),
        memory_clock_mhz: spread(3201.0, 0.0),
        temperature_c: spread(if slow_clock { 71.0 } else { 48.0 }, 1.0),
        power_w: spread(power, 8.0),
        throttle_reasons: if slow_clock {
            vec!["sw-power-cap".into()]
        } else {
            Vec::new()
        },
        energy: Some(Energy {
            mj_per_frame: power * frame_ms,
            method: EnergyMethod::Counter,
            frames: 400,
            window_ms: 500.0,
        }),
        throttled: slow_clock,
        throttle_causes: if slow_clock {
            vec!["power limit reported (sw-power-cap)".into()]
        } else {
            Vec::new()
        },
        clock_warmup_ms: Some(300.0),
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_step_is_where_it_is_said_to_be() {
        let dir = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/runs");
        let first = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().path())
            .min()
            .unwrap();
        let t = RunBundle::read_folder(&first).unwrap();
        let h = StepHistory::h200(6, 3, "native", 1.05);
        let runs = h.runs(&t);
        let native = |n: usize| {
            runs[n].scenarios[0]
                .results
                .iter()
                .find(|v| v.variant == "native")
                .unwrap()
                .gpu_frame_ms
                .unwrap()
                .median
        };
        let jump = native(3) / native(2);
        assert!((jump - 1.05).abs() < 0.01, "{jump}");
        assert!((native(2) / native(1) - 1.0).abs() < 0.01);
        assert_eq!(
            runs[0].scenarios[0].results[0].passes[0].samples_ms.len(),
            30
        );
        assert_eq!(runs[4].run.adapter.device_type, "discrete-gpu");
    }
}
