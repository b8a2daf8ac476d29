//! The two image types every metric takes: 8-bit sRGB-encoded RGB and linear float RGB.
//!
//! For: holding pixels and checking that a pair can be compared. Not for: decoding files (see
//! `io`) or colour conversions (see `srgb`).

use crate::MetricsError;

/// An 8-bit sRGB-encoded RGB image, row-major, top row first, 3 bytes per pixel.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Rgb8Image {
    pub width: u32,
    pub height: u32,
    pub data: Vec<u8>,
}

/// A linear (scene-referred) RGB float image, row-major, top row first, 3 floats per pixel.
#[derive(Debug, Clone, PartialEq)]
pub struct HdrImage {
    pub width: u32,
    pub height: u32,
    pub data: Vec<f32>,
}

impl Rgb8Image {
    /// An image filled with one colour.
    pub fn filled(width: u32, height: u32, rgb: [u8; 3]) -> Self {
        let n = width as usize * height as usize;
        let mut data = Vec::with_capacity(n * 3);
        for _ in 0..n {
            data.extend_from_slice(&rgb);
        }
        Self {
            width,
            height,
            data,
        }
    }

    /// Number of pixels.
    pub fn pixel_count(&self) -> usize {
        self.width as usize * self.height as usize
    }

    /// Checks that the buffer matches the size and that the image is not empty.
    pub fn validate(&self) -> Result<(), MetricsError> {
        check_layout(self.width, self.height, self.data.len())
    }
}

impl HdrImage {
    /// Number of pixels.
    pub fn pixel_count(&self) -> usize {
        self.width as usize * self.height as usize
    }

    /// Checks that the buffer matches the size and that the image is not empty.
    pub fn validate(&self) -> Result<(), MetricsError> {
        check_layout(self.width, self.height, self.data.len())
    }
}

pub(crate) fn check_layout(width: u32, height: u32, len: usize) -> Result<(), MetricsError> {
    if width == 0 || height == 0 {
        return Err(MetricsError::EmptyImage { width, height });
    }
    let expected = width as usize * height as usize * 3;
    if len != expected {
        return Err(MetricsError::BadBufferLength {
            width,
            height,
            expected,
            actual: len,
        });
    }
    Ok(())
}

pub(crate) fn check_same_size(rw: u32, rh: u32, tw: u32, th: u32) -> Result<(), MetricsError> {
    if (rw, rh) != (tw, th) {
        return Err(MetricsError::SizeMismatch {
            ref_width: rw,
            ref_height: rh,
            test_width: tw,
            test_height: th,
        });
    }
    Ok(())
}

/// Checks that a reference/test pair of 8-bit images can be compared.
pub(crate) fn check_pair(reference: &Rgb8Image, test: &Rgb8Image) -> Result<(), MetricsError> {
    check_same_size(reference.width, reference.height, test.width, test.height)?;
    reference.validate()?;
    test.validate()
}

/// Checks that a reference/test pair of float images can be compared.
pub(crate) fn check_hdr_pair(reference: &HdrImage, test: &HdrImage) -> Result<(), MetricsError> {
    check_same_size(reference.width, reference.height, test.width, test.height)?;
    reference.validate()?;
    test.validate()
}
