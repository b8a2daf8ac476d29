//! ColorVideoVDP's constants for the GPU passes, computed on the CPU as the `colorvideovdp` crate
//! 0.1.1 computes them, f32 operation for f32 operation: the calibration (`data/`, parsed as the
//! crate parses it), the band frequencies, castleCSF's tables at each band, the temporal filters,
//! the phase-uncertainty blur, and the display's decoding of a pixel to absolute luminance.
//!
//! For: the numbers the passes are given (so both back ends start from identical f32 values).
//! Not for: anything done per pixel (the WGSL passes) or pooling (`tessera_metrics::cvvdp`).
//! The crate's source names (`metric.rs`, `csf.rs`, ...) are cited where each step is mirrored.

use serde::Deserialize;

use crate::error::GpuMetricsError;

const PARAMETERS: &str = include_str!("../../data/cvvdp_parameters.json");
const CSF_LUT: &str = include_str!("../../data/csf_lut_weber_fixed_size.json");

/// The base model v0.5.7 (`parameters.rs`; unused keys ignored).
#[derive(Deserialize)]
pub(crate) struct Parameters {
    pub mask_p: f32,
    pub mask_c: f32,
    pub pu_dilate: f32,
    pub beta: f32,
    pub beta_tch: f32,
    pub sensitivity_correction: f32,
    pub jod_a: f32,
    pub jod_exp: f32,
    pub mask_q: [f32; 4],
    pub ch_chrom_w: f32,
    pub ch_trans_w: f32,
    pub sigma_tf: [f32; 4],
    pub beta_tf: [f32; 4],
    pub xcm_weights: [f32; 16],
    pub baseband_weight: [f32; 4],
    pub d_max: f32,
    pub image_int: f32,
}

impl Parameters {
    pub fn channel_weights(&self) -> [f32; 4] {
        [1.0, self.ch_chrom_w, self.ch_chrom_w, self.ch_trans_w]
    }
}

/// `parameters.rs`: `safe_pow`, an epsilon at both powers.
pub(crate) fn safe_pow(x: f32, p: f32) -> f32 {
    (x + 0.00001).powf(p) - 0.00001_f32.powf(p)
}

#[derive(Deserialize)]
struct Lut {
    #[serde(rename = "L_bkg")]
    luminance: Vec<f32>,
    rho: Vec<f32>,
    o0_c1: Vec<Vec<f32>>,
    o0_c2: Vec<Vec<f32>>,
    o0_c3: Vec<Vec<f32>>,
    o5_c1: Vec<Vec<f32>>,
}

/// Entries of castleCSF's log-luminance axis.
pub(crate) const CSF_LUMINANCES: usize = 32;

/// castleCSF's lookup table (`csf.rs`).
pub(crate) struct Csf {
    pub log_l: Vec<f32>,
    log_rho: Vec<f32>,
    tables: [Vec<Vec<f32>>; 4],
}

impl Csf {
    /// The log-sensitivity of each channel over the luminance axis at `frequency` (`at_frequency`:
    /// linear in log frequency, extrapolated at the ends).
    pub fn at_frequency(&self, frequency: f32) -> [[f32; CSF_LUMINANCES]; 4] {
        let query = frequency.log10();
        let hi = self
            .log_rho
            .partition_point(|&x| x < query)
            .clamp(1, self.log_rho.len() - 1);
        let lo = hi - 1;
        std::array::from_fn(|c| {
            std::array::from_fn(|l| {
                let r = &self.tables[c][l];
                let slope = (r[hi] - r[lo]) / (self.log_rho[hi] - self.log_rho[lo]);
                r[lo] + slope * (query - self.log_rho[lo])
            })
        })
    }
}

/// Everything that does not depend on the display or the frames.
pub(crate) struct Model {
    pub p: Parameters,
    pub csf: Csf,
    /// The phase-uncertainty Gaussian (`pyramid.rs`: `gaussian_kernel(pu_dilate)`).
    pub blur: Vec<f32>,
    /// Cross-channel masking weights, `2^xcm_weights`, `[source * 4 + channel]`.
    pub xcm: [f32; 16],
}

