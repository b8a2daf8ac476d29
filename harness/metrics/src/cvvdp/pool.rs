//! ColorVideoVDP's pooling, redone from the per-channel, per-frame, per-band differences the
//! `colorvideovdp` crate returns (the reference's `Q_per_ch`), to get what the crate does not
//! pool for us: a JOD per frame, the transient (flicker) channel alone, and several shots pooled
//! as one sequence.
//!
//! For: those derived numbers. Not for: anything before pooling (the crate does it).
//!
//! The reference (`cvvdp_metric.py`, `do_pooling_and_jods`, model v0.5.7) pools band differences
//! with an Lp norm (beta_sch = 4) per channel, channels with beta_tch = 4 per frame, then frames
//! with a *mean* Lp norm (beta_t = 2), and maps the result to JOD with `met2jod`. Every norm
//! uses `safe_pow` (an epsilon of 1e-5 at both powers). The constants below are the crate's
//! embedded `cvvdp_parameters.json` (v0.5.7); `tests::pooling_reproduces_the_crate` checks that
//! pooling the crate's `quality_per_channel` here gives the crate's JOD.

/// beta_sch: Lp exponent across spatial bands.
const BETA_SCH: f32 = 4.0;
/// beta_tch: Lp exponent across channels.
const BETA_TCH: f32 = 4.0;
/// beta_t: Lp exponent across frames (mean-normalised).
const BETA_T: f32 = 2.0;
// The JSON's digits, kept verbatim as f64 and rounded to f32 as serde does when the crate loads them.
/// Channel weights: achromatic, red-green, yellow-violet (ch_chrom_w), transient (ch_trans_w).
const CHANNEL_WEIGHTS: [f32; 4] = [1.0, 1.0, 1.0, 0.808_113_455_772_399_9_f64 as f32];
/// Weights of the baseband (the last band), per channel.
const BASEBAND_WEIGHT: [f32; 4] = [
    0.003_633_448_621_258_139_6_f64 as f32,
    1.662_772_417_068_481_4_f64 as f32,
    4.118_745_326_995_85_f64 as f32,
    25.259_698_867_797_85_f64 as f32,
];
/// image_int: images are scaled by this before `met2jod`.
const IMAGE_INT: f32 = 0.577_918_291_091_919_f64 as f32;
const JOD_A: f32 = 0.043_956_939_131_021_5_f64 as f32;
const JOD_EXP: f32 = 0.930_204_272_270_202_6_f64 as f32;

/// The transient channel's index in a video's `quality_per_channel`.
pub(crate) const TRANSIENT: usize = 3;

fn safe_pow(x: f32, p: f32) -> f32 {
    (x + 0.00001).powf(p) - 0.00001_f32.powf(p)
}

/// The crate's `norm`: f32 `safe_pow` per value, an f64 sum, divided by `count`.
fn norm(values: impl Iterator<Item = f32>, p: f32, count: usize) -> f32 {
    let sum: f64 = values.map(|x| safe_pow(x, p) as f64).sum();
    safe_pow((sum / count as f64) as f32, 1.0 / p)
}

/// `met2jod`, with its linear segment below Q = 0.1.
pub(crate) fn jod(q: f32) -> f32 {
    if q <= 0.1 {
        10.0 - JOD_A * 0.1_f32.powf(JOD_EXP - 1.0) * q
    } else {
        10.0 - JOD_A * q.powf(JOD_EXP)
    }
}

/// One prediction's pooled differences, `quality[(channel * frames + frame) * bands + band]`.
pub(crate) struct Features<'a> {
    pub quality: &'a [f32],
    pub channels: usize,
    pub frames: usize,
    pub bands: usize,
}

