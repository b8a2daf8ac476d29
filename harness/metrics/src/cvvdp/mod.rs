//! ColorVideoVDP (Mantiuk et al., SIGGRAPH 2024): a test frame sequence against its reference as
//! a video on a display model, in JOD (10 = no visible difference; 1 JOD = 75% of viewers
//! prefer the higher). Computed by the `colorvideovdp` crate, a pure-Rust port of the reference
//! PyTorch implementation (PyPI `cvvdp`, model v0.5.7); `tools/crosscheck_cvvdp.py` checks it.
//!
//! For: the JOD of a sequence, per frame and per shot, the transient-channel share and its own
//! JOD ("perceptual flicker"), and distortion maps of chosen frames. Not for: decoding files
//! (see `sequence`), or deciding pass/fail.
//!
//! **Back ends.** A shot's pooled differences come from a [`ShotPredictor`]: [`CpuPredictor`]
//! (the crate, the reference) or `tessera-metrics-gpu`'s compute passes ([`cvvdp_with`]); the
//! shots, per-frame values, flicker and maps around it are computed here for both alike.
//!
//! **Shots.** Frames across a camera cut are not one video: each shot is predicted on its own
//! (the temporal filters start again, replicating the shot's first frame, the reference's
//! default padding), and the shots are pooled as the reference pools frames: JOD of the mean Lp
//! norm (beta_t = 2) of every frame's pooled difference. A sequence of one shot therefore gets
//! exactly the reference's JOD. A one-frame shot is an image to the reference (three channels,
//! scaled by image_int); its one value joins the pool as one frame.
//!
//! **Per frame.** The reference pools each frame to one difference before pooling frames; the
//! JOD of frame *f* is `met2jod` of that value: the JOD of a sequence whose every frame looked
//! like frame *f*.
//!
//! **Perceptual flicker.** A video has a fourth, achromatic transient channel besides the three
//! sustained ones. `transient_share` is that channel's part of the visible difference (its
//! beta_tch power over all channels', summed over frames; 0 to 1: near 1 is "shimmering", near
//! 0 "blurry or wrong but steady"); `flicker_jod` is the JOD of the transient channel alone
//! (10 = no visible temporal artefact).

mod display;
mod pool;

pub use display::{
    display_names, CustomDisplay, DisplaySpec, DEFAULT_DISPLAY, PAPER_27IN_4K, PAPER_27IN_4K_PPD,
};

use crate::{HdrImage, MetricsError, Rgb8Image};
use colorvideovdp::{Color, Cvvdp, Image, Options};
use pool::Features;
use serde::Serialize;

/// Luminance (cd/m²) that linear value 1.0 is shown at, by default: ITU-R BT.2408's HDR
/// reference white (203 cd/m²).
pub const DEFAULT_HDR_WHITE: f64 = 203.0;

/// A frame sequence as the harness has it.
#[derive(Debug, Clone, Copy)]
pub enum Frames<'a> {
    /// sRGB-encoded 8-bit frames (the SDR output), shown on the display's sRGB curve.
    Srgb(&'a [Rgb8Image]),
    /// Linear BT.709 frames (HDR), shown at `white` cd/m² per unit and clipped to the display's
    /// black and peak luminance (the reference's linear display model).
    Linear { frames: &'a [HdrImage], white: f64 },
}

impl Frames<'_> {
    fn len(&self) -> usize {
        match self {
            Self::Srgb(f) => f.len(),
            Self::Linear { frames, .. } => frames.len(),
        }
    }

    fn size(&self, i: usize) -> (u32, u32) {
        match self {
            Self::Srgb(f) => (f[i].width, f[i].height),
            Self::Linear { frames, .. } => (frames[i].width, frames[i].height),
        }
    }

    fn validate(&self) -> Result<(), MetricsError> {
        match self {
            Self::Srgb(f) => f.iter().try_for_each(Rgb8Image::validate),
            Self::Linear { frames, white } => {
                if !(white.is_finite() && *white > 0.0) {
                    return Err(MetricsError::InvalidParameter {
                        name: "hdr white luminance",
                        value: *white,
                        expected: "a positive, finite luminance in cd/m²",
                    });
                }
                frames.iter().try_for_each(HdrImage::validate)
            }
        }
    }

    /// Frame `i` as the crate's f32 image: sRGB values / 255, or linear values * white.
    fn image(&self, i: usize) -> Result<Image, MetricsError> {
        let (w, h) = self.size(i);
        let data: Vec<f32> = match self {
            Self::Srgb(f) => f[i].data.iter().map(|&v| v as f32 / 255.0).collect(),
            Self::Linear { frames, white } => {
                let white = *white as f32;
                frames[i].data.iter().map(|&v| v * white).collect()
            }
        };
        Image::new(w as usize, h as usize, 3, data).map_err(crate_error)
    }

    fn color(&self) -> Color {
        match self {
            Self::Srgb(_) => Color::Srgb,
            Self::Linear { .. } => Color::Linear,
        }
    }
}

