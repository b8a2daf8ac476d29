//! Reading images for `tessera diff` and writing PNGs.
//!
//! For: turning a file into an [`Rgb8Image`] or [`HdrImage`] and back, with errors that name the
//! path. Not for: colour management (no ICC, no gamma chunk handling: PNG pixels are taken as
//! sRGB-encoded, `.hdr`/`.exr` pixels as linear).

use crate::{HdrImage, MetricsError, Rgb8Image};
use image::{DynamicImage, ImageFormat, ImageReader};
use std::io::{BufReader, BufWriter};
use std::path::Path;

/// What `load_image` can read.
pub const SUPPORTED_INPUTS: &str = "PNG (8- or 16-bit; grey, grey+alpha, RGB, RGBA; alpha is \
                                    dropped) as sRGB, Radiance .hdr and OpenEXR as linear RGB";

/// A decoded image: 8-bit sRGB (from PNG) or linear float (from `.hdr` / `.exr`).
#[derive(Debug, Clone, PartialEq)]
pub enum LoadedImage {
    Ldr(Rgb8Image),
    /// A 16-bit PNG, kept at 16 bits.
    Ldr16(crate::Rgb16Image),
    Hdr(HdrImage),
}

impl LoadedImage {
    /// "LDR" or "HDR", for messages.
    pub fn kind(&self) -> &'static str {
        match self {
            LoadedImage::Ldr(_) | LoadedImage::Ldr16(_) => "LDR",
            LoadedImage::Hdr(_) => "HDR",
        }
    }
}

/// Reads a PNG (to 8-bit sRGB; 16-bit is reduced by rounding `v * 255 / 65535`), or a Radiance
/// `.hdr` / OpenEXR file (to linear f32). The format is sniffed from the file's first bytes, not
/// its extension.
pub fn load_image(path: &Path) -> Result<LoadedImage, MetricsError> {
    let file = std::fs::File::open(path).map_err(|source| MetricsError::Io {
        action: "open",
        path: path.to_owned(),
        source,
    })?;
    let reader = ImageReader::new(BufReader::new(file))
        .with_guessed_format()
        .map_err(|source| MetricsError::Io {
            action: "read",
            path: path.to_owned(),
            source,
        })?;
    let decode_err = |reason: String| MetricsError::Decode {
        path: path.to_owned(),
        reason,
        supported: SUPPORTED_INPUTS,
    };
    let format = match reader.format() {
        Some(f @ (ImageFormat::Png | ImageFormat::Hdr | ImageFormat::OpenExr)) => f,
        Some(other) => return Err(decode_err(format!("{other:?} files are not supported"))),
        None => return Err(decode_err("unrecognised file format".to_owned())),
    };
    let decoded = reader.decode().map_err(|e| match e {
        image::ImageError::IoError(source) => MetricsError::Io {
            action: "read",
            path: path.to_owned(),
            source,
        },
        other => decode_err(other.to_string()),
    })?;
    let (width, height) = (decoded.width(), decoded.height());
    if width == 0 || height == 0 {
        return Err(MetricsError::EmptyImage { width, height });
    }
    if format == ImageFormat::Png {
        let sixteen = matches!(
            decoded,
            DynamicImage::ImageLuma16(_)
                | DynamicImage::ImageLumaA16(_)
                | DynamicImage::ImageRgb16(_)
                | DynamicImage::ImageRgba16(_)
        );
        if sixteen {
            return Ok(LoadedImage::Ldr16(crate::Rgb16Image {
                width,
                height,
                data: decoded.into_rgb16().into_raw(),
            }));
        }
        Ok(LoadedImage::Ldr(to_rgb8(decoded)))
    } else {
        Ok(LoadedImage::Hdr(HdrImage {
            width,
            height,
            data: decoded.into_rgb32f().into_raw(),
        }))
    }
}

/// 8-bit RGB from a decoded 8-bit PNG: grey is expanded, alpha is dropped.
fn to_rgb8(decoded: DynamicImage) -> Rgb8Image {
    let (width, height) = (decoded.width(), decoded.height());
    Rgb8Image {
        width,
        height,
        data: decoded.into_rgb8().into_raw(),
    }
}

/// `round(v * 255 / 65535)` in integers.
pub(crate) fn round_16_to_8(v: u16) -> u8 {
    ((v as u32 * 255 + 32767) / 65535) as u8
}

/// Writes an 8-bit RGB PNG.
pub fn save_png(path: &Path, image: &Rgb8Image) -> Result<(), MetricsError> {
    image.validate()?;
    let file = std::fs::File::create(path).map_err(|source| MetricsError::Io {
        action: "create",
        path: path.to_owned(),
        source,
    })?;
    // Fast deflate and one filter: the run folder's PNGs are for looking at; a 4K frame took
    // about 150 ms at the default level, 129 ms with the adaptive filter (five filters tried per
    // row) and 63 ms with Paeth alone, 3% larger (this 2-core machine). The pixels are the same.
    let encoder = image::codecs::png::PngEncoder::new_with_quality(
        BufWriter::new(file),
        image::codecs::png::CompressionType::Fast,
        image::codecs::png::FilterType::Paeth,
    );
    image::ImageEncoder::write_image(
        encoder,
        &image.data,
        image.width,
        image.height,
        image::ExtendedColorType::Rgb8,
    )
    .map_err(|e| match e {
        image::ImageError::IoError(source) => MetricsError::Io {
            action: "write",
            path: path.to_owned(),
            source,
        },
        other => MetricsError::Encode {
            path: path.to_owned(),
            reason: other.to_string(),
        },
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rounds_16_bit_to_nearest() {
        assert_eq!(round_16_to_8(0), 0);
        assert_eq!(round_16_to_8(65535), 255);
        assert_eq!(round_16_to_8(257 * 100), 100);
        assert_eq!(round_16_to_8(257 * 100 + 128), 100); // 100.498
        assert_eq!(round_16_to_8(257 * 100 + 129), 101); // 100.502
    }
}
