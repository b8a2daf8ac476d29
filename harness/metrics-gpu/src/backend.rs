//! One metric interface, two back ends: [`MetricsBackend`], implemented by [`CpuMetrics`] (the
//! reference implementations of `tessera-metrics`, which stay the fallback) and by
//! [`GpuMetrics`]. Every value they return carries the [`Backend`] that computed it.
//!
//! For: callers that should not care where a metric runs (a run's evaluate step, `tessera
//! diff`). Not for: GPU-resident frames (use `GpuMetrics::evaluate` or
//! `GpuMetrics::sequence_frames` with `GpuFrame`s directly).

use serde::Serialize;
use tessera_metrics::{HdrImage, Rgb8Image};

use crate::context::GpuMetrics;
use crate::error::GpuMetricsError;
use crate::frame::GpuFrame;
use crate::pair::{Backend, FlipPooling, FlipValues, PairRequest, PairValues};

/// A reference/test pair as both back ends take it: 8-bit frames, and their linear floats when
/// HDR-FLIP is requested.
#[derive(Clone, Copy)]
pub struct Pair<'a> {
    pub reference: &'a Rgb8Image,
    pub test: &'a Rgb8Image,
    pub reference_hdr: Option<&'a HdrImage>,
    pub test_hdr: Option<&'a HdrImage>,
}

/// A reference/test sequence (same length); the HDR slices are empty or as long as the frames.
#[derive(Clone, Copy)]
pub struct Sequence<'a> {
    pub reference: &'a [Rgb8Image],
    pub test: &'a [Rgb8Image],
    pub reference_hdr: &'a [HdrImage],
    pub test_hdr: &'a [HdrImage],
}

/// What a sequence request gives: the pair values of every frame (the request of frame `i` is
/// `request(i)`), and flicker of frames 1.. of the test when asked.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SequenceValues {
    pub backend: Backend,
    pub frames: Vec<PairValues>,
    pub flicker: Option<Vec<f64>>,
}

/// The metrics, wherever they run.
pub trait MetricsBackend {
    /// Which back end this is (recorded with the results).
    fn backend(&self) -> Backend;

    /// The requested metrics of one pair.
    fn pair(
        &mut self,
        pair: Pair<'_>,
        request: &PairRequest,
    ) -> Result<PairValues, GpuMetricsError>;

    /// Flicker between two consecutive frames (mean absolute difference, 8-bit units).
    fn flicker(
        &mut self,
        previous: &Rgb8Image,
        current: &Rgb8Image,
    ) -> Result<f64, GpuMetricsError>;

    /// TDE of one frame (see `tessera_metrics::temporal_difference_error`).
    #[allow(clippy::too_many_arguments)]
    fn tde(
        &mut self,
        test_prev: &Rgb8Image,
        test: &Rgb8Image,
        reference_prev: &Rgb8Image,
        reference: &Rgb8Image,
        motion: &[[f32; 2]],
        valid: &[bool],
    ) -> Result<Option<f64>, GpuMetricsError>;

    /// Every frame of a sequence: `request(i)` for frame `i`, plus flicker when `flicker`.
    fn sequence(
        &mut self,
        seq: Sequence<'_>,
        request: &dyn Fn(usize) -> PairRequest,
        flicker: bool,
    ) -> Result<SequenceValues, GpuMetricsError> {
        let n = seq.reference.len().min(seq.test.len());
        let mut frames = Vec::with_capacity(n);
        for i in 0..n {
            frames.push(self.pair(pair_of(&seq, i), &request(i))?);
        }
        let flicker = if flicker {
            let mut v = Vec::new();
            for w in seq.test.windows(2) {
                v.push(self.flicker(&w[0], &w[1])?);
            }
            Some(v)
        } else {
            None
        };
        Ok(SequenceValues {
            backend: self.backend(),
            frames,
            flicker,
        })
    }
}

fn pair_of<'a>(seq: &Sequence<'a>, i: usize) -> Pair<'a> {
    Pair {
        reference: &seq.reference[i],
        test: &seq.test[i],
        reference_hdr: seq.reference_hdr.get(i),
        test_hdr: seq.test_hdr.get(i),
    }
}

/// The CPU back end: `tessera-metrics`, the reference.
#[derive(Debug, Default, Clone, Copy)]
pub struct CpuMetrics;

impl MetricsBackend for CpuMetrics {
    fn backend(&self) -> Backend {
        Backend::Cpu
    }

