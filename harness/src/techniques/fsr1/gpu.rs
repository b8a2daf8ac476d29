//! The GPU part of `fsr1`: a `scene` render pass at the render size (the ground's derivatives
//! scaled by the mip bias; with `input = "msaa4x"` into 4x multisampled targets resolved into
//! `color_low` at the end of the pass), an `easu` compute pass to the output size and, when RCAS is on, an
//! `rcas` compute pass (`fsr1.wgsl` after the shared `rcas.wgsl`; CPU models in `model.rs` and
//! `shared/rcas_model.rs`). With RCAS, EASU writes
//! perceptual values into `easu` and RCAS the linear output; without, EASU writes the output.

use std::collections::HashMap;

use super::{Input, Options};
use crate::gpu::Gpu;
use crate::render::graph::{Graph, PassKind, Plan, Res, TextureDesc};
use crate::render::kit::{allocate, record_scene_pass_resolved, TextureMap};
use crate::render::renderer::{FrameInfo, Renderer};
use crate::render::scene::{Objects, SceneGpu, ScenePipeline, View, COLOR_FORMAT, DEPTH_FORMAT};
use crate::render::timers::Timers;
use crate::techniques::shared::rcas::{rcas_pass, FsrPass, Params, RCAS_WGSL};

/// EASU, appended to the shared RCAS module whose bindings and encoding it uses.
pub static FSR1_WGSL: &str = include_str!("fsr1.wgsl");

/// The module the GPU compiles: `shared/rcas.wgsl` then `fsr1.wgsl`.
pub fn module() -> String {
    format!("{RCAS_WGSL}\n{FSR1_WGSL}")
}

/// The render-size scene targets, EASU's perceptual output (with RCAS) and the output.
const COLOR_LOW: Res = Res::new("color_low");
const DEPTH_LOW: Res = Res::new("depth_low");
const EASU: Res = Res::new("easu");
const COLOR: Res = Res::new("color");
/// The 4x multisampled scene targets (`input = "msaa4x"`), resolved into [`COLOR_LOW`].
const COLOR_MS: Res = Res::new("color_msaa");
const DEPTH_MS: Res = Res::new("depth_msaa");
/// MSAA sample count of the anti-aliased input.
const MSAA_SAMPLES: u32 = 4;

/// The pass graph at output `width` x `height`.
pub fn graph(options: &Options, width: u32, height: u32) -> Plan {
    let (lw, lh) = options.render_size(width, height);
    let tex = |format, width, height| TextureDesc {
        format,
        width,
        height,
        samples: 1,
        layers: 1,
    };
    let mut g = Graph::default();
    g.resource(COLOR_LOW, tex(COLOR_FORMAT, lw, lh))
        .resource(COLOR, tex(COLOR_FORMAT, width, height));
    match options.input {
        Input::Aliased => {
            g.resource(DEPTH_LOW, tex(DEPTH_FORMAT, lw, lh)).pass(
                "scene",
                PassKind::Render,
                &[],
                &[COLOR_LOW, DEPTH_LOW],
            );
        }
        Input::Msaa4x => {
            let ms = |format| TextureDesc {
                samples: MSAA_SAMPLES,
                ..tex(format, lw, lh)
            };
            g.resource(COLOR_MS, ms(COLOR_FORMAT))
                .resource(DEPTH_MS, ms(DEPTH_FORMAT))
                .pass(
                    "scene",
                    PassKind::Render,
                    &[],
                    &[COLOR_MS, DEPTH_MS, COLOR_LOW],
                );
        }
    }
    if options.rcas {
        g.resource(EASU, tex(COLOR_FORMAT, width, height))
            .pass("easu", PassKind::Compute, &[COLOR_LOW], &[EASU])
            .pass("rcas", PassKind::Compute, &[EASU], &[COLOR]);
    } else {
        g.pass("easu", PassKind::Compute, &[COLOR_LOW], &[COLOR]);
    }
    g.output(COLOR);
    g.plan().expect("built-in graphs are well formed")
}

pub struct Fsr1Gpu {
    plan: Plan,
    textures: HashMap<&'static str, wgpu::Texture>,
    options: Options,
    passes: Vec<FsrPass>,
    /// The scene pass's colour and depth targets, and its resolve target with MSAA.
    scene_views: (
        wgpu::TextureView,
        wgpu::TextureView,
        Option<wgpu::TextureView>,
    ),
}

impl Fsr1Gpu {
    pub fn new(gpu: &Gpu, options: Options, width: u32, height: u32) -> Fsr1Gpu {
        let device = &gpu.device;
        let plan = graph(&options, width, height);
        let textures = allocate(device, &plan);
        let view = |res: Res| textures.view(res);
        let (lw, lh) = options.render_size(width, height);
        let easu_params = |rcas: bool| Params {
            size: [lw, lh, width, height],
            rcas: [0.0, f32::from(u8::from(rcas)), 0.0, 0.0],
        };
        let module = module();
        let passes = match options.rcas_sharpness() {
            Some(sharpness) => vec![
                FsrPass::new(
                    gpu,
                    "easu",
                    &module,
                    (&view(COLOR_LOW), &view(EASU)),
                    easu_params(true),
                ),
                rcas_pass(
                    gpu,
                    (&view(EASU), &view(COLOR)),
                    (width, height),
                    sharpness,
                    false,
                ),
            ],
            None => vec![FsrPass::new(
                gpu,
                "easu",
                &module,
                (&view(COLOR_LOW), &view(COLOR)),
                easu_params(false),
            )],
        };
        let scene_views = match options.input {
            Input::Aliased => (view(COLOR_LOW), view(DEPTH_LOW), None),
            Input::Msaa4x => (view(COLOR_MS), view(DEPTH_MS), Some(view(COLOR_LOW))),
        };
        Fsr1Gpu {
            plan,
            textures,
            options,
            passes,
            scene_views,
        }
    }

    /// A texture of the plan by resource name (`color_low`, `easu`, `color`), for tests.
    pub fn texture(&self, name: &str) -> Option<&wgpu::Texture> {
        self.textures.get(name)
    }

    pub fn options(&self) -> Options {
        self.options
    }
}

impl Renderer for Fsr1Gpu {
    fn plan(&self) -> &Plan {
        &self.plan
    }

    fn output(&self) -> &wgpu::Texture {
        self.textures.texture(COLOR)
    }

    fn record(
        &mut self,
        gpu: &Gpu,
        scene: &mut SceneGpu,
        timers: &Timers,
        encoder: &mut wgpu::CommandEncoder,
        frame: FrameInfo,
    ) {
        let view = View {
            gradient_scale: self.options.gradient_scale(),
            ..View::whole(frame.time, frame.prev_time)
        };
        scene.write_view(&gpu.queue, 0, &view);
        let (color, depth, resolve) = &self.scene_views;
        let samples = match resolve {
            Some(_) => MSAA_SAMPLES,
            None => 1,
        };
        record_scene_pass_resolved(
            gpu,
            scene,
            timers,
            encoder,
            ("scene", 0, ScenePipeline::Forward { samples }, Objects::All),
            (color, resolve.as_ref()),
            depth,
            wgpu::LoadOp::Clear(0.0),
        );
        for p in &self.passes {
            p.record(timers, encoder);
        }
    }
}
