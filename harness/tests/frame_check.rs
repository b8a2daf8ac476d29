//! The device's per-frame checks (`render/frame_check.rs`) on a frame bound in row bands, as a
//! frame beyond the storage-binding limit is (an 8K Rgba16Float frame is 253 MiB against wgpu's
//! default 128 MiB): the non-finite count, the mask's pixels and the compare must be those of
//! the frame whatever the bands.

mod common;

use tessera::render::frame_check::FrameCheck;

const W: u32 = 37;
const H: u32 = 29;

/// An Rgba16Float texture of `pixels` (f16 bits, 4 per pixel).
fn texture(gpu: &tessera::gpu::Gpu, pixels: &[u16]) -> wgpu::Texture {
    let t = gpu.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("frame check test"),
        size: wgpu::Extent3d {
            width: W,
            height: H,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::Rgba16Float,
        usage: wgpu::TextureUsages::COPY_SRC | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    });
    gpu.queue.write_texture(
        t.as_image_copy(),
        bytemuck::cast_slice(pixels),
        wgpu::TexelCopyBufferLayout {
            offset: 0,
            bytes_per_row: Some(W * 8),
            rows_per_image: Some(H),
        },
        wgpu::Extent3d {
            width: W,
            height: H,
            depth_or_array_layers: 1,
        },
    );
    t
}

fn check(
    gpu: &tessera::gpu::Gpu,
    limit: u64,
    frame: &wgpu::Texture,
    snapshot: &wgpu::Texture,
) -> tessera::render::frame_check::Checked {
    let c = FrameCheck::with_binding_limit(gpu, W, H, limit);
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    c.snapshot(&mut encoder, snapshot);
    c.record(gpu, &mut encoder, frame, true);
    gpu.queue.submit([encoder.finish()]);
    c.read(gpu, true).unwrap()
}

#[test]
fn banded_checks_count_mask_and_compare_as_one_band() {
    let gpu = common::gpu();
    let one = 0x3c00u16; // 1.0
    let mut pixels = vec![one; (W * H * 4) as usize];
    // NaN, +Inf and -Inf in R, G, B of pixels spread over every band; alpha is not checked.
    let bad = [
        (0, 0, 0, 0x7e00u16),
        (5, 3, 1, 0x7c00),
        (36, 10, 2, 0xfc00),
        (17, 28, 0, 0x7e01),
    ];
    for &(x, y, c, v) in &bad {
        pixels[((y * W + x) * 4 + c) as usize] = v;
    }
    pixels[((20 * W + 20) * 4 + 3) as usize] = 0x7e00;
    let frame = texture(&gpu, &pixels);
    let mut other = pixels.clone();
    other[((11 * W + 2) * 4) as usize] = 0x4000; // one pixel differs: 2.0
    let other = texture(&gpu, &other);
    let row = 256u64; // 37 x 8 bytes, padded to 256
    let whole = check(&gpu, 1 << 30, &frame, &frame);
    assert_eq!(whole.non_finite, 4);
    assert_eq!(whole.same_as_snapshot, Some(true));
    let expected: Vec<usize> = bad
        .iter()
        .map(|&(x, y, _, _)| (y * W + x) as usize)
        .collect();
    let bits = |m: &Option<Vec<u64>>| -> Vec<usize> {
        let m = m.as_ref().unwrap();
        (0..(W * H) as usize)
            .filter(|i| m[i / 64] >> (i % 64) & 1 == 1)
            .collect()
    };
    let mut sorted = expected.clone();
    sorted.sort();
    assert_eq!(bits(&whole.non_finite_mask), sorted);
    // Bands of 1, 5 and 28 rows: the same answers.
    for rows in [1u64, 5, 28] {
        let banded = check(&gpu, rows * row, &frame, &frame);
        assert_eq!(banded.non_finite, 4, "{rows} rows per band");
        assert_eq!(
            bits(&banded.non_finite_mask),
            sorted,
            "{rows} rows per band"
        );
        assert_eq!(banded.same_as_snapshot, Some(true), "{rows} rows per band");
        let differs = check(&gpu, rows * row, &frame, &other);
        assert_eq!(
            differs.same_as_snapshot,
            Some(false),
            "{rows} rows per band"
        );
    }
}
