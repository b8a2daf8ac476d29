//! `diff_images` on every input kind `tessera diff` accepts: 16-bit PNGs are compared at 16 bits,
//! OpenEXR gets HDR-FLIP, and an LDR/HDR mix is refused.

use image::{ImageBuffer, Rgb};
use tessera_metrics::{diff_images, load_image, LoadedImage, MetricsError};

fn write_png16(path: &std::path::Path, f: impl Fn(u32, u32) -> [u16; 3]) {
    let img: ImageBuffer<Rgb<u16>, Vec<u16>> = ImageBuffer::from_fn(16, 12, |x, y| Rgb(f(x, y)));
    img.save(path).unwrap();
}

fn write_exr(path: &std::path::Path, f: impl Fn(u32, u32) -> [f32; 3]) {
    let img: ImageBuffer<Rgb<f32>, Vec<f32>> = ImageBuffer::from_fn(16, 12, |x, y| Rgb(f(x, y)));
    img.save(path).unwrap();
}

#[test]
fn sixteen_bit_pngs_are_compared_at_sixteen_bits() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("a.png"), dir.path().join("b.png"));
    let base = |x: u32, y: u32| [(x * 15 * 257) as u16, (y * 20 * 257) as u16, 120 * 257];
    write_png16(&a, base);
    // +100 on red: below one 8-bit step (257).
    write_png16(&b, |x, y| {
        let p = base(x, y);
        [p[0] + 100, p[1], p[2]]
    });
    let (ra, rb) = (load_image(&a).unwrap(), load_image(&b).unwrap());
    assert!(matches!(ra, LoadedImage::Ldr16(_)));
    let r = diff_images(&ra, &rb).unwrap();
    assert_eq!(r.bit_depth, 16);
    // MSE: 100^2 on one channel of three.
    assert!((r.mse_rgb - 10000.0 / 3.0).abs() < 1e-9, "{}", r.mse_rgb);
    let psnr = 10.0 * (65535.0f64 * 65535.0 / (10000.0 / 3.0)).log10();
    assert!((r.psnr_rgb - psnr).abs() < 1e-9);
    assert!(r.ssim_rgb.unwrap() < 1.0);
    // At 8 bits the two are the same picture.
    assert_eq!(r.max_abs_error, 0);
    assert_eq!(r.flip.mean, 0.0);
    assert!(r.to_text().contains("at 16 bits"));
}

#[test]
fn exr_pairs_get_hdr_flip_and_mixed_kinds_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("a.exr"), dir.path().join("b.exr"));
    write_exr(&a, |x, y| [x as f32 * 0.5, y as f32 * 0.2, 4.0]);
    write_exr(&b, |x, y| [x as f32 * 0.5, y as f32 * 0.2 + 1.0, 4.0]);
    let (ra, rb) = (load_image(&a).unwrap(), load_image(&b).unwrap());
    let r = diff_images(&ra, &rb).unwrap();
    let hdr = r.flip_hdr.as_ref().expect("HDR-FLIP for EXR inputs");
    assert!(hdr.mean > 0.0 && hdr.mean <= 1.0);
    let range = r.exposure_range.unwrap();
    assert!(range.count >= 2 && range.stop > range.start);
    let json = serde_json::to_value(&r).unwrap();
    assert!(json["flip_hdr"]["mean"].is_number());
    assert_eq!(diff_images(&ra, &ra).unwrap().flip_hdr.unwrap().mean, 0.0);

    let png = dir.path().join("c.png");
    write_png16(&png, |_, _| [0, 0, 0]);
    let err = diff_images(&ra, &load_image(&png).unwrap()).unwrap_err();
    assert!(matches!(err, MetricsError::KindMismatch { .. }), "{err}");
}
