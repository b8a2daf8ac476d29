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
use std::collections::BTreeMap;
use std::time::Instant;

use tessera_results::conditions::StopReason;

use super::capture::Capture;
use super::phases;
use super::rendered::{Keep, RenderError, Rendered};
use super::sequence::{compared_last, Sequence};
use crate::conditions::sampler::Sampler;
use crate::conditions::{Sample, ENERGY_SAMPLE_INTERVAL_MS, ENERGY_STEPS, ENERGY_WINDOW_MS};
use crate::gpu::Gpu;
use crate::render::frame_check::FrameCheck;
use crate::render::graph::PassKind;
use crate::render::readback::Readback;
use crate::render::renderer::Renderer;
use crate::render::scene::SceneGpu;
use crate::render::timers::{FrameMeasurements, Timers};
use crate::scenario::Scenario;

/// The clock warm-up ends early once its load has run at the top graphics clock for this long...
const CLOCK_SETTLED_MS: f64 = 50.0;
/// ...and it has lasted at least this long.
const MIN_CLOCK_WARMUP_MS: f64 = 100.0;

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

/// What renders a technique's sequence and captures its frames: the sequence with its timers
/// (the technique's render passes), the capture (readback, the device's checks) and the empty
/// result they fill.
fn prepare<'a>(
    gpu: &'a Gpu,
    scene: &'a mut SceneGpu,
    scenario: &'a Scenario,
    technique: &'a mut dyn Renderer,
    keep: Keep,
) -> Result<(Sequence<'a>, Capture<'a>, Rendered), RenderError> {
    let render_passes: Vec<&'static str> = technique
        .plan()
        .passes
        .iter()
        .filter(|p| p.kind == PassKind::Render && !p.self_counted)
        .map(|p| p.name)
        .collect();
    let timers = Timers::new(&gpu.device, &render_passes)?;
    let out = technique.output();
    let readback = Readback::new(&gpu.device, out.width(), out.height());
    let check = FrameCheck::new(gpu, out.width(), out.height());
    let rendered = Rendered::empty(timers.has_timestamps(), readback.bytes() + check.bytes());
    let capture = Capture::new(gpu, scenario, out, keep, readback, check)?;
    let seq = Sequence {
        gpu,
        scene,
        scenario,
        technique,
        timers,
    };
    Ok((seq, capture, rendered))
}

/// A history-free reference (the converged or supersampled ground truth: each frame a function of
/// its scene time alone) captured once, measured frames only: no clock warm-up, no timed phase,
/// no warm-up frames. Its timings are never read, and a renderer without history has nothing for
/// the warm-up frames to build, so the frames kept are the same bits as after the full sequence
/// (scene time is set per frame from its index). On the H200 a 32-sample 4K city reference
/// rendered its 42 frames twice for the 10 it is compared on.
pub fn render_history_free(
    gpu: &Gpu,
    scene: &mut SceneGpu,
    scenario: &Scenario,
    technique: &mut dyn Renderer,
    keep: Keep,
    on_frame: &mut dyn FnMut(),
) -> Result<Rendered, RenderError> {
    let (mut seq, mut capture, mut rendered) = prepare(gpu, scene, scenario, technique, keep)?;
    seq.timers.enable_stats(true);
    for index in scenario.warmup_frames..scenario.total_frames() {
        capture.frame(&mut seq, index, &mut rendered)?;
        on_frame();
    }
    capture.finish(&mut rendered);
    // Nothing was rendered twice to compare.
    rendered.deterministic = None;
    Ok(rendered)
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
    let (mut seq, mut capture, mut rendered) = prepare(gpu, scene, scenario, technique, keep)?;

    // Clock warm-up, so that the GPU reaches its working clocks before the first timed frame,
    // and the energy window. The clocks of the measured frames are recorded either way
    // (`conditions`), and a low one is flagged.
    let warmup_ms = scenario.clock_warmup_ms(&gpu.info.device_type);
    let energy_ms = scenario.energy_window_ms.unwrap_or(ENERGY_WINDOW_MS);
    match sampler.filter(|_| energy_ms > 0.0) {
        Some(s) => energy_window(&mut seq, s, warmup_ms, energy_ms, &mut rendered),
        None => clock_warmup(&mut seq, sampler, warmup_ms, &mut rendered),
    }
    timed(&mut seq, sampler, capture.check(), &mut rendered, on_frame);
    // The last compared frame of the timed phase was copied aside as it completed: the capture
    // phase renders the sequence again from frame 0 and must end on the same bits (determinism,
    // histories included), compared on the device.
    // Nothing of the warm-up frames is captured: they are pipelined as in the timed phase
    // instead of waited for one by one (the same commands in the same order on one queue).
    let warmup = scenario.warmup_frames;
    phases::time("capture: render", || {
        seq.pipelined(0..warmup, None, &mut |_, _| on_frame())
    });
    seq.timers.enable_stats(true);
    for index in warmup..scenario.total_frames() {
        capture.frame(&mut seq, index, &mut rendered)?;
        on_frame();
    }
    capture.finish(&mut rendered);
    Ok(rendered)
}

