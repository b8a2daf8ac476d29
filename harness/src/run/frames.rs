//! Renders one variant's frames: warm-up, then measured frames with per-pass GPU timings, CPU wall
//! time and fragment-shader invocations; then the same sequence again to read back every measured
//! frame.
//!
//! One frame is encoded, submitted and waited for before the next. Timing and capture are separate
//! passes over the sequence, so readback, image encoding and metrics never sit between timed frames
//! (on a real GPU, idle gaps between frames lower its clocks and inflate the next frame's time:
//! measured on an H200, the same 1080p pass took 3.9 ms or 17.7 ms depending on what ran before).
//! Timed frames are pipelined, up to three in flight, after a time-based clock warm-up. This module does not compute metrics or write files.

use std::collections::{BTreeMap, VecDeque};
use std::time::Instant;

use tessera_metrics::{encode_srgb8, HdrImage, Rgb8Image};

use crate::gpu::Gpu;
use crate::render::graph::PassKind;
use crate::render::readback::Readback;
use crate::render::renderer::{FrameExtras, FrameInfo, Renderer};
use crate::render::scene::SceneGpu;
use crate::render::timers::{FrameMeasurements, Timers, MAX_PENDING_FRAMES};
use crate::scenario::Scenario;

/// What rendering a variant produced.
pub struct Rendered {
    /// One entry per measured frame.
    pub measurements: Vec<FrameMeasurements>,
    pub cpu_ms: Vec<f64>,
    /// sRGB frames of every measured frame, when asked to keep them.
    pub frames: Vec<Rgb8Image>,
    /// Linear frames, when asked to keep them (HDR metrics).
    pub hdr_frames: Vec<HdrImage>,
    pub non_finite: u64,
    /// Per measured frame, the pixels with a non-finite channel (bit per pixel, row-major);
    /// `None` for a frame without any.
    pub non_finite_masks: Vec<Option<Vec<u64>>>,
    /// The capture phase's last frame equals the timed phase's bit for bit (`None`: no frames).
    pub deterministic: Option<bool>,
    pub timestamps: bool,
    pub readback_bytes: u64,
    /// The technique's extras of every measured frame ([`Renderer::frame_extras`]).
    pub extras: Vec<FrameExtras>,
    /// Per measured frame, a hash of its exact bits, when `TESSERA_FRAME_HASHES` is set (see
    /// [`frame_hash_file`]); empty otherwise.
    pub hashes: Vec<u64>,
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
}

/// Whether frame `index` continues the previous frame's shot: false on the first frame and at a
/// camera cut, where techniques must not read history.
pub fn history_valid(scenario: &Scenario, index: u32) -> bool {
    let cam = &scenario.camera;
    index > 0
        && cam.pose_at(scenario.frame_time(index)).segment
            == cam.pose_at(scenario.frame_time(index - 1)).segment
}

/// Encodes and submits frame `index` without waiting for it.
pub fn submit_frame(
    gpu: &Gpu,
    scene: &mut SceneGpu,
    scenario: &Scenario,
    technique: &mut dyn Renderer,
    timers: &mut Timers,
    index: u32,
) -> wgpu::SubmissionIndex {
    let time = scenario.frame_time(index);
    let prev_time = if index == 0 {
        time
    } else {
        scenario.frame_time(index - 1)
    };
    scene.write_objects(&gpu.queue, time, prev_time);
    let mut encoder = gpu
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("frame"),
        });
    let history_valid = history_valid(scenario, index);
    technique.record(
        gpu,
        scene,
        timers,
        &mut encoder,
        FrameInfo {
            index,
            time,
            prev_time,
            history_valid,
        },
    );
    timers.resolve(&mut encoder);
    let submission = gpu.queue.submit([encoder.finish()]);
    timers.end_frame();
    submission
}

/// Renders `frames` back to back with up to `MAX_PENDING_FRAMES - 1` in flight, so the GPU never
/// waits for the CPU; `done(index, pass times)` is called as each frame completes, in order.
fn pipelined(
    gpu: &Gpu,
    scene: &mut SceneGpu,
    scenario: &Scenario,
    technique: &mut dyn Renderer,
    timers: &mut Timers,
    frames: impl Iterator<Item = u32>,
    done: &mut dyn FnMut(u32, BTreeMap<String, f64>),
) {
    let mut in_flight: VecDeque<(u32, wgpu::SubmissionIndex)> = VecDeque::new();
    let mut drain_one = |in_flight: &mut VecDeque<(u32, wgpu::SubmissionIndex)>,
                         timers: &mut Timers| {
        let Some((index, submission)) = in_flight.pop_front() else {
            return;
        };
        let _ = gpu.device.poll(wgpu::PollType::Wait {
            submission_index: Some(submission),
            timeout: None,
        });
        let times = timers.try_collect(&gpu.queue).or_else(|| {
            let _ = gpu.device.poll(wgpu::PollType::Wait {
                submission_index: None,
                timeout: None,
            });
            timers.try_collect(&gpu.queue)
        });
        done(index, times.unwrap_or_default());
    };
    for index in frames {
        let submission = submit_frame(gpu, scene, scenario, technique, timers, index);
        in_flight.push_back((index, submission));
        while in_flight.len() >= MAX_PENDING_FRAMES - 1 {
            drain_one(&mut in_flight, timers);
        }
    }
    while !in_flight.is_empty() {
        drain_one(&mut in_flight, timers);
    }
}

