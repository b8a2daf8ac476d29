//! `fsr2`'s WGSL passes against AMD's own compiled GLSL (issue 36, item 2), on the default
//! adapter (lavapipe in CI) through wgpu's SPIR-V passthrough: both run on the same inputs and
//! their outputs are compared pixel by pixel. AMD's passes are compiled as
//! `tests/fsr2_amd/README.md` says and bound as their pass files declare (samplers at set 0,
//! resources and the std140 constant buffers at set 1, every declared binding bound, the gaps
//! a pass file leaves in set 1 closed by unread textures: lavapipe 22.3 crashes on them).
//! All six proven: `lock` (the new locks of a thin-feature test over a luma image
//! with ridges, valleys, flat regions and noise must be the same pixels, and both must clear the
//! reconstructed previous depth), `rcas` (the sharpened colour of an HDR image with edges,
//! peaks, flat and noisy regions at two sharpnesses, within one f16 step), `depth_clip` (the
//! prepared colour and depth clip within one f16 step, the dilated reactive masks within one
//! 8-bit step after the port's f32 is rounded as AMD's rg8 unorm store rounds, on a moving box
//! that uncovers the background, a steep ground, swirling motion and HDR colour),
//! `reconstruct` (dilated depth, dilated motion and lock luma within one f16 step, the
//! reconstructed previous depth bit for bit, on a moving box, a thin pole moving below AMD's
//! threshold, a ground reprojecting off the screen and noisy HDR colour) and `accumulate` (the
//! accumulated colour and temporal reactive factor and the lock status within one f16 step, the
//! luma history within one 8-bit step, on a moving box with its uncovered trail, locks on a
//! thin line, shading change, luma instability, new samples at the edge and mask patches) and
//! the luminance pyramid (AMD's SPD pass with its global atomic counter against the port's
//! `luminance_pyramid` and `auto_exposure`: the shading-change mip within one f16 step, the
//! average log luma and exposure within one f16 step of AMD's level 5, on a frame like a
//! rendered one, once the port's two stated deviations from SPD, computed on the CPU from the
//! input, are added to the port's; where they vanish, without them).
//! Each test's tolerance is stated beside its assertion and in `techniques/fsr2/README.md`.

mod common;

use tessera::render::kit::{bind_group, compute_pipeline};
use tessera::techniques::fsr2::gpu::{
    module, ACCUMULATE_WGSL, DEPTH_CLIP_WGSL, LOCK_WGSL, LUMINANCE_WGSL, RCAS_WGSL,
    RECONSTRUCT_WGSL,
};

static LOCK_SPV: &[u8] = include_bytes!("fsr2_amd/ffx_fsr2_lock_pass.spv");
static RCAS_SPV: &[u8] = include_bytes!("fsr2_amd/ffx_fsr2_rcas_pass.spv");
static DEPTH_CLIP_SPV: &[u8] = include_bytes!("fsr2_amd/ffx_fsr2_depth_clip_pass.spv");
static RECONSTRUCT_SPV: &[u8] =
    include_bytes!("fsr2_amd/ffx_fsr2_reconstruct_previous_depth_pass.spv");
static ACCUMULATE_SPV: &[u8] = include_bytes!("fsr2_amd/ffx_fsr2_accumulate_pass.spv");
static LUMINANCE_SPV: &[u8] =
    include_bytes!("fsr2_amd/ffx_fsr2_compute_luminance_pyramid_pass.spv");
const RENDER: (u32, u32) = (40, 30);
const DISPLAY: (u32, u32) = (60, 45);
const JITTER: [f32; 2] = [0.3125, -0.2222];
/// RCAS's image: whole 16x16 tiles, as AMD's pass writes them (ffx_fsr2_rcas.h `RCAS`).
const RCAS_SIZE: (u32, u32) = (64, 48);

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

/// Deterministic noise in [0, 1) for texel `i`, channel `k`.
fn noise(i: u32, k: u32) -> f32 {
    ((i.wrapping_mul(2654435761)
        .wrapping_add(k.wrapping_mul(40503))
        >> 16)
        % 1000) as f32
        / 1000.0
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
            half::f16::from_f32(v + 0.01 * noise(i, 0)).to_f32()
        })
        .collect()
}

/// RCAS's input, the accumulated colour (linear HDR, AMD's rgba16f internal colour), by bands
/// of 16 rows: a vertical step and a dark one-pixel line; smooth shading with isolated HDR peaks
/// and black dips; noise. Over them: a bright HDR block (above 1 after the exposure, where RCAS
/// does not clip), a flat grey block and a pure red block (zero green and blue: RCAS's limiters
/// divide by zero there).
fn rcas_colour() -> Vec<half::f16> {
    let (w, _) = RCAS_SIZE;
    (0..w * RCAS_SIZE.1)
        .flat_map(|i| {
            let (x, y) = (i % w, i / w);
            let (fx, fy) = (x as f32, y as f32);
            let mut c = [
                0.2 + 0.1 * (fx * 0.2).sin(),
                0.3 + 0.1 * (fy * 0.3).cos(),
                0.25 + 0.05 * ((fx + fy) * 0.1).sin(),
            ];
            if y < 16 {
                if x >= 12 {
                    c = [0.8, 0.7, 0.6];
                }
                if y == 8 {
                    c = [0.05, 0.05, 0.1];
                }
            } else if y < 32 {
                if x % 7 == 3 && y % 5 == 2 {
                    c = [3.0, 2.5, 2.0];
                }
                if x % 9 == 5 && y % 6 == 1 {
                    c = [0.0; 3];
                }
            } else {
                for (k, v) in (0..).zip(c.iter_mut()) {
                    *v += 0.2 * noise(i, k) - 0.1;
                }
            }
            if x >= 48 && y < 24 {
                c = [
                    1.5 + noise(i, 0),
                    2.0 + noise(i, 1),
                    1.0 + 4.0 * noise(i, 2),
                ];
            }
            if (20..30).contains(&x) && (36..46).contains(&y) {
                c = [0.4; 3];
            }
            if (4..10).contains(&x) && (36..42).contains(&y) {
                c = [0.6, 0.0, 0.0];
            }
            [c[0], c[1], c[2], 1.0].map(half::f16::from_f32)
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

/// A texture holding `bytes`, `texel` bytes per texel, rows unpadded.
fn texture_with(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    size: (u32, u32),
    (format, usage): (wgpu::TextureFormat, wgpu::TextureUsages),
    bytes: &[u8],
    texel: u32,
) -> wgpu::Texture {
    let t = texture(device, size, format, usage);
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
    t
}

fn view(t: &wgpu::Texture) -> wgpu::TextureView {
    t.create_view(&Default::default())
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

/// Reads an `Rgba16Float` texture back as f32 values, four per texel.
fn read_f16(device: &wgpu::Device, queue: &wgpu::Queue, t: &wgpu::Texture) -> Vec<f32> {
    bytemuck::cast_slice::<u8, half::f16>(&read(device, queue, t, 8))
        .iter()
        .map(|v| v.to_f32())
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

/// AMD's `cbFSR2` (ffx_fsr2_callbacks_glsl.h), std140, at render size `render` and display
/// size `display`: what the passes here read of it.
fn amd_constants(render: (u32, u32), display: (u32, u32)) -> Vec<u8> {
    let mut w = [0u32; 32];
    w[0] = render.0; // iRenderSize
    w[1] = render.1;
    w[2] = render.0; // iMaxRenderSize
    w[3] = render.1;
    w[4] = display.0; // iDisplaySize
    w[5] = display.1;
    w[6] = render.0; // iInputColorResourceDimensions
    w[7] = render.1;
    w[12..16].copy_from_slice(&depth_to_view().map(f32::to_bits)); // fDeviceToViewDepth at 48
    w[16] = JITTER[0].to_bits(); // fJitter at byte 64
    w[17] = JITTER[1].to_bits();
    w[18] = 1f32.to_bits(); // fMotionVectorScale at 72: the motion given in uv
    w[19] = 1f32.to_bits();
    w[20] = (render.0 as f32 / display.0 as f32).to_bits(); // fDownscaleFactor at 80
    w[21] = (render.1 as f32 / display.1 as f32).to_bits();
    w[24] = 1f32.to_bits(); // fPreExposure at 96
    w[25] = 1f32.to_bits();
    w[30] = 1f32.to_bits(); // fViewSpaceToMetersFactor at 120
    bytemuck::cast_slice(&w).to_vec()
}

/// `fsr2`'s `Params` (common.wgsl), as bytes: sizes, jitter, auto exposure on (the exposure
/// buffer is read); the rest unused by the passes here.
fn port_params(render: (u32, u32), display: (u32, u32)) -> Vec<u8> {
    let mut w = [0u32; 36];
    w[..4].copy_from_slice(&[render.0, render.1, display.0, display.1]);
    w[4] = JITTER[0].to_bits();
    w[5] = JITTER[1].to_bits();
    w[8..12].copy_from_slice(&depth_to_view().map(f32::to_bits));
    w[15] = 1; // mode.w
    bytemuck::cast_slice(&w).to_vec()
}

/// The camera's `DeviceToViewSpaceTransformFactors`: reversed depth, near 0.1, far 100, a
/// vertical field of view of 60 degrees at 4:3.
fn depth_to_view() -> [f32; 4] {
    let b = 1.0 / 30f32.to_radians().tan();
    tessera::techniques::fsr2::gpu::depth_to_view(0.1, 100.0, b * 0.75, b)
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

/// One binding of an AMD pass at set 1, typed as its pass file declares it.
enum Amd<'a> {
    /// `texture2D`, read with `texelFetch` (float, not filtered).
    Texture(&'a wgpu::TextureView),
    /// `texture2D` read through `s_LinearClamp` (a filterable format).
    Filtered(&'a wgpu::TextureView),
    /// `utexture2D`.
    UintTexture(&'a wgpu::TextureView),
    /// `image2D` or `uimage2D` in `format`: the SPIR-V's declared format, or the app's where
    /// the file leaves it open.
    Image(&'a wgpu::TextureView, wgpu::TextureFormat),
    /// A std140 uniform block.
    Uniform(&'a wgpu::Buffer),
}

/// A compute pipeline and its bind groups (group i at index i), ready to dispatch.
struct Pass {
    pipeline: wgpu::ComputePipeline,
    groups: Vec<wgpu::BindGroup>,
}

/// AMD's pass compiled as `spv` (entry `main`, `workgroup` invocations) through SPIR-V
/// passthrough: set 0 the two samplers every pass file declares (ffx_fsr2_callbacks_glsl.h),
/// set 1 `bindings`.
fn amd_pass(
    device: &wgpu::Device,
    label: &str,
    spv: &[u8],
    workgroup: (u32, u32, u32),
    bindings: &[(u32, Amd)],
) -> Pass {
    let module = unsafe {
        device.create_shader_module_passthrough(wgpu::ShaderModuleDescriptorPassthrough {
            label: Some(label),
            entry_points: std::borrow::Cow::Owned(vec![wgpu::PassthroughShaderEntryPoint {
                name: "main".into(),
                workgroup_size: workgroup,
            }]),
            spirv: Some(std::borrow::Cow::Owned(words(spv))),
            ..Default::default()
        })
    };
    let samplers = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: None,
        entries: &[
            (0, wgpu::SamplerBindingType::NonFiltering),
            (1, wgpu::SamplerBindingType::Filtering),
        ]
        .map(|(binding, ty)| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Sampler(ty),
            count: None,
        }),
    });
    let texture = |sample_type| wgpu::BindingType::Texture {
        sample_type,
        view_dimension: wgpu::TextureViewDimension::D2,
        multisampled: false,
    };
    let entries: Vec<wgpu::BindGroupLayoutEntry> = bindings
        .iter()
        .map(|(binding, b)| wgpu::BindGroupLayoutEntry {
            binding: *binding,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: match b {
                Amd::Texture(_) => texture(wgpu::TextureSampleType::Float { filterable: false }),
                Amd::Filtered(_) => texture(wgpu::TextureSampleType::Float { filterable: true }),
                Amd::UintTexture(_) => texture(wgpu::TextureSampleType::Uint),
                Amd::Image(_, format) => wgpu::BindingType::StorageTexture {
                    access: wgpu::StorageTextureAccess::WriteOnly,
                    format: *format,
                    view_dimension: wgpu::TextureViewDimension::D2,
                },
                Amd::Uniform(_) => wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Uniform,
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
            },
            count: None,
        })
        .collect();
    let resources = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: None,
        entries: &entries,
    });
    let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: None,
        bind_group_layouts: &[Some(&samplers), Some(&resources)],
        immediate_size: 0,
    });
    let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some(label),
        layout: Some(&layout),
        module: &module,
        entry_point: Some("main"),
        compilation_options: Default::default(),
        cache: None,
    });
    // s_PointClamp and s_LinearClamp.
    let point = device.create_sampler(&Default::default());
    let linear = device.create_sampler(&wgpu::SamplerDescriptor {
        mag_filter: wgpu::FilterMode::Linear,
        min_filter: wgpu::FilterMode::Linear,
        ..Default::default()
    });
    let g0 = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout: &samplers,
        entries: &[(0, &point), (1, &linear)].map(|(binding, sampler)| wgpu::BindGroupEntry {
            binding,
            resource: wgpu::BindingResource::Sampler(sampler),
        }),
    });
    let entries: Vec<wgpu::BindGroupEntry> = bindings
        .iter()
        .map(|(binding, b)| wgpu::BindGroupEntry {
            binding: *binding,
            resource: match b {
                Amd::Texture(v) | Amd::Filtered(v) | Amd::UintTexture(v) | Amd::Image(v, _) => {
                    wgpu::BindingResource::TextureView(v)
                }
                Amd::Uniform(buffer) => buffer.as_entire_binding(),
            },
        })
        .collect();
    let g1 = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout: &resources,
        entries: &entries,
    });
    Pass {
        pipeline,
        groups: vec![g0, g1],
    }
}

