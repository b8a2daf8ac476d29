//! `fsr2`'s WGSL passes against AMD's own compiled GLSL (issue 36, item 2), on the default
//! adapter (lavapipe in CI) through wgpu's SPIR-V passthrough: both run on the same inputs and
//! their outputs are compared. So far the `lock` pass (`lock.wgsl` against AMD's
//! `ffx_fsr2_lock_pass.glsl`, compiled as `tests/fsr2_amd/README.md` says): the new locks it sets
//! (a thin-feature test over a luma image with ridges, valleys, flat regions and noise) must be
//! the same pixels, and both must clear the reconstructed previous depth they are given.

mod common;

use tessera::techniques::fsr2::gpu::{module, LOCK_WGSL};

static LOCK_SPV: &[u8] = include_bytes!("fsr2_amd/ffx_fsr2_lock_pass.spv");

const RENDER: (u32, u32) = (40, 30);
const DISPLAY: (u32, u32) = (60, 45);
const JITTER: [f32; 2] = [0.3125, -0.2222];

/// A device with SPIR-V passthrough on the adapter the harness picks.
fn device() -> (wgpu::Device, wgpu::Queue) {
    common::gpu();
    let adapter = tessera::gpu::select(None).expect("no adapter");
    let needed = wgpu::Features::PASSTHROUGH_SHADERS
        | wgpu::Features::TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES;
    assert!(
        adapter.features().contains(needed),
        "the adapter lacks {:?}",
        needed - adapter.features()
    );
    pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
        label: Some("fsr2 amd"),
        required_features: needed,
        required_limits: adapter.limits(),
        ..Default::default()
    }))
    .expect("device")
}

/// The lock luma: smooth shading, one-pixel bright and dark lines (ridges), isolated peaks and
/// a little deterministic noise, rounded to f16 (AMD keeps it in R16F).
fn luma() -> Vec<f32> {
    let (w, h) = RENDER;
    (0..w * h)
        .map(|i| {
            let (x, y) = ((i % w) as f32, (i / w) as f32);
            let mut v = 0.5 + 0.2 * (x * 0.37).sin() * (y * 0.23).cos();
            if (i % w) == 13 || (i / w) == 9 {
                v = 0.9;
            }
            if (i % w) == 27 {
                v = 0.1;
            }
            if i % 97 == 5 {
                v = 0.95;
            }
            let noise = ((i.wrapping_mul(2654435761) >> 16) % 1000) as f32 / 1000.0;
            half::f16::from_f32(v + 0.01 * noise).to_f32()
        })
        .collect()
}

