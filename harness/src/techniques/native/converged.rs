//! The converged ground-truth reference: `N` renders of the scene per frame at the output
//! resolution, the projection offset each time by one point of Roberts' R2 low-discrepancy
//! sequence inside the pixel, averaged in f32 (`accumulate.wgsl`). What a temporal
//! technique converges to on a still camera, told from native's aliasing; unlike the NxN
//! supersampled ground truth it needs no texture N times the output's size (32 samples at 4K
//! would be a 6x6 grid of 23040 x 12960 texels, beyond most adapters' limit).
//!
//! Sample pattern: R2 (Roberts 2018, "The unreasonable effectiveness of quasirandom sequences"),
//! a rank-1 lattice built on the plastic number, not the Halton (2, 3) points `taau` jitters with,
//! so a temporal technique is compared with an independent estimate of the same box-filtered
//! pixel. The ground's analytic filter width is scaled by 1/sqrt(N) (the samples' spacing), as
//! the NxN ground truth's renders are by 1/N;
//! texture gradients too (`material.wgsl`), so textures are sampled at the samples' spacing.

use glam::Vec2;

use crate::gpu::Gpu;
use crate::render::graph::{Graph, PassKind, Plan, TextureDesc};
use crate::render::kit::{allocate, bind_group, compute_pipeline};
use crate::render::renderer::{FrameInfo, Renderer, Unsupported};
use crate::render::scene::{SceneGpu, ScenePipeline, View, COLOR_FORMAT, DEPTH_FORMAT};
use crate::render::timers::Timers;

pub static ACCUMULATE_WGSL: &str = include_str!("accumulate.wgsl");

/// The plastic number, R2's generator: the real root of x^3 = x + 1.
const PLASTIC: f64 = 1.324_717_957_244_746;

/// Sample `n` of R2 in the pixel, relative to its centre (x right, y down), in (-0.5, 0.5).
pub fn r2(n: u32) -> Vec2 {
    let a1 = 1.0 / PLASTIC;
    let a2 = 1.0 / (PLASTIC * PLASTIC);
    let f = |a: f64| ((0.5 + a * n as f64).fract() - 0.5) as f32;
    Vec2::new(f(a1), f(a2))
}

/// Bytes the converged reference allocates at `width` x `height`: a colour and a depth target,
/// the f32 sum and the output.
pub fn bytes(width: u32, height: u32) -> u64 {
    let px = width as u64 * height as u64;
    px * (8 + 4 + 16 + 8)
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Params {
    size: [u32; 4],
}

pub struct Converged {
    plan: Plan,
    textures: std::collections::HashMap<&'static str, wgpu::Texture>,
    samples: u32,
    width: u32,
    height: u32,
    accumulate: wgpu::ComputePipeline,
    resolve: wgpu::ComputePipeline,
    /// Accumulate bind groups: the first sample (starts the sum), the others.
    groups: [wgpu::BindGroup; 2],
    resolve_group: wgpu::BindGroup,
    scene_views: (wgpu::TextureView, wgpu::TextureView),
    _buffers: Vec<wgpu::Buffer>,
}

/// The converged reference's pass graph: `samples` jittered scene passes and accumulations
/// recorded as one `scene` and one `accumulate` pass each (their timers are not read), then
/// `resolve`.
fn graph(width: u32, height: u32) -> Plan {
    let tex = |format| TextureDesc {
        format,
        width,
        height,
        samples: 1,
        layers: 1,
    };
    let mut g = Graph::default();
    g.resource("color_sample", tex(COLOR_FORMAT))
        .resource("depth_sample", tex(DEPTH_FORMAT))
        .resource("color", tex(COLOR_FORMAT))
        .pass(
            "scene",
            PassKind::Render,
            &[],
            &["color_sample", "depth_sample"],
        )
        .pass(
            "accumulate",
            PassKind::Compute,
            &["color_sample"],
            &["color"],
        )
        .output("color");
    g.plan().expect("built-in graphs are well formed")
}

impl Converged {
    pub fn new(gpu: &Gpu, width: u32, height: u32, samples: u32) -> Converged {
        use wgpu::util::DeviceExt;
        let device = &gpu.device;
        let plan = graph(width, height);
        let textures = allocate(device, &plan);
        let view = |name: &str| textures[name].create_view(&Default::default());
        let accumulate = compute_pipeline(device, "accumulate", ACCUMULATE_WGSL, "accumulate");
        let resolve = compute_pipeline(device, "resolve", ACCUMULATE_WGSL, "resolve");
        let sum = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("converged sum"),
            size: (width as u64 * height as u64 * 16).max(16),
            usage: wgpu::BufferUsages::STORAGE,
            mapped_at_creation: false,
        });
        let params = |first: u32| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("converged params"),
                contents: bytemuck::bytes_of(&Params {
                    size: [width, height, first, samples],
                }),
                usage: wgpu::BufferUsages::UNIFORM,
            })
        };
        let (first, rest) = (params(1), params(0));
        let src = view("color_sample");
        let layout = accumulate.get_bind_group_layout(0);
        let groups = [&first, &rest].map(|p| {
            bind_group(
                device,
                "accumulate",
                &layout,
                &[(0, p), (1, &sum)],
                &[(2, &src)],
            )
        });
        let resolve_group = bind_group(
            device,
            "resolve",
            &resolve.get_bind_group_layout(0),
            &[(0, &rest), (1, &sum)],
            &[(3, &view("color"))],
        );
        let scene_views = (src, view("depth_sample"));
        Converged {
            plan,
            textures,
            samples,
            width,
            height,
            accumulate,
            resolve,
            groups,
            resolve_group,
            scene_views,
            _buffers: vec![sum, first, rest],
        }
    }
}