/// The port's pass `entry` of the pass file `source` (compiled after `common.wgsl`), its group 0
/// bound by number.
fn port_pass(
    device: &wgpu::Device,
    source: &str,
    entry: &str,
    buffers: &[(u32, &wgpu::Buffer)],
    views: &[(u32, &wgpu::TextureView)],
) -> Pass {
    let pipeline = compute_pipeline(device, entry, &module(source), entry);
    let group = bind_group(
        device,
        entry,
        &pipeline.get_bind_group_layout(0),
        buffers,
        views,
    );
    Pass {
        pipeline,
        groups: vec![group],
    }
}

/// Records each pass over its workgroup count, in order, and submits them.
fn dispatch(device: &wgpu::Device, queue: &wgpu::Queue, passes: &[(&Pass, (u32, u32))]) {
    let mut enc = device.create_command_encoder(&Default::default());
    {
        let mut cp = enc.begin_compute_pass(&Default::default());
        for (pass, (x, y)) in passes {
            cp.set_pipeline(&pass.pipeline);
            for (i, g) in (0..).zip(&pass.groups) {
                cp.set_bind_group(i, g, &[]);
            }
            cp.dispatch_workgroups(*x, *y, 1);
        }
    }
    queue.submit([enc.finish()]);
}

/// How two outputs differ: largest and mean absolute difference, where the largest is, and how
/// many values are further apart than their tolerance.
#[derive(Debug)]
struct Diff {
    max: f32,
    mean: f64,
    at: usize,
    over: usize,
}

/// `amd` against `port` value by value, each allowed `tolerance(amd value)`.
fn diff(amd: &[f32], port: &[f32], tolerance: impl Fn(f32) -> f32) -> Diff {
    assert_eq!(amd.len(), port.len());
    let mut d = Diff {
        max: 0.0,
        mean: 0.0,
        at: 0,
        over: 0,
    };
    for (i, (a, p)) in amd.iter().zip(port).enumerate() {
        let e = (a - p).abs();
        // NaN on one side only is a difference; on both, none.
        let e = if a.is_nan() && p.is_nan() {
            0.0
        } else if e.is_nan() {
            f32::INFINITY
        } else {
            e
        };
        if e > d.max {
            d.max = e;
            d.at = i;
        }
        d.mean += f64::from(e);
        d.over += usize::from(e > tolerance(*a));
    }
    d.mean /= amd.len() as f64;
    d
}