impl Features<'_> {
    /// One channel of one frame, pooled over bands and weighted (Q_sc in the reference).
    fn channel(&self, c: usize, f: usize) -> f32 {
        let b_last = self.bands - 1;
        norm(
            (0..self.bands).map(|b| {
                let w = if b == b_last { BASEBAND_WEIGHT[c] } else { 1.0 };
                self.quality[(c * self.frames + f) * self.bands + b] * CHANNEL_WEIGHTS[c] * w
            }),
            BETA_SCH,
            1,
        )
    }

    /// The pooled difference of each frame, as the frame-pooling step sees it (an image's one
    /// value already scaled by image_int).
    pub fn per_frame(&self) -> Vec<f32> {
        let scale = if self.frames == 1 { IMAGE_INT } else { 1.0 };
        (0..self.frames)
            .map(|f| norm((0..self.channels).map(|c| self.channel(c, f)), BETA_TCH, 1) * scale)
            .collect()
    }

    /// Per frame: (the transient channel's band-pooled difference, the beta_tch power sum over
    /// all channels). `None` for an image (no transient channel).
    pub fn transient(&self) -> Option<Vec<(f32, f64)>> {
        (self.channels > TRANSIENT).then(|| {
            (0..self.frames)
                .map(|f| {
                    let total = (0..self.channels)
                        .map(|c| safe_pow(self.channel(c, f), BETA_TCH) as f64)
                        .sum();
                    (self.channel(TRANSIENT, f), total)
                })
                .collect()
        })
    }
}

/// Pools per-frame differences over frames (the mean Lp norm, beta_t) and maps them to JOD. One
/// frame on its own pools to itself, so a shot's frames and several shots' frames pool alike.
pub(crate) fn pool_frames(per_frame: &[f32]) -> f32 {
    if per_frame.len() == 1 {
        return jod(per_frame[0]);
    }
    jod(norm(per_frame.iter().copied(), BETA_T, per_frame.len()))
}

/// The transient channel's share of the visible difference: its beta_tch power over all
/// channels', summed over frames; 0 when there is no difference at all.
pub(crate) fn transient_share(per_frame: &[(f32, f64)]) -> f64 {
    let total: f64 = per_frame.iter().map(|&(_, t)| t).sum();
    if total <= 0.0 {
        return 0.0;
    }
    let transient: f64 = per_frame
        .iter()
        .map(|&(q, _)| safe_pow(q, BETA_TCH) as f64)
        .sum();
    (transient / total).clamp(0.0, 1.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use colorvideovdp::{Color, Cvvdp, DisplayModel, Execution, Image, Options};

    fn frames(n: usize, amplitude: f32) -> (Vec<Image>, Vec<Image>) {
        let (w, h) = (32, 24);
        let base: Vec<f32> = (0..w * h * 3)
            .map(|i| 0.3 + 0.4 * ((i / 3 % w) as f32 / w as f32))
            .collect();
        let reference = vec![Image::new(w, h, 3, base.clone()).unwrap(); n];
        let test = (0..n)
            .map(|f| {
                let s = if f % 2 == 0 { amplitude } else { -amplitude };
                let d = base
                    .iter()
                    .enumerate()
                    .map(|(i, v)| v + s + 0.02 * ((i % 7) as f32 / 7.0));
                Image::new(w, h, 3, d.collect()).unwrap()
            })
            .collect();
        (test, reference)
    }

    #[test]
    fn pooling_reproduces_the_crate() {
        let metric = Cvvdp::new(
            DisplayModel::from_name("standard_4k").unwrap(),
            Options::default().with_execution(Execution::SingleThread),
        )
        .unwrap();
        for n in [1, 6] {
            let (t, r) = frames(n, 0.15);
            let p = metric.predict_video(&t, &r, 30.0, Color::Srgb).unwrap();
            let features = Features {
                quality: &p.quality_per_channel,
                channels: p.channels,
                frames: p.frames,
                bands: p.band_frequencies.len(),
            };
            let ours = pool_frames(&features.per_frame());
            assert!(p.jod < 9.9, "the test pair must differ visibly: {}", p.jod);
            assert!(
                (ours - p.jod).abs() < 1e-5,
                "{n} frames: {ours} vs {}",
                p.jod
            );
            assert_eq!(features.transient().is_some(), n > 1);
        }
    }

    #[test]
    fn share_is_a_fraction_and_zero_without_difference() {
        assert_eq!(transient_share(&[(0.0, 0.0), (0.0, 0.0)]), 0.0);
        let s = transient_share(&[(1.0, safe_pow(1.0, 4.0) as f64 * 2.0)]);
        assert!((s - 0.5).abs() < 1e-6, "{s}");
    }

    #[test]
    fn jod_is_10_without_difference_and_falls() {
        assert_eq!(jod(0.0), 10.0);
        assert!(jod(1.0) < jod(0.5) && jod(0.5) < jod(0.1));
    }
}
