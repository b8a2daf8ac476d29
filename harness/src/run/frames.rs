//! Renders one variant's frames: warm-up, then measured frames with per-pass GPU timings, CPU wall
//! time, fragment-shader invocations and a readback of every measured frame.
//!
//! One frame is encoded, submitted and waited for before the next: timings are per frame and never
//! overlap readback or metrics. This module does not compute metrics or write files.

use std::time::Instant;

use tessera_metrics::{encode_srgb8, HdrImage, Rgb8Image};

use crate::gpu::Gpu;
use crate::render::graph::PassKind;
use crate::render::readback::Readback;
use crate::render::scene::SceneGpu;
use crate::render::technique::{FrameInfo, Technique};
use crate::render::timers::{FrameMeasurements, Timers};
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
    pub timestamps: bool,
    pub readback_bytes: u64,
}

#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    #[error("{0}")]
    Timers(#[from] crate::render::timers::TimerError),
    #[error("reading the frame back failed (device lost?)")]
    Readback,
}

/// Renders warm-up and measured frames. `on_frame` is called after each frame (progress).
pub fn render(
    gpu: &Gpu,
    scene: &mut SceneGpu,
    scenario: &Scenario,
    technique: &mut dyn Technique,
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
        timestamps: timers.has_timestamps(),
        readback_bytes: readback.bytes(),
    };
    for index in 0..scenario.total_frames() {
        let measured = index >= scenario.warmup_frames;
        let time = scenario.frame_time(index);
        let prev_time = if index == 0 {
            time
        } else {
            scenario.frame_time(index - 1)
        };
        let start = Instant::now();
        scene.write_objects(&gpu.queue, time, prev_time);
        let mut encoder = gpu
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("frame"),
            });
        technique.record(
            gpu,
            scene,
            &timers,
            &mut encoder,
            FrameInfo {
                index,
                time,
                prev_time,
            },
        );
        timers.resolve(&mut encoder);
        gpu.queue.submit([encoder.finish()]);
        let m = timers.collect(&gpu.device, &gpu.queue);
        let cpu_ms = start.elapsed().as_secs_f64() * 1000.0;
        if measured {
            // The copy is its own submission, after the frame's timings are complete.
            let mut encoder = gpu
                .device
                .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                    label: Some("readback"),
                });
            readback.copy(&mut encoder, technique.output());
            gpu.queue.submit([encoder.finish()]);
            let frame = readback
                .read(&gpu.device)
                .map_err(|_| RenderError::Readback)?;
            rendered.non_finite += frame.non_finite;
            if keep_frames {
                rendered.frames.push(encode_srgb8(&frame.image));
            }
            if keep_hdr {
                rendered.hdr_frames.push(frame.image);
            }
            rendered.measurements.push(m);
            rendered.cpu_ms.push(cpu_ms);
        }
        on_frame();
    }
    Ok(rendered)
}