/// The spacing of f16 values at `v`: one step of AMD's (and the port's) f16 storage.
fn f16_step(v: f32) -> f32 {
    let h = half::f16::from_f32(v.abs());
    (half::f16::from_bits(h.to_bits() + 1).to_f32() - h.to_f32()).abs()
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
    let (sampled, storage) = (
        wgpu::TextureUsages::TEXTURE_BINDING,
        wgpu::TextureUsages::STORAGE_BINDING,
    );
    use wgpu::TextureFormat::{R16Float, R32Float, R32Uint, R8Unorm};

    // AMD's pass: the luma in R16F, new locks in R8 unorm, the depth in R32 uint.
    let halves: Vec<half::f16> = luma.iter().map(|v| half::f16::from_f32(*v)).collect();
    let amd_luma = texture_with(
        &device,
        &queue,
        RENDER,
        (R16Float, sampled),
        bytemuck::cast_slice(&halves),
        2,
    );
    let amd_locks = texture_with(
        &device,
        &queue,
        DISPLAY,
        (R8Unorm, storage),
        &vec![0u8; display_px],
        1,
    );
    let amd_depth = texture_with(
        &device,
        &queue,
        RENDER,
        (R32Uint, storage),
        bytemuck::cast_slice(&depth_bits),
        4,
    );
    let cb = uniform(&device, &queue, &amd_constants(RENDER, DISPLAY));
    let (lv, kv, dv) = (view(&amd_luma), view(&amd_locks), view(&amd_depth));
    let amd = amd_pass(
        &device,
        "ffx_fsr2_lock_pass",
        LOCK_SPV,
        (8, 8, 1),
        &[
            (0, Amd::Texture(&lv)),
            (1, Amd::Image(&kv, R8Unorm)),
            (2, Amd::Image(&dv, R32Uint)),
            (3, Amd::Uniform(&cb)),
        ],
    );

    // The port: `lock.wgsl` after `common.wgsl`, on the same inputs (the luma in R32F).
    let port_luma = texture_with(
        &device,
        &queue,
        RENDER,
        (R32Float, sampled),
        bytemuck::cast_slice(&luma),
        4,
    );
    let port_locks = storage_buffer(&device, &queue, &vec![0u8; display_px * 4]);
    let port_depth = storage_buffer(&device, &queue, bytemuck::cast_slice(&depth_bits));
    let params = uniform(&device, &queue, &port_params(RENDER, DISPLAY));
    let port = port_pass(
        &device,
        LOCK_WGSL,
        "lock",
        &[(0, &params), (2, &port_locks), (3, &port_depth)],
        &[(1, &view(&port_luma))],
    );
    dispatch(&device, &queue, &[(&amd, groups), (&port, groups)]);

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

/// AMD's `FsrRcasCon` (ffx_fsr1.h, called by ffx_fsr2.cpp `fsr2Dispatch` with
/// `-2 * sharpness + 2` stops): the linear sharpness's f32 bits, then it twice as packed f16.
fn rcas_con(sharpness: f32) -> [u32; 4] {
    let linear = (-(2.0 - 2.0 * sharpness)).exp2();
    let h = u32::from(half::f16::from_f32(linear).to_bits());
    [linear.to_bits(), h | (h << 16), 0, 0]
}

#[test]
fn rcas_equals_amds_compiled_glsl() {
    let (device, queue) = device();
    use wgpu::TextureFormat::{Rg32Float, Rgba16Float};
    let (sampled, storage) = (
        wgpu::TextureUsages::TEXTURE_BINDING,
        wgpu::TextureUsages::STORAGE_BINDING,
    );
    // One input for both sides, as both keep the accumulated colour in rgba16f.
    let colour = texture_with(
        &device,
        &queue,
        RCAS_SIZE,
        (Rgba16Float, sampled),
        bytemuck::cast_slice(&rcas_colour()),
        8,
    );
    // The exposure (and an average log luma RCAS does not read): AMD's auto exposure is a 1x1
    // rg32f texture, the port's a storage buffer.
    let exposure = [0.7f32, -1.0];
    let amd_exposure = texture_with(
        &device,
        &queue,
        (1, 1),
        (Rg32Float, sampled),
        bytemuck::cast_slice(&exposure),
        8,
    );
    let port_exposure = storage_buffer(&device, &queue, bytemuck::cast_slice(&exposure));
    let cb = uniform(&device, &queue, &amd_constants(RCAS_SIZE, RCAS_SIZE));
    let params = uniform(&device, &queue, &port_params(RCAS_SIZE, RCAS_SIZE));
    let (cv, ev) = (view(&colour), view(&amd_exposure));
    let px = (RCAS_SIZE.0 * RCAS_SIZE.1) as usize;
    for sharpness in [0.2f32, 0.8] {
        let con = uniform(&device, &queue, bytemuck::cast_slice(&rcas_con(sharpness)));
        let amd_out = texture(&device, RCAS_SIZE, Rgba16Float, storage);
        let port_out = texture(&device, RCAS_SIZE, Rgba16Float, storage);
        let (aov, pov) = (view(&amd_out), view(&port_out));
        // ffx_fsr2_rcas_pass.glsl: its output's format is the app's (image load formatted).
        let amd = amd_pass(
            &device,
            "ffx_fsr2_rcas_pass",
            RCAS_SPV,
            (64, 1, 1),
            &[
                (0, Amd::Texture(&ev)),
                (1, Amd::Texture(&cv)),
                (2, Amd::Image(&aov, Rgba16Float)),
                (3, Amd::Uniform(&cb)),
                (4, Amd::Uniform(&con)),
            ],
        );
        let port = port_pass(
            &device,
            RCAS_WGSL,
            "rcas",
            &[(0, &params), (2, &port_exposure), (4, &con)],
            &[(1, &cv), (3, &pov)],
        );
        // AMD: 64 invocations per 16x16 tile (ffx_fsr2_rcas.h `RCAS`); the port: 8x8.
        let tiles = (RCAS_SIZE.0.div_ceil(16), RCAS_SIZE.1.div_ceil(16));
        let groups = (RCAS_SIZE.0.div_ceil(8), RCAS_SIZE.1.div_ceil(8));
        dispatch(&device, &queue, &[(&amd, tiles), (&port, groups)]);
        // Red, green and blue (both store alpha 1).
        let rgb = |t: &wgpu::Texture| -> Vec<f32> {
            read_f16(&device, &queue, t)
                .chunks(4)
                .flat_map(|c| c[..3].to_vec())
                .collect()
        };
        let (amd, port, input) = (rgb(&amd_out), rgb(&port_out), rgb(&colour));
        let sharpened = (0..px * 3)
            .filter(|i| (amd[*i] - input[*i]).abs() > 0.01)
            .count();
        // Both store f16: at most one f16 step apart (the same f32 arithmetic, compiled from two
        // languages, may round differently before the store).
        let d = diff(&amd, &port, f16_step);
        eprintln!(
            "rcas at sharpness {sharpness}: {sharpened} of {} values moved by more than 0.01 by AMD's pass; max |AMD - port| {:.3e} at value {} (AMD {}, port {}), mean {:.3e}, {} values beyond one f16 step",
            px * 3, d.max, d.at, amd[d.at], port[d.at], d.mean, d.over
        );
        assert!(
            sharpened > px / 10,
            "AMD's pass barely sharpened: the input has no edges?"
        );
        assert_eq!(
            d.over, 0,
            "the port's RCAS differs from AMD's beyond one f16 step: {d:?}"
        );
    }
}

/// f16-rounded, as AMD keeps dilated depth and motion (r16f, rg16f): both sides read the same
/// values.
fn f16_round(v: f32) -> f32 {
    half::f16::from_f32(v).to_f32()
}

/// Depth clip's inputs at the render size, per pixel: dilated depth (reversed, AMD: r16f),
/// reconstructed previous depth, dilated motion and the previous frame's (uv, current to
/// previous; AMD: rg16f), the engine's motion (rg32f) and colour (rgba16f, 4 values).
struct DepthClipInputs {
    depth: Vec<f32>,
    previous_depth: Vec<f32>,
    motion: Vec<[f32; 2]>,
    previous_motion: Vec<[f32; 2]>,
    input_motion: Vec<[f32; 2]>,
    colour: Vec<half::f16>,
}

/// A box (device depth 0.3) over a far background (0.02) moving right by 10 render pixels a
/// frame over a slowly panning background, with a ground (rows 22 and down) receding steeply in
/// the previous depth. The previous depth has the box 10 pixels to the left (uncovered pixels:
/// depth clip), a hole of 0 (nothing reprojected there); the previous motion has the box still
/// (temporal divergence); the engine's motion swirls around (30, 15) with a still region at
/// the top left (motion divergence, and its early out); the colour is noisy HDR with a few
/// negative values (clamped by the preparation).
fn depth_clip_inputs() -> DepthClipInputs {
    let (w, h) = RENDER;
    let mut inputs = DepthClipInputs {
        depth: vec![],
        previous_depth: vec![],
        motion: vec![],
        previous_motion: vec![],
        input_motion: vec![],
        colour: vec![],
    };
    for i in 0..w * h {
        let (x, y) = (i % w, i / w);
        let in_box = (12..24).contains(&x) && (8..20).contains(&y);
        let was_box = (2..14).contains(&x) && (8..20).contains(&y);
        let ground = y >= 22;
        let depth = if in_box {
            0.3
        } else if ground {
            0.05 + 0.02 * (y - 22) as f32
        } else {
            0.02
        };
        inputs.depth.push(f16_round(depth));
        let previous = if was_box {
            0.3
        } else if ground {
            0.05 * 1.2f32.powi(y as i32 - 22)
        } else if x >= 32 && y < 6 {
            0.0
        } else {
            0.02
        };
        inputs.previous_depth.push(previous);
        let pan = [0.004, 0.001];
        let motion = if in_box {
            [-10.0 / w as f32, 0.0]
        } else if x < 8 && y < 6 {
            [0.0; 2]
        } else {
            pan
        };
        inputs.motion.push(motion.map(f16_round));
        inputs
            .previous_motion
            .push(if was_box { [0.0; 2] } else { pan }.map(f16_round));
        let (dx, dy) = (x as f32 - 30.0, y as f32 - 15.0);
        inputs.input_motion.push(if x < 8 && y < 6 {
            [0.0; 2]
        } else {
            [motion[0] - 0.002 * dy, motion[1] + 0.002 * dx]
        });
        let n = |k| noise(i, k);
        let c = [4.0 * n(0), n(1), 0.5 * n(2) - 0.1, 1.0];
        inputs.colour.extend(c.map(half::f16::from_f32));
    }
    inputs
}

#[test]
fn depth_clip_equals_amds_compiled_glsl() {
    let (device, queue) = device();
    use wgpu::TextureFormat::{
        R16Float, R32Float, R32Uint, R8Unorm, Rg16Float, Rg32Float, Rg8Unorm, Rgba16Float,
    };
    let (sampled, storage) = (
        wgpu::TextureUsages::TEXTURE_BINDING,
        wgpu::TextureUsages::STORAGE_BINDING,
    );
    let px = (RENDER.0 * RENDER.1) as usize;
    let inp = depth_clip_inputs();
    let tex = |format, bytes: &[u8], texel| {
        texture_with(&device, &queue, RENDER, (format, sampled), bytes, texel)
    };
    let halves =
        |v: &[f32]| -> Vec<half::f16> { v.iter().map(|x| half::f16::from_f32(*x)).collect() };
    let flat = |v: &[[f32; 2]]| -> Vec<f32> { v.iter().flatten().copied().collect() };
    // Shared by both sides: the engine's motion and colour, the exposure as in the RCAS test.
    let input_motion = tex(Rg32Float, bytemuck::cast_slice(&flat(&inp.input_motion)), 8);
    let colour = tex(Rgba16Float, bytemuck::cast_slice(&inp.colour), 8);
    let exposure = [0.7f32, -1.0];

    // AMD's pass, its every binding (ffx_fsr2_depth_clip_pass.glsl): the masks zero (no
    // reactive or transparency mask), its input depth and prepared-colour SRV unread. AMD's
    // prepared colour resource is R16G16B16A16_FLOAT (ffx_fsr2.cpp) though the GLSL declares
    // `rgba16`: bound as the resource AMD makes, as AMD's Vulkan backend does.
    let amd_depth = tex(R16Float, bytemuck::cast_slice(&halves(&inp.depth)), 2);
    let previous_bits: Vec<u32> = inp.previous_depth.iter().map(|v| v.to_bits()).collect();
    let amd_previous = tex(R32Uint, bytemuck::cast_slice(&previous_bits), 4);
    let amd_motion = tex(
        Rg16Float,
        bytemuck::cast_slice(&halves(&flat(&inp.motion))),
        4,
    );
    let amd_previous_motion = tex(
        Rg16Float,
        bytemuck::cast_slice(&halves(&flat(&inp.previous_motion))),
        4,
    );
    let zeros = tex(R8Unorm, &vec![0u8; px], 1);
    let unread = tex(R32Float, &vec![0u8; px * 4], 4);
    let amd_exposure = texture_with(
        &device,
        &queue,
        (1, 1),
        (Rg32Float, sampled),
        bytemuck::cast_slice(&exposure),
        8,
    );
    let amd_prepared = texture(&device, RENDER, Rgba16Float, storage);
    let amd_reactive = texture(&device, RENDER, Rg8Unorm, storage);
    let cb = uniform(&device, &queue, &amd_constants(RENDER, DISPLAY));
    let v = [
        &amd_previous,
        &amd_motion,
        &amd_depth,
        &zeros,
        &amd_previous_motion,
        &input_motion,
        &colour,
        &unread,
        &amd_exposure,
        &amd_reactive,
        &amd_prepared,
    ]
    .map(view);
    let amd = amd_pass(
        &device,
        "ffx_fsr2_depth_clip_pass",
        DEPTH_CLIP_SPV,
        (8, 8, 1),
        &[
            (0, Amd::UintTexture(&v[0])),
            (1, Amd::Texture(&v[1])),
            (2, Amd::Texture(&v[2])),
            (3, Amd::Texture(&v[3])),
            (4, Amd::Texture(&v[3])),
            (5, Amd::Texture(&v[7])),
            (6, Amd::Filtered(&v[4])),
            (7, Amd::Texture(&v[5])),
            (8, Amd::Texture(&v[6])),
            (9, Amd::Texture(&v[7])),
            (10, Amd::Texture(&v[8])),
            // Declared by the pass file (FSR2_BIND_UAV_DEPTH_CLIP) but by no binding in the
            // callbacks: left out, the set's gap at 11 crashes lavapipe 22.3's
            // vkCreateComputePipelines (SIGSEGV); an unread texture here closes it.
            (11, Amd::Texture(&v[7])),
            (12, Amd::Image(&v[9], Rg8Unorm)),
            (13, Amd::Image(&v[10], Rgba16Float)),
            (14, Amd::Uniform(&cb)),
        ],
    );

    // The port: f32 textures holding the same (f16-rounded) values, the previous depth in a
    // storage buffer, the reactive masks in rg32f.
    let port_depth = tex(R32Float, bytemuck::cast_slice(&inp.depth), 4);
    let port_motion = tex(Rg32Float, bytemuck::cast_slice(&flat(&inp.motion)), 8);
    let port_previous_motion = tex(
        Rg32Float,
        bytemuck::cast_slice(&flat(&inp.previous_motion)),
        8,
    );
    let port_previous = storage_buffer(&device, &queue, bytemuck::cast_slice(&previous_bits));
    let port_exposure = storage_buffer(&device, &queue, bytemuck::cast_slice(&exposure));
    let port_prepared = texture(&device, RENDER, Rgba16Float, storage);
    let port_reactive = texture(&device, RENDER, Rg32Float, storage);
    let params = uniform(&device, &queue, &port_params(RENDER, DISPLAY));
    let port = port_pass(
        &device,
        DEPTH_CLIP_WGSL,
        "depth_clip",
        &[(0, &params), (6, &port_exposure), (7, &port_previous)],
        &[
            (1, &view(&port_depth)),
            (2, &view(&port_motion)),
            (3, &view(&port_previous_motion)),
            (4, &v[5]),
            (5, &v[6]),
            (8, &view(&port_prepared)),
            (9, &view(&port_reactive)),
        ],
    );
    let groups = (RENDER.0.div_ceil(8), RENDER.1.div_ceil(8));
    dispatch(&device, &queue, &[(&amd, groups), (&port, groups)]);

    // The prepared colour (YCoCg) and depth clip: both f16.
    let (amd_p, port_p) = (
        read_f16(&device, &queue, &amd_prepared),
        read_f16(&device, &queue, &port_prepared),
    );
    let colour_d = diff(
        &amd_p
            .chunks(4)
            .flat_map(|c| c[..3].to_vec())
            .collect::<Vec<_>>(),
        &port_p
            .chunks(4)
            .flat_map(|c| c[..3].to_vec())
            .collect::<Vec<_>>(),
        f16_step,
    );
    let (amd_clip, port_clip): (Vec<f32>, Vec<f32>) = (
        amd_p.chunks(4).map(|c| c[3]).collect(),
        port_p.chunks(4).map(|c| c[3]).collect(),
    );
    let clip_d = diff(&amd_clip, &port_clip, f16_step);
    // The reactive masks: AMD's rg8 unorm, the port's f32 rounded to 8 bits the same way.
    let amd_r: Vec<f32> = read(&device, &queue, &amd_reactive, 2)
        .iter()
        .map(|b| f32::from(*b) / 255.0)
        .collect();
    let port_r: Vec<f32> =
        bytemuck::cast_slice::<u8, f32>(&read(&device, &queue, &port_reactive, 8))
            .iter()
            .map(|v| (v.clamp(0.0, 1.0) * 255.0).round() / 255.0)
            .collect();
    let reactive_d = diff(&amd_r, &port_r, |_| 1.0 / 255.0 + 1e-6);
    let clipped = amd_clip.iter().filter(|c| **c > 0.01).count();
    let reactive = amd_r
        .iter()
        .skip(1)
        .step_by(2)
        .filter(|r| **r > 0.0)
        .count();
    let where_ = |d: &Diff, per: usize| {
        (
            (d.at / per) as u32 % RENDER.0,
            (d.at / per) as u32 / RENDER.0,
        )
    };
    eprintln!(
        "depth_clip: AMD clips {clipped} of {px} pixels, marks {reactive} reactive; colour {colour_d:?} at {:?}; depth clip {clip_d:?} at {:?} (AMD {}, port {}); reactive masks {reactive_d:?} at {:?} (AMD {}, port {})",
        where_(&colour_d, 3), where_(&clip_d, 1), amd_clip[clip_d.at], port_clip[clip_d.at],
        where_(&reactive_d, 2), amd_r[reactive_d.at], port_r[reactive_d.at]
    );
    for (i, (a, p)) in amd_clip.iter().zip(&port_clip).enumerate() {
        if (a - p).abs() > f16_step(*a) {
            eprintln!(
                "  clip differs at {:?}: AMD {a}, port {p}",
                (i as u32 % RENDER.0, i as u32 / RENDER.0)
            );
        }
    }
    for (i, (a, p)) in amd_r.iter().zip(&port_r).enumerate() {
        if (a - p).abs() > 1.5 / 255.0 {
            eprintln!(
                "  reactive {} differs at {:?}: AMD {a}, port {p}",
                i % 2,
                ((i / 2) as u32 % RENDER.0, (i / 2) as u32 / RENDER.0)
            );
        }
    }
    assert!(
        clipped > 20 && reactive > 20,
        "the inputs exercise too little: {clipped} clipped, {reactive} reactive"
    );
    assert_eq!(
        colour_d.over, 0,
        "prepared colour differs beyond one f16 step: {colour_d:?}"
    );
    assert_eq!(
        clip_d.over, 0,
        "depth clip differs beyond one f16 step: {clip_d:?}"
    );
    assert_eq!(
        reactive_d.over, 0,
        "reactive masks differ beyond one 8-bit step: {reactive_d:?}"
    );
}

/// Reconstruct's inputs at the render size: the engine's depth (reversed), motion (uv, current
/// to previous) and colour (rgba16f, 4 values per pixel).
struct ReconstructInputs {
    depth: Vec<f32>,
    motion: Vec<[f32; 2]>,
    colour: Vec<half::f16>,
}

/// A far background (device depth about 0.02, with a little noise: the nearest of nine is not
/// always the centre) panning by a fraction of a pixel; a box (0.3) moving left by 10.3 render
/// pixels and down by 0.4; a one-pixel pole (0.5) at x = 30 moving by less than AMD's 0.1
/// display-pixel threshold (its reconstruction stays in place); a ground (rows 22 and down)
/// nearer row by row whose motion grows with the row, its last rows reprojecting below the
/// image (taps off the screen). Noisy HDR colour with negatives, as depth clip's.
fn reconstruct_inputs() -> ReconstructInputs {
    let (w, h) = RENDER;
    let mut inputs = ReconstructInputs {
        depth: vec![],
        motion: vec![],
        colour: vec![],
    };
    for i in 0..w * h {
        let (x, y) = (i % w, i / w);
        let in_box = (12..24).contains(&x) && (8..20).contains(&y);
        let pole = x == 30 && y < 22;
        let ground = y >= 22;
        let (depth, motion) = if in_box {
            (0.3, [-10.3 / w as f32, 0.4 / h as f32])
        } else if pole {
            (0.5, [0.05 / DISPLAY.0 as f32, 0.0])
        } else if ground {
            (
                0.05 + 0.02 * (y - 22) as f32,
                [0.0013, 0.02 * (y - 21) as f32],
            )
        } else {
            (0.02 + 0.002 * noise(i, 3), [0.0043, -0.0021])
        };
        inputs.depth.push(depth);
        inputs.motion.push(motion);
        let n = |k| noise(i, k);
        let c = [4.0 * n(0), n(1), 0.5 * n(2) - 0.1, 1.0];
        inputs.colour.extend(c.map(half::f16::from_f32));
    }
    inputs
}

#[test]
fn reconstruct_equals_amds_compiled_glsl() {
    let (device, queue) = device();
    use wgpu::TextureFormat::{
        R16Float, R32Float, R32Uint, Rg16Float, Rg32Float, Rgba16Float, Rgba8Unorm,
    };
    let (sampled, storage) = (
        wgpu::TextureUsages::TEXTURE_BINDING,
        wgpu::TextureUsages::STORAGE_BINDING,
    );
    let px = (RENDER.0 * RENDER.1) as usize;
    let inp = reconstruct_inputs();
    let tex = |format, bytes: &[u8], texel| {
        texture_with(&device, &queue, RENDER, (format, sampled), bytes, texel)
    };
    let flat: Vec<f32> = inp.motion.iter().flatten().copied().collect();
    // Shared by both sides: the engine's depth (Depth32Float, as the scene pass makes it),
    // motion (rg32f) and colour (rgba16f); the exposure as in the RCAS test.
    let depth = common::depth_texture(&device, &queue, RENDER, &inp.depth);
    let motion = tex(Rg32Float, bytemuck::cast_slice(&flat), 8);
    let colour = tex(Rgba16Float, bytemuck::cast_slice(&inp.colour), 8);
    let exposure = [0.7f32, -1.0];
    // The reconstructed previous depth starts cleared (the lock pass of the frame before).
    let cleared = vec![0u8; px * 4];

    // AMD's pass, its every binding (ffx_fsr2_reconstruct_previous_depth_pass.glsl): the
    // exposure as the 1x1 rg32f auto exposure AMD binds as its input exposure; the luma history
    // (read and write) and prepared colour declared by the pass file but unused by this pass.
    let amd_exposure = texture_with(
        &device,
        &queue,
        (1, 1),
        (Rg32Float, sampled),
        bytemuck::cast_slice(&exposure),
        8,
    );
    let unread = tex(R32Float, &cleared, 4);
    let amd_reconstructed = texture_with(&device, &queue, RENDER, (R32Uint, storage), &cleared, 4);
    let amd_motion = texture(&device, RENDER, Rg16Float, storage);
    let amd_depth = texture(&device, RENDER, R16Float, storage);
    let amd_prepared = texture(&device, RENDER, Rgba16Float, storage);
    let amd_luma_history = texture(&device, RENDER, Rgba8Unorm, storage);
    let amd_luma = texture(&device, RENDER, R16Float, storage);
    let cb = uniform(&device, &queue, &amd_constants(RENDER, DISPLAY));
    let v = [
        &motion,
        &depth,
        &colour,
        &amd_exposure,
        &unread,
        &amd_reconstructed,
        &amd_motion,
        &amd_depth,
        &amd_prepared,
        &amd_luma_history,
        &amd_luma,
    ]
    .map(view);
    let amd = amd_pass(
        &device,
        "ffx_fsr2_reconstruct_previous_depth_pass",
        RECONSTRUCT_SPV,
        (8, 8, 1),
        &[
            (0, Amd::Texture(&v[0])),
            (1, Amd::Texture(&v[1])),
            (2, Amd::Texture(&v[2])),
            (3, Amd::Texture(&v[3])),
            (4, Amd::Texture(&v[4])),
            (5, Amd::Image(&v[5], R32Uint)),
            (6, Amd::Image(&v[6], Rg16Float)),
            (7, Amd::Image(&v[7], R16Float)),
            (8, Amd::Image(&v[8], Rgba16Float)),
            (9, Amd::Image(&v[9], Rgba8Unorm)),
            // Declared by the pass file (FSR2_BIND_UAV_LUMA_INSTABILITY) but by no binding in
            // the callbacks: a gap at 10 crashes lavapipe 22.3's vkCreateComputePipelines, as
            // depth clip's at 11 did; an unread texture here closes it.
            (10, Amd::Texture(&v[4])),
            (11, Amd::Image(&v[10], R16Float)),
            (12, Amd::Uniform(&cb)),
        ],
    );

    // The port: f32 outputs, the reconstructed depth in a storage buffer.
    let port_exposure = storage_buffer(&device, &queue, bytemuck::cast_slice(&exposure));
    let port_reconstructed = storage_buffer(&device, &queue, &cleared);
    let port_depth = texture(&device, RENDER, R32Float, storage);
    let port_motion = texture(&device, RENDER, Rg32Float, storage);
    let port_luma = texture(&device, RENDER, R32Float, storage);
    let params = uniform(&device, &queue, &port_params(RENDER, DISPLAY));
    let port = port_pass(
        &device,
        RECONSTRUCT_WGSL,
        "reconstruct",
        &[(0, &params), (4, &port_exposure), (8, &port_reconstructed)],
        &[
            (1, &v[1]),
            (2, &v[0]),
            (3, &v[2]),
            (5, &view(&port_depth)),
            (6, &view(&port_motion)),
            (7, &view(&port_luma)),
        ],
    );
    let groups = (RENDER.0.div_ceil(8), RENDER.1.div_ceil(8));
    dispatch(&device, &queue, &[(&amd, groups), (&port, groups)]);

    let halves = |t: &wgpu::Texture, texel| -> Vec<f32> {
        bytemuck::cast_slice::<u8, half::f16>(&read(&device, &queue, t, texel))
            .iter()
            .map(|v| v.to_f32())
            .collect()
    };
    // Dilated depth and motion, lock luma: AMD's r16f and rg16f, the port's f32 rounded to f16
    // as AMD's store rounds.
    let floats = |t: &wgpu::Texture, texel| -> Vec<f32> {
        bytemuck::cast_slice::<u8, f32>(&read(&device, &queue, t, texel))
            .iter()
            .map(|v| f16_round(*v))
            .collect()
    };
    let depth_d = diff(&halves(&amd_depth, 2), &floats(&port_depth, 4), f16_step);
    let (amd_m, port_m) = (halves(&amd_motion, 4), floats(&port_motion, 8));
    let motion_d = diff(&amd_m, &port_m, f16_step);
    let (amd_l, port_l) = (halves(&amd_luma, 2), floats(&port_luma, 4));
    let luma_d = diff(&amd_l, &port_l, f16_step);
    // The reconstructed previous depth: the same f32 bits pushed by the same atomic max.
    let amd_r: Vec<u32> =
        bytemuck::cast_slice(&read(&device, &queue, &amd_reconstructed, 4)).to_vec();
    let port_r: Vec<u32> =
        bytemuck::cast_slice(&read_storage(&device, &queue, &port_reconstructed)).to_vec();
    let reconstructed = amd_r.iter().filter(|v| **v != 0).count();
    let differ: Vec<(u32, u32)> = (0..px)
        .filter(|&i| amd_r[i] != port_r[i])
        .map(|i| (i as u32 % RENDER.0, i as u32 / RENDER.0))
        .collect();
    let dilated = inp
        .depth
        .iter()
        .zip(halves(&amd_depth, 2))
        .filter(|(d, a)| (f16_round(**d) - a).abs() > 1e-6)
        .count();
    let moved = (0..px)
        .filter(|&i| (f16_round(inp.motion[i][0]) - amd_m[2 * i]).abs() > 1e-6)
        .count();
    eprintln!(
        "reconstruct: AMD dilates {dilated} of {px} depths and {moved} motions, reconstructs {reconstructed} previous depths; dilated depth {depth_d:?}, motion {motion_d:?}, lock luma {luma_d:?} (AMD {}, port {}); reconstructed depths differ at {} pixels {:?}",
        amd_l[luma_d.at], port_l[luma_d.at], differ.len(), &differ[..differ.len().min(12)]
    );
    assert!(
        dilated > 50 && moved > 50 && reconstructed > px / 2 && reconstructed < px,
        "the inputs exercise too little: {dilated} dilated, {moved} moved, {reconstructed} reconstructed"
    );
    // One f16 step: AMD stores f16 (r16f, rg16f), the port f32 of the same arithmetic; the
    // test rounds the port's to nearest where lavapipe's store may round the other way (about
    // half the values one step apart).
    assert_eq!(depth_d.over, 0, "dilated depth differs: {depth_d:?}");
    assert_eq!(motion_d.over, 0, "dilated motion differs: {motion_d:?}");
    assert_eq!(luma_d.over, 0, "lock luma differs: {luma_d:?}");
    // Exact: both push the input depth's f32 bits.
    assert!(
        differ.is_empty(),
        "reconstructed depths differ at {differ:?}"
    );
}

/// Accumulate's sizes: the shading-change mip (level 4 of AMD's half-size luminance chain)
/// needs a render size of 32 texels or more per mip texel: 4x3 here.
const ACC_RENDER: (u32, u32) = (128, 96);
const ACC_DISPLAY: (u32, u32) = (192, 144);
/// The luminance chain's level AMD samples (FFX_FSR2_SHADING_CHANGE_MIP_LEVEL) and its size.
const LUMA_LEVEL: u32 = 4;
const LUMA_MIP: (u32, u32) = (ACC_RENDER.0 / 32, ACC_RENDER.1 / 32);
/// The jitter phase count (`JitterSequenceLength`) and a frame index other than a reset.
const PHASES: f32 = 18.0;
const EXPOSURE: f32 = 0.7;

/// AMD's `RGBToYCoCg` (ffx_fsr2_common.h).
fn ycocg(c: [f32; 3]) -> [f32; 3] {
    [
        0.25 * c[0] + 0.5 * c[1] + 0.25 * c[2],
        0.5 * c[0] - 0.5 * c[2],
        -0.25 * c[0] + 0.5 * c[1] - 0.25 * c[2],
    ]
}

/// Accumulate's inputs, stored as AMD stores them and read by both sides from the same
/// textures: at the render size the prepared colour (YCoCg, depth clip in w; rgba16f), dilated
/// motion (rg16f) and reactive masks (rg8 unorm values, as bytes); the shading-change mip (r16f log
/// luma); at the display size the history (linear rgb and the signed temporal reactive factor;
/// rgba16f), lock status (lifetime, temporal luma; rg16f), luma history (rgba8 unorm values,
/// as bytes) and new locks (r8 unorm, as bytes).
struct AccumulateInputs {
    prepared: Vec<half::f16>,
    motion: Vec<half::f16>,
    reactive: Vec<u8>,
    luma_mip: Vec<half::f16>,
    history: Vec<half::f16>,
    lock_status: Vec<half::f16>,
    luma_history: Vec<u8>,
    new_locks: Vec<u8>,
}

/// The scene, in render-size uv: shaded background with a vertical step edge at u = 0.3, a
/// one-pixel bright line at render column 90 (thin feature: new locks), noise at the right; a
/// box (u 0.25-0.45, v 0.2-0.5) moving left 9.6 display pixels a frame (in motion: negative
/// temporal reactive factors), its trail uncovered (depth clip 0.3-1), the background panning
/// by 0.38 display pixels, a still patch, the left 6% moving off the screen (new samples), and
/// patches of reactive and accumulation masks.
fn accumulate_inputs() -> AccumulateInputs {
    let h16 = half::f16::from_f32;
    let colour = |u: f32, v: f32, k: u32| -> [f32; 3] {
        let mut c = [
            0.3 + 0.2 * (u * 9.0).sin(),
            0.35 + 0.15 * (v * 7.0).cos(),
            0.25 + 0.1 * ((u + v) * 5.0).sin(),
        ];
        if u > 0.3 {
            c = [c[0] * 3.0, c[1] * 2.5, c[2] * 2.0];
        }
        if (0.25..0.45).contains(&u) && (0.2..0.5).contains(&v) {
            c = [1.8, 0.4, 0.2];
        }
        if u > 0.8 {
            for (j, x) in (0..).zip(c.iter_mut()) {
                *x += 0.6 * noise(k, j);
            }
        }
        c
    };
    let box_at = |u: f32, v: f32| (0.25..0.45).contains(&u) && (0.2..0.5).contains(&v);
    let (rw, rh) = ACC_RENDER;
    let mut inp = AccumulateInputs {
        prepared: vec![],
        motion: vec![],
        reactive: vec![],
        luma_mip: vec![],
        history: vec![],
        lock_status: vec![],
        luma_history: vec![],
        new_locks: vec![],
    };
    for i in 0..rw * rh {
        let (x, y) = (i % rw, i / rw);
        let (u, v) = ((x as f32 + 0.5) / rw as f32, (y as f32 + 0.5) / rh as f32);
        let mut c = colour(u, v, i);
        if x == 90 {
            c = [2.5, 2.5, 2.2];
        }
        let p = ycocg(c.map(|x| (x * EXPOSURE).clamp(0.0, 65504.0)));
        // Depth clip: the box's trail (uncovered this frame), weaker at its edges; a little
        // below the lock threshold elsewhere in places.
        let clip = if (0.45..0.5).contains(&u) && (0.2..0.5).contains(&v) {
            0.3 + 0.7 * noise(i, 5)
        } else if x % 17 == 3 && y % 13 == 5 {
            0.05
        } else {
            0.0
        };
        inp.prepared.extend([p[0], p[1], p[2], clip].map(h16));
        let m = if box_at(u, v) {
            [-0.05, 0.0]
        } else if u < 0.06 {
            [-0.1, 0.002]
        } else if (0.6..0.7).contains(&u) && (0.6..0.7).contains(&v) {
            [0.0, 0.0]
        } else {
            [0.002, 0.001]
        };
        inp.motion.extend(m.map(h16));
        let reactive = if (0.75..0.85).contains(&u) && (0.1..0.3).contains(&v) {
            128
        } else {
            0
        };
        let accumulation = if (0.5..0.6).contains(&u) && (0.7..0.9).contains(&v) {
            (200.0 * noise(i, 6)) as u8
        } else {
            0
        };
        inp.reactive.extend([reactive, accumulation]);
    }
    for i in 0..LUMA_MIP.0 * LUMA_MIP.1 {
        // Log luma of the exposed scene's 32x32 blocks: one block brighter than the history's
        // temporal luma below (shading change: locks killed there).
        let l = if i == 5 {
            0.9f32
        } else {
            0.25 + 0.05 * i as f32
        };
        inp.luma_mip.push(h16(l.ln()));
    }
    let (dw, dh) = ACC_DISPLAY;
    for i in 0..dw * dh {
        let (x, y) = (i % dw, i / dw);
        let (u, v) = ((x as f32 + 0.5) / dw as f32, (y as f32 + 0.5) / dh as f32);
        // The previous frame: the box 9.6 display pixels to the right, a little noise.
        let mut c = colour(u - 0.002, v - 0.001, i);
        if box_at(u - 0.05, v) {
            c = [1.8, 0.4, 0.2];
        } else if box_at(u, v) {
            c = colour(u + 0.2, v, i);
        }
        if (x * 2 / 3) == 90 {
            c = [2.4, 2.6, 2.1];
        }
        let n = |k| 0.05 * noise(i, k) - 0.025;
        let reactive = if box_at(u - 0.05, v) {
            -0.3
        } else if x % 11 == 0 {
            0.9
        } else {
            0.05 + 0.1 * noise(i, 7)
        };
        inp.history
            .extend([c[0] + n(0), c[1] + n(1), c[2] + n(2), reactive].map(h16));
        // Locks on the thin line and scattered; temporal luma near the mip's, lower in places.
        let locked = (x * 2 / 3) == 90 || i % 23 == 0;
        let lifetime = if locked {
            1.5
        } else if i % 7 == 0 {
            0.6
        } else {
            0.0
        };
        let temporal = if i % 5 == 0 {
            0.0
        } else {
            0.8 + 0.05 * noise(i, 8)
        };
        inp.lock_status.extend([lifetime, temporal].map(h16));
        // Luma history: stable around 0.3 mostly, alternating in places (instability), the
        // oldest unset in places.
        let base = 70 + (30.0 * noise(i, 9)) as u8;
        let hist = if i % 3 == 0 {
            [base, base + 40, base, base + 40]
        } else if i % 29 == 0 {
            [base, base, base, 0]
        } else {
            [base, base + 1, base, base + 2]
        };
        inp.luma_history.extend(hist);
        inp.new_locks.push(if (x * 2 / 3) == 90 || i % 41 == 0 {
            255
        } else {
            0
        });
    }
    inp
}

/// AMD's constants for accumulate: `amd_constants` at its sizes, a frame that is not a reset
/// (`iFrameIndex` 5), the shading-change mip's size and level, the jitter phase count.
fn amd_accumulate_constants() -> Vec<u8> {
    let mut w = words(&amd_constants(ACC_RENDER, ACC_DISPLAY));
    w[8] = LUMA_MIP.0; // iLumaMipDimensions at 32
    w[9] = LUMA_MIP.1;
    w[10] = LUMA_LEVEL; // iLumaMipLevelToUse
    w[11] = 5; // iFrameIndex
    w[27] = PHASES.to_bits(); // fJitterSequenceLength at 108
    bytemuck::cast_slice(&w).to_vec()
}

/// The port's `Params` for accumulate: as `port_params`, with the phase count and the mip.
fn port_accumulate_params() -> Vec<u8> {
    let mut w = words(&port_params(ACC_RENDER, ACC_DISPLAY));
    w[7] = PHASES.to_bits(); // jitter.w
    w[16..20].copy_from_slice(&[LUMA_MIP.0, LUMA_MIP.1, LUMA_LEVEL, 0]); // luma
    bytemuck::cast_slice(&w).to_vec()
}

/// Little-endian words of `bytes`.
fn words(bytes: &[u8]) -> Vec<u32> {
    bytes
        .chunks_exact(4)
        .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect()
}

#[test]
fn accumulate_equals_amds_compiled_glsl() {
    let (device, queue) = device();
    use wgpu::TextureFormat::{
        R16Float, R32Float, R8Unorm, Rg16Float, Rg32Float, Rgba16Float, Rgba8Unorm,
    };
    let (sampled, storage) = (
        wgpu::TextureUsages::TEXTURE_BINDING,
        wgpu::TextureUsages::STORAGE_BINDING,
    );
    let inp = accumulate_inputs();
    let display_px = (ACC_DISPLAY.0 * ACC_DISPLAY.1) as usize;
    let low = |format, bytes: &[u8], texel| {
        texture_with(&device, &queue, ACC_RENDER, (format, sampled), bytes, texel)
    };
    let high = |format, bytes: &[u8], texel| {
        texture_with(
            &device,
            &queue,
            ACC_DISPLAY,
            (format, sampled),
            bytes,
            texel,
        )
    };
    // Shared by both sides, in AMD's formats (the port reads them with textureLoad), except the
    // two 8-bit textures AMD reads through its linear sampler, the reactive masks (rg8 unorm)
    // and the luma history (rgba8 unorm): they hold the same k/255 values in f16. Lavapipe
    // filters 8-bit unorm textures with coarser weights than f16 ones: in AMD's formats, with
    // the port's exact bilinear reads, 82 colour values and 112 lock statuses differed beyond
    // one f16 step (max 0.049 and 0.0027) at the reactive patch's edges and where the luma
    // history decides instability; the same values in f16 give none. That is the sampler's
    // precision (D3D asks for 8 fractional bits), not the pass's code.
    let prepared = low(Rgba16Float, bytemuck::cast_slice(&inp.prepared), 8);
    let motion = low(Rg16Float, bytemuck::cast_slice(&inp.motion), 4);
    let unorm_halves = |b: &[u8]| -> Vec<half::f16> {
        b.iter()
            .map(|v| half::f16::from_f32(f32::from(*v) / 255.0))
            .collect()
    };
    let reactive = low(
        Rg16Float,
        bytemuck::cast_slice(&unorm_halves(&inp.reactive)),
        4,
    );
    let history = high(Rgba16Float, bytemuck::cast_slice(&inp.history), 8);
    let lock_status = high(Rg16Float, bytemuck::cast_slice(&inp.lock_status), 4);
    let luma_history = high(
        Rgba16Float,
        bytemuck::cast_slice(&unorm_halves(&inp.luma_history)),
        8,
    );
    let exposure = [EXPOSURE, -1.0];

    // AMD's pass, its every binding (ffx_fsr2_accumulate_pass.glsl). The luminance chain: half
    // the render size with every mip (ffx_fsr2.cpp), the mip at LUMA_LEVEL filled (the pass
    // samples no other). The Lanczos and maximum-bias LUTs are declared but unread with
    // FFX_FSR2_OPTION_UPSAMPLE_USE_LANCZOS_TYPE 2. New locks read and cleared in place.
    let mips = device.create_texture(&wgpu::TextureDescriptor {
        label: Some("luminance chain"),
        size: wgpu::Extent3d {
            width: ACC_RENDER.0 / 2,
            height: ACC_RENDER.1 / 2,
            depth_or_array_layers: 1,
        },
        mip_level_count: LUMA_LEVEL + 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: R16Float,
        usage: sampled | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    });
    queue.write_texture(
        wgpu::TexelCopyTextureInfo {
            texture: &mips,
            mip_level: LUMA_LEVEL,
            origin: wgpu::Origin3d::ZERO,
            aspect: wgpu::TextureAspect::All,
        },
        bytemuck::cast_slice(&inp.luma_mip),
        wgpu::TexelCopyBufferLayout {
            offset: 0,
            bytes_per_row: Some(LUMA_MIP.0 * 2),
            rows_per_image: None,
        },
        wgpu::Extent3d {
            width: LUMA_MIP.0,
            height: LUMA_MIP.1,
            depth_or_array_layers: 1,
        },
    );
    let amd_exposure = texture_with(
        &device,
        &queue,
        (1, 1),
        (Rg32Float, sampled),
        bytemuck::cast_slice(&exposure),
        8,
    );
    let unread = low(
        R32Float,
        &vec![0u8; (ACC_RENDER.0 * ACC_RENDER.1 * 4) as usize],
        4,
    );
    let lut = low(
        R16Float,
        &vec![0u8; (ACC_RENDER.0 * ACC_RENDER.1 * 2) as usize],
        2,
    );
    let amd_colour = texture(&device, ACC_DISPLAY, Rgba16Float, storage);
    let amd_lock = texture(&device, ACC_DISPLAY, Rg16Float, storage);
    let amd_output = texture(&device, ACC_DISPLAY, Rgba16Float, storage);
    let amd_new_locks = texture_with(
        &device,
        &queue,
        ACC_DISPLAY,
        (R8Unorm, storage),
        &inp.new_locks,
        1,
    );
    let amd_luma = texture(&device, ACC_DISPLAY, Rgba8Unorm, storage);
    let cb = uniform(&device, &queue, &amd_accumulate_constants());
    let v = [
        &amd_exposure,
        &reactive,
        &motion,
        &history,
        &lock_status,
        &unread,
        &prepared,
        &lut,
        &mips,
        &luma_history,
        &amd_colour,
        &amd_lock,
        &amd_output,
        &amd_new_locks,
        &amd_luma,
    ]
    .map(view);
    let amd = amd_pass(
        &device,
        "ffx_fsr2_accumulate_pass",
        ACCUMULATE_SPV,
        (8, 8, 1),
        &[
            (0, Amd::Texture(&v[0])),
            (1, Amd::Filtered(&v[1])),
            (2, Amd::Texture(&v[2])),
            (3, Amd::Texture(&v[3])),
            (4, Amd::Filtered(&v[4])),
            // FSR2_BIND_SRV_INPUT_DEPTH_CLIP and FSR2_BIND_SRV_LUMA_INSTABILITY: declared by the
            // pass file, by no binding in the callbacks: the gaps closed as in depth clip.
            (5, Amd::Texture(&v[5])),
            (6, Amd::Filtered(&v[6])),
            (7, Amd::Texture(&v[5])),
            (8, Amd::Filtered(&v[7])),
            (9, Amd::Filtered(&v[7])),
            (10, Amd::Filtered(&v[8])),
            (11, Amd::Texture(&v[0])),
            (12, Amd::Filtered(&v[9])),
            (13, Amd::Image(&v[10], Rgba16Float)),
            (14, Amd::Image(&v[11], Rg16Float)),
            (15, Amd::Image(&v[12], Rgba16Float)),
            (16, Amd::Image(&v[13], R8Unorm)),
            (17, Amd::Image(&v[14], Rgba8Unorm)),
            (18, Amd::Uniform(&cb)),
        ],
    );

    // The port: the mip as its own texture, new locks as f32 in a storage buffer, its
    // outputs rgba16f.
    let port_mip = texture_with(
        &device,
        &queue,
        LUMA_MIP,
        (R16Float, sampled),
        bytemuck::cast_slice(&inp.luma_mip),
        2,
    );
    let locks: Vec<f32> = inp
        .new_locks
        .iter()
        .map(|b| f32::from(*b) / 255.0)
        .collect();
    let port_new_locks = storage_buffer(&device, &queue, bytemuck::cast_slice(&locks));
    let port_exposure = storage_buffer(&device, &queue, bytemuck::cast_slice(&exposure));
    let port_colour = texture(&device, ACC_DISPLAY, Rgba16Float, storage);
    let port_lock = texture(&device, ACC_DISPLAY, Rgba16Float, storage);
    let port_luma = texture(&device, ACC_DISPLAY, Rgba16Float, storage);
    let params = uniform(&device, &queue, &port_accumulate_params());
    let port = port_pass(
        &device,
        ACCUMULATE_WGSL,
        "accumulate",
        &[(0, &params), (8, &port_exposure), (9, &port_new_locks)],
        &[
            (1, &v[6]),
            (2, &v[2]),
            (3, &v[1]),
            (4, &v[3]),
            (5, &v[4]),
            (6, &v[9]),
            (7, &view(&port_mip)),
            (10, &view(&port_colour)),
            (11, &view(&port_lock)),
            (12, &view(&port_luma)),
        ],
    );
    let groups = (ACC_DISPLAY.0.div_ceil(8), ACC_DISPLAY.1.div_ceil(8));
    dispatch(&device, &queue, &[(&amd, groups), (&port, groups)]);

    // The accumulated colour and temporal reactive factor: both rgba16f.
    let (amd_c, port_c) = (
        read_f16(&device, &queue, &amd_colour),
        read_f16(&device, &queue, &port_colour),
    );
    let colour_d = diff(&amd_c, &port_c, f16_step);
    // Lock status: AMD's rg16f, the port's rgba16f (its first two).
    let amd_l: Vec<f32> =
        bytemuck::cast_slice::<u8, half::f16>(&read(&device, &queue, &amd_lock, 4))
            .iter()
            .map(|v| v.to_f32())
            .collect();
    let port_l: Vec<f32> = read_f16(&device, &queue, &port_lock)
        .chunks(4)
        .flat_map(|c| c[..2].to_vec())
        .collect();
    let lock_d = diff(&amd_l, &port_l, f16_step);
    // Luma history: AMD's rgba8 unorm, the port's rgba16f rounded to 8 bits as the store does.
    let amd_h: Vec<f32> = read(&device, &queue, &amd_luma, 4)
        .iter()
        .map(|b| f32::from(*b) / 255.0)
        .collect();
    let port_h: Vec<f32> = read_f16(&device, &queue, &port_luma)
        .iter()
        .map(|v| (v.clamp(0.0, 1.0) * 255.0).round() / 255.0)
        .collect();
    let luma_d = diff(&amd_h, &port_h, |_| 1.0 / 255.0 + 1e-6);
    // Both clear the new locks.
    let amd_cleared = read(&device, &queue, &amd_new_locks, 1)
        .iter()
        .all(|b| *b == 0);
    let port_cleared =
        bytemuck::cast_slice::<u8, f32>(&read_storage(&device, &queue, &port_new_locks))
            .iter()
            .all(|v| *v == 0.0);

    let history_in: Vec<f32> = inp.history.iter().map(|v| v.to_f32()).collect();
    let changed = (0..display_px)
        .filter(|&i| (0..3).any(|k| (amd_c[4 * i + k] - history_in[4 * i + k]).abs() > 0.01))
        .count();
    let locked = amd_l.iter().step_by(2).filter(|l| **l > 0.0).count();
    let where_ = |d: &Diff, per: usize| {
        (
            (d.at / per) as u32 % ACC_DISPLAY.0,
            (d.at / per) as u32 / ACC_DISPLAY.0,
        )
    };
    eprintln!(
        "accumulate: AMD's pass changes {changed} of {display_px} pixels' colour by more than 0.01, keeps {locked} locks; colour and reactive {colour_d:?} at {:?} (AMD {}, port {}); lock status {lock_d:?} at {:?} (AMD {}, port {}); luma history {luma_d:?} at {:?} (AMD {}, port {})",
        where_(&colour_d, 4), amd_c[colour_d.at], port_c[colour_d.at],
        where_(&lock_d, 2), amd_l[lock_d.at], port_l[lock_d.at],
        where_(&luma_d, 4), amd_h[luma_d.at], port_h[luma_d.at],
    );
    let mut shown = 0;
    for i in 0..amd_c.len() {
        if (amd_c[i] - port_c[i]).abs() > f16_step(amd_c[i]) && shown < 20 {
            shown += 1;
            eprintln!(
                "  colour {} differs at {:?}: AMD {}, port {}",
                i % 4,
                (
                    (i / 4) as u32 % ACC_DISPLAY.0,
                    (i / 4) as u32 / ACC_DISPLAY.0
                ),
                amd_c[i],
                port_c[i]
            );
        }
    }
    assert!(
        amd_cleared && port_cleared,
        "new locks left: AMD {amd_cleared}, port {port_cleared}"
    );
    assert!(
        changed > display_px / 4 && locked > 100,
        "the inputs exercise too little: {changed} changed, {locked} locked"
    );
    // One f16 step (colour, reactive factor, lock status: both store f16 after the same f32
    // arithmetic, which two compilers may round apart), one 8-bit step for the luma history
    // (AMD's rgba8 store against the port's f16 rounded to 8 bits).
    assert_eq!(colour_d.over, 0, "colour differs: {colour_d:?}");
    assert_eq!(lock_d.over, 0, "lock status differs: {lock_d:?}");
    assert_eq!(luma_d.over, 0, "luma history differs: {luma_d:?}");
}

/// A render-size frame like a recorded one, at any size (uv in [0, 1], y down; linear HDR,
/// rgba16f, 4 values per pixel): a sky brightening towards the horizon with an HDR sun (40),
/// a building lit on one face with dark and lit (HDR) windows, a black shadow (luma below
/// AMD's 1e-3 floor), a one-pixel bright cable, textured ground with a road and its stripes,
/// sensor-like noise everywhere. Edges and one-pixel features are where a sub-pixel shift of
/// the reads (SPD's jittered bilinear colour) moves a block's mean.
fn frame_colour((w, h): (u32, u32)) -> Vec<half::f16> {
    (0..w * h)
        .flat_map(|i| {
            let (x, y) = (i % w, i / w);
            let (u, v) = ((x as f32 + 0.5) / w as f32, (y as f32 + 0.5) / h as f32);
            let n = |k| noise(i, k);
            let mut c = if v < 0.45 {
                let t = v / 0.45;
                [0.6 + 0.5 * t, 0.8 + 0.25 * t, 1.4 - 0.3 * t]
            } else {
                let g = 0.6 + 0.8 * n(3);
                let mut c = [0.08 * g, 0.1 * g, 0.05 * g];
                if (0.45..0.7).contains(&(u - 0.3 * (v - 0.45))) {
                    c = [0.12, 0.12, 0.13];
                    if (0.56..0.58).contains(&(u - 0.3 * (v - 0.45))) && (y / 3) % 3 == 0 {
                        c = [0.9, 0.85, 0.7];
                    }
                }
                c
            };
            let (du, dv) = ((u - 0.78) * w as f32 / h as f32, v - 0.14);
            if du * du + dv * dv < 0.0016 {
                c = [40.0, 36.0, 30.0];
            }
            if (0.1..0.34).contains(&u) && (0.18..0.72).contains(&v) {
                c = if u < 0.26 {
                    [0.5, 0.45, 0.4]
                } else {
                    [0.15, 0.14, 0.14]
                };
                if x % 6 < 3 && y % 8 < 4 && v < 0.65 {
                    c = if (x / 6 + y / 8) % 3 == 0 {
                        [2.5, 2.0, 1.2]
                    } else {
                        [0.02, 0.02, 0.03]
                    };
                }
            }
            if (0.34..0.5).contains(&u) && (0.62..0.72).contains(&v) {
                c = [0.0; 3];
            }
            if y == h / 3 && u > 0.34 {
                c = [3.0, 3.0, 2.8];
            }
            for (k, x) in (0..).zip(c.iter_mut()) {
                *x *= 0.95 + 0.1 * n(k);
            }
            [c[0], c[1], c[2], 1.0].map(half::f16::from_f32)
        })
        .collect()
}

/// SPD's mip count for the render size (ffx_spd.h `SpdSetup`, as ffx_fsr2.cpp calls it):
/// floor(log2(max(w, h))), at most 12. Its last level (`MipCount() - 1`) is the one whose
/// texel (0, 0) AMD takes as the 1x1 average.
fn spd_mips((w, h): (u32, u32)) -> u32 {
    ((w.max(h) as f32).log2().floor() as u32).min(12)
}

/// Level `level` of AMD's luminance chain (`FSR2_ExposureMips`: half the render size, every
/// level down to 1x1): level 4 the shading-change mip, level 5 the one SPD's last workgroup
/// reads back.
fn spd_level((w, h): (u32, u32), level: u32) -> (u32, u32) {
    (((w / 2) >> level).max(1), ((h / 2) >> level).max(1))
}

/// What one side of the luminance pyramid gave: the shading-change mip (level 4), AMD's level 5
/// (empty for the port), the exposure buffer (exposure, average log luma) and AMD's atomic
/// counter after the dispatch.
struct Luminance {
    mip: Vec<f32>,
    mip5: Vec<f32>,
    exposure: [f32; 2],
    counter: u32,
}

/// One frame of the luminance pyramid: its render size, `Jitter()`, the exposure buffer it
/// starts from (average log luma 1e8 and above: a reset, no smoothing) and `DeltaTime()`.
#[derive(Clone, Copy)]
struct LumaFrame {
    size: (u32, u32),
    jitter: [f32; 2],
    previous: [f32; 2],
    dt: f32,
}

/// AMD's compute luminance pyramid pass (ffx_fsr2_compute_luminance_pyramid_pass.glsl:
/// `SpdDownsample` over 64x64 render pixels per workgroup of 256) on `colour`, every binding
/// its pass file declares bound: the atomic counter (r32ui, zeroed as AMD creates it), levels 4
/// and 5 of the chain (r16f, at AMD's sizes: level 5's size is what its last workgroup reads
/// as zero beyond), the auto exposure (rg32f), `cbFSR2` and `cbSPD` as `fsr2Dispatch` fills
/// them.
fn amd_luminance(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    colour: &wgpu::TextureView,
    f: LumaFrame,
) -> Luminance {
    use wgpu::TextureFormat::{R16Float, R32Uint, Rg32Float};
    let storage = wgpu::TextureUsages::STORAGE_BINDING;
    let (m4, m5) = (spd_level(f.size, 4), spd_level(f.size, 5));
    let counter = texture_with(device, queue, (1, 1), (R32Uint, storage), &[0; 4], 4);
    let zeros = |(w, h): (u32, u32)| vec![0u8; (w * h * 2) as usize];
    let mip = texture_with(device, queue, m4, (R16Float, storage), &zeros(m4), 2);
    let mip5 = texture_with(device, queue, m5, (R16Float, storage), &zeros(m5), 2);
    let exposure = texture_with(
        device,
        queue,
        (1, 1),
        (Rg32Float, storage),
        bytemuck::cast_slice(&f.previous),
        8,
    );
    let mut w = words(&amd_constants(f.size, f.size));
    w[8] = m4.0; // iLumaMipDimensions: maxRenderSize / 32
    w[9] = m4.1;
    w[10] = 4; // iLumaMipLevelToUse (FFX_FSR2_SHADING_CHANGE_MIP_LEVEL)
    w[11] = u32::from(f.previous[1] < 1e8); // iFrameIndex: 0 on a reset
    w[16] = f.jitter[0].to_bits(); // fJitter
    w[17] = f.jitter[1].to_bits();
    w[28] = f.dt.to_bits(); // fDeltaTime at 112
    let cb = uniform(device, queue, bytemuck::cast_slice(&w));
    // cbSPD: mips, numWorkGroups, workGroupOffset, renderSize (SpdSetup over the render rect).
    let groups = (f.size.0.div_ceil(64), f.size.1.div_ceil(64));
    let spd = [
        spd_mips(f.size),
        groups.0 * groups.1,
        0,
        0,
        f.size.0,
        f.size.1,
        0,
        0,
    ];
    let spd = uniform(device, queue, bytemuck::cast_slice(&spd));
    let v = [&counter, &mip, &mip5, &exposure].map(view);
    let amd = amd_pass(
        device,
        "ffx_fsr2_compute_luminance_pyramid_pass",
        LUMINANCE_SPV,
        (256, 1, 1),
        &[
            (0, Amd::Filtered(colour)),
            (1, Amd::Image(&v[0], R32Uint)),
            (2, Amd::Image(&v[1], R16Float)),
            (3, Amd::Image(&v[2], R16Float)),
            (4, Amd::Image(&v[3], Rg32Float)),
            (5, Amd::Uniform(&cb)),
            (6, Amd::Uniform(&spd)),
        ],
    );
    dispatch(device, queue, &[(&amd, groups)]);
    let halves = |t: &wgpu::Texture| -> Vec<f32> {
        bytemuck::cast_slice::<u8, half::f16>(&read(device, queue, t, 2))
            .iter()
            .map(|v| v.to_f32())
            .collect()
    };
    let e: Vec<f32> = bytemuck::cast_slice(&read(device, queue, &exposure, 8)).to_vec();
    Luminance {
        mip: halves(&mip),
        mip5: halves(&mip5),
        exposure: [e[0], e[1]],
        counter: bytemuck::cast_slice::<u8, u32>(&read(device, queue, &counter, 4))[0],
    }
}

/// The port's `luminance_pyramid` (one 8x8 workgroup per texel of the shading-change mip, r32f)
/// then `auto_exposure` (one workgroup) on `colour`, with the exposure buffer starting from
/// `f.previous` (a reset frame where AMD's would be: `mode.x` 1).
fn port_luminance(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    colour: &wgpu::TextureView,
    f: LumaFrame,
) -> Luminance {
    let m4 = tessera::techniques::fsr2::gpu::luma_mip_size(f.size);
    let mip = texture(
        device,
        m4,
        wgpu::TextureFormat::R32Float,
        wgpu::TextureUsages::STORAGE_BINDING | wgpu::TextureUsages::TEXTURE_BINDING,
    );
    let exposure = storage_buffer(device, queue, bytemuck::cast_slice(&f.previous));
    let mut w = words(&port_params(f.size, f.size));
    w[4] = f.jitter[0].to_bits();
    w[5] = f.jitter[1].to_bits();
    w[6] = f.dt.to_bits(); // jitter.z: DeltaTime
    w[12] = u32::from(f.previous[1] >= 1e8); // mode.x: a reset frame
    w[16..20].copy_from_slice(&[m4.0, m4.1, 4, 0]); // luma
    let params = uniform(device, queue, bytemuck::cast_slice(&w));
    let mv = view(&mip);
    let pyramid = port_pass(
        device,
        LUMINANCE_WGSL,
        "luminance_pyramid",
        &[(0, &params)],
        &[(1, colour), (2, &mv)],
    );
    let auto = port_pass(
        device,
        LUMINANCE_WGSL,
        "auto_exposure",
        &[(0, &params), (4, &exposure)],
        &[(3, &mv)],
    );
    dispatch(device, queue, &[(&pyramid, m4), (&auto, (1, 1))]);
    let e: Vec<f32> = bytemuck::cast_slice(&read_storage(device, queue, &exposure)).to_vec();
    Luminance {
        mip: bytemuck::cast_slice(&read(device, queue, &mip, 4)).to_vec(),
        mip5: vec![],
        exposure: [e[0], e[1]],
        counter: 0,
    }
}

/// `RGBToLuma`'s log as SPD's source load takes it: log(max(1e-3, luma)).
fn log_luma(c: [f32; 3]) -> f64 {
    f64::from((0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]).max(1e-3)).ln()
}

