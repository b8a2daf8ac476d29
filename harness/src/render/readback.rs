//! Copies a frame's Rgba16Float output to the CPU, outside every timed pass; and whole textures
//! for tests and per-frame extras ([`read_texture`], [`read_texture_raw`]).
//!
//! Returns linear RGB floats plus the count of non-finite channel values (NaN and ±Inf are counted
//! before anything can clamp them). Converting to sRGB for images and metrics is the caller's job.

use tessera_metrics::HdrImage;

use crate::gpu::Gpu;

pub struct Readback {
    buffer: wgpu::Buffer,
    width: u32,
    height: u32,
    padded_row: u32,
}

/// A frame on the CPU.
pub struct CpuFrame {
    pub image: HdrImage,
    /// NaN or infinite values among the R, G and B channels.
    pub non_finite: u64,
    /// The pixels with such a value, one bit each (row-major); `None` when there are none.
    pub non_finite_mask: Option<Vec<u64>>,
}

impl Readback {
    pub fn new(device: &wgpu::Device, width: u32, height: u32) -> Readback {
        let row = width * 8;
        let padded_row =
            row.div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
        let buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("frame readback"),
            size: padded_row as u64 * height as u64,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        Readback {
            buffer,
            width,
            height,
            padded_row,
        }
    }

    pub fn bytes(&self) -> u64 {
        self.buffer.size()
    }

