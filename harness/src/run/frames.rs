//! Renders one variant's frames: warm-up, then measured frames with per-pass GPU timings, CPU wall
//! time and fragment-shader invocations; then the same sequence again to read back every measured
//! frame.
//!
//! One frame is encoded, submitted and waited for before the next. Timing and capture are separate
//! passes over the sequence, so readback, image encoding and metrics never sit between timed frames
//! (on a real GPU, idle gaps between frames lower its clocks and inflate the next frame's time:
//! measured on an H200, the same 1080p pass took 3.9 ms or 17.7 ms depending on what ran before).
//! Timed frames are pipelined, up to three in flight, after a time-based clock warm-up. This module does not compute metrics or write files.
//!
//! The sensor window ([`Sampler`]) opens as the last warm-up frame completes and closes as the last
//! measured frame does; under `measured = "auto"` the timed phase renders measured frames until
//! the stop rule ends it ([`crate::timing::stop`]), and the last compared frame is copied aside as
//! it completes, for the determinism check (a copy submitted between two frames, outside every
//! timed pass). With sensors, an energy window follows: the sequence goes on, untimed, for at
//! least [`ENERGY_WINDOW_MS`] while the sampler reads the energy counter.

use std::cell::Cell;
use std::collections::{BTreeMap, VecDeque};
use std::time::Instant;

use tessera_results::conditions::StopReason;

use tessera_metrics::{encode_srgb8, HdrImage, Rgb8Image};

use crate::conditions::sampler::Sampler;
use crate::conditions::{Sample, ENERGY_WINDOW_MS};
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
    /// Per timed measured frame, the sum of its pass times (its CPU frame time without
    /// timestamps): what the stop rule read.
    pub frame_ms: Vec<f64>,
    /// What ended the timed phase.
    pub ended_by: StopReason,
    /// The sensor samples of the measured frames; `None` without a sampler.
    pub conditions: Option<Vec<Sample>>,
    /// The sensor samples of the energy window and its frame count; `None` without a sampler.
    pub energy_window: Option<(Vec<Sample>, u32)>,
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
#[allow(clippy::too_many_arguments)]
fn pipelined(
    gpu: &Gpu,
    scene: &mut SceneGpu,
    scenario: &Scenario,
    technique: &mut dyn Renderer,
    timers: &mut Timers,
    frames: impl Iterator<Item = u32>,
    snapshot: Option<(u32, &Readback)>,
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
        let mut submission = submit_frame(gpu, scene, scenario, technique, timers, index);
        if let Some((_, readback)) = snapshot.filter(|(i, _)| *i == index) {
            let mut encoder = gpu
                .device
                .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                    label: Some("snapshot"),
                });
            readback.copy(&mut encoder, technique.output());
            submission = gpu.queue.submit([encoder.finish()]);
        }
        in_flight.push_back((index, submission));
        while in_flight.len() >= MAX_PENDING_FRAMES - 1 {
            drain_one(&mut in_flight, timers);
        }
    }
    while !in_flight.is_empty() {
        drain_one(&mut in_flight, timers);
    }
}

/// Renders the scenario's frames twice: once timed, once captured; no sensors.
pub fn render(
    gpu: &Gpu,
    scene: &mut SceneGpu,
    scenario: &Scenario,
    technique: &mut dyn Renderer,
    keep_frames: bool,
    keep_hdr: bool,
    on_frame: &mut dyn FnMut(),
) -> Result<Rendered, RenderError> {
    render_sampled(
        gpu,
        scene,
        scenario,
        technique,
        keep_frames,
        keep_hdr,
        None,
        on_frame,
    )
}