/// The two stated deviations of the port from AMD's pass, computed on the CPU from the input
/// alone (f64 sums of f32 log lumas): per texel of the shading-change mip, the mean of the log
/// luma SPD reads (`SpdLoadSourceImage`: the colour bilinear at (p + 0.5 + Jitter()), clamped
/// half a texel inside the image by `ClampUv`) minus the mean of the pixels' own (the port's);
/// for the 1x1 average, AMD's (the mean over the 2^mips square from the origin of those reads,
/// zero for a pixel off the image or, once the last workgroup takes over at 7 mips and more,
/// in no texel of level 5: AMD's imageLoad beyond level 5's size reads zero) minus the port's
/// (the mean of its mip: the whole 32x32 blocks, the rest of the image left out). Zero jitter
/// on a power-of-two square makes both zero.
struct LumaDeviation {
    mip: Vec<f64>,
    lavg: f64,
}

fn luma_deviation(colour: &[half::f16], f: LumaFrame) -> LumaDeviation {
    let (w, h) = (f.size.0 as i32, f.size.1 as i32);
    let rgb = |x: i32, y: i32| -> [f32; 3] {
        let i = 4 * (y.clamp(0, h - 1) * w + x.clamp(0, w - 1)) as usize;
        [0, 1, 2].map(|k| colour[i + k].to_f32())
    };
    let own = |x: i32, y: i32| log_luma(rgb(x, y));
    let spd_read = |x: i32, y: i32| -> f64 {
        // ClampUv, then the sampler's texel space (clamp-to-edge addressing).
        let s = [
            (x as f32 + 0.5 + f.jitter[0]).clamp(0.5, w as f32 - 0.5) - 0.5,
            (y as f32 + 0.5 + f.jitter[1]).clamp(0.5, h as f32 - 0.5) - 0.5,
        ];
        let (x0, y0) = (s[0].floor(), s[1].floor());
        let (fx, fy) = (s[0] - x0, s[1] - y0);
        let (x0, y0) = (x0 as i32, y0 as i32);
        let (a, b, c, d) = (
            rgb(x0, y0),
            rgb(x0 + 1, y0),
            rgb(x0, y0 + 1),
            rgb(x0 + 1, y0 + 1),
        );
        log_luma([0, 1, 2].map(|k| {
            (a[k] * (1.0 - fx) + b[k] * fx) * (1.0 - fy) + (c[k] * (1.0 - fx) + d[k] * fx) * fy
        }))
    };
    let (mw, mh) = spd_level(f.size, 4);
    let block = |x0: i32, y0: i32, side: i32, g: &dyn Fn(i32, i32) -> f64| -> f64 {
        let mut s = 0.0;
        for y in y0..y0 + side {
            for x in x0..x0 + side {
                if x < w && y < h {
                    s += g(x, y);
                }
            }
        }
        s
    };
    let mut mip = vec![];
    let mut port_sum = 0.0;
    for ty in 0..mh as i32 {
        for tx in 0..mw as i32 {
            let own_sum = block(32 * tx, 32 * ty, 32, &own);
            port_sum += own_sum;
            mip.push((block(32 * tx, 32 * ty, 32, &spd_read) - own_sum) / 1024.0);
        }
    }
    let mips = spd_mips(f.size);
    let side = 1i32 << mips;
    let amd_sum = if mips <= 6 {
        block(0, 0, side, &spd_read)
    } else {
        let (m5w, m5h) = spd_level(f.size, 5);
        let n = 1i32 << (mips - 6);
        let mut s = 0.0;
        for ty in 0..n.min(m5h as i32) {
            for tx in 0..n.min(m5w as i32) {
                s += block(64 * tx, 64 * ty, 64, &spd_read);
            }
        }
        s
    };
    LumaDeviation {
        mip,
        lavg: amd_sum / f64::from(side * side) - port_sum / f64::from(mw * mh * 1024),
    }
}

