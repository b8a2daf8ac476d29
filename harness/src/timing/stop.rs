//! The stop rule of `measured = "auto"`: keep rendering measured frames until the median GPU frame
//! time is known to a target relative precision, or a cap is reached (a frame count, or a wall
//! time since the first measured frame).
//!
//! Modelled on nvbench (at least a minimum of samples, then stop once the estimate is tight, with
//! a ceiling and a timeout, 15 s by default as nvbench's): the estimate here is the median, and its precision the half-width of its
//! distribution-free 95% confidence interval over the median
//! ([`tessera_results::conditions::median_precision`]). The rule is checked at every frame up to
//! 64, then every n/32 frames (sorting n samples each frame would put O(n log n) CPU work between
//! frames of a long run); `min` and `max` are always checked.

use tessera_results::conditions::{median_precision, Sampling, SamplingMode, StopReason};

/// Default target: the 95% interval of the median within ±0.5% of it.
pub const DEFAULT_PRECISION: f64 = 0.005;
/// Default least number of measured frames (nvbench's minimum sample count).
pub const AUTO_MIN: i64 = 10;
/// Default cap on measured frames.
pub const AUTO_MAX: i64 = 2000;
/// Default cap on the wall time of the measured frames, in seconds (nvbench's timeout).
pub const AUTO_TIMEOUT_S: f64 = 15.0;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AutoRule {
    pub min: u32,
    pub max: u32,
    /// Relative half-width of the median's 95% interval to reach (0.005 = 0.5%).
    pub precision: f64,
    /// Wall time after which sampling ends whatever the precision (once `min` frames are in).
    pub timeout_s: f64,
}

impl AutoRule {
    fn checkpoint(&self, n: u32) -> bool {
        let step = (n / 32).max(1);
        n == self.min || n >= self.max || n < 64 || n / step * step == n
    }

    /// After `frame_ms.len()` measured frames and `elapsed_s` seconds since the first began:
    /// `Some(reason)` to stop, `None` to render another.
    pub fn decide(&self, frame_ms: &[f64], elapsed_s: f64) -> Option<StopReason> {
        let n = frame_ms.len() as u32;
        let timed_out = elapsed_s >= self.timeout_s;
        if n < self.min || !(self.checkpoint(n) || timed_out) {
            return None;
        }
        if median_precision(frame_ms).is_some_and(|p| p <= self.precision) {
            Some(StopReason::Precision)
        } else if n >= self.max {
            Some(StopReason::Cap)
        } else if timed_out {
            Some(StopReason::Timeout)
        } else {
            None
        }
    }

    /// The result's record once sampling ended with `reason` after `frame_ms`.
    pub fn record(&self, frame_ms: &[f64], reason: StopReason) -> Sampling {
        Sampling {
            mode: SamplingMode::Auto,
            frames: frame_ms.len() as u32,
            min: Some(self.min),
            max: Some(self.max),
            target_precision: Some(self.precision),
            timeout_s: Some(self.timeout_s),
            precision: median_precision(frame_ms),
            ended_by: reason,
        }
    }
}

