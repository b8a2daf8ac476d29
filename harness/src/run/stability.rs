//! Stability checks on every result (issue 8): non-finite pixels and whether a technique spread
//! them beyond the reference's, determinism (the same sequence rendered twice), and whether the
//! error is back at its steady level within 2 frames of a camera cut. Pure functions over frames
//! already read back; nothing here touches the GPU.

use tessera_metrics::Rgb8Image;
use tessera_results::{CutRecovery, Stability};

use super::plan::Plan;

/// How far (in PSNR dB) the second frame after a cut may stay below the steady level.
pub const CUT_TOLERANCE_DB: f64 = 1.0;

/// Frames after a cut (the cut frame included) that are not part of the steady level.
const SETTLE_FRAMES: u32 = 3;

/// The error around each cut: `mse` holds one value per measured frame. A cut's steady level is
/// the median error of its own shot (the new view's content sets the level) from
/// [`SETTLE_FRAMES`] after the cut to the next cut.
pub fn cut_recovery(mse: &[f64], cuts: &[u32]) -> Vec<CutRecovery> {
    // PSNR within `tol` dB of the steady PSNR  <=>  MSE within a factor 10^(tol/10) of it.
    let factor = 10f64.powf(CUT_TOLERANCE_DB / 10.0);
    cuts.iter()
        .enumerate()
        .map(|(i, &c)| {
            let shot_end = cuts.get(i + 1).map_or(mse.len(), |&n| n as usize);
            let mut steady: Vec<f64> = mse
                .get((c + SETTLE_FRAMES) as usize..shot_end)
                .unwrap_or(&[])
                .to_vec();
            steady.sort_by(|a, b| a.total_cmp(b));
            let n = steady.len();
            let steady_mse = (n > 0).then(|| {
                if n % 2 == 1 {
                    steady[n / 2]
                } else {
                    0.5 * (steady[n / 2 - 1] + steady[n / 2])
                }
            });
            let window: Vec<f64> = (c..c + SETTLE_FRAMES)
                .filter_map(|m| mse.get(m as usize).copied())
                .collect();
            let recovered = match (steady_mse, window.get(2)) {
                (Some(s), Some(&after)) => Some(after <= s * factor + 1e-12),
                _ => None,
            };
            CutRecovery {
                frame: c,
                mse: window,
                steady_mse,
                recovered,
                tolerance_db: CUT_TOLERANCE_DB,
            }
        })
        .collect()
}

/// A render's measured frames and, per frame, its non-finite pixels (bit per pixel; `None` for a
/// frame without any).
pub struct Frames<'a> {
    pub frames: &'a [Rgb8Image],
    pub masks: &'a [Option<Vec<u64>>],
}

/// The stability record of one rendered variant. `reference` is `None` without a reference render
/// (then spread and cut recovery are not measured).
/// `deterministic`: whether the second render of the sequence ended on the same bits.
/// `mse`: per measured frame, the MSE against the reference when the metrics computed it (the
/// GPU's: the frames are then not on the CPU); else it is computed here from the frames.
pub fn check(
    plan: &Plan<'_>,
    own: Frames<'_>,
    deterministic: Option<bool>,
    reference: Option<Frames<'_>>,
    mse: Option<&[f64]>,
) -> Stability {
    let non_finite_pixels = own
        .masks
        .iter()
        .flatten()
        .map(|m| m.iter().map(|w| w.count_ones() as u64).sum::<u64>())
        .sum();
    let (spread, cuts) = match reference {
        Some(r) => {
            let spread = own
                .masks
                .iter()
                .enumerate()
                .map(|(i, m)| {
                    spread_pixels(m.as_deref(), r.masks.get(i).and_then(|x| x.as_deref()))
                })
                .sum();
            let cut_list = &plan.cuts;
            let cuts = if cut_list.is_empty() {
                Vec::new()
            } else {
                let mse: Vec<f64> = match mse {
                    Some(m) => m.to_vec(),
                    None => own
                        .frames
                        .iter()
                        .zip(r.frames)
                        .map(|(t, r)| tessera_metrics::mse_rgb(r, t).unwrap_or(f64::INFINITY))
                        .collect(),
                };
                cut_recovery(&mse, cut_list)
            };
            (Some(spread), cuts)
        }
        None => (None, Vec::new()),
    };
    Stability {
        non_finite_pixels,
        spread_pixels: spread,
        deterministic,
        cuts,
    }
}

