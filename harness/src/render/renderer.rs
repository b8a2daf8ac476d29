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
    /// Why the frames just rendered are not the technique's (a pass it could not build on this
    /// device): the run loop then records the variant as failed with this reason instead of
    /// measuring empty frames. None by default.
    fn failure(&self) -> Option<String> {
        None
    }

    /// Render passes recorded outside wgpu (hardware variable-rate shading's raw Vulkan pass),
    /// which count their own fragment-shader invocations ([`Renderer::raw_invocations`]) instead
    /// of through [`Timers`]' queries. None by default.
    fn raw_passes(&self) -> &'static [&'static str] {
        &[]
    }

    /// Fragment-shader invocations of the [`Renderer::raw_passes`] of the last frame, asked for
    /// after each captured frame has completed. Empty by default.
    fn raw_invocations(&mut self, _gpu: &Gpu) -> std::collections::BTreeMap<String, u64> {
        std::collections::BTreeMap::new()
    }

    /// Per-frame values and images beyond the output, asked for after each captured frame has
    /// been submitted and waited for (never between timed frames): e.g. adaptive shading's
    /// average shading rate and shading-rate image. `frame` is the frame's output as read back;
    /// `image`: whether this frame is saved (make images only then). None by default.
    fn frame_extras(
        &mut self,
        _gpu: &Gpu,
        _frame: &tessera_metrics::HdrImage,
        _image: bool,
    ) -> FrameExtras {
        FrameExtras::default()
    }
}

/// What [`Renderer::frame_extras`] reports for one frame.
#[derive(Clone, Debug, Default)]
pub struct FrameExtras {
    /// Named values (e.g. `shading-rate`): each becomes a metric of the variant's own frames.
    pub values: Vec<(&'static str, f64)>,
    /// Named images (image kinds, e.g. `rate`: a shading-rate image), saved next to the frame's as
    /// `<variant>-<kind>-fNNN.png`.
    pub images: Vec<(&'static str, tessera_metrics::Rgb8Image)>,
}