    /// Records the copy of `texture` (Rgba16Float, the readback's size) into the buffer.
    pub fn copy(&self, encoder: &mut wgpu::CommandEncoder, texture: &wgpu::Texture) {
        encoder.copy_texture_to_buffer(
            texture.as_image_copy(),
            wgpu::TexelCopyBufferInfo {
                buffer: &self.buffer,
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

    /// Maps the buffer (after the copy's submission) and decodes it.
    pub fn read(&self, device: &wgpu::Device) -> Result<CpuFrame, wgpu::BufferAsyncError> {
        let slice = self.buffer.slice(..);
        let (tx, rx) = std::sync::mpsc::channel();
        slice.map_async(wgpu::MapMode::Read, move |r| {
            let _ = tx.send(r);
        });
        let _ = device.poll(wgpu::PollType::Wait {
            submission_index: None,
            timeout: None,
        });
        rx.recv().unwrap_or(Err(wgpu::BufferAsyncError))?;
        let (w, h) = (self.width as usize, self.height as usize);
        let mut data = vec![0.0f32; w * h * 3];
        let mut non_finite = 0u64;
        let mut mask: Vec<u64> = Vec::new();
        {
            let mapped = slice
                .get_mapped_range()
                .map_err(|_| wgpu::BufferAsyncError)?;
            // Rows decoded in bands on every core (a 4K frame is 25M half floats); the values
            // and the mask do not depend on the banding.
            let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
            let band_rows = h.div_ceil(threads.min(h.max(1))).max(1);
            let padded = self.padded_row as usize;
            let bands: Vec<(u64, Vec<usize>)> = std::thread::scope(|scope| {
                let handles: Vec<_> = data
                    .chunks_mut(band_rows * w * 3)
                    .enumerate()
                    .map(|(b, out)| {
                        let mapped = &mapped;
                        scope.spawn(move || {
                            let mut count = 0u64;
                            let mut pixels = Vec::new();
                            for (dy, out_row) in out.chunks_exact_mut(w * 3).enumerate() {
                                let y = b * band_rows + dy;
                                let start = y * padded;
                                let row: &[half::f16] =
                                    bytemuck::cast_slice(&mapped[start..start + w * 8]);
                                for (x, (px, o)) in row
                                    .chunks_exact(4)
                                    .zip(out_row.chunks_exact_mut(3))
                                    .enumerate()
                                {
                                    let mut bad = false;
                                    for (c, v) in px[..3].iter().zip(o.iter_mut()) {
                                        *v = c.to_f32();
                                        if !v.is_finite() {
                                            count += 1;
                                            bad = true;
                                        }
                                    }
                                    if bad {
                                        pixels.push(y * w + x);
                                    }
                                }
                            }
                            (count, pixels)
                        })
                    })
                    .collect();
                handles
                    .into_iter()
                    .map(|t| t.join().unwrap_or_else(|e| std::panic::resume_unwind(e)))
                    .collect()
            });
            for (count, pixels) in bands {
                non_finite += count;
                for i in pixels {
                    if mask.is_empty() {
                        mask = vec![0; (w * h).div_ceil(64)];
                    }
                    mask[i / 64] |= 1 << (i % 64);
                }
            }
        }
        self.buffer.unmap();
        Ok(CpuFrame {
            image: HdrImage {
                width: self.width,
                height: self.height,
                data,
            },
            non_finite,
            non_finite_mask: (!mask.is_empty()).then_some(mask),
        })
    }
}

/// Reads a whole single-sample texture back as f32 values, for tests and debugging:
/// Rgba16Float gives 4 values per texel, Depth32Float and R32Float 1. Blocks until done. Array
/// layer 0 only: [`read_texture_layer`] reads the others.
pub fn read_texture(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    texture: &wgpu::Texture,
) -> Vec<f32> {
    read_texture_layer(device, queue, texture, 0)
}

/// [`read_texture`] of one array layer.
pub fn read_texture_layer(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    texture: &wgpu::Texture,
    layer: u32,
) -> Vec<f32> {
    let raw = read_raw(device, queue, texture, layer);
    if matches!(
        texture.format(),
        wgpu::TextureFormat::Depth32Float | wgpu::TextureFormat::R32Float
    ) {
        bytemuck::pod_collect_to_vec::<u8, f32>(&raw)
    } else {
        bytemuck::pod_collect_to_vec::<u8, half::f16>(&raw)
            .iter()
            .map(|v| v.to_f32())
            .collect()
    }
}

/// Reads a single-sample texture back as raw texel bytes, rows unpadded (tests, extras).
pub fn read_texture_raw(gpu: &Gpu, texture: &wgpu::Texture) -> Vec<u8> {
    read_raw(&gpu.device, &gpu.queue, texture, 0)
}

/// One array layer of a single-sample texture as raw texel bytes, rows unpadded (the depth
/// aspect of a depth texture); empty if mapping failed. Blocks until done.
fn read_raw(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    texture: &wgpu::Texture,
    layer: u32,
) -> Vec<u8> {
    let (w, h) = (texture.width(), texture.height());
    let depth = texture.format() == wgpu::TextureFormat::Depth32Float;
    let texel = if depth {
        4
    } else {
        texture.format().block_copy_size(None).unwrap_or(4)
    };
    let row = w * texel;
    let padded =
        row.div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
    let buffer = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("texture readback"),
        size: padded as u64 * h as u64,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut encoder = device.create_command_encoder(&Default::default());
    let mut source = texture.as_image_copy();
    source.origin.z = layer;
    if depth {
        source.aspect = wgpu::TextureAspect::DepthOnly;
    }
    encoder.copy_texture_to_buffer(
        source,
        wgpu::TexelCopyBufferInfo {
            buffer: &buffer,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(padded),
                rows_per_image: Some(h),
            },
        },
        wgpu::Extent3d {
            width: w,
            height: h,
            depth_or_array_layers: 1,
        },
    );
    queue.submit([encoder.finish()]);
    let slice = buffer.slice(..);
    slice.map_async(wgpu::MapMode::Read, |_| {});
    let _ = device.poll(wgpu::PollType::Wait {
        submission_index: None,
        timeout: None,
    });
    let mut out = Vec::with_capacity((row * h) as usize);
    if let Ok(data) = slice.get_mapped_range() {
        for y in 0..h as usize {
            let start = y * padded as usize;
            out.extend_from_slice(&data[start..start + row as usize]);
        }
    }
    out
}