fn texture(
    device: &wgpu::Device,
    (width, height): (u32, u32),
    format: wgpu::TextureFormat,
    usage: wgpu::TextureUsages,
) -> wgpu::Texture {
    device.create_texture(&wgpu::TextureDescriptor {
        label: None,
        size: wgpu::Extent3d {
            width,
            height,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage: usage | wgpu::TextureUsages::COPY_DST | wgpu::TextureUsages::COPY_SRC,
        view_formats: &[],
    })
}

fn upload(queue: &wgpu::Queue, t: &wgpu::Texture, bytes: &[u8], texel: u32) {
    queue.write_texture(
        t.as_image_copy(),
        bytes,
        wgpu::TexelCopyBufferLayout {
            offset: 0,
            bytes_per_row: Some(t.width() * texel),
            rows_per_image: None,
        },
        t.size(),
    );
}

/// Reads a texture back, `texel` bytes per texel, rows unpadded.
fn read(device: &wgpu::Device, queue: &wgpu::Queue, t: &wgpu::Texture, texel: u32) -> Vec<u8> {
    let row = (t.width() * texel).div_ceil(256) * 256;
    let buf = device.create_buffer(&wgpu::BufferDescriptor {
        label: None,
        size: (row * t.height()) as u64,
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    let mut enc = device.create_command_encoder(&Default::default());
    enc.copy_texture_to_buffer(
        t.as_image_copy(),
        wgpu::TexelCopyBufferInfo {
            buffer: &buf,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(row),
                rows_per_image: None,
            },
        },
        t.size(),
    );
    queue.submit([enc.finish()]);
    read_buffer(device, &buf)
        .chunks(row as usize)
        .flat_map(|r| r[..(t.width() * texel) as usize].to_vec())
        .collect()
}

fn read_buffer(device: &wgpu::Device, buf: &wgpu::Buffer) -> Vec<u8> {
    buf.slice(..).map_async(wgpu::MapMode::Read, |r| r.unwrap());
    device.poll(wgpu::PollType::wait_indefinitely()).unwrap();
    let out = buf.slice(..).get_mapped_range().expect("mapped").to_vec();
    buf.unmap();
    out
}

fn storage_buffer(device: &wgpu::Device, queue: &wgpu::Queue, bytes: &[u8]) -> wgpu::Buffer {
    let b = device.create_buffer(&wgpu::BufferDescriptor {
        label: None,
        size: bytes.len() as u64,
        usage: wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::COPY_DST
            | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    queue.write_buffer(&b, 0, bytes);
    b
}

fn read_storage(device: &wgpu::Device, queue: &wgpu::Queue, src: &wgpu::Buffer) -> Vec<u8> {
    let buf = device.create_buffer(&wgpu::BufferDescriptor {
        label: None,
        size: src.size(),
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    let mut enc = device.create_command_encoder(&Default::default());
    enc.copy_buffer_to_buffer(src, 0, &buf, 0, src.size());
    queue.submit([enc.finish()]);
    read_buffer(device, &buf)
}

/// AMD's `cbFSR2` (ffx_fsr2_callbacks_glsl.h), std140: what the lock pass reads of it.
fn amd_constants() -> Vec<u8> {
    let mut w = [0u32; 32];
    w[0] = RENDER.0; // iRenderSize
    w[1] = RENDER.1;
    w[2] = RENDER.0; // iMaxRenderSize
    w[3] = RENDER.1;
    w[4] = DISPLAY.0; // iDisplaySize
    w[5] = DISPLAY.1;
    w[6] = RENDER.0; // iInputColorResourceDimensions
    w[7] = RENDER.1;
    w[16] = JITTER[0].to_bits(); // fJitter at byte 64
    w[17] = JITTER[1].to_bits();
    w[20] = (RENDER.0 as f32 / DISPLAY.0 as f32).to_bits(); // fDownscaleFactor at 80
    w[21] = (RENDER.1 as f32 / DISPLAY.1 as f32).to_bits();
    w[24] = 1f32.to_bits(); // fPreExposure at 96
    w[25] = 1f32.to_bits();
    bytemuck::cast_slice(&w).to_vec()
}

/// `fsr2`'s `Params` (common.wgsl), as bytes: sizes, jitter; the rest unused by `lock`.
fn port_params() -> Vec<u8> {
    let mut w = [0u32; 36];
    w[..4].copy_from_slice(&[RENDER.0, RENDER.1, DISPLAY.0, DISPLAY.1]);
    w[4] = JITTER[0].to_bits();
    w[5] = JITTER[1].to_bits();
    bytemuck::cast_slice(&w).to_vec()
}

fn uniform(device: &wgpu::Device, queue: &wgpu::Queue, bytes: &[u8]) -> wgpu::Buffer {
    let b = device.create_buffer(&wgpu::BufferDescriptor {
        label: None,
        size: bytes.len() as u64,
        usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    queue.write_buffer(&b, 0, bytes);
    b
}

#[test]
fn lock_equals_amds_compiled_glsl() {
    let (device, queue) = device();
    let luma = luma();
    let render_px = (RENDER.0 * RENDER.1) as usize;
    let display_px = (DISPLAY.0 * DISPLAY.1) as usize;
    // A reconstructed previous depth to be cleared: every texel 0.5.
    let depth_bits = vec![0.5f32.to_bits(); render_px];
    let groups = (RENDER.0.div_ceil(8), RENDER.1.div_ceil(8));

    // AMD's pass: the SPIR-V as compiled, its bindings as ffx_fsr2_lock_pass.glsl declares them.
    let words: Vec<u32> = LOCK_SPV
        .chunks_exact(4)
        .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect();
    let amd_module = unsafe {
        device.create_shader_module_passthrough(wgpu::ShaderModuleDescriptorPassthrough {
            label: Some("ffx_fsr2_lock_pass"),
            entry_points: std::borrow::Cow::Owned(vec![wgpu::PassthroughShaderEntryPoint {
                name: "main".into(),
                workgroup_size: (8, 8, 1),
            }]),
            spirv: Some(std::borrow::Cow::Owned(words)),
            ..Default::default()
        })
    };
    let samplers = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: None,
        entries: &[0, 1].map(|b| wgpu::BindGroupLayoutEntry {
            binding: b,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::NonFiltering),
            count: None,
        }),
    });
    let storage = |binding, format| wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::StorageTexture {
            access: wgpu::StorageTextureAccess::WriteOnly,
            format,
            view_dimension: wgpu::TextureViewDimension::D2,
        },
        count: None,
    };
    let resources = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: None,
        entries: &[
            wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::COMPUTE,
                ty: wgpu::BindingType::Texture {
                    sample_type: wgpu::TextureSampleType::Float { filterable: false },
                    view_dimension: wgpu::TextureViewDimension::D2,
                    multisampled: false,
                },
                count: None,
            },
            storage(1, wgpu::TextureFormat::R8Unorm),
            storage(2, wgpu::TextureFormat::R32Uint),
            wgpu::BindGroupLayoutEntry {
                binding: 3,
                visibility: wgpu::ShaderStages::COMPUTE,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Uniform,
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            },
        ],
    });
    let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: None,
        bind_group_layouts: &[Some(&samplers), Some(&resources)],
        immediate_size: 0,
    });
    let amd_pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some("amd lock"),
        layout: Some(&layout),
        module: &amd_module,
        entry_point: Some("main"),
        compilation_options: Default::default(),
        cache: None,
    });
    let sampler = device.create_sampler(&Default::default());
    let amd_luma = texture(
        &device,
        RENDER,
        wgpu::TextureFormat::R16Float,
        wgpu::TextureUsages::TEXTURE_BINDING,
    );
    let halves: Vec<half::f16> = luma.iter().map(|v| half::f16::from_f32(*v)).collect();
    upload(&queue, &amd_luma, bytemuck::cast_slice(&halves), 2);
    let amd_locks = texture(
        &device,
        DISPLAY,
        wgpu::TextureFormat::R8Unorm,
        wgpu::TextureUsages::STORAGE_BINDING,
    );
    upload(&queue, &amd_locks, &vec![0u8; display_px], 1);
    let amd_depth = texture(
        &device,
        RENDER,
        wgpu::TextureFormat::R32Uint,
        wgpu::TextureUsages::STORAGE_BINDING,
    );
    upload(&queue, &amd_depth, bytemuck::cast_slice(&depth_bits), 4);
    let cb = uniform(&device, &queue, &amd_constants());
    let view = |t: &wgpu::Texture| t.create_view(&Default::default());
    let g0 = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout: &samplers,
        entries: &[0, 1].map(|b| wgpu::BindGroupEntry {
            binding: b,
            resource: wgpu::BindingResource::Sampler(&sampler),
        }),
    });
    let (lv, kv, dv) = (view(&amd_luma), view(&amd_locks), view(&amd_depth));
    let g1 = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout: &resources,
        entries: &[
            wgpu::BindGroupEntry {
                binding: 0,
                resource: wgpu::BindingResource::TextureView(&lv),
            },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: wgpu::BindingResource::TextureView(&kv),
            },
            wgpu::BindGroupEntry {
                binding: 2,
                resource: wgpu::BindingResource::TextureView(&dv),
            },
            wgpu::BindGroupEntry {
                binding: 3,
                resource: cb.as_entire_binding(),
            },
        ],
    });

    // The port: `lock.wgsl` after `common.wgsl`, on the same inputs (the luma in R32F).
    let port_pipeline =
        tessera::render::kit::compute_pipeline(&device, "lock", &module(LOCK_WGSL), "lock");
    let port_luma = texture(
        &device,
        RENDER,
        wgpu::TextureFormat::R32Float,
        wgpu::TextureUsages::TEXTURE_BINDING,
    );
    upload(&queue, &port_luma, bytemuck::cast_slice(&luma), 4);
    let port_locks = storage_buffer(&device, &queue, &vec![0u8; display_px * 4]);
    let port_depth = storage_buffer(&device, &queue, bytemuck::cast_slice(&depth_bits));
    let params = uniform(&device, &queue, &port_params());
    let pv = view(&port_luma);
    let port_group = tessera::render::kit::bind_group(
        &device,
        "lock",
        &port_pipeline.get_bind_group_layout(0),
        &[(0, &params), (2, &port_locks), (3, &port_depth)],
        &[(1, &pv)],
    );

    let mut enc = device.create_command_encoder(&Default::default());
    {
        let mut cp = enc.begin_compute_pass(&Default::default());
        cp.set_pipeline(&amd_pipeline);
        cp.set_bind_group(0, &g0, &[]);
        cp.set_bind_group(1, &g1, &[]);
        cp.dispatch_workgroups(groups.0, groups.1, 1);
        cp.set_pipeline(&port_pipeline);
        cp.set_bind_group(0, &port_group, &[]);
        cp.dispatch_workgroups(groups.0, groups.1, 1);
    }
    queue.submit([enc.finish()]);

    let amd: Vec<bool> = read(&device, &queue, &amd_locks, 1)
        .iter()
        .map(|v| *v > 127)
        .collect();
    let port: Vec<bool> =
        bytemuck::cast_slice::<u8, f32>(&read_storage(&device, &queue, &port_locks))
            .iter()
            .map(|v| *v > 0.5)
            .collect();
    let locked = amd.iter().filter(|v| **v).count();
    let differ: Vec<usize> = (0..display_px).filter(|&i| amd[i] != port[i]).collect();
    eprintln!(
        "lock: {locked} locks set by AMD's pass, {} by the port, {} pixels differ",
        port.iter().filter(|v| **v).count(),
        differ.len()
    );
    assert!(
        locked > 20 && locked < display_px / 2,
        "AMD set {locked} locks: the input has no ridges?"
    );
    assert!(differ.is_empty(), "new locks differ at {differ:?}");
    // Both cleared the reconstructed previous depth.
    let amd_depth: Vec<u32> = bytemuck::cast_slice(&read(&device, &queue, &amd_depth, 4)).to_vec();
    let port_depth: Vec<u32> =
        bytemuck::cast_slice(&read_storage(&device, &queue, &port_depth)).to_vec();
    assert!(amd_depth.iter().all(|v| *v == 0), "AMD's pass left depth");
    assert!(port_depth.iter().all(|v| *v == 0), "the port left depth");
}