/// How to compute ColorVideoVDP on a sequence.
#[derive(Debug, Clone, PartialEq)]
pub struct CvvdpSettings {
    pub display: DisplaySpec,
    /// Frames per second (the scenario's `1 / time_step`); ignored for one frame.
    pub fps: f64,
    /// Indices of the first frame of each shot after the first (camera cuts), ascending.
    pub cuts: Vec<usize>,
    /// Frames whose distortion map to keep (for saved frames); none computes no map at all.
    pub map_frames: Vec<usize>,
    /// Upper bound on the crate's working memory for one shot (its conservative estimate).
    pub memory_limit_bytes: usize,
}

impl Default for CvvdpSettings {
    fn default() -> Self {
        Self {
            display: DisplaySpec::default(),
            fps: 60.0,
            cuts: Vec::new(),
            map_frames: Vec::new(),
            memory_limit_bytes: 4 << 30,
        }
    }
}

/// One shot's own JOD.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ShotJod {
    pub first_frame: usize,
    pub frames: usize,
    pub jod: f64,
}

/// The raw distortion map of one frame: the reference's `heatmap="raw"`, `1 - JOD/10` per pixel
/// (0 = invisible, 0.1 = one JOD), not clipped.
#[derive(Debug, Clone, PartialEq)]
pub struct DistortionMap {
    pub frame: usize,
    pub width: u32,
    pub height: u32,
    pub values: Vec<f32>,
}

/// ColorVideoVDP of one test sequence against its reference.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CvvdpResult {
    /// The sequence's quality in JOD; 10 = no visible difference, higher is better.
    pub jod: f64,
    /// JOD per frame (see the module doc).
    pub frame_jod: Vec<f64>,
    /// JOD of the transient channel alone; `None` when no shot has two frames.
    pub flicker_jod: Option<f64>,
    /// The transient channel's share of the visible difference, 0 to 1; `None` as above.
    pub transient_share: Option<f64>,
    /// Per frame: the transient channel's own JOD and its share (empty when `flicker_jod` is
    /// `None`; a one-frame shot's frame has no transient difference).
    pub frame_flicker_jod: Vec<f64>,
    pub frame_transient_share: Vec<f64>,
    /// Each shot's own JOD (one entry when there is no cut).
    pub shots: Vec<ShotJod>,
    /// The display's label, pixels per degree and peak luminance.
    pub display: String,
    pub pixels_per_degree: f64,
    pub peak_luminance: f64,
    pub fps: f64,
    /// Maps of the frames asked for in [`CvvdpSettings::map_frames`] (not serialised).
    #[serde(skip)]
    pub maps: Vec<DistortionMap>,
}

fn crate_error(e: colorvideovdp::Error) -> MetricsError {
    MetricsError::Cvvdp {
        reason: e.to_string(),
    }
}

/// ColorVideoVDP of `test` against `reference` (same length, same size, same kind), computed by
/// the `colorvideovdp` crate on the CPU (the reference).
pub fn cvvdp(
    reference: Frames<'_>,
    test: Frames<'_>,
    settings: &CvvdpSettings,
) -> Result<CvvdpResult, MetricsError> {
    cvvdp_with(reference, test, settings, &mut CpuPredictor)
}

/// One shot of a sequence as a [`ShotPredictor`] gets it: the whole sequences, the shot's
/// frames in them, the display model and the frame rate.
pub struct Shot<'a> {
    pub reference: Frames<'a>,
    pub test: Frames<'a>,
    /// The shot's frames (sequence indices).
    pub frames: std::ops::Range<usize>,
    pub model: &'a colorvideovdp::DisplayModel,
    pub fps: f32,
    /// Frames of this shot (sequence indices, ascending) whose distortion map is wanted.
    pub map_frames: Vec<usize>,
    pub memory_limit_bytes: usize,
}

/// What predicting one shot gives: the crate's `Prediction` in the parts the pooling reads.
#[derive(Debug, Clone, PartialEq)]
pub struct ShotPrediction {
    /// The shot's JOD as the predictor pooled it; `None` pools `quality_per_channel` here (the
    /// crate's pooling, reproduced in `pool.rs`).
    pub jod: Option<f32>,
    /// Spatially pooled differences, `[(channel * frames + frame) * bands + band]`.
    pub quality_per_channel: Vec<f32>,
    /// 3 for a one-frame shot (an image), 4 for a video.
    pub channels: usize,
    /// Spatial bands, the baseband last.
    pub bands: usize,
    /// The distortion maps of `Shot::map_frames`: (sequence frame index, one value per pixel).
    pub maps: Vec<(usize, Vec<f32>)>,
}

