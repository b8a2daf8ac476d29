//! The one error type of this crate.
//!
//! For: every way a metric or an image load/save can refuse its input. Not for: anything that is
//! a *result* (identical images give an infinite PSNR, which is a value, not an error).

use std::path::PathBuf;

/// Why a metric could not be computed or an image could not be read or written.
#[derive(Debug, thiserror::Error)]
pub enum MetricsError {
    /// The two images of a comparison do not have the same width and height.
    #[error(
        "image sizes differ: reference is {ref_width}x{ref_height}, test is \
         {test_width}x{test_height}; both images of a comparison must have the same size"
    )]
    SizeMismatch {
        ref_width: u32,
        ref_height: u32,
        test_width: u32,
        test_height: u32,
    },
    /// An image has zero width or zero height.
    #[error("image is empty ({width}x{height}); metrics need at least one pixel")]
    EmptyImage { width: u32, height: u32 },
    /// An image's buffer length does not match its width and height.
    #[error(
        "image buffer holds {actual} values but {width}x{height} with 3 channels needs {expected}"
    )]
    BadBufferLength {
        width: u32,
        height: u32,
        expected: usize,
        actual: usize,
    },
    /// A per-pixel input (motion field, mask) does not match the images' pixel count.
    #[error("{what} has {actual} entries for {expected} pixels")]
    PerPixelLength {
        what: &'static str,
        expected: usize,
        actual: usize,
    },
    /// The image is smaller than a metric's window (SSIM needs at least 11x11 pixels).
    #[error("{metric} needs images of at least {min}x{min} pixels, got {width}x{height}")]
    TooSmall {
        metric: &'static str,
        min: u32,
        width: u32,
        height: u32,
    },
    /// A metric parameter is out of its domain (e.g. pixels per degree not positive and finite).
    #[error("invalid parameter {name} = {value}: {expected}")]
    InvalidParameter {
        name: &'static str,
        value: f64,
        expected: &'static str,
    },
    /// The two images are of different kinds (one LDR, one HDR).
    #[error("cannot compare {reference} reference with {test} test image; convert one first")]
    KindMismatch {
        reference: &'static str,
        test: &'static str,
    },
    /// An HDR image holds NaN or infinite values, which FLIP cannot compare.
    #[error(
        "{image} image holds {count} non-finite values (NaN or infinity); fix or mask them first"
    )]
    NonFinite { image: &'static str, count: usize },
    /// Reading or writing a file failed.
    #[error("cannot {action} {path}: {source}")]
    Io {
        action: &'static str,
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// The file could be read but not decoded, or its format is not supported.
    #[error("cannot decode {path}: {reason}; supported: {supported}")]
    Decode {
        path: PathBuf,
        reason: String,
        supported: &'static str,
    },
    /// Encoding an output image failed.
    #[error("cannot encode {path}: {reason}")]
    Encode { path: PathBuf, reason: String },
    /// A ColorVideoVDP display could not be built from what was given.
    #[error("invalid display `{spec}`: {reason}")]
    InvalidDisplay { spec: String, reason: String },
    /// The `colorvideovdp` crate refused the input or failed (its message).
    #[error("ColorVideoVDP: {reason}")]
    Cvvdp { reason: String },
    /// Two sequences of a comparison differ in length, or are empty.
    #[error(
        "sequences differ in length or are empty: reference has {reference} frames, test has \
         {test}; both need the same number, at least one"
    )]
    SequenceLength { reference: usize, test: usize },
    /// A path given as an image sequence holds no numbered frames.
    #[error(
        "{path} holds no numbered PNG/EXR/HDR frames (expected a folder of files like \
             `0001.png`, or a run folder's `<variant>` stem with `<variant>-f000.png`)"
    )]
    NoFrames { path: PathBuf },
    /// Two files of one sequence folder carry the same frame number.
    #[error(
        "{first} and {second} both hold frame {number}; a sequence folder needs one file per frame"
    )]
    DuplicateFrame {
        number: u64,
        first: PathBuf,
        second: PathBuf,
    },
}
