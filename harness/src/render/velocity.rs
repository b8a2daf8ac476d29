//! The optional velocity pass that reprojecting techniques share: a full-resolution render of each
//! pixel's motion (the scene's velocity pipeline) with its own depth buffer, declared in the pass
//! graph beside the technique's passes and read by its reconstruction only where objects move by
//! themselves and the technique's `velocity` option is on. Otherwise nothing reads it, the graph
//! culls it, and a 1x1 placeholder is bound in its place, so one bind group layout serves both.
//!
//! Infrastructure: knows no technique. Not for the motion target of the `tde` metric (native's
//! velocity-only forward path) or a technique's own motion pass drawn over a pre-conditioned
//! depth buffer.

use std::collections::HashMap;

use super::graph::{Graph, PassKind, Plan, Res, TextureDesc};
use super::kit::{placeholder_texture, record_scene_pass, TextureMap};
use super::scene::{SceneGpu, ScenePipeline, View, COLOR_FORMAT, DEPTH_FORMAT};
use super::timers::Timers;
use crate::gpu::Gpu;

/// The motion target the reconstruction reads.
pub const VELOCITY: Res = Res::new("velocity");
/// Its depth buffer.
pub const VELOCITY_DEPTH: Res = Res::new("velocity_depth");
/// The pass's name in the plan and the timings.
pub const PASS: &str = "velocity";

/// Declares [`VELOCITY`], [`VELOCITY_DEPTH`] (both `width` x `height`) and the velocity pass in
/// `g`. It runs only when a later pass reads [`VELOCITY`]: the technique adds it to its
/// reconstruction's reads where objects move and its option asks for it.
pub fn declare(g: &mut Graph, width: u32, height: u32) {
    let tex = |format| TextureDesc {
        format,
        width,
        height,
        samples: 1,
        layers: 1,
    };
    g.resource(VELOCITY, tex(COLOR_FORMAT))
        .resource(VELOCITY_DEPTH, tex(DEPTH_FORMAT))
        .pass(PASS, PassKind::Render, &[], &[VELOCITY, VELOCITY_DEPTH]);
}

/// The velocity pass of a built variant: its targets when the plan keeps it, and what the
/// reconstruction binds either way.
pub struct VelocityPass {
    targets: Option<(wgpu::TextureView, wgpu::TextureView)>,
    binding: wgpu::TextureView,
    _placeholder: Option<wgpu::Texture>,
}

impl VelocityPass {
    /// From the plan's allocated `textures`: the pass runs when `plan` kept it.
    pub fn new(
        device: &wgpu::Device,
        plan: &Plan,
        textures: &HashMap<&'static str, wgpu::Texture>,
    ) -> VelocityPass {
        if plan.runs(PASS) {
            VelocityPass {
                targets: Some((textures.view(VELOCITY), textures.view(VELOCITY_DEPTH))),
                binding: textures.view(VELOCITY),
                _placeholder: None,
            }
        } else {
            let t = placeholder_texture(device, "no velocity", COLOR_FORMAT);
            VelocityPass {
                targets: None,
                binding: t.create_view(&Default::default()),
                _placeholder: Some(t),
            }
        }
    }

    /// Whether the pass runs (the reconstruction reads real motion).
    pub fn runs(&self) -> bool {
        self.targets.is_some()
    }

    /// What the reconstruction binds: the motion target, or the placeholder.
    pub fn binding(&self) -> &wgpu::TextureView {
        &self.binding
    }

    /// Records the pass when it runs: the whole, unjittered view of `time` (from `prev_time`)
    /// written to the scene's view `slot`, then the velocity pipeline into the targets, timed as
    /// [`PASS`]. Returns [`VelocityPass::runs`].
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &self,
        gpu: &Gpu,
        scene: &mut SceneGpu,
        timers: &Timers,
        encoder: &mut wgpu::CommandEncoder,
        slot: u32,
        time: f64,
        prev_time: f64,
    ) -> bool {
        let Some((color, depth)) = &self.targets else {
            return false;
        };
        scene.write_view(&gpu.queue, slot, &View::whole(time, prev_time));
        record_scene_pass(
            gpu,
            scene,
            timers,
            encoder,
            PASS,
            color,
            depth,
            slot,
            ScenePipeline::Velocity,
        );
        true
    }
}
