//! Renders one variant's frames: warm-up, then measured frames with per-pass GPU timings, CPU wall
//! time and fragment-shader invocations; then the same sequence again to capture every measured
//! frame: read back to the CPU, or, for the GPU metrics, kept on the device ([`Keep`]).
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
//! timed pass, compared bit for bit on the device with the capture phase's last frame:
//! `render/frame_check.rs`). With sensors, the clock warm-up and the energy window before the
//! timed frames are one window: the sequence runs pipelined, untimed, while the sampler reads the
//! clock and the energy counter, and from the top clock on it counts frames until the counter has
//! stepped [`ENERGY_STEPS`] times or for [`ENERGY_WINDOW_MS`] at most.

use std::cell::Cell;
use std::collections::{BTreeMap, VecDeque};
use std::time::Instant;

use tessera_results::conditions::StopReason;

use tessera_metrics::{encode_srgb8, HdrImage, Rgb8Image};
use tessera_metrics_gpu::GpuFrame;

use super::phases;
use crate::conditions::sampler::Sampler;
use crate::conditions::{Sample, ENERGY_SAMPLE_INTERVAL_MS, ENERGY_STEPS, ENERGY_WINDOW_MS};
use crate::gpu::Gpu;
use crate::render::frame_check::FrameCheck;
use crate::render::graph::PassKind;
use crate::render::readback::Readback;
use crate::render::renderer::{FrameExtras, FrameInfo, Renderer};
use crate::render::scene::SceneGpu;
use crate::render::timers::{FrameMeasurements, Timers, MAX_PENDING_FRAMES};
use crate::scenario::Scenario;

/// The clock warm-up ends early once its load has run at the top graphics clock for this long...
const CLOCK_SETTLED_MS: f64 = 50.0;
/// ...and it has lasted at least this long.
const MIN_CLOCK_WARMUP_MS: f64 = 100.0;

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
    snapshot: Option<(u32, &FrameCheck)>,
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
        if let Some((_, check)) = snapshot.filter(|(i, _)| *i == index) {
            let mut encoder = gpu
                .device
                .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                    label: Some("snapshot"),
                });
            check.snapshot(&mut encoder, technique.output());
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

/// Renders the scenario's frames twice: once timed, once captured; no sensors. Keeps every
/// measured frame on the CPU when `keep_frames`, their linear floats when `keep_hdr`.
pub fn render(
    gpu: &Gpu,
    scene: &mut SceneGpu,
    scenario: &Scenario,
    technique: &mut dyn Renderer,
    keep_frames: bool,
    keep_hdr: bool,
    on_frame: &mut dyn FnMut(),
) -> Result<Rendered, RenderError> {
    let keep = Keep {
        frames: keep_frames,
        hdr: keep_hdr,
        ..Keep::default()
    };
    render_keeping(gpu, scene, scenario, technique, keep, on_frame)
}

/// [`render`], keeping what `keep` says.
pub fn render_keeping(
    gpu: &Gpu,
    scene: &mut SceneGpu,
    scenario: &Scenario,
    technique: &mut dyn Renderer,
    keep: Keep,
    on_frame: &mut dyn FnMut(),
) -> Result<Rendered, RenderError> {
    render_sampled(gpu, scene, scenario, technique, keep, None, on_frame)
}