/// How one frame compares: the shading-change mip (AMD's r16f against the port's f32 plus the
/// modelled deviation, one f16 step of AMD's value each; `raw_mip` without the deviation) and
/// the 1x1 level: the average log luma (absolute) and the exposure (relative) against theirs
/// (`raw_` without the deviation).
#[derive(Debug)]
struct LumaCompare {
    mip: Diff,
    raw_mip: Diff,
    lavg: f32,
    raw_lavg: f32,
    lavg_tolerance: f32,
    exposure: f32,
    raw_exposure: f32,
    exposure_tolerance: f32,
}

/// AMD's outputs against the port's plus `dev` (the stated deviations; smoothed by the same
/// temporal factor as the average is on a frame that is not a reset).
fn compare_luminance(
    amd: &Luminance,
    port: &Luminance,
    dev: &LumaDeviation,
    f: LumaFrame,
) -> LumaCompare {
    let expected: Vec<f32> = port
        .mip
        .iter()
        .zip(&dev.mip)
        .map(|(p, d)| (f64::from(*p) + d) as f32)
        .collect();
    // One f16 step: AMD stores the level in r16f (lavapipe's store rounds towards zero: up to
    // one step from its f32, always towards zero); the f32 sums of two orders (SPD's 2x2 tree;
    // 4x4 parts then a tree) and the model's f64 are far below it.
    let mip = diff(&amd.mip, &expected, f16_step);
    let raw_mip = diff(&amd.mip, &port.mip, f16_step);
    // The 1x1 level: with 7 mips or more AMD's last workgroup averages level 5's r16f texels
    // (one f16 step of the largest of them: lavapipe's store rounds every one towards zero, so
    // their errors do not cancel), plus the f32 rounding of two sums of up to 2^16 values in
    // different orders (1e-5). The exposure is 0.65 x 12.5 / 78 x exp(-lavg),
    // so its relative error is the average's, plus exp/log2/pow in f32 (1e-5).
    let largest5 = amd.mip5.iter().fold(0f32, |m, v| m.max(v.abs()));
    let tolerance = if spd_mips(f.size) >= 7 {
        f16_step(largest5) + 1e-5
    } else {
        1e-5
    };
    let k = if f.previous[1] < 1e8 {
        1.0 - (-f64::from(f.dt)).exp()
    } else {
        1.0
    };
    let lavg_expected = f64::from(port.exposure[1]) + k * dev.lavg;
    let lavg = (f64::from(amd.exposure[1]) - lavg_expected).abs() as f32;
    let raw_lavg = (amd.exposure[1] - port.exposure[1]).abs();
    let raw_exposure = (amd.exposure[0] / port.exposure[0] - 1.0).abs();
    let exposure_expected = f64::from(port.exposure[0]) * (-k * dev.lavg).exp();
    let exposure = (f64::from(amd.exposure[0]) / exposure_expected - 1.0).abs() as f32;
    LumaCompare {
        mip,
        raw_mip,
        lavg,
        raw_lavg,
        lavg_tolerance: tolerance,
        exposure,
        raw_exposure,
        exposure_tolerance: tolerance + 1e-5,
    }
}