/// With sensors: the clock warm-up and the energy window are one window, before the timed
/// frames. The sequence runs pipelined from frame 0 while the sensors are read every
/// millisecond; from the first sample at the top clock (or after `warmup_ms`, where the clock
/// stays below it or its maximum is unknown) the window counts frames and the energy
/// counter's steps, and it ends ENERGY_STEPS steps later (at least CLOCK_SETTLED_MS later, and
/// MIN_CLOCK_WARMUP_MS after its start), or `energy_ms` after that point at most. A clock below
/// the top restarts the count. Energy per frame is read from the samples and frames after
/// that point; the timed frames then follow a GPU at its working clock.
fn energy_window(
    seq: &mut Sequence<'_>,
    s: &Sampler,
    warmup_ms: f64,
    energy_ms: f64,
    rendered: &mut Rendered,
) {
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
    let steps_wanted = seq.scenario.energy_steps.unwrap_or(ENERGY_STEPS);
    let go_on = || {
        // At the top clock, or warmed up as long as the clock warm-up may last.
        let at_top = ms(start) >= warmup_ms
            || max_mhz.is_some_and(|max| {
                s.latest_clock_mhz()
                    .is_some_and(|c| c >= crate::conditions::summary::TOP_CLOCK_FRACTION * max)
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
    seq.pipelined((0..).take_while(|_| go_on()), None, &mut |_, _| {
        frames.set(frames.get() + 1)
    });
    let samples = s.end();
    rendered.clock_warmup_ms = since
        .get()
        .map_or(ms(start), |(t, _, _, _)| (t - start).as_secs_f64() * 1000.0);
    // The samples and frames of the counted part (all of them if it never began).
    let (from_s, from_frames) = since.get().map_or((0.0, 0), |(_, at, _, f)| (at, f));
    let counted: Vec<Sample> = samples.into_iter().filter(|x| x.at_s >= from_s).collect();
    rendered.energy_window = Some((counted, frames.get() - from_frames));
}

/// Without sensors (or without an energy window): frame 0 (which never reads history)
/// repeated until the GPU has been busy for `warmup_ms`, so that it reaches its working clocks
/// before the first timed frame; where the sensors read the clock and know its maximum, it
/// ends once the load has run at the top clock for CLOCK_SETTLED_MS (after at least
/// MIN_CLOCK_WARMUP_MS).
fn clock_warmup(
    seq: &mut Sequence<'_>,
    sampler: Option<&Sampler>,
    warmup_ms: f64,
    rendered: &mut Rendered,
) {
    let _span = phases::span("clock warm-up");
    let warm_start = Instant::now();
    let top_clock = sampler.and_then(|s| Some((s, s.limits().max_graphics_clock_mhz?)));
    let mut settled_since: Option<Instant> = None;
    while warm_start.elapsed().as_secs_f64() * 1000.0 < warmup_ms {
        let chunk_start = Instant::now();
        if let Some((s, _)) = top_clock {
            s.begin();
        }
        seq.pipelined(std::iter::repeat_n(0, 4), None, &mut |_, _| {});
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

/// Timed phase: warm-up then measured frames, pipelined, nothing else on the queue. CPU frame
/// time is the interval between consecutive frame completions. A fixed count ends after its
/// frames; `auto` when its rule says so (frames already in flight then are not counted). The
/// last compared frame is copied aside by `check` as it completes.
fn timed(
    seq: &mut Sequence<'_>,
    sampler: Option<&Sampler>,
    check: &FrameCheck,
    rendered: &mut Rendered,
    on_frame: &mut dyn FnMut(),
) {
    let scenario = seq.scenario;
    let mut last = Instant::now();
    let warmup = scenario.warmup_frames;
    let timed_end = warmup + scenario.auto.map_or(scenario.measured_frames, |a| a.max);
    let stop: Cell<Option<StopReason>> = Cell::new(None);
    // When the first measured frame began: the completion of the frame before it.
    let mut measuring_since: Option<Instant> = None;
    let timestamps = rendered.timestamps;
    if warmup == 0 {
        if let Some(s) = sampler {
            s.begin();
        }
    }
    let _span = phases::span("timed frames");
    seq.pipelined(
        (0..timed_end).take_while(|_| stop.get().is_none()),
        compared_last(scenario).map(|i| (i, check)),
        &mut |index, times| {
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
}