/// [`render`], with `sampler` reading the sensors during the measured frames.
pub fn render_sampled(
    gpu: &Gpu,
    scene: &mut SceneGpu,
    scenario: &Scenario,
    technique: &mut dyn Renderer,
    keep: Keep,
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
    let check = FrameCheck::new(gpu, out.width(), out.height());
    // The metrics' own copy of each captured frame (the output is the technique's and changes
    // with the next frame), when frames stay on the device.
    let metric_copy = keep.gpu.then(|| metric_texture(gpu, out));
    let mut rendered = Rendered {
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
        timestamps: timers.has_timestamps(),
        readback_bytes: readback.bytes() + check.bytes(),
        extras: Vec::new(),
        frame_ms: Vec::new(),
        ended_by: StopReason::Count,
        conditions: None,
        energy_window: None,
        clock_warmup_ms: 0.0,
        hashes: Vec::new(),
        digests: Vec::new(),
    };
    let hash_frames = frame_hash_file().is_some();

    // Clock warm-up, so that the GPU reaches its working clocks before the first timed frame,
    // and the energy window. The clocks of the measured frames are recorded either way
    // (`conditions`), and a low one is flagged.
    let warmup_ms = scenario.clock_warmup_ms(&gpu.info.device_type);
    let energy_ms = scenario.energy_window_ms.unwrap_or(ENERGY_WINDOW_MS);
    match sampler.filter(|_| energy_ms > 0.0) {
        // With sensors: the clock warm-up and the energy window are one window, before the
        // timed frames. The sequence runs pipelined from frame 0 while the sensors are read
        // every millisecond; from the first sample at the top clock (or after `warmup_ms`, where
        // the clock stays below it or its maximum is unknown) the window counts frames and the
        // energy counter's steps,
        // and it ends ENERGY_STEPS steps later (at least CLOCK_SETTLED_MS later, and
        // MIN_CLOCK_WARMUP_MS after its start), or energy_ms after that point at most. A clock
        // below the top restarts the count. Energy per frame is read from the samples and frames
        // after that point; the timed frames then follow a GPU at its working clock.
        Some(s) => {
            let _span = phases::span("clock warm-up + energy window");
            let start = Instant::now();
            let max_mhz = s.limits().max_graphics_clock_mhz;
            // When counting began: (instant, window time in s, energy steps then, frames then).
            let since: Cell<Option<(Instant, f64, u32, u32)>> = Cell::new(None);
            let frames = Cell::new(0u32);
            let ms = |t: Instant| t.elapsed().as_secs_f64() * 1000.0;
            s.begin_every(std::time::Duration::from_secs_f64(
                ENERGY_SAMPLE_INTERVAL_MS / 1000.0,
            ));
            let cap_ms = warmup_ms + energy_ms;
            let steps_wanted = scenario.energy_steps.unwrap_or(ENERGY_STEPS);
            let go_on = || {
                // At the top clock, or warmed up as long as the clock warm-up may last.
                let at_top = ms(start) >= warmup_ms
                    || max_mhz.is_some_and(|max| {
                        s.latest_clock_mhz().is_some_and(|c| {
                            c >= crate::conditions::summary::TOP_CLOCK_FRACTION * max
                        })
                    });
                if !at_top {
                    since.set(None);
                } else if since.get().is_none() {
                    let now = Instant::now();
                    since.set(Some((
                        now,
                        (now - start).as_secs_f64(),
                        s.energy_steps(),
                        frames.get(),
                    )));
                }
                let done = since.get().is_some_and(|(t, _, steps, _)| {
                    (s.energy_steps() - steps >= steps_wanted && ms(t) >= CLOCK_SETTLED_MS
                        || ms(t) >= energy_ms)
                        && ms(start) >= MIN_CLOCK_WARMUP_MS
                });
                !done && ms(start) < cap_ms
            };
            pipelined(
                gpu,
                scene,
                scenario,
                technique,
                &mut timers,
                (0..).take_while(|_| go_on()),
                None,
                &mut |_, _| frames.set(frames.get() + 1),
            );
            let samples = s.end();
            rendered.clock_warmup_ms = since
                .get()
                .map_or(ms(start), |(t, _, _, _)| (t - start).as_secs_f64() * 1000.0);
            // The samples and frames of the counted part (all of them if it never began).
            let (from_s, from_frames) = since.get().map_or((0.0, 0), |(_, at, _, f)| (at, f));
            let counted: Vec<Sample> = samples.into_iter().filter(|x| x.at_s >= from_s).collect();
            rendered.energy_window = Some((counted, frames.get() - from_frames));
        }
        None => {
            // Without sensors (or without an energy window): frame 0 (which never reads
            // history) repeated until the GPU has been busy for `warmup_ms`, so that it reaches
            // its working clocks before the first timed frame; where the sensors read the clock
            // and know its maximum, it ends once the load has run at the top clock for
            // CLOCK_SETTLED_MS (after at least MIN_CLOCK_WARMUP_MS).
            let _span = phases::span("clock warm-up");
            let warm_start = Instant::now();
            let top_clock = sampler.and_then(|s| Some((s, s.limits().max_graphics_clock_mhz?)));
            let mut settled_since: Option<Instant> = None;
            while warm_start.elapsed().as_secs_f64() * 1000.0 < warmup_ms {
                let chunk_start = Instant::now();
                if let Some((s, _)) = top_clock {
                    s.begin();
                }
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
                if let Some((s, max)) = top_clock {
                    let at_top = crate::conditions::summary::at_top_clock(&s.end(), max);
                    settled_since = if at_top {
                        settled_since.or(Some(chunk_start))
                    } else {
                        None
                    };
                    let ms = |t: Instant| t.elapsed().as_secs_f64() * 1000.0;
                    if settled_since.is_some_and(|t| ms(t) >= CLOCK_SETTLED_MS)
                        && ms(warm_start) >= MIN_CLOCK_WARMUP_MS
                    {
                        break;
                    }
                }
            }

            rendered.clock_warmup_ms = warm_start.elapsed().as_secs_f64() * 1000.0;
        }
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
    let timed_span = phases::span("timed frames");
    pipelined(
        gpu,
        scene,
        scenario,
        technique,
        &mut timers,
        (0..timed_end).take_while(|_| stop.get().is_none()),
        compared_last.map(|i| (i, &check)),
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

    drop(timed_span);
    // The last compared frame of the timed phase was copied aside as it completed: the capture
    // phase renders the sequence again from frame 0 and must end on the same bits (determinism,
    // histories included), compared on the device.

    // Capture phase: the same frames again, one at a time (rendering is deterministic, histories
    // included); each measured frame is counted (fragment invocations) and checked (non-finite
    // values), then read back or kept on the device for images and metrics. Not timed. A frame
    // comes back to the CPU only when something on the CPU needs it: CPU frames asked for, a
    // saved frame, `TESSERA_FRAME_HASHES`.
    timers.enable_stats(true);
    // `reference.motion_blur`: the compared frames are blurred along the scene's motion first.
    let mut blur = if scenario.motion_blur {
        Some(
            super::motion_blur::BlurredCapture::new(gpu, scenario.width, scenario.height)
                .map_err(RenderError::MotionBlur)?,
        )
    } else {
        None
    };
    for index in 0..scenario.total_frames() {
        let render_span = phases::span("capture: render");
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
        drop(render_span);
        if index >= scenario.warmup_frames {
            let m = index - scenario.warmup_frames;
            if let Some(fm) = rendered.measurements.get_mut(m as usize) {
                fm.fragment_invocations = stats;
            }
            let saved = scenario.save_frames.contains(&m);
            // An sRGB frame the CPU needs (a saved frame; the frames of ColorVideoVDP, which
            // reads CPU images) comes from the metrics' copy, encoded on the device (half the
            // float frame's bytes, no CPU encode), unless the floats themselves are needed.
            // Every measured frame's 8-bit form is digested (approved frames), so each comes
            // back as 8-bit sRGB: encoded on the device where the metrics keep frames there
            // (the same bytes as the CPU's encode: metrics-gpu's `encode` test), else here.
            let ldr_from_device = metric_copy.is_some() && !(keep.hdr || hash_frames);
            let on_cpu = keep.hdr || hash_frames || !ldr_from_device;
            let last = index + 1 == scenario.total_frames();
            let compare = last && compared_last.is_some();
            let output = technique.output();
            // What the metrics, images and hashes see: the output, or it motion-blurred (its
            // own submission; the checks below read the output itself).
            let blurring = blur.is_some();
            let compared = match blur.as_mut() {
                Some(b) => {
                    let _span = phases::span("capture: motion blur");
                    let (motion, motion_timers) = b.motion_pass();
                    submit_frame(gpu, scene, scenario, motion, motion_timers, index);
                    let _ = gpu.device.poll(wgpu::PollType::Wait {
                        submission_index: None,
                        timeout: None,
                    });
                    b.blur(gpu, output, history_valid(scenario, index))
                        .map_err(RenderError::MotionBlur)?
                }
                None => output,
            };
            // The device's checks (every frame not read back; the determinism check on the
            // last), the metrics' copy, and the readback's copy: one submission.
            let checks_span = phases::span("capture: checks");
            let mut encoder = gpu
                .device
                .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                    label: Some("capture"),
                });
            // A blurred read-back frame's non-finite values are not the output's: then the
            // device checks the output.
            let checked = !on_cpu || compare || blurring;
            if checked {
                check.record(gpu, &mut encoder, output, compare);
            }
            if let Some(copy) = &metric_copy {
                encoder.copy_texture_to_texture(
                    compared.as_image_copy(),
                    copy.as_image_copy(),
                    compared.size(),
                );
            }
            if on_cpu {
                readback.copy(&mut encoder, compared);
            }
            gpu.queue.submit([encoder.finish()]);
            let mut device_srgb = None;
            if let Some(copy) = &metric_copy {
                let mut metrics = gpu.metrics();
                let frame = metrics
                    .frame_from_texture_with(copy, keep.gpu_hdr)
                    .map_err(|e| RenderError::Metrics(e.to_string()))?;
                if ldr_from_device {
                    let _span = phases::span("capture: readback");
                    device_srgb = Some(
                        metrics
                            .read_ldr(&frame)
                            .map_err(|e| RenderError::Metrics(e.to_string()))?,
                    );
                }
                rendered.gpu_frames.push(frame);
            }
            let results = if checked {
                Some(
                    check
                        .read(gpu, compare)
                        .map_err(|_| RenderError::Readback)?,
                )
            } else {
                None
            };
            drop(checks_span);
            let frame = if on_cpu {
                let _span = phases::span("capture: readback");
                Some(
                    readback
                        .read(&gpu.device)
                        .map_err(|_| RenderError::Readback)?,
                )
            } else {
                None
            };
            if compare {
                rendered.deterministic = results.as_ref().and_then(|r| r.same_as_snapshot);
            }
            let (non_finite, mask) = match (&frame, results) {
                (_, Some(r)) if blurring => (r.non_finite, r.non_finite_mask),
                (Some(f), _) => (f.non_finite, f.non_finite_mask.clone()),
                (None, Some(r)) => (r.non_finite, r.non_finite_mask),
                (None, None) => (0, None),
            };
            rendered.non_finite += non_finite;
            rendered.non_finite_counts.push(non_finite);
            rendered.non_finite_masks.push(mask);
            if let Some(frame) = &frame {
                if hash_frames {
                    let _span = phases::span("capture: frame hashes");
                    rendered.hashes.push(image_hash(&frame.image));
                }
            }
            // The sRGB frame: encoded on the device, or here from the read-back floats.
            let srgb = match (device_srgb, &frame) {
                (Some(img), _) => Some(img),
                (None, Some(f)) => {
                    let _span = phases::span("capture: srgb encode");
                    Some(encode_srgb8(&f.image))
                }
                _ => None,
            };
            if let Some(img) = &srgb {
                let _span = phases::span("capture: digests");
                rendered.digests.push(tessera_results::digest::frame_digest(
                    img.width, img.height, &img.data,
                ));
            }
            let extras_span = phases::span("capture: technique extras");
            // Techniques read the frame only for the images of saved frames.
            let empty = Rgb8Image {
                width: 0,
                height: 0,
                data: Vec::new(),
            };
            let image = srgb.as_ref().filter(|_| saved).unwrap_or(&empty);
            rendered
                .extras
                .push(technique.frame_extras(gpu, image, saved));
            drop(extras_span);
            if let Some(srgb) = srgb {
                match (saved, keep.frames) {
                    (true, true) => {
                        rendered.saved.push((m, srgb.clone()));
                        rendered.frames.push(srgb);
                    }
                    (true, false) => rendered.saved.push((m, srgb)),
                    (false, true) => rendered.frames.push(srgb),
                    (false, false) => {}
                }
            }
            if let Some(frame) = frame {
                if keep.hdr {
                    rendered.hdr_frames.push(frame.image);
                }
            }
        }
        on_frame();
    }
    Ok(rendered)
}

/// The metrics' texture a captured frame is copied into: the output's size and format, readable
/// by the metrics' encode pass.
fn metric_texture(gpu: &Gpu, output: &wgpu::Texture) -> wgpu::Texture {
    gpu.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("metrics frame copy"),
        size: output.size(),
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: output.format(),
        usage: wgpu::TextureUsages::COPY_DST | wgpu::TextureUsages::TEXTURE_BINDING,
        view_formats: &[],
    })
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
