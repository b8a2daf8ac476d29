//! Checks of a rendered frame that need every pixel but not the frame on the CPU, run on the
//! device after the frame (never between timed frames): its non-finite values (how many, and a
//! bit per pixel, as [`super::readback::Readback`] reports them) and whether two renders of it
//! are bit for bit the same (the determinism check). Only a few counters come back, and the mask
//! only when a frame has non-finite values.
//!
//! The frame's raw Rgba16Float bits are copied into a storage buffer first
//! (`copy_texture_to_buffer` is a bit copy), so the checks see exactly what a readback would:
//! `shaders/frame_check.wgsl`. Not for: metrics (`tessera-metrics-gpu`), images.

use wgpu::util::DeviceExt;

use crate::gpu::Gpu;

/// The check pipelines of a device, made once (`Gpu::frame_check`).
pub struct FrameCheckPipelines {
    non_finite: wgpu::ComputePipeline,
    compare: wgpu::ComputePipeline,
}

impl FrameCheckPipelines {
    pub fn new(device: &wgpu::Device) -> FrameCheckPipelines {
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("frame check"),
            source: wgpu::ShaderSource::Wgsl(FRAME_CHECK_WGSL.into()),
        });
        let make = |entry: &str| {
            device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(entry),
                layout: None,
                module: &module,
                entry_point: Some(entry),
                compilation_options: Default::default(),
                cache: None,
            })
        };
        FrameCheckPipelines {
            non_finite: make("non_finite"),
            compare: make("compare"),
        }
    }
}

impl Gpu {
    /// The frame-check pipelines of this device, made on first use.
    pub fn frame_check(&self) -> &FrameCheckPipelines {
        self.frame_check
            .get_or_init(|| Box::new(FrameCheckPipelines::new(&self.device)))
            .downcast_ref::<FrameCheckPipelines>()
            .expect("only this module fills the slot, with its pipelines")
    }
}

pub static FRAME_CHECK_WGSL: &str = include_str!("../../../shaders/frame_check.wgsl");

/// What the checks of one frame found.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Checked {
    /// NaN or infinite values among the R, G and B channels.
    pub non_finite: u64,
    /// The pixels with such a value, one bit each (row-major, as `CpuFrame::non_finite_mask`);
    /// `None` when there are none.
    pub non_finite_mask: Option<Vec<u64>>,
    /// Whether the frame equals the snapshot bit for bit (R, G, B), when compared.
    pub same_as_snapshot: Option<bool>,
}

/// The buffers of the checks for one frame size.
pub struct FrameCheck {
    width: u32,
    height: u32,
    padded_row: u32,
    raw: wgpu::Buffer,
    snapshot: wgpu::Buffer,
    counters: wgpu::Buffer,
    mask: wgpu::Buffer,
    staging: wgpu::Buffer,
    /// Row bands of the frame, each bound within the device's storage-binding limit (an 8K
    /// Rgba16Float frame is 253 MiB, twice wgpu's default 128 MiB): the non-finite and the
    /// compare bind group of each band and its rows.
    bands: Vec<Band>,
}

struct Band {
    non_finite: wgpu::BindGroup,
    compare: wgpu::BindGroup,
    rows: u32,
}

impl FrameCheck {
    pub fn new(gpu: &Gpu, width: u32, height: u32) -> FrameCheck {
        let limit = gpu.device.limits().max_storage_buffer_binding_size;
        FrameCheck::with_binding_limit(gpu, width, height, limit)
    }