/// The record of a fixed count of measured frames.
pub fn fixed_record(frame_ms: &[f64]) -> Sampling {
    Sampling {
        mode: SamplingMode::Fixed,
        frames: frame_ms.len() as u32,
        min: None,
        max: None,
        target_precision: None,
        timeout_s: None,
        precision: median_precision(frame_ms),
        ended_by: StopReason::Count,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A deterministic fake frame-time source: 5 ms with uniform noise of ±`spread` (relative),
    /// from a fixed linear congruential sequence.
    struct FakeFrames {
        state: u64,
        spread: f64,
    }

    impl FakeFrames {
        fn new(spread: f64) -> FakeFrames {
            FakeFrames { state: 42, spread }
        }
        fn next(&mut self) -> f64 {
            self.state = self
                .state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            let u = (self.state >> 11) as f64 / (1u64 << 53) as f64;
            5.0 * (1.0 + self.spread * (2.0 * u - 1.0))
        }
    }

    /// The render loop's use of the rule: one frame, then a decision. The clock is fake: each
    /// frame advances it by its own time.
    fn sample_until(rule: &AutoRule, source: &mut FakeFrames) -> (Vec<f64>, StopReason) {
        let mut frames = Vec::new();
        let mut clock_s = 0.0;
        loop {
            let ms = source.next();
            clock_s += ms / 1000.0;
            frames.push(ms);
            if let Some(reason) = rule.decide(&frames, clock_s) {
                return (frames, reason);
            }
        }
    }

    #[test]
    fn quiet_frames_stop_on_precision_noisy_frames_at_the_cap() {
        let rule = AutoRule {
            min: 10,
            max: 2000,
            precision: DEFAULT_PRECISION,
            timeout_s: 60.0,
        };
        // ±2% noise: the interval of the median shrinks as 1/sqrt(n) and meets 0.5% well before
        // the cap.
        let (frames, reason) = sample_until(&rule, &mut FakeFrames::new(0.02));
        assert_eq!(reason, StopReason::Precision);
        assert!(frames.len() > 10 && frames.len() < 2000, "{}", frames.len());
        let record = rule.record(&frames, reason);
        assert!(record.precision.unwrap() <= 0.005);
        assert_eq!(record.frames as usize, frames.len());
        // The frame before the stop was not yet precise enough (the rule checks every frame
        // below 64, and every n/32 frames beyond).
        let n = frames.len();
        let previous_check = if n <= 64 { n - 1 } else { n - n / 32 };
        assert!(median_precision(&frames[..previous_check]).unwrap() > 0.005);

        // ±60% noise cannot reach 0.5% in 200 frames: the cap ends it, after exactly max frames.
        let capped = AutoRule { max: 200, ..rule };
        let (frames, reason) = sample_until(&capped, &mut FakeFrames::new(0.6));
        assert_eq!((frames.len(), reason), (200, StopReason::Cap));
        let record = capped.record(&frames, reason);
        assert!(record.precision.unwrap() > 0.005);
        assert_eq!(record.ended_by, StopReason::Cap);

        // The same noise with a 0.5 s timeout: 5 ms frames, so it ends after about 100 frames
        // (the first whose fake clock passes 0.5 s), before the frame cap.
        let timed = AutoRule {
            timeout_s: 0.5,
            ..rule
        };
        let (frames, reason) = sample_until(&timed, &mut FakeFrames::new(0.6));
        assert_eq!(reason, StopReason::Timeout);
        let total: f64 = frames.iter().sum();
        assert!(
            total >= 500.0 && total - frames.last().unwrap() < 500.0,
            "{total}"
        );
    }

    #[test]
    fn constant_frames_stop_at_min_never_before() {
        let rule = AutoRule {
            min: 8,
            max: 100,
            precision: 0.005,
            timeout_s: 15.0,
        };
        let frames = vec![4.0; 7];
        assert_eq!(rule.decide(&frames, 0.0), None);
        // Not even a timeout ends it before `min` frames.
        assert_eq!(rule.decide(&frames, 100.0), None);
        let frames = vec![4.0; 8];
        assert_eq!(rule.decide(&frames, 0.0), Some(StopReason::Precision));
        // With fewer than 6 frames there is no interval: only the caps can end it.
        let tiny = AutoRule {
            min: 1,
            max: 3,
            precision: 0.005,
            timeout_s: 15.0,
        };
        assert_eq!(tiny.decide(&[4.0, 4.0], 0.0), None);
        assert_eq!(tiny.decide(&[4.0, 4.0], 15.0), Some(StopReason::Timeout));
        assert_eq!(tiny.decide(&[4.0, 4.0, 4.0], 0.0), Some(StopReason::Cap));
    }

    #[test]
    fn fixed_counts_are_recorded_as_such() {
        let r = fixed_record(&[1.0; 10]);
        assert_eq!(r.mode, SamplingMode::Fixed);
        assert_eq!(r.ended_by, StopReason::Count);
        assert_eq!(r.frames, 10);
        assert_eq!(r.precision, Some(0.0));
    }
}
