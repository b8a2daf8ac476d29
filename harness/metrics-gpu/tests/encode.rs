//! A rendered float texture becomes a `GpuFrame` on the device: its 8-bit form must equal
//! `tessera_metrics::encode_srgb8` of the floats, for every f16 value (NaN, infinities,
//! subnormals and negatives included), and its floats must be the texture's.

use tessera_metrics::HdrImage;
use tessera_metrics_gpu::GpuMetrics;
use wgpu::util::DeviceExt;

#[test]
fn every_f16_value_encodes_as_the_cpu_encodes_it() {
    let wanted = std::env::var("TESSERA_METRICS_ADAPTER").ok();
    let adapter = tessera_metrics_gpu::select_adapter(wanted.as_deref())
        .expect("no GPU adapter: run ci/setup.sh to install lavapipe");
    let name = adapter.get_info().name;
    let d = tessera_metrics_gpu::open(adapter).unwrap();
    let mut gpu = GpuMetrics::new(&d.device, &d.queue, &name);
    // 256x256 pixels: R holds f16 bit pattern i, G and B two permutations of it.
    let (w, h) = (256u32, 256u32);
    let mut halves = Vec::with_capacity((w * h * 4) as usize);
    for i in 0..(w * h) {
        for bits in [i, i ^ 0x5555, (i.wrapping_mul(40503)) & 0xffff] {
            halves.push(half_bits(bits as u16));
        }
        halves.push(half_bits(0x3c00)); // alpha 1.0
    }
    let texture = d.device.create_texture_with_data(
        &d.queue,
        &wgpu::TextureDescriptor {
            label: Some("f16 values"),
            size: wgpu::Extent3d {
                width: w,
                height: h,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::Rgba16Float,
            usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
            view_formats: &[],
        },
        wgpu::util::TextureDataOrder::LayerMajor,
        bytemuck::cast_slice(&halves),
    );
    let frame = gpu.frame_from_texture(&texture).unwrap();
    let ldr = gpu.read_ldr(&frame).unwrap();
    let floats = HdrImage {
        width: w,
        height: h,
        data: halves
            .chunks_exact(4)
            .flat_map(|p| [f16_to_f32(p[0]), f16_to_f32(p[1]), f16_to_f32(p[2])])
            .collect(),
    };
    let cpu = tessera_metrics::encode_srgb8(&floats);
    let mismatches: Vec<(f32, u8, u8)> = floats
        .data
        .iter()
        .zip(cpu.data.iter().zip(&ldr.data))
        .filter(|(_, (c, g))| c != g)
        .map(|(v, (c, g))| (*v, *c, *g))
        .take(10)
        .collect();
    assert!(mismatches.is_empty(), "value, cpu, gpu: {mismatches:?}");
    // The frame then behaves as the uploaded CPU image does.
    let uploaded = gpu.upload(&cpu, None).unwrap();
    let req = tessera_metrics_gpu::PairRequest {
        mse_rgb: true,
        max_abs: true,
        ..Default::default()
    };
    let v = gpu.evaluate(&frame, &uploaded, &req).unwrap();
    assert_eq!((v.mse_rgb, v.max_abs), (Some(0.0), Some(0)));
    // A texture format the pass cannot read is an error, not a panic.
    let bad = d.device.create_texture(&wgpu::TextureDescriptor {
        label: None,
        size: wgpu::Extent3d {
            width: 4,
            height: 4,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::Rgba8Unorm,
        usage: wgpu::TextureUsages::TEXTURE_BINDING,
        view_formats: &[],
    });
    assert!(gpu.frame_from_texture(&bad).is_err());
}

fn half_bits(b: u16) -> u16 {
    b
}

/// IEEE binary16 to f32 (exact).
fn f16_to_f32(h: u16) -> f32 {
    let sign = if h & 0x8000 != 0 { -1.0f32 } else { 1.0 };
    let exp = ((h >> 10) & 0x1f) as i32;
    let mant = (h & 0x3ff) as f32;
    match exp {
        0 => sign * mant * 2f32.powi(-24),
        31 => {
            if mant == 0.0 {
                sign * f32::INFINITY
            } else {
                f32::NAN
            }
        }
        e => sign * (1.0 + mant / 1024.0) * 2f32.powi(e - 15),
    }
}
