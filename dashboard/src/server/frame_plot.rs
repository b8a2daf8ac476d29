//! The plot both per-frame chart modules draw on (`frame_charts.rs`, one variant synced with the
//! viewer; `run_frame_charts.rs`, every variant of a scenario on the run page): the frame range
//! across, the value range up, the axes' labels and grid lines, and a series drawn as polylines
//! with a gap at every non-finite value (an infinite PSNR).

use std::fmt::Write;

use crate::html::{esc, num};

/// The chart's box (width, height and margins, in SVG units) and what it shows: frames `f0` to
/// `f1` across, values `lo` to `hi` up.
pub struct FramePlot {
    pub w: f64,
    pub h: f64,
    pub left: f64,
    pub right: f64,
    pub top: f64,
    pub bottom: f64,
    pub f0: u32,
    pub f1: u32,
    pub lo: f64,
    pub hi: f64,
}

/// A box: width, height, left, right, top and bottom margins.
pub type Frame = [f64; 6];

impl FramePlot {
    /// The plot of every (frame, value) pair of `series` in `frame`: frames from the first to
    /// the last (at least one apart), values from the least to the greatest finite one (a
    /// constant series gets a band around its value; no finite value, 0 to 1).
    pub fn over<'a>(
        frame: Frame,
        series: impl Iterator<Item = (&'a [u32], &'a [f64])> + Clone,
    ) -> FramePlot {
        let frames = series.clone().flat_map(|(f, _)| f.iter().copied());
        let (f0, f1) = frames.fold((u32::MAX, 0), |(a, b), f| (a.min(f), b.max(f)));
        let f0 = if f0 == u32::MAX { 0 } else { f0 };
        let f1 = f1.max(f0 + 1);
        let finite = series
            .flat_map(|(_, v)| v.iter().copied())
            .filter(|v| v.is_finite());
        let (lo, hi) = finite.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        });
        let (lo, hi) = if !lo.is_finite() {
            (0.0, 1.0)
        } else if hi - lo < 1e-12 * hi.abs().max(1e-300) {
            (lo - 0.5 * lo.abs().max(1e-9), hi + 0.5 * hi.abs().max(1e-9))
        } else {
            (lo, hi)
        };
        let [w, h, left, right, top, bottom] = frame;
        FramePlot {
            w,
            h,
            left,
            right,
            top,
            bottom,
            f0,
            f1,
            lo,
            hi,
        }
    }

    /// SVG units per frame.
    pub fn dx(&self) -> f64 {
        (self.w - self.left - self.right) / f64::from(self.f1 - self.f0)
    }

    pub fn x(&self, f: u32) -> f64 {
        self.left + f64::from(f - self.f0) * self.dx()
    }

    pub fn y(&self, v: f64) -> f64 {
        self.top + (self.h - self.top - self.bottom) * (1.0 - (v - self.lo) / (self.hi - self.lo))
    }

    /// The value axis (the greatest and least value, each with a grid line) and the frame axis
    /// (the first and last frame).
    pub fn axes(&self, out: &mut String) {
        for v in [self.hi, self.lo] {
            let yy = self.y(v);
            let _ = write!(
                out,
                "<text x={} y={:.1} font-size=10 text-anchor=end fill=#555>{}</text><line x1={} x2={} y1={yy:.1} y2={yy:.1} stroke=#eee />",
                self.left - 4.0,
                yy + 3.0,
                num(v),
                self.left,
                self.w - self.right
            );
        }
        let _ = write!(
            out,
            "<text x={} y={} font-size=10 fill=#555>frame {}</text><text x={} y={} font-size=10 text-anchor=end fill=#555>{}</text>",
            self.left,
            self.h - 4.0,
            self.f0,
            self.w - self.right,
            self.h - 4.0,
            self.f1
        );
    }

    /// `values` at `frames` as polylines of `stroke`, one per run of finite values, each titled
    /// `title` where given.
    pub fn lines(
        &self,
        out: &mut String,
        frames: &[u32],
        values: &[f64],
        stroke: &str,
        title: Option<&str>,
    ) {
        let mut runs: Vec<String> = vec![String::new()];
        for (&f, &v) in frames.iter().zip(values) {
            if !v.is_finite() {
                runs.push(String::new());
                continue;
            }
            let last = runs.last_mut().expect("one run");
            let _ = write!(last, "{:.1},{:.1} ", self.x(f), self.y(v));
        }
        let title = title.map_or(String::new(), |t| format!("<title>{}</title>", esc(t)));
        for pts in runs.iter().filter(|p| !p.is_empty()) {
            let _ = write!(
                out,
                "<polyline points=\"{}\" fill=none stroke=\"{stroke}\" stroke-width=1.5>{title}</polyline>",
                pts.trim()
            );
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_gap_at_every_non_finite_value_and_a_band_around_a_constant() {
        let frames = [0u32, 1, 2, 3, 4];
        let values = [1.0, 2.0, f64::INFINITY, 3.0, 4.0];
        let plot = FramePlot::over(
            [100.0, 50.0, 10.0, 0.0, 0.0, 10.0],
            std::iter::once((&frames[..], &values[..])),
        );
        assert_eq!((plot.f0, plot.f1, plot.lo, plot.hi), (0, 4, 1.0, 4.0));
        let mut out = String::new();
        plot.lines(&mut out, &frames, &values, "#000", None);
        assert_eq!(out.matches("<polyline").count(), 2, "{out}");
        let flat = [2.0, 2.0];
        let plot = FramePlot::over(
            [100.0, 50.0, 10.0, 0.0, 0.0, 10.0],
            std::iter::once((&frames[..2], &flat[..])),
        );
        assert!(plot.lo < 2.0 && plot.hi > 2.0, "{} {}", plot.lo, plot.hi);
    }
}