fn invalid(what: &str, e: impl std::fmt::Display) -> GpuMetricsError {
    GpuMetricsError::Unsupported(format!("ColorVideoVDP calibration {what}: {e}"))
}

impl Model {
    pub fn load() -> Result<Model, GpuMetricsError> {
        let p: Parameters =
            serde_json::from_str(PARAMETERS).map_err(|e| invalid("parameters", e))?;
        let lut: Lut = serde_json::from_str(CSF_LUT).map_err(|e| invalid("CSF table", e))?;
        let tables = [lut.o0_c1, lut.o0_c2, lut.o0_c3, lut.o5_c1];
        if lut.luminance.len() != CSF_LUMINANCES
            || lut.rho.len() < 2
            || tables.iter().any(|t| {
                t.len() != lut.luminance.len() || t.iter().any(|r| r.len() != lut.rho.len())
            })
        {
            return Err(invalid("CSF table", "unexpected shape"));
        }
        let csf = Csf {
            log_l: lut.luminance.iter().map(|x| x.log10()).collect(),
            log_rho: lut.rho.iter().map(|x| x.log10()).collect(),
            tables,
        };
        let blur = gaussian_kernel(p.pu_dilate);
        let xcm = p.xcm_weights.map(|x| 2.0_f32.powf(x));
        Ok(Model { p, csf, blur, xcm })
    }
}

fn gaussian_kernel(sigma: f32) -> Vec<f32> {
    let radius = (sigma * 2.0) as usize;
    let mut kernel: Vec<f32> = (0..2 * radius + 1)
        .map(|i| (-0.5 * ((i as f32 - radius as f32) / sigma).powi(2)).exp())
        .collect();
    let sum: f32 = kernel.iter().sum();
    for x in &mut kernel {
        *x /= sum;
    }
    kernel
}

/// `pyramid.rs`: `frequencies`: the band frequencies in cycles per degree, the 0.1 cpd baseband
/// last.
pub(crate) fn frequencies(width: usize, height: usize, ppd: f64) -> Vec<f32> {
    let max_levels = (width.min(height).ilog2() as usize).saturating_sub(1);
    let first_invalid = (0..15)
        .find(|&i| {
            let frequency = if i == 0 {
                1.0
            } else {
                0.3228 * 2.0_f64.powi(-(i - 1))
            };
            frequency * ppd / 2.0 <= 0.2
        })
        .unwrap_or(max_levels as i32) as usize;
    let levels = (first_invalid + 1).min(max_levels);
    let mut freqs: Vec<f32> = (0..levels + 1)
        .map(|i| {
            (if i == 0 {
                1.0
            } else {
                0.3228 * 2.0_f64.powi(-(i as i32 - 1))
            } * ppd
                / 2.0) as f32
        })
        .collect();
    freqs[levels] = 0.1;
    freqs
}

/// `temporal.rs`: `filter_length`.
pub(crate) fn filter_length(fps: f32) -> usize {
    (0.250 * fps as f64 / 2.0).ceil() as usize * 2 + 1
}

/// `temporal.rs`: `filters`: the sustained (achromatic, red-green, yellow-violet) and transient
/// impulse responses, `n` taps each.
pub(crate) fn filters(fps: f32, p: &Parameters) -> [Vec<f32>; 4] {
    let n = filter_length(fps);
    let frequencies = n / 2 + 1;
    std::array::from_fn(|channel| {
        let response: Vec<f32> = (0..frequencies)
            .map(|i| {
                let omega = i as f32 * (fps / 2.0) / (frequencies - 1) as f32;
                if channel < 3 {
                    (-omega.powf(p.beta_tf[channel]) / p.sigma_tf[channel]).exp()
                } else {
                    (-(omega.powf(p.beta_tf[3]) - 5.0_f32.powf(p.beta_tf[3])).powi(2)
                        / p.sigma_tf[3])
                        .exp()
                }
            })
            .collect();
        let nonzero: Vec<(usize, f32)> = response
            .iter()
            .copied()
            .enumerate()
            .skip(1)
            .filter(|&(_, r)| r != 0.0)
            .collect();
        (0..n)
            .map(|i| {
                let t = (i + n - n / 2) % n;
                let mut value = response[0] as f64;
                for &(k, r) in &nonzero {
                    value += 2.0
                        * r as f64
                        * (std::f64::consts::TAU * k as f64 * t as f64 / n as f64).cos();
                }
                (value / n as f64) as f32
            })
            .collect()
    })
}