/// Renders the scenario's frames twice: once timed, once captured.
pub fn render(
    gpu: &Gpu,
    scene: &mut SceneGpu,
    scenario: &Scenario,
    technique: &mut dyn Renderer,
    keep_frames: bool,
    keep_hdr: bool,
    on_frame: &mut dyn FnMut(),
) -> Result<Rendered, RenderError> {
    let render_passes: Vec<&'static str> = technique
        .plan()
        .passes
        .iter()
        .filter(|p| p.kind == PassKind::Render)
        .map(|p| p.name)
        .collect();
    let mut timers = Timers::new(&gpu.device, &render_passes)?;
    let out = technique.output();
    let readback = Readback::new(&gpu.device, out.width(), out.height());
    let mut rendered = Rendered {
        measurements: Vec::new(),
        cpu_ms: Vec::new(),
        frames: Vec::new(),
        hdr_frames: Vec::new(),
        non_finite: 0,
        non_finite_masks: Vec::new(),
        deterministic: None,
        timestamps: timers.has_timestamps(),
        readback_bytes: readback.bytes(),
        extras: Vec::new(),
        hashes: Vec::new(),
    };
    let hash_frames = frame_hash_file().is_some();

    // Clock warm-up: frame 0 (which never reads history) repeated until the GPU has been busy for
    // `warmup_ms`, so that it reaches its working clocks before the first timed frame.
    let warm_start = Instant::now();
    let warmup_ms = scenario.clock_warmup_ms(&gpu.info.device_type);
    while warm_start.elapsed().as_secs_f64() * 1000.0 < warmup_ms {
        pipelined(
            gpu,
            scene,
            scenario,
            technique,
            &mut timers,
            std::iter::repeat_n(0, 4),
            &mut |_, _| {},
        );
    }

    // Timed phase: warm-up then measured frames, pipelined, nothing else on the queue. CPU frame
    // time is the interval between consecutive frame completions.
    let mut last = Instant::now();
    let warmup = scenario.warmup_frames;
    pipelined(
        gpu,
        scene,
        scenario,
        technique,
        &mut timers,
        0..scenario.total_frames(),
        &mut |index, times| {
            let now = Instant::now();
            if index >= warmup {
                rendered.measurements.push(FrameMeasurements {
                    gpu_ms: times,
                    fragment_invocations: BTreeMap::new(),
                });
                rendered.cpu_ms.push((now - last).as_secs_f64() * 1000.0);
            }
            last = now;
            on_frame();
        },
    );

    // The timed phase's last frame, kept as a hash: the capture phase renders the sequence again
    // from frame 0 and must end on the same bits (determinism, histories included).
    let timed_hash = if scenario.measured_frames > 0 {
        Some(image_hash(&read_output(gpu, &readback, technique)?.image))
    } else {
        None
    };

    // Capture phase: the same frames again, one at a time (rendering is deterministic, histories
    // included); each measured frame is counted (fragment invocations) and read back for
    // non-finite checks, images and metrics. Not timed.
    timers.enable_stats(true);
    for index in 0..scenario.total_frames() {
        submit_frame(gpu, scene, scenario, technique, &mut timers, index);
        let _ = gpu.device.poll(wgpu::PollType::Wait {
            submission_index: None,
            timeout: None,
        });
        let _ = timers.try_collect(&gpu.queue);
        let stats = timers.read_stats(&gpu.device);
        if index >= scenario.warmup_frames {
            if let Some(m) = rendered
                .measurements
                .get_mut((index - scenario.warmup_frames) as usize)
            {
                m.fragment_invocations = stats;
            }
            let frame = read_output(gpu, &readback, technique)?;
            rendered.non_finite += frame.non_finite;
            let saved = scenario
                .save_frames
                .contains(&(index - scenario.warmup_frames));
            rendered
                .extras
                .push(technique.frame_extras(gpu, &frame.image, saved));
            rendered.non_finite_masks.push(frame.non_finite_mask);
            if hash_frames {
                rendered.hashes.push(image_hash(&frame.image));
            }
            if index + 1 == scenario.total_frames() {
                rendered.deterministic = timed_hash.map(|h| h == image_hash(&frame.image));
            }
            if keep_frames {
                rendered.frames.push(encode_srgb8(&frame.image));
            }
            if keep_hdr {
                rendered.hdr_frames.push(frame.image);
            }
        }
        on_frame();
    }
    Ok(rendered)
}

fn read_output(
    gpu: &Gpu,
    readback: &Readback,
    technique: &dyn Renderer,
) -> Result<crate::render::readback::CpuFrame, RenderError> {
    let mut encoder = gpu
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("readback"),
        });
    readback.copy(&mut encoder, technique.output());
    gpu.queue.submit([encoder.finish()]);
    readback
        .read(&gpu.device)
        .map_err(|_| RenderError::Readback)
}

/// A hash of the exact bits of a frame (NaN payloads included).
fn image_hash(image: &HdrImage) -> u64 {
    use std::hash::{Hash, Hasher};
    let mut h = std::hash::DefaultHasher::new();
    for v in &image.data {
        v.to_bits().hash(&mut h);
    }
    h.finish()
}
