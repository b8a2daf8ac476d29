//! The motion-blurred comparison (`reference.motion_blur`): before the metrics, every compared
//! frame, the reference's and each variant's, is filtered by a box of each pixel's motion along
//! that motion (`render/motion_blur.rs`). NVIDIA's adaptive shading derives its motion factors
//! (seeds/nvidia-adaptive-shading.txt, section 4, Eq. 17-24) for frames seen through that blur,
//! display persistence or an engine's motion blur, and judges them so (Fig. 9: "All results
//! shaded in lower rate look identical to the native rate shading after motion blur"); against a
//! sharp reference the errors motion hides are counted in full.
//!
//! The motion is the scene's own (the velocity pass of `tde`, `techniques::MotionPass`), rendered
//! for each captured frame right after the technique's frame, never during timed work. The
//! frame's checks (non-finite values, determinism) read the unblurred output; the metrics, the
//! saved images and frame hashes see the blurred one.

use crate::gpu::Gpu;
use crate::render::motion_blur::MotionBlur;
use crate::render::timers::Timers;
use crate::techniques::MotionPass;

/// The scene's motion pass and the blur, for one scenario's frames.
pub struct BlurredCapture {
    motion: MotionPass,
    timers: Timers,
    blur: MotionBlur,
}

impl BlurredCapture {
    pub fn new(gpu: &Gpu, width: u32, height: u32) -> Result<BlurredCapture, String> {
        Ok(BlurredCapture {
            motion: MotionPass::new(gpu, width, height),
            timers: Timers::new(&gpu.device, &[]).map_err(|e| e.to_string())?,
            blur: MotionBlur::new(gpu, width, height),
        })
    }

    /// The scene's velocity pass, to render frame `index`'s motion with (`frames.rs` submits it
    /// right after the technique's frame, with [`BlurredCapture::timers`]).
    pub fn motion_pass(&mut self) -> (&mut dyn crate::render::renderer::Renderer, &mut Timers) {
        (self.motion.renderer(), &mut self.timers)
    }

    /// `frame` blurred by the motion the velocity pass last rendered, or copied where the frame
    /// has no previous frame in its shot (`enabled` false). Waits for the GPU.
    pub fn blur(
        &mut self,
        gpu: &Gpu,
        frame: &wgpu::Texture,
        enabled: bool,
    ) -> Result<&wgpu::Texture, String> {
        let _ = self.timers.try_collect(&gpu.queue);
        let motion = self.motion.motion().create_view(&Default::default());
        self.blur.blur(gpu, frame, &motion, enabled)
    }
}