/// Runs both sides on `frame`'s colour (and the port on it 2% brighter) and checks them:
/// returns the comparison, the perturbed one and AMD's outputs.
fn luminance_case(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    f: LumaFrame,
) -> (LumaCompare, LumaCompare, Luminance, LumaDeviation) {
    let colour = frame_colour(f.size);
    let input = |c: &[half::f16]| {
        texture_with(
            device,
            queue,
            f.size,
            (
                wgpu::TextureFormat::Rgba16Float,
                wgpu::TextureUsages::TEXTURE_BINDING,
            ),
            bytemuck::cast_slice(c),
            8,
        )
    };
    let brighter: Vec<half::f16> = colour
        .chunks(4)
        .flat_map(|c| {
            [c[0], c[1], c[2]]
                .map(|v| half::f16::from_f32(v.to_f32() * 1.02))
                .into_iter()
                .chain([c[3]])
        })
        .collect();
    let (cv, bv) = (view(&input(&colour)), view(&input(&brighter)));
    let amd = amd_luminance(device, queue, &cv, f);
    let port = port_luminance(device, queue, &cv, f);
    let perturbed = port_luminance(device, queue, &bv, f);
    let dev = luma_deviation(&colour, f);
    let c = compare_luminance(&amd, &port, &dev, f);
    let p = compare_luminance(&amd, &perturbed, &dev, f);
    let max_dev = dev.mip.iter().fold(0f64, |m, d| m.max(d.abs()));
    eprintln!(
        "luminance_pyramid {}x{} jitter {:?}{}: {} mip texels, {} SPD mips; modelled deviation: mip max {max_dev:.3e}, average log luma {:.4e}; AMD average {} exposure {} (port {} / {}); |AMD - port| mip {:?}, average {:.3e}, exposure relative {:.3e}; after the deviation mip {:?}, average {:.3e} (tolerance {:.3e}), exposure relative {:.3e} (tolerance {:.3e}); the port's colour 2% brighter: mip {} of {} beyond, max {:.3e}, average {:.3e}, exposure {:.3e}",
        f.size.0,
        f.size.1,
        f.jitter,
        if f.previous[1] < 1e8 { format!(", smoothed from {} over {} s", f.previous[1], f.dt) } else { String::new() },
        amd.mip.len(),
        spd_mips(f.size),
        dev.lavg,
        amd.exposure[1],
        amd.exposure[0],
        port.exposure[1],
        port.exposure[0],
        c.raw_mip,
        c.raw_lavg,
        c.raw_exposure,
        c.mip,
        c.lavg,
        c.lavg_tolerance,
        c.exposure,
        c.exposure_tolerance,
        p.mip.over,
        amd.mip.len(),
        p.mip.max,
        p.lavg,
        p.exposure,
    );
    (c, p, amd, dev)
}

