//! The sequence metrics on the device: static-scene `flicker` between consecutive test frames
//! and the temporal difference error `tde` (tessera-metrics `temporal.rs`).
//!
//! For: one value per frame. Not for: aggregating over frames (the caller's, as on the CPU).

use wgpu::util::DeviceExt;

use crate::context::GpuMetrics;
use crate::error::GpuMetricsError;
use crate::frame::GpuFrame;
use crate::pair::{pixel_sums, Params1};
use crate::plumbing::{Grid1, Layout};

fn same_size(a: &GpuFrame, b: &GpuFrame) -> Result<(), GpuMetricsError> {
    if (a.width, a.height) != (b.width, b.height) {
        return Err(tessera_metrics::MetricsError::SizeMismatch {
            ref_width: a.width,
            ref_height: a.height,
            test_width: b.width,
            test_height: b.height,
        }
        .into());
    }
    Ok(())
}

impl GpuMetrics {
    /// Flicker of one frame: the mean absolute difference from the previous frame over pixels
    /// and RGB channels, in 8-bit units (exact: integer sums).
    pub fn flicker_frames(
        &mut self,
        previous: &GpuFrame,
        current: &GpuFrame,
    ) -> Result<f64, GpuMetricsError> {
        same_size(previous, current)?;
        let n = current.width * current.height;
        let grid = Grid1::new(n);
        let mut layout = Layout::default();
        let slot = layout.param(&Params1 {
            count: n,
            groups_x: grid.x,
            _p: [0; 2],
        });
        let out = layout.output(24 * grid.groups() as u64);
        self.fit(&layout);
        let mut encoder = self.device.create_command_encoder(&Default::default());
        let bind = self.bind(
            &self.pipelines.pixel,
            &[
                self.slot::<Params1>(slot),
                previous.ldr.as_entire_binding(),
                current.ldr.as_entire_binding(),
                self.out(out),
            ],
        );
        {
            let mut pass = self.pass(&mut encoder, 0);
            pass.set_pipeline(&self.pipelines.pixel);
            pass.set_bind_group(0, &bind, &[]);
            pass.dispatch_workgroups(grid.x, grid.y, 1);
        }
        let bytes = self.finish(&layout, encoder, &["flicker"])?;
        let words: &[u32] =
            bytemuck::cast_slice(&bytes[out.offset as usize..][..out.size as usize]);
        Ok(pixel_sums(words).sum_abs as f64 / (3.0 * n as f64))
    }

    /// TDE of one frame, in 8-bit units: `motion[p]` moves pixel `p` from the previous frame
    /// (pixels, x right, y down), `valid[p]` is the mask; `None` when no pixel is valid.
    pub fn tde_frames(
        &mut self,
        test_prev: &GpuFrame,
        test: &GpuFrame,
        reference_prev: &GpuFrame,
        reference: &GpuFrame,
        motion: &[[f32; 2]],
        valid: &[bool],
    ) -> Result<Option<f64>, GpuMetricsError> {
        same_size(reference, test)?;
        same_size(reference, test_prev)?;
        same_size(reference, reference_prev)?;
        let n = reference.width * reference.height;
        for (what, actual) in [("motion field", motion.len()), ("valid mask", valid.len())] {
            if actual != n as usize {
                return Err(tessera_metrics::MetricsError::PerPixelLength {
                    what,
                    expected: n as usize,
                    actual,
                }
                .into());
            }
        }
        let init = |label, contents: &[u8]| {
            self.device
                .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some(label),
                    contents,
                    usage: wgpu::BufferUsages::STORAGE,
                })
        };
        let motion_buffer = init("tde motion", bytemuck::cast_slice(motion));
        let mask: Vec<u32> = valid.iter().map(|&v| v as u32).collect();
        let mask_buffer = init("tde valid", bytemuck::cast_slice(&mask));
        let grid = Grid1::new(n);
        let mut layout = Layout::default();
        let slot = layout.param(&[reference.width, reference.height, n, grid.x]);
        let out = layout.output(8 * grid.groups() as u64);
        self.fit(&layout);
        let mut encoder = self.device.create_command_encoder(&Default::default());
        let bind = self.bind(
            &self.pipelines.tde,
            &[
                self.slot::<[u32; 4]>(slot),
                test_prev.ldr.as_entire_binding(),
                test.ldr.as_entire_binding(),
                reference_prev.ldr.as_entire_binding(),
                reference.ldr.as_entire_binding(),
                motion_buffer.as_entire_binding(),
                mask_buffer.as_entire_binding(),
                self.out(out),
            ],
        );
        {
            let mut pass = self.pass(&mut encoder, 0);
            pass.set_pipeline(&self.pipelines.tde);
            pass.set_bind_group(0, &bind, &[]);
            pass.dispatch_workgroups(grid.x, grid.y, 1);
        }
        let bytes = self.finish(&layout, encoder, &["tde"])?;
        let words: &[u32] =
            bytemuck::cast_slice(&bytes[out.offset as usize..][..out.size as usize]);
        let (mut sum, mut count) = (0.0f64, 0u64);
        for p in words.chunks_exact(2) {
            sum += f32::from_bits(p[0]) as f64;
            count += p[1] as u64;
        }
        Ok((count > 0).then(|| sum / count as f64))
    }
}