/// Predicts ColorVideoVDP's pooled differences of one shot: the crate on the CPU
/// ([`CpuPredictor`]) or another back end (`tessera-metrics-gpu`'s compute passes).
pub trait ShotPredictor {
    type Error: From<MetricsError>;
    fn predict(&mut self, shot: &Shot<'_>) -> Result<ShotPrediction, Self::Error>;
}

/// The `colorvideovdp` crate on the CPU: the reference and the fallback.
#[derive(Debug, Default, Clone, Copy)]
pub struct CpuPredictor;

impl ShotPredictor for CpuPredictor {
    type Error = MetricsError;

    fn predict(&mut self, shot: &Shot<'_>) -> Result<ShotPrediction, MetricsError> {
        let metric = Cvvdp::new(
            shot.model.clone(),
            Options::default()
                .with_distortion_map(!shot.map_frames.is_empty())
                .with_memory_limit_bytes(shot.memory_limit_bytes),
        )
        .map_err(crate_error)?;
        let load = |frames: &Frames<'_>| -> Result<Vec<Image>, MetricsError> {
            shot.frames.clone().map(|i| frames.image(i)).collect()
        };
        let (t, r) = (load(&shot.test)?, load(&shot.reference)?);
        let p = metric
            .predict_video(&t, &r, shot.fps, shot.test.color())
            .map_err(crate_error)?;
        drop((t, r));
        let mut maps = Vec::new();
        if let Some(map) = &p.distortion_map {
            let px = map.width * map.height;
            for &f in &shot.map_frames {
                let k = f - shot.frames.start;
                maps.push((f, map.data[k * px..(k + 1) * px].to_vec()));
            }
        }
        Ok(ShotPrediction {
            jod: Some(p.jod),
            quality_per_channel: p.quality_per_channel,
            channels: p.channels,
            bands: p.band_frequencies.len(),
            maps,
        })
    }
}

/// [`cvvdp`] with the shots predicted by `predictor`; everything around the prediction (checks,
/// shots, per-frame and transient pooling, maps) is the same for every back end.
pub fn cvvdp_with<P: ShotPredictor>(
    reference: Frames<'_>,
    test: Frames<'_>,
    settings: &CvvdpSettings,
    predictor: &mut P,
) -> Result<CvvdpResult, P::Error> {
    let n = reference.len();
    if n == 0 || test.len() != n {
        return Err(MetricsError::SequenceLength {
            reference: n,
            test: test.len(),
        }
        .into());
    }
    if std::mem::discriminant(&reference) != std::mem::discriminant(&test) {
        return Err(MetricsError::KindMismatch {
            reference: kind(&reference),
            test: kind(&test),
        }
        .into());
    }
    reference.validate()?;
    test.validate()?;
    let (w, h) = reference.size(0);
    for i in 0..n {
        for (rw, rh) in [reference.size(i), test.size(i)] {
            crate::image::check_same_size(w, h, rw, rh)?;
        }
    }
    if w < 4 || h < 4 {
        return Err(MetricsError::TooSmall {
            metric: "ColorVideoVDP",
            min: 4,
            width: w,
            height: h,
        }
        .into());
    }
    if !(settings.fps.is_finite() && settings.fps > 0.0 && settings.fps <= 16384.0) {
        return Err(MetricsError::InvalidParameter {
            name: "fps",
            value: settings.fps,
            expected: "frames per second in (0, 16384]",
        }
        .into());
    }
    let mut starts = vec![0];
    for &c in &settings.cuts {
        if c <= *starts.last().unwrap_or(&0) || c >= n {
            return Err(MetricsError::InvalidParameter {
                name: "camera cut frame",
                value: c as f64,
                expected: "ascending frame indices inside the sequence, after frame 0",
            }
            .into());
        }
        starts.push(c);
    }
    let model = settings.display.model()?;
    let (ppd, peak) = (
        model.geometry.pixels_per_degree(),
        model.photometry.peak_luminance,
    );

    let mut per_frame = Vec::with_capacity(n);
    let mut transient = Vec::with_capacity(n);
    let mut any_video = false;
    let mut shots = Vec::with_capacity(starts.len());
    let mut maps = Vec::new();
    for (s, &first) in starts.iter().enumerate() {
        let end = starts.get(s + 1).copied().unwrap_or(n);
        let mut map_frames: Vec<usize> = settings
            .map_frames
            .iter()
            .copied()
            .filter(|f| (first..end).contains(f))
            .collect();
        map_frames.sort_unstable();
        map_frames.dedup();
        let shot = Shot {
            reference,
            test,
            frames: first..end,
            model: &model,
            fps: settings.fps as f32,
            map_frames,
            memory_limit_bytes: settings.memory_limit_bytes,
        };
        let p = predictor.predict(&shot)?;
        let features = Features {
            quality: &p.quality_per_channel,
            channels: p.channels,
            frames: end - first,
            bands: p.bands,
        };
        let q = features.per_frame();
        shots.push(ShotJod {
            first_frame: first,
            frames: end - first,
            jod: p.jod.unwrap_or_else(|| pool::pool_frames(&q)) as f64,
        });
        match features.transient() {
            Some(tr) => {
                any_video = true;
                transient.extend(tr);
            }
            None => transient.extend(q.iter().map(|&v| (0.0, v.powi(4) as f64))),
        }
        per_frame.extend(q);
        for (f, values) in p.maps {
            maps.push(DistortionMap {
                frame: f,
                width: w,
                height: h,
                values,
            });
        }
    }
    let jod = if shots.len() == 1 {
        shots[0].jod
    } else {
        pool::pool_frames(&per_frame) as f64
    };
    let (flicker_jod, transient_share, frame_flicker_jod, frame_transient_share) = if any_video {
        let tq: Vec<f32> = transient.iter().map(|&(q, _)| q).collect();
        (
            Some(pool::pool_frames(&tq) as f64),
            Some(pool::transient_share(&transient)),
            tq.iter().map(|&q| pool::jod(q) as f64).collect(),
            transient
                .iter()
                .map(|t| pool::transient_share(std::slice::from_ref(t)))
                .collect(),
        )
    } else {
        (None, None, Vec::new(), Vec::new())
    };
    maps.sort_by_key(|m| m.frame);
    Ok(CvvdpResult {
        jod,
        frame_jod: per_frame.iter().map(|&q| pool::jod(q) as f64).collect(),
        flicker_jod,
        transient_share,
        frame_flicker_jod,
        frame_transient_share,
        shots,
        display: settings.display.label(),
        pixels_per_degree: ppd,
        peak_luminance: peak,
        fps: settings.fps,
        maps,
    })
}