    fn pair(
        &mut self,
        pair: Pair<'_>,
        request: &PairRequest,
    ) -> Result<PairValues, GpuMetricsError> {
        use tessera_metrics as m;
        let (r, t) = (pair.reference, pair.test);
        let mut v = PairValues::empty(Backend::Cpu);
        if request.mse_rgb {
            v.mse_rgb = Some(m::mse_rgb(r, t)?);
        }
        if request.mse_luma {
            v.mse_luma = Some(m::mse_luma(r, t)?);
        }
        if request.max_abs {
            v.max_abs = Some(m::max_abs_error(r, t)?);
        }
        if request.ssim_rgb {
            v.ssim_rgb = Some(m::ssim_rgb(r, t)?);
        }
        if request.ssim_luma {
            v.ssim_luma = Some(m::ssim_luma(r, t)?);
        }
        if let Some(f) = &request.flip {
            let res = m::flip_ldr(r, t, f.pixels_per_degree)?;
            v.flip = Some(FlipValues {
                mean: res.mean,
                exact_mean: res.exact_mean,
                pooling: FlipPooling::FlipEvaluator,
                max: res.max,
                heatmap: f.heatmap.then(|| m::flip_heatmap(&res)),
                error_map: None,
            });
        }
        if let Some(f) = &request.flip_hdr {
            let (Some(rh), Some(th)) = (pair.reference_hdr, pair.test_hdr) else {
                return Err(hdr_missing(pair));
            };
            let res = m::flip_hdr(rh, th, &f.range, f.pixels_per_degree)?;
            v.flip_hdr = Some(FlipValues {
                mean: res.mean,
                exact_mean: res.exact_mean,
                pooling: FlipPooling::FlipEvaluator,
                max: res.max,
                heatmap: f.heatmap.then(|| m::flip_heatmap(&res)),
                error_map: None,
            });
        }
        Ok(v)
    }

    fn flicker(
        &mut self,
        previous: &Rgb8Image,
        current: &Rgb8Image,
    ) -> Result<f64, GpuMetricsError> {
        tessera_metrics::port::check_pair(previous, current)?;
        let sum: u64 = previous
            .data
            .iter()
            .zip(&current.data)
            .map(|(a, b)| a.abs_diff(*b) as u64)
            .sum();
        Ok(sum as f64 / current.data.len() as f64)
    }

    fn tde(
        &mut self,
        test_prev: &Rgb8Image,
        test: &Rgb8Image,
        reference_prev: &Rgb8Image,
        reference: &Rgb8Image,
        motion: &[[f32; 2]],
        valid: &[bool],
    ) -> Result<Option<f64>, GpuMetricsError> {
        Ok(tessera_metrics::temporal_difference_error(
            test_prev,
            test,
            reference_prev,
            reference,
            motion,
            valid,
        )?)
    }
}

fn hdr_missing(pair: Pair<'_>) -> GpuMetricsError {
    tessera_metrics::MetricsError::KindMismatch {
        reference: if pair.reference_hdr.is_some() {
            "HDR"
        } else {
            "LDR"
        },
        test: if pair.test_hdr.is_some() {
            "HDR"
        } else {
            "LDR"
        },
    }
    .into()
}

impl GpuMetrics {
    fn upload_pair_frame(
        &self,
        ldr: &Rgb8Image,
        hdr: Option<&HdrImage>,
        request: &PairRequest,
    ) -> Result<GpuFrame, GpuMetricsError> {
        self.upload(ldr, hdr.filter(|_| request.flip_hdr.is_some()))
    }
}

impl MetricsBackend for GpuMetrics {
    fn backend(&self) -> Backend {
        Backend::Gpu
    }

    fn pair(
        &mut self,
        pair: Pair<'_>,
        request: &PairRequest,
    ) -> Result<PairValues, GpuMetricsError> {
        tessera_metrics::port::check_pair(pair.reference, pair.test)?;
        if let Some(f) = &request.flip_hdr {
            let (Some(rh), Some(th)) = (pair.reference_hdr, pair.test_hdr) else {
                return Err(hdr_missing(pair));
            };
            // The CPU's checks (size, range, finite values) and messages.
            tessera_metrics::port::flip_hdr_check(rh, th, &f.range)?;
        }
        let r = self.upload_pair_frame(pair.reference, pair.reference_hdr, request)?;
        let t = self.upload_pair_frame(pair.test, pair.test_hdr, request)?;
        self.evaluate(&r, &t, request)
    }

    fn flicker(
        &mut self,
        previous: &Rgb8Image,
        current: &Rgb8Image,
    ) -> Result<f64, GpuMetricsError> {
        tessera_metrics::port::check_pair(previous, current)?;
        let a = self.upload(previous, None)?;
        let b = self.upload(current, None)?;
        self.flicker_frames(&a, &b)
    }

    fn tde(
        &mut self,
        test_prev: &Rgb8Image,
        test: &Rgb8Image,
        reference_prev: &Rgb8Image,
        reference: &Rgb8Image,
        motion: &[[f32; 2]],
        valid: &[bool],
    ) -> Result<Option<f64>, GpuMetricsError> {
        let up = |i: &Rgb8Image| self.upload(i, None);
        let (tp, t, rp, r) = (
            up(test_prev)?,
            up(test)?,
            up(reference_prev)?,
            up(reference)?,
        );
        self.tde_frames(&tp, &t, &rp, &r, motion, valid)
    }