/// [`render`], with `sampler` reading the sensors during the measured frames.
#[allow(clippy::too_many_arguments)]
pub fn render_sampled(
    gpu: &Gpu,
    scene: &mut SceneGpu,
    scenario: &Scenario,
    technique: &mut dyn Renderer,
    keep_frames: bool,
    keep_hdr: bool,
    sampler: Option<&Sampler>,
    on_frame: &mut dyn FnMut(),
) -> Result<Rendered, RenderError> {
    let render_passes: Vec<&'static str> = technique
        .plan()
        .passes
        .iter()
        .filter(|p| p.kind == PassKind::Render && !p.self_counted)
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
        frame_ms: Vec::new(),
        ended_by: StopReason::Count,
        conditions: None,
        energy_window: None,
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
            None,
            &mut |_, _| {},
        );
    }

    // Timed phase: warm-up then measured frames, pipelined, nothing else on the queue. CPU frame
    // time is the interval between consecutive frame completions. A fixed count ends after its
    // frames; `auto` when its rule says so (frames already in flight then are not counted).
    let mut last = Instant::now();
    let warmup = scenario.warmup_frames;
    let compared_last = scenario
        .total_frames()
        .checked_sub(1)
        .filter(|_| scenario.measured_frames > 0);
    let timed_end = warmup + scenario.auto.map_or(scenario.measured_frames, |a| a.max);
    let stop: Cell<Option<StopReason>> = Cell::new(None);
    // When the first measured frame began: the completion of the frame before it.
    let mut measuring_since: Option<Instant> = None;
    // The last frame the timed phase rendered (counted or, after an auto stop, not).
    let mut last_done = 0u32;
    let timestamps = rendered.timestamps;
    if warmup == 0 {
        if let Some(s) = sampler {
            s.begin();
        }
    }
    pipelined(
        gpu,
        scene,
        scenario,
        technique,
        &mut timers,
        (0..timed_end).take_while(|_| stop.get().is_none()),
        compared_last.map(|i| (i, &readback)),
        &mut |index, times| {
            last_done = index;
            if stop.get().is_some() {
                return;
            }
            let now = Instant::now();
            let cpu_ms = (now - last).as_secs_f64() * 1000.0;
            if index >= warmup {
                rendered.frame_ms.push(if timestamps {
                    times.values().sum()
                } else {
                    cpu_ms
                });
                rendered.measurements.push(FrameMeasurements {
                    gpu_ms: times,
                    fragment_invocations: BTreeMap::new(),
                });
                rendered.cpu_ms.push(cpu_ms);
                let first = *measuring_since.get_or_insert(last);
                let ended = match scenario.auto {
                    Some(rule) => rule.decide(&rendered.frame_ms, (now - first).as_secs_f64()),
                    None => (index + 1 == timed_end).then_some(StopReason::Count),
                };
                if let Some(reason) = ended {
                    stop.set(Some(reason));
                    rendered.ended_by = reason;
                    rendered.conditions = sampler.map(Sampler::end);
                }
            } else if index + 1 == warmup {
                if let Some(s) = sampler {
                    s.begin();
                }
            }
            last = now;
            on_frame();
        },
    );

    // The last compared frame of the timed phase, copied aside as it completed, kept as a hash:
    // the capture phase renders the sequence again from frame 0 and must end on the same bits
    // (determinism, histories included).
    let timed_hash = match compared_last {
        Some(_) => Some(image_hash(
            &readback
                .read(&gpu.device)
                .map_err(|_| RenderError::Readback)?
                .image,
        )),
        None => None,
    };

    // Energy window, with sensors only: the sequence goes on from the last timed frame, pipelined,
    // for at least ENERGY_WINDOW_MS, while the sampler reads the energy counter.
    if let Some(s) = sampler {
        let first = last_done + 1;
        let window = std::time::Duration::from_secs_f64(ENERGY_WINDOW_MS / 1000.0);
        let mut frames = 0u32;
        s.begin();
        let start = Instant::now();
        pipelined(
            gpu,
            scene,
            scenario,
            technique,
            &mut timers,
            (first..).take_while(|_| start.elapsed() < window),
            None,
            &mut |_, _| frames += 1,
        );
        rendered.energy_window = Some((s.end(), frames));
    }

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
        let mut stats = timers.read_stats(&gpu.device);
        if timers.stats_enabled() {
            stats.extend(technique.own_statistics(gpu));
        }
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