fn kind(f: &Frames<'_>) -> &'static str {
    match f {
        Frames::Srgb(_) => "sRGB 8-bit",
        Frames::Linear { .. } => "linear HDR",
    }
}

/// A distortion map in the reference's `threshold` colours with no context image
/// (`visualize_diff_map.py`: blue, cyan, green, yellow, red from 0 to 1 JOD per pixel, each
/// colour at luminance 0.5), as 8-bit sRGB.
pub fn cvvdp_heatmap(map: &DistortionMap) -> Rgb8Image {
    const COLORS: [[f32; 3]; 5] = [
        [0.2, 0.2, 1.0],
        [0.2, 1.0, 1.0],
        [0.2, 1.0, 0.2],
        [1.0, 1.0, 0.2],
        [1.0, 0.2, 0.2],
    ];
    let chroma = COLORS.map(|c| {
        let l = c[0] * 0.212656 + c[1] * 0.715158 + c[2] * 0.072186;
        c.map(|v| v / (l + 0.0001))
    });
    let mut data = Vec::with_capacity(map.values.len() * 3);
    for &v in &map.values {
        let x = v.clamp(0.0, 0.1) / 0.1 * 4.0;
        let i = (x.floor() as usize).min(3);
        let t = x - i as f32;
        for (a, b) in chroma[i].iter().zip(&chroma[i + 1]) {
            let value = (a * (1.0 - t) + b * t) * 0.5;
            data.push((value.clamp(0.0, 1.0) * 255.0).round() as u8);
        }
    }
    Rgb8Image {
        width: map.width,
        height: map.height,
        data,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn heatmap_runs_from_blue_to_red() {
        let map = DistortionMap {
            frame: 0,
            width: 3,
            height: 1,
            values: vec![0.0, 0.05, 0.5],
        };
        let img = cvvdp_heatmap(&map);
        let px = |i: usize| &img.data[i * 3..i * 3 + 3];
        assert!(px(0)[2] == 255 && px(0)[0] < 100, "{:?}", px(0));
        assert!(px(1)[1] > px(1)[0] && px(1)[1] > px(1)[2], "{:?}", px(1));
        assert!(px(2)[0] == 255 && px(2)[2] < 100, "{:?}", px(2));
    }
}