    /// [`FrameCheck::new`] with the frame bound in bands of at most `limit` bytes (at least one
    /// row each): the device's storage-binding limit, or less in tests.
    pub fn with_binding_limit(gpu: &Gpu, width: u32, height: u32, limit: u64) -> FrameCheck {
        let pipelines = gpu.frame_check();
        let device = &gpu.device;
        let padded_row = (width * 8).div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT)
            * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
        let frame_bytes = padded_row as u64 * height as u64;
        let buffer = |label, size, usage| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage,
                mapped_at_creation: false,
            })
        };
        use wgpu::BufferUsages as U;
        let raw = buffer("frame check raw", frame_bytes, U::STORAGE | U::COPY_DST);
        let snapshot = buffer(
            "frame check snapshot",
            frame_bytes,
            U::STORAGE | U::COPY_DST,
        );
        let counters = buffer(
            "frame check counters",
            8,
            U::STORAGE | U::COPY_SRC | U::COPY_DST,
        );
        let mask_bytes = (4 * (width as u64 * height as u64).div_ceil(32)).max(4);
        let mask = buffer(
            "frame check mask",
            mask_bytes,
            U::STORAGE | U::COPY_SRC | U::COPY_DST,
        );
        let staging = buffer(
            "frame check staging",
            mask_bytes.max(8),
            U::MAP_READ | U::COPY_DST,
        );
        // Rows per band: whole padded rows (256-byte aligned, so every band's offset meets the
        // storage offset alignment) within the binding limit.
        let band_rows = ((limit / u64::from(padded_row)).max(1) as u32).min(height.max(1));
        let mut bands = Vec::new();
        let mut row0 = 0;
        while row0 < height.max(1) {
            let rows = band_rows.min(height.max(1) - row0);
            let params = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("frame check params"),
                contents: bytemuck::cast_slice(&[width, rows, padded_row / 4, row0]),
                usage: U::UNIFORM,
            });
            let offset = u64::from(row0) * u64::from(padded_row);
            let size = std::num::NonZeroU64::new(u64::from(rows) * u64::from(padded_row));
            fn band(
                b: &wgpu::Buffer,
                offset: u64,
                size: Option<std::num::NonZeroU64>,
            ) -> wgpu::BindingResource<'_> {
                wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                    buffer: b,
                    offset,
                    size,
                })
            }
            // Both checks bind the params, the band of the frame and the counters; the non-finite
            // check adds the mask, the compare the same band of the snapshot.
            let group = |pipeline: &wgpu::ComputePipeline, last: wgpu::BindGroupEntry| {
                let entries = [
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: params.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 1,
                        resource: band(&raw, offset, size),
                    },
                    wgpu::BindGroupEntry {
                        binding: 2,
                        resource: counters.as_entire_binding(),
                    },
                    last,
                ];
                device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("frame check"),
                    layout: &pipeline.get_bind_group_layout(0),
                    entries: &entries,
                })
            };
            let non_finite = group(
                &pipelines.non_finite,
                wgpu::BindGroupEntry {
                    binding: 3,
                    resource: mask.as_entire_binding(),
                },
            );
            let compare = group(
                &pipelines.compare,
                wgpu::BindGroupEntry {
                    binding: 4,
                    resource: band(&snapshot, offset, size),
                },
            );
            bands.push(Band {
                non_finite,
                compare,
                rows,
            });
            row0 += rows;
        }
        FrameCheck {
            width,
            height,
            padded_row,
            raw,
            snapshot,
            counters,
            mask,
            staging,
            bands,
        }
    }

    /// Bytes of the check's buffers.
    pub fn bytes(&self) -> u64 {
        self.raw.size() + self.snapshot.size() + self.mask.size() + self.staging.size() + 8
    }

    fn copy_into(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        texture: &wgpu::Texture,
        to: &wgpu::Buffer,
    ) {
        encoder.copy_texture_to_buffer(
            texture.as_image_copy(),
            wgpu::TexelCopyBufferInfo {
                buffer: to,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(self.padded_row),
                    rows_per_image: Some(self.height),
                },
            },
            wgpu::Extent3d {
                width: self.width,
                height: self.height,
                depth_or_array_layers: 1,
            },
        );
    }

    /// Records the copy of `texture` (Rgba16Float, the check's size) aside, for a later
    /// [`FrameCheck::record`] with `compare`.
    pub fn snapshot(&self, encoder: &mut wgpu::CommandEncoder, texture: &wgpu::Texture) {
        self.copy_into(encoder, texture, &self.snapshot);
    }

    /// Records the checks of `texture`: its non-finite values, and with `compare` whether it
    /// equals the snapshot. Read them with [`FrameCheck::read`] after the submission.
    pub fn record(
        &self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        texture: &wgpu::Texture,
        compare: bool,
    ) {
        let pipelines = gpu.frame_check();
        self.copy_into(encoder, texture, &self.raw);
        encoder.clear_buffer(&self.counters, 0, None);
        encoder.clear_buffer(&self.mask, 0, None);
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("frame check"),
            timestamp_writes: None,
        });
        for band in &self.bands {
            let groups = (self.width.div_ceil(16), band.rows.div_ceil(16));
            pass.set_pipeline(&pipelines.non_finite);
            pass.set_bind_group(0, &band.non_finite, &[]);
            pass.dispatch_workgroups(groups.0, groups.1, 1);
            if compare {
                pass.set_pipeline(&pipelines.compare);
                pass.set_bind_group(0, &band.compare, &[]);
                pass.dispatch_workgroups(groups.0, groups.1, 1);
            }
        }
        drop(pass);
        encoder.copy_buffer_to_buffer(&self.counters, 0, &self.staging, 0, 8);
    }

    /// The results of the last recorded checks (after their submission); `compared`: whether
    /// that recording compared with the snapshot. Blocks until done.
    pub fn read(&self, gpu: &Gpu, compared: bool) -> Result<Checked, wgpu::BufferAsyncError> {
        let counters: [u32; 2] = {
            let bytes = map(&gpu.device, &self.staging, 8)?;
            [
                u32::from_le_bytes(bytes[0..4].try_into().expect("8 bytes")),
                u32::from_le_bytes(bytes[4..8].try_into().expect("8 bytes")),
            ]
        };
        let mask = if counters[0] > 0 {
            let mut encoder = gpu.device.create_command_encoder(&Default::default());
            encoder.copy_buffer_to_buffer(&self.mask, 0, &self.staging, 0, self.mask.size());
            gpu.queue.submit([encoder.finish()]);
            let bytes = map(&gpu.device, &self.staging, self.mask.size())?;
            let words: &[u32] = bytemuck::cast_slice(&bytes);
            let pixels = self.width as usize * self.height as usize;
            // Bit i of the mask is pixel i: u64 word k holds u32 words 2k (low) and 2k + 1.
            let mut out = vec![0u64; pixels.div_ceil(64)];
            for (k, w) in out.iter_mut().enumerate() {
                let lo = words.get(2 * k).copied().unwrap_or(0) as u64;
                let hi = words.get(2 * k + 1).copied().unwrap_or(0) as u64;
                *w = lo | hi << 32;
            }
            Some(out)
        } else {
            None
        };
        Ok(Checked {
            non_finite: counters[0] as u64,
            non_finite_mask: mask,
            same_as_snapshot: compared.then_some(counters[1] == 0),
        })
    }
}

/// Maps the first `size` bytes of `buffer` and copies them out.
fn map(
    device: &wgpu::Device,
    buffer: &wgpu::Buffer,
    size: u64,
) -> Result<Vec<u8>, wgpu::BufferAsyncError> {
    let slice = buffer.slice(..size);
    let (tx, rx) = std::sync::mpsc::channel();
    slice.map_async(wgpu::MapMode::Read, move |r| {
        let _ = tx.send(r);
    });
    let _ = device.poll(wgpu::PollType::Wait {
        submission_index: None,
        timeout: None,
    });
    rx.recv().unwrap_or(Err(wgpu::BufferAsyncError))?;
    let bytes = slice
        .get_mapped_range()
        .map_err(|_| wgpu::BufferAsyncError)?
        .to_vec();
    buffer.unmap();
    Ok(bytes)
}
