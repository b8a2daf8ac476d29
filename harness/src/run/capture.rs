//! The capture phase of a variant's render: the same frames as the timed phase again, one at a
//! time (rendering is deterministic, histories included); each measured frame is counted
//! (fragment invocations) and checked (non-finite values), then read back or kept on the device
//! for images and metrics. Not timed. A frame comes back to the CPU only when something on the
//! CPU needs it: CPU frames asked for, a saved frame, `TESSERA_FRAME_HASHES`.
//!
//! For: [`Capture`], driven frame by frame by `frames::render_sampled`. Not for: the timed
//! phase, metrics or files.

use tessera_metrics::{encode_srgb8, Rgb8Image};

use super::motion_blur::BlurredCapture;
use super::phases;
use super::rendered::{frame_hash_file, Keep, RenderError, Rendered};
use super::sequence::{compared_last, history_valid, submit_frame, Sequence};
use crate::gpu::Gpu;
use crate::render::frame_check::{Checked, FrameCheck};
use crate::render::readback::{CpuFrame, Readback};
use crate::scenario::Scenario;

/// What captures a variant's measured frames: the readback, the device's checks, the metrics'
/// copy and the motion blur, made once per variant.
pub(super) struct Capture<'a> {
    gpu: &'a Gpu,
    scenario: &'a Scenario,
    keep: Keep,
    readback: Readback,
    check: FrameCheck,
    /// The metrics' own copy of each captured frame (the output is the technique's and changes
    /// with the next frame), when frames stay on the device.
    metric_copy: Option<wgpu::Texture>,
    /// `reference.motion_blur`: the compared frames are blurred along the scene's motion first.
    blur: Option<BlurredCapture>,
    hash_frames: bool,
    /// Digests being computed beside the next frames' work, in frame order ([`Capture::finish`]).
    digests: Vec<std::thread::JoinHandle<String>>,
}

/// Where a captured frame's bits went: what the CPU got, the device's check results, and the
/// 8-bit frame the device encoded.
struct Captured {
    frame: Option<CpuFrame>,
    checks: Option<Checked>,
    /// The compared frame is the output motion-blurred: its non-finite values are the output's,
    /// as the device's checks counted them.
    blurred: bool,
    device_srgb: Option<Rgb8Image>,
}

