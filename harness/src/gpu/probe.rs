//! Adapter facts no limit or feature flag tells: the 2x MSAA sample positions, read back from a
//! probe render, and the check a technique asks before it renders 2x MSAA.

use super::{Gpu, Unsupported};

pub static PROBE_WGSL: &str = include_str!("../../../shaders/sample_positions.wgsl");

/// The standard 2x positions (Vulkan/D3D, origin top-left): sample 0, sample 1.
pub const STANDARD_2X: [[f32; 2]; 2] = [[0.75, 0.75], [0.25, 0.25]];

/// The probe's render target format.
const PROBE_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;

impl Gpu {
    /// Unsupported unless the adapter renders 2x MSAA to `formats` at the standard sample
    /// positions (probed once per device).
    pub fn check_msaa2x(&self, formats: &[(wgpu::TextureFormat, &str)]) -> Result<(), Unsupported> {
        let gpu = self;
        for &(format, name) in formats {
            let counts = gpu
                .adapter
                .get_texture_format_features(format)
                .flags
                .supported_sample_counts();
            let has_feature = gpu.has(wgpu::Features::TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES);
            if !has_feature || !counts.contains(&2) {
                let list: Vec<String> = counts.iter().map(|c| format!("{c}x")).collect();
                return Err(Unsupported(format!(
                    "needs MULTISAMPLE_X2 for {name} (the adapter has {})",
                    list.join(", ")
                )));
            }
        }
        let positions = gpu
            .msaa2x_positions
            .get_or_init(|| probe_sample_positions(gpu));
        match positions {
            Ok(p) if close(p, &STANDARD_2X) => Ok(()),
            Ok(p) => Err(Unsupported(format!(
                "2x MSAA sample positions are {p:?}, not the standard {STANDARD_2X:?}"
            ))),
            Err(e) => Err(Unsupported(format!(
                "cannot probe 2x MSAA sample positions: {e}"
            ))),
        }
    }
}

fn close(a: &[[f32; 2]; 2], b: &[[f32; 2]; 2]) -> bool {
    a.iter()
        .flatten()
        .zip(b.iter().flatten())
        .all(|(x, y)| (x - y).abs() < 1e-3)
}

/// Renders a 1x1 2x MSAA target whose samples record their own positions, and reads them back.
fn probe_sample_positions(gpu: &Gpu) -> Result<[[f32; 2]; 2], String> {
    let device = &gpu.device;
    let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("sample_positions.wgsl"),
        source: wgpu::ShaderSource::Wgsl(PROBE_WGSL.into()),
    });
    let target = device.create_texture(&wgpu::TextureDescriptor {
        label: Some("sample probe"),
        size: wgpu::Extent3d {
            width: 1,
            height: 1,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 2,
        dimension: wgpu::TextureDimension::D2,
        format: PROBE_FORMAT,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
        view_formats: &[],
    });
    let render = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some("sample probe"),
        layout: None,
        vertex: wgpu::VertexState {
            module: &module,
            entry_point: Some("vs_main"),
            compilation_options: Default::default(),
            buffers: &[],
        },
        fragment: Some(wgpu::FragmentState {
            module: &module,
            entry_point: Some("fs_main"),
            compilation_options: Default::default(),
            targets: &[Some(PROBE_FORMAT.into())],
        }),
        primitive: Default::default(),
        depth_stencil: None,
        multisample: wgpu::MultisampleState {
            count: 2,
            ..Default::default()
        },
        multiview_mask: None,
        cache: None,
    });
    let copy = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some("sample probe copy"),
        layout: None,
        module: &module,
        entry_point: Some("copy_samples"),
        compilation_options: Default::default(),
        cache: None,
    });
    let storage = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("sample positions"),
        size: 32,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let readback = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("sample positions readback"),
        size: 32,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let view = target.create_view(&Default::default());
    let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("sample probe"),
        layout: &copy.get_bind_group_layout(0),
        entries: &[
            wgpu::BindGroupEntry {
                binding: 0,
                resource: wgpu::BindingResource::TextureView(&view),
            },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: storage.as_entire_binding(),
            },
        ],
    });
    let mut encoder = device.create_command_encoder(&Default::default());
    {
        let mut rp = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("sample probe"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: None,
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        rp.set_pipeline(&render);
        rp.draw(0..3, 0..1);
    }
    {
        let mut cp = encoder.begin_compute_pass(&Default::default());
        cp.set_pipeline(&copy);
        cp.set_bind_group(0, &bind_group, &[]);
        cp.dispatch_workgroups(1, 1, 1);
    }
    encoder.copy_buffer_to_buffer(&storage, 0, &readback, 0, 32);
    gpu.queue.submit([encoder.finish()]);
    if let Some(e) = pollster::block_on(scope.pop()) {
        return Err(e.to_string());
    }
    let slice = readback.slice(..);
    slice.map_async(wgpu::MapMode::Read, |_| {});
    let _ = device.poll(wgpu::PollType::Wait {
        submission_index: None,
        timeout: None,
    });
    let data = slice.get_mapped_range().map_err(|e| format!("{e:?}"))?;
    let v: &[f32] = bytemuck::cast_slice(&data);
    Ok([[v[0], v[1]], [v[4], v[5]]])
}
