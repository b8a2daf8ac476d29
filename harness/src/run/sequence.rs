//! A variant's frames on the device, in order: frame `index` encoded and submitted with its
//! camera and objects at their time ([`submit_frame`]), frames pipelined with up to
//! `MAX_PENDING_FRAMES - 1` in flight ([`pipelined`]), and where each shot begins
//! ([`history_valid`]).
//!
//! For: the timed and capture phases (`frames.rs`, `capture.rs`), the motion capture. Not for:
//! what is kept of a frame (`capture.rs`) or how long to render (`frames.rs`).

use std::collections::{BTreeMap, VecDeque};

use super::output::first_line;
use crate::gpu::Gpu;
use crate::render::frame_check::FrameCheck;
use crate::render::renderer::{FrameInfo, Renderer};
use crate::render::scene::SceneGpu;
use crate::render::timers::{Timers, MAX_PENDING_FRAMES};
use crate::scenario::Scenario;

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

/// One variant's frame sequence on the device: what renders a frame and times its passes.
pub struct Sequence<'a> {
    pub gpu: &'a Gpu,
    pub scene: &'a mut SceneGpu,
    pub scenario: &'a Scenario,
    pub technique: &'a mut dyn Renderer,
    pub timers: Timers,
}

impl Sequence<'_> {
    /// [`pipelined`] over this sequence.
    pub fn pipelined(
        &mut self,
        frames: impl Iterator<Item = u32>,
        snapshot: Option<(u32, &FrameCheck)>,
        done: &mut dyn FnMut(u32, BTreeMap<String, f64>),
    ) {
        pipelined(
            self.gpu,
            self.scene,
            self.scenario,
            self.technique,
            &mut self.timers,
            frames,
            snapshot,
            done,
        );
    }

    /// Encodes and submits frame `index` ([`submit_frame`]).
    pub fn submit(&mut self, index: u32) -> wgpu::SubmissionIndex {
        submit_frame(
            self.gpu,
            self.scene,
            self.scenario,
            self.technique,
            &mut self.timers,
            index,
        )
    }
}

/// The last compared frame (the determinism check's), when the scenario measures frames.
pub fn compared_last(scenario: &Scenario) -> Option<u32> {
    scenario
        .total_frames()
        .checked_sub(1)
        .filter(|_| scenario.measured_frames > 0)
}

/// Runs `f` inside the device's validation and out-of-memory error scopes: the error the device
/// reported (`GPU error: <its first line>`), else what `f` returned. Every render of a run, the
/// reference's and each variant's, goes through it.
pub fn in_error_scope<T>(gpu: &Gpu, f: impl FnOnce() -> T) -> Result<T, String> {
    let validation = gpu.device.push_error_scope(wgpu::ErrorFilter::Validation);
    let oom = gpu.device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
    let value = f();
    let oom = pollster::block_on(oom.pop());
    let validation = pollster::block_on(validation.pop());
    match oom.or(validation) {
        Some(e) => Err(format!("GPU error: {}", first_line(&e.to_string()))),
        None => Ok(value),
    }
}