impl<'a> Capture<'a> {
    pub fn new(
        gpu: &'a Gpu,
        scenario: &'a Scenario,
        output: &wgpu::Texture,
        keep: Keep,
        readback: Readback,
        check: FrameCheck,
    ) -> Result<Capture<'a>, RenderError> {
        let blur = if scenario.motion_blur {
            Some(
                BlurredCapture::new(gpu, scenario.width, scenario.height)
                    .map_err(RenderError::MotionBlur)?,
            )
        } else {
            None
        };
        Ok(Capture {
            gpu,
            scenario,
            keep,
            readback,
            check,
            metric_copy: keep.gpu.then(|| metric_texture(gpu, output)),
            blur,
            hash_frames: frame_hash_file().is_some(),
            digests: Vec::new(),
        })
    }

    /// Waits for the captured frames' digests, into `rendered` in frame order.
    pub fn finish(&mut self, rendered: &mut Rendered) {
        let _span = phases::span("capture: digests");
        for job in self.digests.drain(..) {
            rendered
                .digests
                .push(job.join().unwrap_or_else(|e| std::panic::resume_unwind(e)));
        }
    }

    /// The device's checks (the timed phase copies its last compared frame aside into them).
    pub fn check(&self) -> &FrameCheck {
        &self.check
    }

    /// Renders frame `index` again and, when it is measured, captures it into `rendered`.
    pub fn frame(
        &mut self,
        seq: &mut Sequence<'_>,
        index: u32,
        rendered: &mut Rendered,
    ) -> Result<(), RenderError> {
        let gpu = self.gpu;
        let render_span = phases::span("capture: render");
        seq.submit(index);
        let _ = gpu.device.poll(wgpu::PollType::Wait {
            submission_index: None,
            timeout: None,
        });
        let _ = seq.timers.try_collect(&gpu.queue);
        let mut stats = seq.timers.read_stats(&gpu.device);
        if seq.timers.stats_enabled() {
            stats.extend(seq.technique.own_statistics(gpu));
        }
        drop(render_span);
        let Some(m) = index.checked_sub(self.scenario.warmup_frames) else {
            return Ok(());
        };
        if let Some(fm) = rendered.measurements.get_mut(m as usize) {
            fm.fragment_invocations = stats;
        }
        let last = index + 1 == self.scenario.total_frames();
        let compare = last && compared_last(self.scenario).is_some();
        let captured = self.copy_out(seq, index, compare, rendered)?;
        if compare {
            rendered.deterministic = captured.checks.as_ref().and_then(|r| r.same_as_snapshot);
        }
        self.keep_frame(seq, m, captured, rendered);
        Ok(())
    }

    /// Whether the 8-bit frame comes from the metrics' copy, encoded on the device (half the
    /// float frame's bytes, no CPU encode), unless the floats themselves are needed. Every
    /// measured frame's 8-bit form is digested (approved frames), so each comes back as 8-bit
    /// sRGB: encoded on the device where the metrics keep frames there (the same bytes as the
    /// CPU's encode: metrics-gpu's `encode` test), else here.
    fn ldr_from_device(&self) -> bool {
        self.metric_copy.is_some() && !(self.keep.hdr || self.hash_frames)
    }

    /// The device's checks (every frame not read back; the determinism check on the last), the
    /// metrics' copy, and the readback's copy in one submission; then what comes back of them.
    fn copy_out(
        &mut self,
        seq: &mut Sequence<'_>,
        index: u32,
        compare: bool,
        rendered: &mut Rendered,
    ) -> Result<Captured, RenderError> {
        let gpu = self.gpu;
        let ldr_from_device = self.ldr_from_device();
        let on_cpu = self.keep.hdr || self.hash_frames || !ldr_from_device;
        let output = seq.technique.output();
        // What the metrics, images and hashes see: the output, or it motion-blurred (its own
        // submission; the checks below read the output itself).
        let blurring = self.blur.is_some();
        let compared = match self.blur.as_mut() {
            Some(b) => {
                let _span = phases::span("capture: motion blur");
                let (motion, motion_timers) = b.motion_pass();
                submit_frame(gpu, seq.scene, seq.scenario, motion, motion_timers, index);
                let _ = gpu.device.poll(wgpu::PollType::Wait {
                    submission_index: None,
                    timeout: None,
                });
                b.blur(gpu, output, history_valid(seq.scenario, index))
                    .map_err(RenderError::MotionBlur)?
            }
            None => output,
        };
        let checks_span = phases::span("capture: checks");
        let mut encoder = gpu
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("capture"),
            });
        // A blurred read-back frame's non-finite values are not the output's: then the device
        // checks the output.
        let checked = !on_cpu || compare || blurring;
        if checked {
            self.check.record(gpu, &mut encoder, output, compare);
        }
        if let Some(copy) = &self.metric_copy {
            encoder.copy_texture_to_texture(
                compared.as_image_copy(),
                copy.as_image_copy(),
                compared.size(),
            );
        }
        if on_cpu {
            self.readback.copy(&mut encoder, compared);
        }
        gpu.queue.submit([encoder.finish()]);
        let mut device_srgb = None;
        if let Some(copy) = &self.metric_copy {
            let mut metrics = gpu.metrics();
            let frame = metrics
                .frame_from_texture_with(copy, self.keep.gpu_hdr)
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
        let checks = if checked {
            Some(
                self.check
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
                self.readback
                    .read(&gpu.device)
                    .map_err(|_| RenderError::Readback)?,
            )
        } else {
            None
        };
        Ok(Captured {
            frame,
            checks,
            blurred: blurring,
            device_srgb,
        })
    }

    /// Counts a captured frame's non-finite values, hashes and digests it, hands it to the
    /// technique's extras, and keeps what `keep` and `save_frames` ask for.
    fn keep_frame(
        &mut self,
        seq: &mut Sequence<'_>,
        m: u32,
        captured: Captured,
        rendered: &mut Rendered,
    ) {
        let Captured {
            frame,
            checks,
            blurred,
            device_srgb,
        } = captured;
        let saved = self.scenario.save_frames.contains(&m);
        let (non_finite, mask) = match (&frame, checks) {
            (_, Some(r)) if blurred => (r.non_finite, r.non_finite_mask),
            (Some(f), _) => (f.non_finite, f.non_finite_mask.clone()),
            (None, Some(r)) => (r.non_finite, r.non_finite_mask),
            (None, None) => (0, None),
        };
        rendered.non_finite += non_finite;
        rendered.non_finite_counts.push(non_finite);
        rendered.non_finite_masks.push(mask);
        if let Some(frame) = &frame {
            if self.hash_frames {
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
            // SHA-256 of a 4K frame is about 20 ms on one core: hashed on its own thread while
            // the next frame renders.
            let _span = phases::span("capture: digests");
            let img = img.clone();
            self.digests.push(std::thread::spawn(move || {
                tessera_results::digest::frame_digest(img.width, img.height, &img.data)
            }));
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
            .push(seq.technique.frame_extras(self.gpu, image, saved));
        drop(extras_span);
        if let Some(srgb) = srgb {
            match (saved, self.keep.frames) {
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
            if self.keep.hdr {
                rendered.hdr_frames.push(frame.image);
            }
        }
    }
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
fn image_hash(image: &tessera_metrics::HdrImage) -> u64 {
    use std::hash::{Hash, Hasher};
    let mut h = std::hash::DefaultHasher::new();
    for v in &image.data {
        v.to_bits().hash(&mut h);
    }
    h.finish()
}