/// The ground-truth reference with `samples` jittered samples per pixel, or why the adapter
/// cannot render it.
pub fn converged(
    gpu: &Gpu,
    width: u32,
    height: u32,
    samples: u32,
) -> Result<Box<dyn Renderer>, Unsupported> {
    gpu.check_size(width, height)?;
    Ok(Box::new(Converged::new(gpu, width, height, samples)))
}

impl Renderer for Converged {
    fn plan(&self) -> &Plan {
        &self.plan
    }

    fn output(&self) -> &wgpu::Texture {
        &self.textures["color"]
    }

    fn record(
        &mut self,
        gpu: &Gpu,
        scene: &mut SceneGpu,
        _timers: &Timers,
        encoder: &mut wgpu::CommandEncoder,
        frame: FrameInfo,
    ) {
        let groups = (self.width.div_ceil(8), self.height.div_ceil(8));
        let kind = ScenePipeline::Forward { samples: 1 };
        scene.pipeline(&gpu.device, kind);
        // Each sample's view is written into slot 0 and its render submitted before the next
        // write (queue writes are ordered before later submissions): a frame has more samples
        // than the scene has view slots. Untimed: the reference's cost is not a measure.
        for n in 0..self.samples {
            let j = r2(n);
            // As `taau`'s jitter (`techniques/shared/jitter.rs`): pixel q samples at q + 0.5 + j.
            let view = View {
                ndc_offset: Vec2::new(
                    -2.0 * j.x / self.width as f32,
                    2.0 * j.y / self.height as f32,
                ),
                gradient_scale: 1.0 / (self.samples as f32).sqrt(),
                ..View::whole(frame.time, frame.prev_time)
            };
            scene.write_view(&gpu.queue, 0, &view);
            let mut enc = gpu
                .device
                .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                    label: Some("converged sample"),
                });
            {
                let mut rp = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some("scene"),
                    color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                        view: &self.scene_views.0,
                        depth_slice: None,
                        resolve_target: None,
                        ops: wgpu::Operations {
                            load: wgpu::LoadOp::Clear(scene.clear_color()),
                            store: wgpu::StoreOp::Store,
                        },
                    })],
                    depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                        view: &self.scene_views.1,
                        depth_ops: Some(wgpu::Operations {
                            load: wgpu::LoadOp::Clear(0.0),
                            store: wgpu::StoreOp::Store,
                        }),
                        stencil_ops: None,
                    }),
                    timestamp_writes: None,
                    occlusion_query_set: None,
                    multiview_mask: None,
                });
                // Every object, the textured models (glTF materials, the city) included.
                scene.draw_kind(&mut rp, kind, 0);
            }
            {
                let mut cp = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some("accumulate"),
                    timestamp_writes: None,
                });
                cp.set_pipeline(&self.accumulate);
                cp.set_bind_group(0, &self.groups[usize::from(n > 0)], &[]);
                cp.dispatch_workgroups(groups.0, groups.1, 1);
            }
            gpu.queue.submit([enc.finish()]);
        }
        let mut cp = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("resolve"),
            timestamp_writes: None,
        });
        cp.set_pipeline(&self.resolve);
        cp.set_bind_group(0, &self.resolve_group, &[]);
        cp.dispatch_workgroups(groups.0, groups.1, 1);
    }
}
