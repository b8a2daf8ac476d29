//! [`GpuFrame`]: a frame as the metric passes read it, on the device: the 8-bit sRGB pixels
//! packed `r | g << 8 | b << 16` in one u32 each, and optionally the linear RGB floats HDR-FLIP
//! reads.
//!
//! For: uploading CPU images, and turning a rendered float texture into a frame without it
//! leaving the device (the encode pass, bit-exact with `tessera_metrics::encode_srgb8`). Not
//! for: reading frames back (only metric values and requested images come back).

use tessera_metrics::{HdrImage, Rgb8Image};
use wgpu::util::DeviceExt;

use crate::context::GpuMetrics;
use crate::error::GpuMetricsError;
use crate::plumbing::{pack, read_buffer, unpack, Layout};

/// A frame on the device.
pub struct GpuFrame {
    pub width: u32,
    pub height: u32,
    pub(crate) ldr: wgpu::Buffer,
    pub(crate) hdr: Option<wgpu::Buffer>,
}

impl GpuFrame {
    pub fn pixel_count(&self) -> usize {
        self.width as usize * self.height as usize
    }

    /// Whether the frame has linear floats (needed by HDR-FLIP).
    pub fn has_hdr(&self) -> bool {
        self.hdr.is_some()
    }
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct EncodeParams {
    width: u32,
    height: u32,
    with_hdr: u32,
    _p: u32,
}

impl GpuMetrics {
    /// Uploads an 8-bit frame, and its linear floats when given (same size).
    pub fn upload(
        &self,
        ldr: &Rgb8Image,
        hdr: Option<&HdrImage>,
    ) -> Result<GpuFrame, GpuMetricsError> {
        ldr.validate()?;
        if let Some(h) = hdr {
            h.validate()?;
            if (h.width, h.height) != (ldr.width, ldr.height) {
                return Err(tessera_metrics::MetricsError::SizeMismatch {
                    ref_width: ldr.width,
                    ref_height: ldr.height,
                    test_width: h.width,
                    test_height: h.height,
                }
                .into());
            }
        }
        let n = ldr.pixel_count() as u64;
        self.check_binding("an 8-bit frame", 4 * n)?;
        let ldr_buffer = self
            .device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("metrics frame"),
                contents: bytemuck::cast_slice(&pack(ldr)),
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            });
        let hdr_buffer = match hdr {
            Some(h) => {
                self.check_binding("a float frame", 12 * n)?;
                Some(
                    self.device
                        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                            label: Some("metrics frame hdr"),
                            contents: bytemuck::cast_slice(&h.data),
                            usage: wgpu::BufferUsages::STORAGE,
                        }),
                )
            }
            None => None,
        };
        Ok(GpuFrame {
            width: ldr.width,
            height: ldr.height,
            ldr: ldr_buffer,
            hdr: hdr_buffer,
        })
    }

    /// A frame from a rendered float texture (`Rgba16Float` or `Rgba32Float`, linear RGB, with
    /// `TEXTURE_BINDING` usage), encoded on the device: its 8-bit form exactly as
    /// `encode_srgb8` would encode the read-back floats, and the floats themselves. Submits and
    /// does not wait (later requests on the same queue run after it).
    pub fn frame_from_texture(
        &mut self,
        texture: &wgpu::Texture,
    ) -> Result<GpuFrame, GpuMetricsError> {
        self.frame_from_texture_with(texture, true)
    }

    /// Whether frames of `width` x `height` (with their linear floats when `hdr`) fit this
    /// device's buffer limits, with FLIP's intermediate images: `Err` says which buffer does
    /// not (then the frames must be evaluated on the CPU).
    pub fn frame_fits(&self, width: u32, height: u32, hdr: bool) -> Result<(), GpuMetricsError> {
        let n = width as u64 * height as u64;
        self.check_binding("an 8-bit frame", 4 * n)?;
        if hdr {
            self.check_binding("a float frame", 12 * n)?;
        }
        self.check_binding("FLIP's intermediate images", 16 * n)
    }

    /// [`GpuMetrics::frame_from_texture`], with the linear floats only when `hdr` (HDR-FLIP
    /// needs them; an 8-bit frame takes a quarter of the memory).
    pub fn frame_from_texture_with(
        &mut self,
        texture: &wgpu::Texture,
        hdr: bool,
    ) -> Result<GpuFrame, GpuMetricsError> {
        let with_hdr = hdr;
        let format = texture.format();
        let sample = match format {
            wgpu::TextureFormat::Rgba16Float => wgpu::TextureSampleType::Float { filterable: true },
            wgpu::TextureFormat::Rgba32Float => {
                wgpu::TextureSampleType::Float { filterable: false }
            }
            other => return Err(GpuMetricsError::TextureFormat(other)),
        };
        let (width, height) = (texture.width(), texture.height());
        let n = width as u64 * height as u64;
        self.check_binding("an 8-bit frame", 4 * n)?;
        if with_hdr {
            self.check_binding("a float frame", 12 * n)?;
        }
        let pipeline = self
            .pipelines
            .encode
            .entry(format)
            .or_insert_with(|| encode_pipeline(&self.device, sample))
            .clone();
        let storage = |label, size| {
            self.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            })
        };
        let ldr = storage("metrics frame", 4 * n);
        // Without floats the shader writes none; the binding still needs a buffer.
        let hdr = storage("metrics frame hdr", if with_hdr { 12 * n } else { 16 });
        let mut layout = Layout::default();
        let slot = layout.param(&EncodeParams {
            width,
            height,
            with_hdr: with_hdr as u32,
            _p: 0,
        });
        // The encode pass has its own small uniform buffer: it is submitted on its own, before
        // the requests that read the frame, and must not share their slots.
        let params = self
            .device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("encode params"),
                contents: &layout.params[slot as usize..][..size_of::<EncodeParams>()],
                usage: wgpu::BufferUsages::UNIFORM,
            });
        let view = texture.create_view(&Default::default());
        let bind = self.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("encode"),
            layout: &pipeline.get_bind_group_layout(0),
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: params.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::TextureView(&view),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: self.encode_thresholds.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 3,
                    resource: ldr.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 4,
                    resource: hdr.as_entire_binding(),
                },
            ],
        });
        let mut encoder = self.device.create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_compute_pass(&Default::default());
            pass.set_pipeline(&pipeline);
            pass.set_bind_group(0, &bind, &[]);
            pass.dispatch_workgroups(width.div_ceil(16), height.div_ceil(16), 1);
        }
        self.queue.submit([encoder.finish()]);
        Ok(GpuFrame {
            width,
            height,
            ldr,
            hdr: with_hdr.then_some(hdr),
        })
    }

    /// Reads a frame's 8-bit pixels back (for tests and for saving an image the caller asked for).
    pub fn read_ldr(&self, frame: &GpuFrame) -> Result<Rgb8Image, GpuMetricsError> {
        let bytes = 4 * frame.pixel_count() as u64;
        let staging = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("frame readback"),
            size: bytes,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut encoder = self.device.create_command_encoder(&Default::default());
        encoder.copy_buffer_to_buffer(&frame.ldr, 0, &staging, 0, bytes);
        self.queue.submit([encoder.finish()]);
        let data = read_buffer(&self.device, &staging, bytes)?;
        Ok(unpack(
            bytemuck::cast_slice(&data),
            frame.width,
            frame.height,
        ))
    }
}

/// The encode pipeline for a texture sample type (explicit layout: the auto layout would ask
/// for a filterable float texture, which Rgba32Float is not without a feature).
fn encode_pipeline(
    device: &wgpu::Device,
    sample: wgpu::TextureSampleType,
) -> wgpu::ComputePipeline {
    let storage = |binding, read_only| wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    };
    let bgl = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("encode"),
        entries: &[
            wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::COMPUTE,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Uniform,
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            },
            wgpu::BindGroupLayoutEntry {
                binding: 1,
                visibility: wgpu::ShaderStages::COMPUTE,
                ty: wgpu::BindingType::Texture {
                    sample_type: sample,
                    view_dimension: wgpu::TextureViewDimension::D2,
                    multisampled: false,
                },
                count: None,
            },
            storage(2, true),
            storage(3, false),
            storage(4, false),
        ],
    });
    let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some("encode"),
        bind_group_layouts: &[Some(&bgl)],
        immediate_size: 0,
    });
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("encode"),
        source: wgpu::ShaderSource::Wgsl(crate::shaders::ENCODE.into()),
    });
    device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some("encode"),
        layout: Some(&layout),
        module: &module,
        entry_point: Some("main"),
        compilation_options: Default::default(),
        cache: None,
    })
}
