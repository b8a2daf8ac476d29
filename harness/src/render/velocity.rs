//! The motion provider every reprojecting technique shares (`checkerboard`, `interlace`,
//! `taau`): camera motion is reconstructed from depth in the technique's own reconstruction
//! (its previous camera times the inverse of its current one), and object motion comes from this
//! pass, which draws the objects that move by themselves ([`Objects::Dynamic`]) with the scene's
//! velocity pipeline and its own depth buffer, at the resolution the technique renders and
//! through the view it renders with (`taau`'s jittered render-resolution view, so its depth
//! equals the scene pass's where the dynamic object is in front). That is how engines give
//! motion to a temporal technique (UE's velocity pass of movable objects, FSR 2's
//! render-resolution motion vectors, mosaiikki "Overview" 1: "Only dynamic objects; for static
//! objects camera reprojection is used in the reconstruction pass"). A static object in front
//! of a moving one is then not in the buffer; the reconstruction tells it by comparing
//! [`VELOCITY_DEPTH`] with its own depth. Drawing every object ([`Objects::All`]) stays
//! available as `checkerboard`'s `velocity_objects = "all"` option.
//!
//! Declared in the pass graph beside the technique's passes and read by its reconstruction only
//! where objects move by themselves and the technique's `velocity` option is on. Otherwise
//! nothing reads it, the graph culls it, and 1x1 placeholders are bound in its place, so one
//! bind group layout serves both.
//!
//! Infrastructure: knows no technique. Not for the motion target of the `tde` metric (native's
//! velocity-only forward path) or a technique's own motion pass drawn over a pre-conditioned
//! depth buffer.

use std::collections::HashMap;

use super::graph::{Graph, PassKind, Plan, Res, TextureDesc};
use super::kit::{placeholder_texture, record_scene_pass_on, TextureMap};
use super::scene::{Objects, SceneGpu, ScenePipeline, View, COLOR_FORMAT, DEPTH_FORMAT};
use super::timers::Timers;
use crate::gpu::Gpu;

/// The motion target the reconstruction reads.
pub const VELOCITY: Res = Res::new("velocity");
/// Its depth buffer (reversed-Z, cleared to 0: 0 where nothing was drawn).
pub const VELOCITY_DEPTH: Res = Res::new("velocity_depth");
/// The pass's name in the plan and the timings.
pub const PASS: &str = "velocity";
/// How much nearer (relative, in reversed-Z) a technique's own depth at a sample may be than
/// [`VELOCITY_DEPTH`] there before a static object is taken to hide the dynamic one the motion
/// pass drew: the two rasterise the same triangles at the same sample and differ only by the
/// rounding of their vertex transforms. The reconstruction shaders carry the same constant.
pub const MOTION_DEPTH_EPSILON: f32 = 1e-4;

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
    depth_binding: wgpu::TextureView,
    _placeholders: Vec<wgpu::Texture>,
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
                depth_binding: textures.view(VELOCITY_DEPTH),
                _placeholders: Vec::new(),
            }
        } else {
            let t = placeholder_texture(device, "no velocity", COLOR_FORMAT);
            let d = placeholder_texture(device, "no velocity depth", DEPTH_FORMAT);
            VelocityPass {
                targets: None,
                binding: t.create_view(&Default::default()),
                depth_binding: d.create_view(&Default::default()),
                _placeholders: vec![t, d],
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

    /// What a reconstruction binds to compare depths: [`VELOCITY_DEPTH`], or a placeholder.
    pub fn depth_binding(&self) -> &wgpu::TextureView {
        &self.depth_binding
    }

    /// Records the pass when it runs: the whole, unjittered view of `time` (from `prev_time`)
    /// written to the scene's view `slot`, then [`VelocityPass::record_in`] that slot.
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
        objects: Objects,
    ) -> bool {
        if !self.runs() {
            return false;
        }
        scene.write_view(&gpu.queue, slot, &View::whole(time, prev_time));
        self.record_in(gpu, scene, timers, encoder, slot, objects)
    }

    /// Records the pass when it runs, in the view already written to `slot` this frame (a
    /// technique's own, e.g. jittered, render view): the velocity pipeline drawing `objects`
    /// into the targets, timed as [`PASS`]. Returns [`VelocityPass::runs`].
    pub fn record_in(
        &self,
        gpu: &Gpu,
        scene: &mut SceneGpu,
        timers: &Timers,
        encoder: &mut wgpu::CommandEncoder,
        slot: u32,
        objects: Objects,
    ) -> bool {
        let Some((color, depth)) = &self.targets else {
            return false;
        };
        record_scene_pass_on(
            gpu,
            scene,
            timers,
            encoder,
            (PASS, slot, ScenePipeline::Velocity, objects),
            color,
            depth,
            wgpu::LoadOp::Clear(0.0),
        );
        true
    }
}
