//! The GPU side of a variant as the run loop drives it: [`Renderer`] (plan, output, per-frame
//! recording, per-frame extras), the per-frame facts it is given, and [`Unsupported`].
//!
//! Which renderer a variant gets is the technique's (`techniques/`); this module knows none.

use super::graph::Plan;
use super::scene::SceneGpu;
use super::timers::Timers;
use crate::gpu::Gpu;

/// Per-frame facts a technique needs.
#[derive(Clone, Copy, Debug)]
pub struct FrameInfo {
    /// Frame number from the first warm-up frame.
    pub index: u32,
    pub time: f64,
    pub prev_time: f64,
    /// False on the first frame and after a camera cut: techniques must not read history.
    pub history_valid: bool,
}

pub use crate::gpu::Unsupported;

/// A variant built on a device: what the run loop times and reads back.
pub trait Renderer {
    fn plan(&self) -> &Plan;
    /// The full-resolution Rgba16Float output of the frame.
    fn output(&self) -> &wgpu::Texture;
    fn record(
        &mut self,
        gpu: &Gpu,
        scene: &mut SceneGpu,
        timers: &Timers,
        encoder: &mut wgpu::CommandEncoder,
        frame: FrameInfo,
    );
    /// Fragment-shader invocations of the plan's [`Pass::self_counted`](super::graph::Pass)
    /// passes in the last frame, by pass, asked for after each captured frame has completed: the
    /// run loop records them as it records the timers' counts of the other passes. Empty by
    /// default.
    fn own_statistics(&mut self, _gpu: &Gpu) -> std::collections::BTreeMap<String, u64> {
        std::collections::BTreeMap::new()
    }

    /// Per-frame values and images beyond the output, asked for after each captured frame has
    /// been submitted and waited for (never between timed frames): e.g. adaptive shading's
    /// average shading rate and shading-rate image. `frame` is the saved frame's output in sRGB
    /// (empty when not saved); `image`: whether this frame is saved (make images only then).
    /// None by default.
    fn frame_extras(
        &mut self,
        _gpu: &Gpu,
        _frame: &tessera_metrics::Rgb8Image,
        _image: bool,
    ) -> FrameExtras {
        FrameExtras::default()
    }
}

/// What [`Renderer::frame_extras`] reports for one frame.
#[derive(Clone, Debug, Default)]
pub struct FrameExtras {
    /// Named values (e.g. `shading-rate`): each becomes a metric of the variant's own frames,
    /// with the unit and direction it declares here.
    pub values: Vec<FrameValue>,
    /// Named images (image kinds, e.g. `rate`: a shading-rate image), saved next to the frame's as
    /// `<variant>-<kind>-fNNN.png`.
    pub images: Vec<(&'static str, tessera_metrics::Rgb8Image)>,
}

/// One value a technique measures of its own frame (a check of its own, e.g. adaptive shading's
/// `shading-rate`), with its unit and which way is better: both travel with it into the result
/// (`MetricRecord::check`), so no shared table needs to know it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameValue {
    pub name: &'static str,
    pub value: f64,
    /// The CSV unit (`count`, `x`; empty for a plain ratio).
    pub unit: &'static str,
    pub direction: tessera_results::measure::Direction,
}

impl FrameValue {
    /// A value where lower is better.
    pub fn lower(name: &'static str, value: f64, unit: &'static str) -> FrameValue {
        FrameValue {
            name,
            value,
            unit,
            direction: tessera_results::measure::Direction::LowerIsBetter,
        }
    }

    /// A value with no better direction (a ratio that should be 1).
    pub fn neither(name: &'static str, value: f64, unit: &'static str) -> FrameValue {
        FrameValue {
            name,
            value,
            unit,
            direction: tessera_results::measure::Direction::Neither,
        }
    }
}