    /// Uploads every frame once; flicker reuses the previous test frame on the device.
    fn sequence(
        &mut self,
        seq: Sequence<'_>,
        request: &dyn Fn(usize) -> PairRequest,
        flicker: bool,
    ) -> Result<SequenceValues, GpuMetricsError> {
        self.defer_running_means(true);
        let values = self.upload_sequence(seq, request, flicker);
        self.defer_running_means(false);
        values
    }
}

/// A frame's deferred flip-evaluator means: (frame, ticket, HDR-FLIP).
type Handed = Vec<(usize, crate::pool::Ticket, bool)>;

impl GpuMetrics {
    fn upload_sequence(
        &mut self,
        seq: Sequence<'_>,
        request: &dyn Fn(usize) -> PairRequest,
        flicker: bool,
    ) -> Result<SequenceValues, GpuMetricsError> {
        let n = seq.reference.len().min(seq.test.len());
        let mut frames = Vec::with_capacity(n);
        let mut handed: Handed = Vec::new();
        let mut flickers = Vec::new();
        let mut previous: Option<GpuFrame> = None;
        for i in 0..seq.test.len() {
            let req = if i < n {
                request(i)
            } else {
                PairRequest::default()
            };
            let pair = (i < n).then(|| pair_of(&seq, i));
            if let (Some(p), Some(f)) = (pair, &req.flip_hdr) {
                let (Some(rh), Some(th)) = (p.reference_hdr, p.test_hdr) else {
                    return Err(hdr_missing(p));
                };
                tessera_metrics::port::flip_hdr_check(rh, th, &f.range)?;
            }
            let t = self.upload_pair_frame(&seq.test[i], seq.test_hdr.get(i), &req)?;
            if let Some(p) = pair {
                tessera_metrics::port::check_pair(p.reference, p.test)?;
                let r = self.upload_pair_frame(p.reference, p.reference_hdr, &req)?;
                frames.push(self.evaluate(&r, &t, &req)?);
                handed.extend(self.take_handed_means().into_iter().map(|(k, h)| (i, k, h)));
            }
            if flicker {
                if let Some(prev) = &previous {
                    flickers.push(self.flicker_frames(prev, &t)?);
                }
            }
            previous = Some(t);
        }
        self.fill_running_means(&mut frames, handed)?;
        Ok(SequenceValues {
            backend: Backend::Gpu,
            frames,
            flicker: flicker.then_some(flickers),
        })
    }

    /// Sums the deferred flip-evaluator means and writes them into their frames' values.
    fn fill_running_means(
        &mut self,
        frames: &mut [PairValues],
        handed: Handed,
    ) -> Result<(), GpuMetricsError> {
        self.flush_running_means()?;
        for (i, ticket, hdr) in handed {
            let mean = self.take_running_mean(ticket)?;
            let v = if hdr {
                frames[i].flip_hdr.as_mut()
            } else {
                frames[i].flip.as_mut()
            };
            if let Some(v) = v {
                v.mean = mean;
            }
        }
        Ok(())
    }

    /// [`MetricsBackend::sequence`] of frames already on the device (made by
    /// [`GpuMetrics::frame_from_texture_with`]): the pair values of frame `i` of `reference`
    /// and `test` for `request(i)`, and flicker of the test's frames 1.. when asked. Nothing
    /// but the values comes back (and the heat maps requested); flip-evaluator means of the
    /// whole sequence are summed together at its end. The caller checks what the CPU checks of
    /// the images themselves (HDR-FLIP's finite values: the frames' non-finite counts).
    pub fn sequence_frames(
        &mut self,
        reference: &[GpuFrame],
        test: &[GpuFrame],
        request: &dyn Fn(usize) -> PairRequest,
        flicker: bool,
    ) -> Result<SequenceValues, GpuMetricsError> {
        self.defer_running_means(true);
        let values = self.device_sequence(reference, test, request, flicker);
        self.defer_running_means(false);
        values
    }

    fn device_sequence(
        &mut self,
        reference: &[GpuFrame],
        test: &[GpuFrame],
        request: &dyn Fn(usize) -> PairRequest,
        flicker: bool,
    ) -> Result<SequenceValues, GpuMetricsError> {
        let n = reference.len().min(test.len());
        let mut frames = Vec::with_capacity(n);
        let mut handed: Handed = Vec::new();
        for i in 0..n {
            frames.push(self.evaluate(&reference[i], &test[i], &request(i))?);
            handed.extend(self.take_handed_means().into_iter().map(|(k, h)| (i, k, h)));
        }
        let mut flickers = Vec::new();
        if flicker {
            for w in test.windows(2) {
                flickers.push(self.flicker_frames(&w[0], &w[1])?);
            }
        }
        self.fill_running_means(&mut frames, handed)?;
        Ok(SequenceValues {
            backend: Backend::Gpu,
            frames,
            flicker: flicker.then_some(flickers),
        })
    }
}