/// Pixels set in `mask` but not in `reference` (the non-finite pixels a technique added).
pub fn spread_pixels(mask: Option<&[u64]>, reference: Option<&[u64]>) -> u64 {
    match (mask, reference) {
        (None, _) => 0,
        (Some(m), None) => m.iter().map(|w| w.count_ones() as u64).sum(),
        (Some(m), Some(r)) => m
            .iter()
            .zip(r.iter().chain(std::iter::repeat(&0)))
            .map(|(a, b)| (a & !b).count_ones() as u64)
            .sum(),
    }
}

/// Cuts whose error had not come back to the steady level 2 frames later (the `unrecovered_cuts`
/// measure, defined with the others in `tessera_results::measure`).
pub use tessera_results::measure::unrecovered_cuts;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn recovered_within_two_frames() {
        // Steady MSE 4; a cut at frame 4 with errors 40, 10, 4.5 (within 1 dB: factor 1.259).
        let mse = [9.0, 9.0, 9.0, 9.0, 40.0, 10.0, 4.5, 4.0, 4.0, 4.0];
        let r = cut_recovery(&mse, &[4]);
        assert_eq!(r.len(), 1);
        assert_eq!(r[0].frame, 4);
        assert_eq!(r[0].mse, vec![40.0, 10.0, 4.5]);
        assert_eq!(r[0].steady_mse, Some(4.0));
        assert_eq!(r[0].recovered, Some(true));
    }

    #[test]
    fn ghosting_after_a_cut_is_caught() {
        // Still twice the steady error 2 frames after the cut: 3 dB worse.
        let mse = [4.0, 4.0, 4.0, 4.0, 40.0, 20.0, 8.0, 4.0, 4.0, 4.0];
        let r = cut_recovery(&mse, &[4]);
        assert_eq!(r[0].recovered, Some(false));
        let s = Stability {
            non_finite_pixels: 0,
            spread_pixels: Some(0),
            deterministic: Some(true),
            cuts: r,
        };
        assert_eq!(unrecovered_cuts(&s), 1);
    }

    #[test]
    fn the_steady_level_is_the_new_shots() {
        // Shot 1 is easy (MSE 1), shot 2 harder (MSE 10) but settled by its second frame.
        let mse = [
            1.0, 1.0, 1.0, 1.0, 80.0, 10.0, 10.0, 10.0, 10.0, 30.0, 3.0, 3.0,
        ];
        let r = cut_recovery(&mse, &[4, 9]);
        assert_eq!(r[0].steady_mse, Some(10.0));
        assert_eq!(r[0].recovered, Some(true));
        // The last shot has 3 frames: no steady frame after its settling window.
        assert_eq!(r[1].mse, vec![30.0, 3.0, 3.0]);
        assert_eq!(r[1].steady_mse, None);
        assert_eq!(r[1].recovered, None);
    }

    #[test]
    fn no_steady_level_without_settled_frames() {
        // A cut every frame: nothing is steady, so nothing is judged.
        let mse = [9.0, 9.0, 9.0, 9.0];
        let r = cut_recovery(&mse, &[0, 1, 2, 3]);
        assert!(r
            .iter()
            .all(|c| c.steady_mse.is_none() && c.recovered.is_none()));
    }

    #[test]
    fn identical_frames_recover_exactly() {
        let mse = [0.0; 8];
        let r = cut_recovery(&mse, &[3]);
        assert_eq!(r[0].steady_mse, Some(0.0));
        assert_eq!(r[0].recovered, Some(true));
        let r = cut_recovery(&[0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0], &[3]);
        assert_eq!(r[0].recovered, Some(false));
    }

    #[test]
    fn spread_counts_only_new_pixels() {
        let reference = vec![0b0110u64];
        assert_eq!(spread_pixels(Some(&[0b0110]), Some(&reference)), 0);
        assert_eq!(spread_pixels(Some(&[0b1111]), Some(&reference)), 2);
        assert_eq!(spread_pixels(Some(&[0b1000]), None), 1);
        assert_eq!(spread_pixels(None, Some(&reference)), 0);
    }
}
