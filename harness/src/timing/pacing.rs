//! Frame-time stability (pacing) of a variant's measured frames: how far the slow frames are from
//! the typical one (p95 over p50, 1 for even frames), how much consecutive frames differ (mean
//! absolute difference), and, for techniques that alternate between two kinds of frame
//! (checkerboarding renders even and odd pixel sets on alternate frames), the same figures for
//! even and odd frames apart, whose medians may differ without any frame being irregular.

use tessera_results::conditions::{Pacing, ParityPacing};
use tessera_results::Summary;

/// Pacing of `frame_ms` (measured frames in order; `first_index` is the scenario frame index of
/// the first, which decides parity). `None` with fewer than 2 frames or a median of zero.
pub fn pacing(frame_ms: &[f64], first_index: u32, alternates: bool) -> Option<Pacing> {
    if frame_ms.len() < 2 {
        return None;
    }
    let s = Summary::of(frame_ms)?;
    if s.median <= 0.0 {
        return None;
    }
    let deltas: f64 = frame_ms.windows(2).map(|p| (p[1] - p[0]).abs()).sum();
    let mean_abs_delta_ms = deltas / (frame_ms.len() - 1) as f64;
    let parity = if alternates {
        let of = |parity: u32| -> Vec<f64> {
            frame_ms
                .iter()
                .enumerate()
                .filter(|(i, _)| (first_index + *i as u32) % 2 == parity)
                .map(|(_, v)| *v)
                .collect()
        };
        let (even, odd) = (Summary::of(&of(0))?, Summary::of(&of(1))?);
        Some(ParityPacing {
            even_median_ms: even.median,
            odd_median_ms: odd.median,
            even_over_odd: even.median / odd.median,
            even_p95_over_p50: even.p95 / even.median,
            odd_p95_over_p50: odd.p95 / odd.median,
        })
    } else {
        None
    };
    Some(Pacing {
        p95_over_p50: s.p95 / s.median,
        mean_abs_delta_ms,
        mean_abs_delta_rel: mean_abs_delta_ms / s.median,
        parity,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn even_frames_pace_at_one() {
        let p = pacing(&[4.0; 10], 3, false).unwrap();
        assert_eq!(p.p95_over_p50, 1.0);
        assert_eq!(p.mean_abs_delta_ms, 0.0);
        assert_eq!(p.parity, None);
        assert_eq!(pacing(&[4.0], 0, false), None);
    }

    #[test]
    fn alternating_frames_apart() {
        // Scenario frames 3, 4, 5, ...: odd frames 6 ms, even frames 4 ms.
        let frames: Vec<f64> = (0..10)
            .map(|i| if (3 + i) % 2 == 0 { 4.0 } else { 6.0 })
            .collect();
        let p = pacing(&frames, 3, true).unwrap();
        // Every step changes by 2 ms; the median of five 4s and five 6s is 5.
        assert_eq!(p.mean_abs_delta_ms, 2.0);
        assert!((p.mean_abs_delta_rel - 0.4).abs() < 1e-12);
        assert!((p.p95_over_p50 - 1.2).abs() < 1e-12);
        let parity = p.parity.unwrap();
        assert_eq!(parity.even_median_ms, 4.0);
        assert_eq!(parity.odd_median_ms, 6.0);
        assert!((parity.even_over_odd - 4.0 / 6.0).abs() < 1e-12);
        // Within each parity the frames are even.
        assert_eq!(parity.even_p95_over_p50, 1.0);
        assert_eq!(parity.odd_p95_over_p50, 1.0);
    }

    #[test]
    fn one_slow_frame_raises_p95() {
        let mut frames = vec![5.0; 19];
        frames.push(10.0);
        let p = pacing(&frames, 0, false).unwrap();
        // p95 of 20 values interpolates between the 19th (5) and the 20th (10): 5.25.
        assert!((p.p95_over_p50 - 1.05).abs() < 1e-12, "{}", p.p95_over_p50);
        assert!((p.mean_abs_delta_ms - 5.0 / 19.0).abs() < 1e-12);
    }
}
