//! The luma plane used by `psnr_luma`, `mse_luma` and `ssim_luma`.
//!
//! For: one definition of "luma" for the whole crate. Not for: FLIP, which works in its own
//! opponent colour space from linear RGB.
//!
//! Luma is BT.601 `Y' = 0.299 R' + 0.587 G' + 0.114 B'` on the 8-bit *encoded* values, kept as
//! an unrounded f64 in [0, 255] (data range 255). It is *not* scikit-image's `rgb2gray` (which
//! uses BT.709 weights 0.2125/0.7154/0.0721 and scales to [0,1]) and not MATLAB's `rgb2gray`
//! (which rounds to uint8).

use crate::Rgb8Image;
use rayon::prelude::*;

/// BT.601 luma weights for R', G', B'.
pub const LUMA_WEIGHTS: [f64; 3] = [0.299, 0.587, 0.114];

/// The BT.601 luma of every pixel, row-major, in [0, 255].
pub(crate) fn luma_plane(image: &Rgb8Image) -> Vec<f64> {
    image
        .data
        .par_chunks(3)
        .with_min_len(4096)
        .map(|p| {
            LUMA_WEIGHTS[0] * p[0] as f64
                + LUMA_WEIGHTS[1] * p[1] as f64
                + LUMA_WEIGHTS[2] * p[2] as f64
        })
        .collect()
}