const XYZ_LMS: [[f64; 3]; 3] = [
    [0.187596268556126, 0.585168649077728, -0.026384263306304],
    [-0.133397430663221, 0.405505777260049, 0.034502127690364],
    [0.000244379021663, -0.000542995890619, 0.019406849066323],
];
const LMS_DKL: [[f64; 3]; 3] = [
    [1.0, 1.0, 0.0],
    [1.0, -2.311130179947035, 0.0],
    [-1.0, -1.0, 50.977_571_328_718_78],
];
/// `RGB2X`, `RGB2Y`, `RGB2Z` of the reference's `color_spaces.json` for `sRGB` and
/// `BT.709-linear` (the same BT.709 primaries), rounded to f32 as serde rounds the JSON.
const BT709_TO_XYZ: [[f64; 3]; 3] = [
    [0.4124564, 0.3575761, 0.1804375],
    [0.2126729, 0.7151522, 0.072175],
    [0.0193339, 0.119192, 0.9503041],
];

fn matmul(a: [[f32; 3]; 3], b: [[f32; 3]; 3]) -> [[f32; 3]; 3] {
    std::array::from_fn(|r| {
        std::array::from_fn(|c| (a[r][0] * b[0][c] + a[r][1] * b[1][c]) + a[r][2] * b[2][c])
    })
}

/// How the display shows a pixel (`color.rs`: `transform`), for the two encodings the harness
/// has: 8-bit sRGB (a table of the 256 decoded luminances) and linear BT.709 in cd/m².
pub(crate) struct Decode {
    /// Absolute luminance of each 8-bit sRGB code value on the display.
    pub srgb: [f32; 256],
    /// Linear input: exposure, lower clamp, peak, reflected ambient.
    pub linear: [f32; 4],
    /// Linear RGB (BT.709) to DKL, rows.
    pub dkl: [[f32; 3]; 3],
}

impl Decode {
    pub fn new(photo: &colorvideovdp::Photometry) -> Decode {
        let (black, reflected) = photo.black_level();
        let scale = (photo.peak_luminance - black) as f32;
        let peak = photo.peak_luminance as f32;
        let exposure = photo.exposure as f32;
        let srgb = std::array::from_fn(|code| {
            let v = (code as u8 as f32 / 255.0).clamp(0.0, 1.0);
            let relative = if v > 0.04045 {
                ((v + 0.055) / 1.055).powf(2.4)
            } else {
                v / 12.92
            };
            let relative = if exposure == 1.0 {
                relative
            } else {
                (relative * exposure).clamp(0.0, 1.0)
            };
            scale * relative + black as f32 + reflected as f32
        });
        let rgb = BT709_TO_XYZ.map(|r| r.map(|x| x as f32));
        let dkl = matmul(
            matmul(
                LMS_DKL.map(|r| r.map(|x| x as f32)),
                XYZ_LMS.map(|r| r.map(|x| x as f32)),
            ),
            rgb,
        );
        Decode {
            srgb,
            linear: [exposure, (black as f32).max(0.005), peak, reflected as f32],
            dkl,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn calibration_loads_and_filters_sum_as_low_and_band_pass() {
        let m = Model::load().unwrap();
        assert_eq!(m.blur.len(), 13);
        assert!((m.blur.iter().sum::<f32>() - 1.0).abs() < 1e-6);
        let f = filters(30.0, &m.p);
        assert_eq!(f[0].len(), 9);
        // Sustained filters pass a constant (sum 1); the transient one (band-pass) nearly not.
        assert!((f[0].iter().sum::<f32>() - 1.0).abs() < 1e-3, "{:?}", f[0]);
        assert!(f[3].iter().sum::<f32>().abs() < 0.1, "{:?}", f[3]);
    }

    #[test]
    fn bands_end_with_the_baseband() {
        let f = frequencies(1920, 1080, 75.4);
        assert_eq!(f.len(), 9);
        assert_eq!(*f.last().unwrap(), 0.1);
        assert_eq!(frequencies(8, 8, 75.4).len(), 3);
    }
}
