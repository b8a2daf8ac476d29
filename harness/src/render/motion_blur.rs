//! A frame blurred along each pixel's motion (`shaders/motion_blur.wgsl`: a box of the pixel's
//! motion length along its motion, as display persistence and engines' motion blur filter, NVIDIA
//! adaptive shading section 4), and its CPU model. Infrastructure: takes a frame and a motion
//! target; where they come from is `run/motion_blur.rs`'s.

use super::kit::{bind_group, compute_pipeline};
use crate::gpu::Gpu;

pub static MOTION_BLUR_WGSL: &str = include_str!("../../../shaders/motion_blur.wgsl");

/// The blur's format: the renderers' output format.
const FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;

/// The pass and its targets, for frames of one size.
pub struct MotionBlur {
    /// The frame to blur, copied from the technique's output (which may not be sampleable).
    input: wgpu::Texture,
    /// The blurred frame.
    output: wgpu::Texture,
    params: wgpu::Buffer,
    pipeline: wgpu::ComputePipeline,
    size: [u32; 2],
}

impl MotionBlur {
    pub fn new(gpu: &Gpu, width: u32, height: u32) -> MotionBlur {
        let texture = |label, usage| {
            gpu.device.create_texture(&wgpu::TextureDescriptor {
                label: Some(label),
                size: wgpu::Extent3d {
                    width,
                    height,
                    depth_or_array_layers: 1,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: FORMAT,
                usage,
                view_formats: &[],
            })
        };
        use wgpu::TextureUsages as U;
        MotionBlur {
            input: texture("motion blur input", U::COPY_DST | U::TEXTURE_BINDING),
            output: texture(
                "motion blurred frame",
                U::STORAGE_BINDING | U::COPY_SRC | U::TEXTURE_BINDING,
            ),
            params: gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("motion blur params"),
                size: 16,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
            pipeline: compute_pipeline(&gpu.device, "motion blur", MOTION_BLUR_WGSL, "main"),
            size: [width, height],
        }
    }

    /// `frame` blurred by `motion` (the velocity target's layout: xy in pixels), or copied when
    /// not `enabled`. Waits for the GPU.
    pub fn blur(
        &self,
        gpu: &Gpu,
        frame: &wgpu::Texture,
        motion: &wgpu::TextureView,
        enabled: bool,
    ) -> Result<&wgpu::Texture, String> {
        if frame.format() != FORMAT || [frame.width(), frame.height()] != self.size {
            return Err(format!(
                "motion blur: the frame is {}x{} {:?}, expected {}x{} {FORMAT:?}",
                frame.width(),
                frame.height(),
                frame.format(),
                self.size[0],
                self.size[1]
            ));
        }
        let [w, h] = self.size;
        gpu.queue.write_buffer(
            &self.params,
            0,
            bytemuck::cast_slice(&[w, h, u32::from(enabled), 0]),
        );
        let input = self.input.create_view(&Default::default());
        let output = self.output.create_view(&Default::default());
        let group = bind_group(
            &gpu.device,
            "motion blur",
            &self.pipeline.get_bind_group_layout(0),
            &[(0, &self.params)],
            &[(1, &input), (2, motion), (3, &output)],
        );
        let mut encoder = gpu
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("motion blur"),
            });
        encoder.copy_texture_to_texture(
            frame.as_image_copy(),
            self.input.as_image_copy(),
            frame.size(),
        );
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("motion blur"),
                timestamp_writes: None,
            });
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, &group, &[]);
            pass.dispatch_workgroups(w.div_ceil(8), h.div_ceil(8), 1);
        }
        gpu.queue.submit([encoder.finish()]);
        let _ = gpu.device.poll(wgpu::PollType::Wait {
            submission_index: None,
            timeout: None,
        });
        Ok(&self.output)
    }
}

/// The blur on the CPU, as the shader computes it (the test oracle): `frame` RGBA per pixel,
/// `motion` xy per pixel.
pub fn model(frame: &[[f32; 4]], motion: &[[f32; 2]], width: u32, height: u32) -> Vec<[f32; 4]> {
    let (w, h) = (width as i32, height as i32);
    let load = |x: i32, y: i32| frame[(y.clamp(0, h - 1) * w + x.clamp(0, w - 1)) as usize];
    let mix = |a: [f32; 4], b: [f32; 4], t: f32| std::array::from_fn(|c| a[c] + (b[c] - a[c]) * t);
    let bilinear = |x: f32, y: f32| {
        let (qx, qy) = (x - 0.5, y - 0.5);
        let (ix, iy) = (qx.floor() as i32, qy.floor() as i32);
        let (fx, fy) = (qx - qx.floor(), qy - qy.floor());
        let top = mix(load(ix, iy), load(ix + 1, iy), fx);
        let bottom = mix(load(ix, iy + 1), load(ix + 1, iy + 1), fx);
        mix(top, bottom, fy)
    };
    (0..h * w)
        .map(|i| {
            let (x, y) = (i % w, i / w);
            let v = motion[i as usize];
            let len = (v[0] * v[0] + v[1] * v[1]).sqrt();
            if !(0.5..=1e6).contains(&len) {
                return frame[i as usize];
            }
            let taps = (len.ceil() as u32 + 1).min(129);
            let mut sum = [0.0f32; 4];
            for k in 0..taps {
                let t = k as f32 / (taps - 1) as f32 - 0.5;
                let s = bilinear(x as f32 + 0.5 + v[0] * t, y as f32 + 0.5 + v[1] * t);
                for c in 0..4 {
                    sum[c] += s[c];
                }
            }
            sum.map(|s| s / taps as f32)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    #[test]
    fn a_bright_column_spreads_over_its_motion() {
        // 9x1, a column of 1 at x = 4, motion 4 px to the right everywhere: five points at
        // -2..2 px land on pixel centres, so x = 2..6 each see the column once in five.
        let mut frame = vec![[0.0f32; 4]; 9];
        frame[4] = [1.0, 1.0, 1.0, 1.0];
        let out = super::model(&frame, &[[4.0, 0.0]; 9], 9, 1);
        for (x, px) in out.iter().enumerate() {
            let want = if (2..=6).contains(&x) { 0.2 } else { 0.0 };
            assert!((px[0] - want).abs() < 1e-6, "x = {x}: {px:?}");
        }
        // Still pixels (and a NaN motion) are not blurred.
        let out = super::model(&frame, &[[0.3, 0.0]; 9], 9, 1);
        assert_eq!(out, frame);
        let out = super::model(&frame, &[[f32::NAN, 0.0]; 9], 9, 1);
        assert_eq!(out, frame);
    }
}