/// Checks common to every frame: AMD's pass ran to its 1x1 level (the exposure written; with 7
/// mips and more the last workgroup, found by the atomic counter, reset it to 0), the
/// comparison holds, and fails with the port's input 2% brighter.
fn check_luminance(f: LumaFrame, c: &LumaCompare, p: &LumaCompare, amd: &Luminance) {
    assert!(
        amd.exposure[0] > 0.0 && amd.exposure[0] != -1.0 && amd.exposure[1].abs() < 10.0,
        "AMD's pass wrote no exposure: {:?}",
        amd.exposure
    );
    assert_eq!(
        amd.counter, 0,
        "AMD's last workgroup did not reset the counter"
    );
    assert!(
        spd_mips(f.size) < 7 || amd.mip5.iter().any(|v| *v != 0.0),
        "AMD's level 5 is empty"
    );
    assert_eq!(
        c.mip.over, 0,
        "shading-change mip differs beyond one f16 step: {c:?}"
    );
    assert!(
        c.lavg <= c.lavg_tolerance,
        "average log luma differs: {c:?}"
    );
    assert!(
        c.exposure <= c.exposure_tolerance,
        "exposure differs: {c:?}"
    );
    // The test sees a luma 2% off (log luma 0.0198) in every output.
    assert!(
        p.mip.over > 0 && p.lavg > p.lavg_tolerance && p.exposure > p.exposure_tolerance,
        "the port's colour 2% brighter passes: {p:?}"
    );
}

