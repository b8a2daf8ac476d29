//! Frames that stay on the device: FLIP's flip-evaluator mean summed on the device must be the
//! CPU's running mean bit for bit, and a sequence of frames made from float textures
//! (`frame_from_texture_with`, never read back) must give exactly the values of the same frames
//! encoded on the CPU and uploaded.

use tessera_metrics::{hdr_exposure_range, HdrImage, Rgb8Image, DEFAULT_PIXELS_PER_DEGREE};
use tessera_metrics_gpu::{
    FlipHdrRequest, FlipPooling, FlipRequest, GpuMetrics, MetricsBackend, Pair, PairRequest,
    Sequence,
};
use wgpu::util::DeviceExt;

fn open() -> (GpuMetrics, wgpu::Device, wgpu::Queue) {
    let wanted = std::env::var("TESSERA_METRICS_ADAPTER").ok();
    let adapter = tessera_metrics_gpu::select_adapter(wanted.as_deref())
        .expect("no GPU adapter: run ci/setup.sh to install lavapipe");
    let name = adapter.get_info().name;
    let d = tessera_metrics_gpu::open(adapter).unwrap();
    let gpu = GpuMetrics::new(&d.device, &d.queue, &name);
    (gpu, d.device.clone(), d.queue.clone())
}

struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u32 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 33) as u32
    }
}

fn noisy_pair(w: u32, h: u32, seed: u64, amplitude: u32) -> (Rgb8Image, Rgb8Image) {
    let mut rng = Rng(seed);
    let n = (w * h * 3) as usize;
    let r: Vec<u8> = (0..n)
        .map(|i| ((i as u32 / 3 % w) * 255 / w.max(1)) as u8 ^ (rng.next() as u8 & 0x0f))
        .collect();
    let t: Vec<u8> = r
        .iter()
        .map(|&v| {
            let d = (rng.next() % (2 * amplitude + 1)) as i32 - amplitude as i32;
            (v as i32 + d).clamp(0, 255) as u8
        })
        .collect();
    let img = |data| Rgb8Image {
        width: w,
        height: h,
        data,
    };
    (img(r), img(t))
}

fn flip(pooling: FlipPooling) -> PairRequest {
    PairRequest {
        flip: Some(FlipRequest {
            pixels_per_degree: DEFAULT_PIXELS_PER_DEGREE,
            heatmap: false,
            pooling,
        }),
        ..Default::default()
    }
}

#[test]
fn running_mean_on_the_device_is_the_cpus_bit_for_bit() {
    let (mut gpu, _, _) = open();
    // 640x360: large enough that the f32 running sum drifts from the exact mean.
    for (w, h, seed, amplitude) in [(640, 360, 1, 60), (37, 23, 2, 20), (301, 7, 3, 90)] {
        let (r, t) = noisy_pair(w, h, seed, amplitude);
        let pair = Pair {
            reference: &r,
            test: &t,
            reference_hdr: None,
            test_hdr: None,
        };
        let on_device = gpu.pair(pair, &flip(FlipPooling::FlipEvaluator)).unwrap();
        let read_back = gpu.pair(pair, &flip(FlipPooling::ErrorMap)).unwrap();
        let (d, m) = (on_device.flip.unwrap(), read_back.flip.unwrap());
        assert!(d.error_map.is_none(), "the map stays on the device");
        let map = m.error_map.as_ref().expect("the map came back");
        assert_eq!(
            d.mean.to_bits(),
            tessera_metrics::port::flip_running_mean(map).to_bits(),
            "{w}x{h}: device {} vs CPU running mean of the same map",
            d.mean
        );
        assert_eq!(d.pooling, FlipPooling::FlipEvaluator);
        if (w, h) == (640, 360) {
            // The running mean is not the exact mean here: the test tells them apart.
            assert_ne!(d.mean, d.exact_mean);
        }
    }
}

/// A float texture of `image` (Rgba16Float, alpha 1).
fn texture(device: &wgpu::Device, queue: &wgpu::Queue, image: &HdrImage) -> wgpu::Texture {
    let halves: Vec<u16> = image
        .data
        .chunks_exact(3)
        .flat_map(|p| [p[0], p[1], p[2], 1.0])
        .map(|v| half::f16::from_f32(v).to_bits())
        .collect();
    device.create_texture_with_data(
        queue,
        &wgpu::TextureDescriptor {
            label: Some("frame"),
            size: wgpu::Extent3d {
                width: image.width,
                height: image.height,
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
    )
}

/// Linear frames as f16 holds them (so the CPU sees what the texture holds).
fn hdr_frame(w: u32, h: u32, seed: u64, peak: f32) -> HdrImage {
    let mut rng = Rng(seed);
    let data = (0..w * h * 3)
        .map(|i| {
            let base = (i / 3 % w) as f32 / w as f32;
            let v = base * peak * (0.8 + (rng.next() % 400) as f32 / 1000.0);
            half::f16::from_f32(v).to_f32()
        })
        .collect();
    HdrImage {
        width: w,
        height: h,
        data,
    }
}

#[test]
fn device_sequence_equals_the_uploaded_one() {
    let (mut gpu, device, queue) = open();
    let (w, h) = (48, 32);
    let reference: Vec<HdrImage> = (0..3).map(|i| hdr_frame(w, h, 10 + i, 4.0)).collect();
    let test: Vec<HdrImage> = (0..3).map(|i| hdr_frame(w, h, 20 + i, 4.0)).collect();
    let ranges: Vec<_> = reference.iter().map(hdr_exposure_range).collect();
    let request = |i: usize| PairRequest {
        mse_rgb: true,
        mse_luma: true,
        max_abs: true,
        ssim_rgb: true,
        ssim_luma: true,
        flip: Some(FlipRequest {
            pixels_per_degree: DEFAULT_PIXELS_PER_DEGREE,
            heatmap: i == 1,
            pooling: FlipPooling::FlipEvaluator,
        }),
        flip_hdr: Some(FlipHdrRequest {
            range: ranges[i],
            pixels_per_degree: DEFAULT_PIXELS_PER_DEGREE,
            heatmap: false,
            pooling: FlipPooling::FlipEvaluator,
        }),
    };
    let on_device = |gpu: &mut GpuMetrics, frames: &[HdrImage]| {
        frames
            .iter()
            .map(|f| {
                gpu.frame_from_texture_with(&texture(&device, &queue, f), true)
                    .unwrap()
            })
            .collect::<Vec<_>>()
    };
    let (rd, td) = (on_device(&mut gpu, &reference), on_device(&mut gpu, &test));
    let device_values = gpu.sequence_frames(&rd, &td, &request, true).unwrap();
    let srgb = |f: &[HdrImage]| -> Vec<Rgb8Image> {
        f.iter().map(tessera_metrics::encode_srgb8).collect()
    };
    let (rl, tl) = (srgb(&reference), srgb(&test));
    let seq = Sequence {
        reference: &rl,
        test: &tl,
        reference_hdr: &reference,
        test_hdr: &test,
    };
    let uploaded = gpu.sequence(seq, &request, true).unwrap();
    assert_eq!(device_values, uploaded);
    assert!(device_values.frames[1]
        .flip
        .as_ref()
        .unwrap()
        .heatmap
        .is_some());
    // And an 8-bit-only frame is enough for everything but HDR-FLIP.
    let ldr_only = gpu
        .frame_from_texture_with(&texture(&device, &queue, &test[0]), false)
        .unwrap();
    assert!(!ldr_only.has_hdr());
    assert_eq!(gpu.read_ldr(&ldr_only).unwrap(), tl[0]);
}
