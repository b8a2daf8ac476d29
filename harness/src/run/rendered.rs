//! What rendering a variant produces ([`Rendered`]), what its capture keeps ([`Keep`]), how it
//! fails ([`RenderError`]), and the frame-hash file a refactoring is checked with.
//!
//! For: the render stage's output, read by the evaluate, save and report stages. Not for:
//! rendering (`frames.rs`, `capture.rs`).

use tessera_metrics::{HdrImage, Rgb8Image};
use tessera_metrics_gpu::GpuFrame;
use tessera_results::conditions::StopReason;

use crate::conditions::Sample;
use crate::render::renderer::FrameExtras;
use crate::render::timers::FrameMeasurements;

/// What rendering a variant produced.
pub struct Rendered {
    /// One entry per measured frame.
    pub measurements: Vec<FrameMeasurements>,
    pub cpu_ms: Vec<f64>,
    /// sRGB frames of every measured frame, when asked to keep them.
    pub frames: Vec<Rgb8Image>,
    /// Linear frames, when asked to keep them (HDR metrics).
    pub hdr_frames: Vec<HdrImage>,
    /// Every measured frame on the device, for the GPU metrics, when asked to keep them.
    pub gpu_frames: Vec<GpuFrame>,
    /// The sRGB frames at `save_frames` (measured-frame index, image), whatever is kept.
    pub saved: Vec<(u32, Rgb8Image)>,
    pub non_finite: u64,
    /// Per measured frame, the pixels with a non-finite channel (bit per pixel, row-major);
    /// `None` for a frame without any.
    pub non_finite_masks: Vec<Option<Vec<u64>>>,
    /// Per measured frame, its non-finite channel values.
    pub non_finite_counts: Vec<u64>,
    /// The capture phase's last frame equals the timed phase's bit for bit (`None`: no frames).
    pub deterministic: Option<bool>,
    pub timestamps: bool,
    pub readback_bytes: u64,
    /// The technique's extras of every measured frame ([`Renderer::frame_extras`]).
    pub extras: Vec<FrameExtras>,
    /// Per timed measured frame, the sum of its pass times (its CPU frame time without
    /// timestamps): what the stop rule read.
    pub frame_ms: Vec<f64>,
    /// What ended the timed phase.
    pub ended_by: StopReason,
    /// The sensor samples of the measured frames; `None` without a sampler.
    pub conditions: Option<Vec<Sample>>,
    /// The sensor samples of the energy window and its frame count; `None` without a sampler.
    pub energy_window: Option<(Vec<Sample>, u32)>,
    /// How long the clock warm-up lasted, in milliseconds.
    pub clock_warmup_ms: f64,
    /// Per measured frame, a hash of its exact bits, when `TESSERA_FRAME_HASHES` is set (see
    /// [`frame_hash_file`]); empty otherwise.
    pub hashes: Vec<u64>,
    /// Per measured frame, the digest of its 8-bit display output
    /// ([`tessera_results::digest::frame_digest`]): what approved frames are matched by.
    pub digests: Vec<String>,
}

/// Where to append every measured frame's bit hash (`<scenario> <variant> <frame> <hash>`), from the
/// `TESSERA_FRAME_HASHES` environment variable: a check that a refactoring left every frame
/// bit-identical, not a measure.
pub fn frame_hash_file() -> Option<std::path::PathBuf> {
    std::env::var_os("TESSERA_FRAME_HASHES").map(Into::into)
}

#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    #[error("{0}")]
    Timers(#[from] crate::render::timers::TimerError),
    #[error("reading the frame back failed (device lost?)")]
    Readback,
    #[error("keeping the frame on the device for the metrics failed: {0}")]
    Metrics(String),
    #[error("{0}")]
    MotionBlur(String),
}

/// What the capture phase keeps of each measured frame (the saved frames' images are always
/// kept, in [`Rendered::saved`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Keep {
    /// sRGB frames on the CPU (the CPU metrics, ColorVideoVDP).
    pub frames: bool,
    /// Linear frames on the CPU.
    pub hdr: bool,
    /// Frames on the device ([`GpuFrame`]s, for the GPU metrics); never read back.
    pub gpu: bool,
    /// The device frames' linear floats (HDR-FLIP).
    pub gpu_hdr: bool,
}

impl Keep {
    /// Frames on the CPU, linear ones too when `hdr`.
    pub fn cpu(hdr: bool) -> Keep {
        Keep {
            frames: true,
            hdr,
            ..Keep::default()
        }
    }
}

impl Rendered {
    /// Nothing rendered yet; `timestamps` and `readback_bytes` as the timers and readbacks say.
    pub fn empty(timestamps: bool, readback_bytes: u64) -> Rendered {
        Rendered {
            measurements: Vec::new(),
            cpu_ms: Vec::new(),
            frames: Vec::new(),
            hdr_frames: Vec::new(),
            gpu_frames: Vec::new(),
            saved: Vec::new(),
            non_finite: 0,
            non_finite_masks: Vec::new(),
            non_finite_counts: Vec::new(),
            deterministic: None,
            timestamps,
            readback_bytes,
            extras: Vec::new(),
            frame_ms: Vec::new(),
            ended_by: StopReason::Count,
            conditions: None,
            energy_window: None,
            clock_warmup_ms: 0.0,
            hashes: Vec::new(),
            digests: Vec::new(),
        }
    }
}

/// Appends a variant's frame hashes to the `TESSERA_FRAME_HASHES` file, when set.
pub fn append_hashes(scenario: &str, variant: &str, hashes: &[u64]) {
    use std::io::Write;
    let Some(path) = frame_hash_file() else {
        return;
    };
    let lines: String = hashes
        .iter()
        .enumerate()
        .map(|(i, h)| format!("{scenario} {variant} {i} {h:016x}\n"))
        .collect();
    let written = std::fs::OpenOptions::new()
        .create(true)
        .append(true)
        .open(&path)
        .and_then(|mut f| f.write_all(lines.as_bytes()));
    if let Err(e) = written {
        eprintln!(
            "warning: cannot append frame hashes to {}: {e}",
            path.display()
        );
    }
}