#[test]
fn luminance_pyramid_equals_amds_compiled_glsl() {
    let (device, queue) = device();
    // Where the port's deviations vanish: no jitter (SPD's bilinear read at p + 0.5 is the
    // pixel's own value) on power-of-two squares (SPD's 2^mips square is the image, every
    // 32x32 block whole): 128x128 (7 mips: 4 workgroups, the last one found by the atomic
    // counter takes level 5's 2x2 to the 1x1 at level 6) and 256x256 (8 mips: 16 workgroups,
    // level 5's 4x4 through levels 6 and 7), a reset frame each; then 256x256 smoothed from an
    // earlier average over 0.25 s (`ComputeAutoExposureFromLavg` on
    // prev + (lavg - prev)(1 - exp(-dt))).
    let reset = [1.0, 1e9];
    for f in [
        LumaFrame {
            size: (128, 128),
            jitter: [0.0; 2],
            previous: reset,
            dt: 1.0 / 60.0,
        },
        LumaFrame {
            size: (256, 256),
            jitter: [0.0; 2],
            previous: reset,
            dt: 1.0 / 60.0,
        },
        LumaFrame {
            size: (256, 256),
            jitter: [0.0; 2],
            previous: [0.5, -0.4],
            dt: 0.25,
        },
    ] {
        let (c, p, amd, dev) = luminance_case(&device, &queue, f);
        // The deviation vanishes: the comparison is AMD's against the port's as they are.
        assert!(
            dev.lavg.abs() < 1e-9 && dev.mip.iter().all(|d| *d == 0.0),
            "a deviation remains: {}",
            dev.lavg
        );
        check_luminance(f, &c, &p, &amd);
    }
}

#[test]
fn luminance_pyramid_departs_from_amds_only_as_stated() {
    let (device, queue) = device();
    // Where they do not: 384x224 (whole 32x32 blocks, 8 mips: AMD's 1x1 is the 256x256 square
    // from the origin, a quarter of it below level 5's 3 rows and read as zero, the right 128
    // columns left out; the port's is the whole image) and 426x240 (AMD's Ultra Performance
    // render size for 1280x720; not a multiple of 32: AMD's mip and the port's both leave the
    // last 10 columns and 16 rows out, AMD's 1x1 the same square as 384x224), each with no
    // jitter (only the 1x1 region deviates) and with jitter (SPD's bilinear reads shift every
    // block by a fraction of a pixel).
    let reset = [1.0, 1e9];
    for size in [(384, 224), (426, 240)] {
        for jitter in [[0.0; 2], JITTER] {
            let f = LumaFrame {
                size,
                jitter,
                previous: reset,
                dt: 1.0 / 60.0,
            };
            let (c, p, amd, dev) = luminance_case(&device, &queue, f);
            assert!(dev.lavg.abs() > 0.01, "the 1x1 region deviates too little");
            assert!(
                jitter == [0.0; 2] || dev.mip.iter().any(|d| d.abs() > 1e-3),
                "the jitter moves no block"
            );
            check_luminance(f, &c, &p, &amd);
        }
    }
}

/// The adapter's bilinear filter weights, as AMD's passes get them through their linear
/// sampler and the port does not (it filters with exact weights from `textureLoad`): an
/// `rgba16float` 2x1 texture holding 0 and 1 sampled at 1,024 positions between the texel
/// centres returns the weight itself. D3D asks for at least 8 fractional bits; where an adapter
/// quantises to them, AMD's filtered reads (luma history, reactive masks, the SPD pass's
/// jittered reads) depart from exact ones by up to 1/512 of the neighbours' difference, and a
/// pass decision near its threshold can go the other way. Prints how many distinct weights the
/// adapter gives and their largest departure; asserts they rise with the position and stay
/// within D3D's bound.
#[test]
fn the_adapters_filter_weights_are_measured() {
    let (device, queue) = device();
    const N: u32 = 1024;
    let texels = [0.0f32, 0.0, 0.0, 1.0, 1.0, 1.0, 1.0, 1.0].map(half::f16::from_f32);
    let source = texture_with(
        &device,
        &queue,
        (2, 1),
        (
            wgpu::TextureFormat::Rgba16Float,
            wgpu::TextureUsages::TEXTURE_BINDING,
        ),
        bytemuck::cast_slice(&texels),
        8,
    );
    let out = storage_buffer(&device, &queue, &vec![0u8; N as usize * 4]);
    let shader = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("filter weights"),
        source: wgpu::ShaderSource::Wgsl(
            "@group(0) @binding(0) var src: texture_2d<f32>;
             @group(0) @binding(1) var lin: sampler;
             @group(0) @binding(2) var<storage, read_write> out: array<f32>;
             @compute @workgroup_size(64)
             fn main(@builtin(global_invocation_id) id: vec3<u32>) {
                 let t = f32(id.x) / 1024.0;
                 out[id.x] = textureSampleLevel(src, lin, vec2<f32>((0.5 + t) / 2.0, 0.5), 0.0).r;
             }"
            .into(),
        ),
    });
    let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: None,
        layout: None,
        module: &shader,
        entry_point: Some("main"),
        compilation_options: Default::default(),
        cache: None,
    });
    let linear = device.create_sampler(&wgpu::SamplerDescriptor {
        mag_filter: wgpu::FilterMode::Linear,
        min_filter: wgpu::FilterMode::Linear,
        ..Default::default()
    });
    let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout: &pipeline.get_bind_group_layout(0),
        entries: &[
            wgpu::BindGroupEntry {
                binding: 0,
                resource: wgpu::BindingResource::TextureView(&view(&source)),
            },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: wgpu::BindingResource::Sampler(&linear),
            },
            wgpu::BindGroupEntry {
                binding: 2,
                resource: out.as_entire_binding(),
            },
        ],
    });
    let mut enc = device.create_command_encoder(&Default::default());
    {
        let mut pass = enc.begin_compute_pass(&Default::default());
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &group, &[]);
        pass.dispatch_workgroups(N / 64, 1, 1);
    }
    queue.submit([enc.finish()]);
    let weights: Vec<f32> = bytemuck::cast_slice(&read_storage(&device, &queue, &out)).to_vec();
    let mut distinct = weights.clone();
    distinct.dedup();
    let (worst, at) = weights
        .iter()
        .enumerate()
        .map(|(i, w)| ((w - i as f32 / N as f32).abs(), i))
        .fold((0.0f32, 0), |a, b| if b.0 > a.0 { b } else { a });
    eprintln!(
        "filter weights: {} distinct over {N} positions between two texel centres; largest \
         departure from the exact weight {worst:.6} at {at}/{N} (8 fractional bits: 256 weights, \
         departures up to 1/512 = {:.6})",
        distinct.len(),
        1.0 / 512.0
    );
    assert!(
        weights.windows(2).all(|w| w[1] >= w[0]),
        "the weights fall somewhere: {weights:?}"
    );
    // D3D's 8 fractional bits: a weight within one 256th (and the f16 texel's own rounding).
    assert!(
        worst <= 1.0 / 256.0 + 1e-3,
        "a weight departs by {worst} at {at}"
    );
}
