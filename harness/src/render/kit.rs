//! A kit of GPU helpers techniques build with: allocating a plan's textures (read back by
//! [`Res`] handle, [`TextureMap`]), the timed scene pass, bind groups, compute pipelines,
//! placeholder textures, the one timed compute dispatch, the one ping-pong pair. The optional
//! velocity pass is `velocity.rs`.
//!
//! Infrastructure: it knows no technique.

use std::collections::HashMap;

use super::graph::{Plan, Res};
use super::scene::{Objects, SceneGpu, ScenePipeline};
use super::timers::Timers;
use crate::gpu::Gpu;

/// The textures of a plan by resource, as [`allocate`] makes them, read through a [`Res`]
/// handle. A resource the plan culled was never allocated: asking for it is a bug in the
/// technique (its recording reads what its graph says nobody reads), and panics saying so.
pub trait TextureMap {
    fn texture(&self, res: Res) -> &wgpu::Texture;

    /// A default view of the whole texture.
    fn view(&self, res: Res) -> wgpu::TextureView {
        self.texture(res).create_view(&Default::default())
    }
}

impl TextureMap for HashMap<&'static str, wgpu::Texture> {
    fn texture(&self, res: Res) -> &wgpu::Texture {
        self.get(res.name()).unwrap_or_else(|| {
            panic!(
                "resource `{}` is not in the plan (culled, or never declared)",
                res.name()
            )
        })
    }
}

/// Allocates every texture the plan keeps.
pub fn allocate(device: &wgpu::Device, plan: &Plan) -> HashMap<&'static str, wgpu::Texture> {
    allocate_with(device, plan, wgpu::TextureUsages::empty())
}

/// [`allocate`], every texture also with `extra` usages (e.g. `COPY_DST` for textures a
/// technique fills by copying).
pub fn allocate_with(
    device: &wgpu::Device,
    plan: &Plan,
    extra: wgpu::TextureUsages,
) -> HashMap<&'static str, wgpu::Texture> {
    plan.resources
        .iter()
        .map(|r| {
            let d = &r.desc;
            let mut usage = wgpu::TextureUsages::RENDER_ATTACHMENT
                | wgpu::TextureUsages::TEXTURE_BINDING
                | extra;
            if d.samples == 1 {
                usage |= wgpu::TextureUsages::COPY_SRC;
                if !d.format.is_depth_stencil_format() {
                    usage |= wgpu::TextureUsages::STORAGE_BINDING;
                }
            }
            let t = device.create_texture(&wgpu::TextureDescriptor {
                label: Some(r.name),
                size: wgpu::Extent3d {
                    width: d.width,
                    height: d.height,
                    depth_or_array_layers: d.layers,
                },
                mip_level_count: 1,
                sample_count: d.samples,
                dimension: wgpu::TextureDimension::D2,
                format: d.format,
                usage,
                view_formats: &[],
            });
            (r.name, t)
        })
        .collect()
}

/// The forward `scene` pass into `color` and `depth`, timed and counted.
#[allow(clippy::too_many_arguments)]
pub fn record_scene_pass(
    gpu: &Gpu,
    scene: &mut SceneGpu,
    timers: &Timers,
    encoder: &mut wgpu::CommandEncoder,
    name: &'static str,
    color_view: &wgpu::TextureView,
    depth_view: &wgpu::TextureView,
    slot: u32,
    kind: ScenePipeline,
) {
    record_scene_pass_on(
        gpu,
        scene,
        timers,
        encoder,
        (name, slot, kind, Objects::All),
        color_view,
        depth_view,
        wgpu::LoadOp::Clear(0.0),
    );
}

/// [`record_scene_pass`] with the objects drawn ([`Objects::Dynamic`]: a velocity pass of the
/// dynamic objects only) and the depth buffer's load op: `Load` draws over a pre-conditioned
/// depth buffer (checkerboard-2x2's masks), `Clear(0.0)` starts from the far plane (reversed-Z).
#[allow(clippy::too_many_arguments)]
pub fn record_scene_pass_on(
    gpu: &Gpu,
    scene: &mut SceneGpu,
    timers: &Timers,
    encoder: &mut wgpu::CommandEncoder,
    (name, slot, kind, objects): (&'static str, u32, ScenePipeline, Objects),
    color_view: &wgpu::TextureView,
    depth_view: &wgpu::TextureView,
    depth_load: wgpu::LoadOp<f32>,
) {
    record_scene_pass_resolved(
        gpu,
        scene,
        timers,
        encoder,
        (name, slot, kind, objects),
        (color_view, None),
        depth_view,
        depth_load,
    );
}

/// [`record_scene_pass_on`] into a multisampled `color_view` resolved (the hardware's box
/// average of the samples) into `resolve_target` at the end of the pass, when one is given: an
/// MSAA-anti-aliased render at one sample per pixel.
#[allow(clippy::too_many_arguments)]
pub fn record_scene_pass_resolved(
    gpu: &Gpu,
    scene: &mut SceneGpu,
    timers: &Timers,
    encoder: &mut wgpu::CommandEncoder,
    (name, slot, kind, objects): (&'static str, u32, ScenePipeline, Objects),
    (color_view, resolve_target): (&wgpu::TextureView, Option<&wgpu::TextureView>),
    depth_view: &wgpu::TextureView,
    depth_load: wgpu::LoadOp<f32>,
) {
    // Velocity targets hold motion, not colour: nothing drawn means no motion.
    let clear = match kind {
        ScenePipeline::Velocity => wgpu::Color::TRANSPARENT,
        _ => scene.clear_color(),
    };
    scene.pipeline(&gpu.device, kind);
    let q = timers.begin(name, encoder);
    {
        let mut rp = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some(name),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: color_view,
                depth_slice: None,
                resolve_target,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(clear),
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: depth_view,
                depth_ops: Some(wgpu::Operations {
                    load: depth_load,
                    store: wgpu::StoreOp::Store,
                }),
                stencil_ops: None,
            }),
            timestamp_writes: q.render_pass_timestamp_writes(),
            occlusion_query_set: None,
            multiview_mask: None,
        });
        timers.begin_stats(&mut rp, name);
        scene.draw_objects(&mut rp, kind, slot, objects);
        timers.end_stats(&mut rp, name);
    }
    timers.end(encoder, q);
}

/// A 1x1 texture bound where a technique's optional input (a history, a velocity buffer) is not
/// kept, so one bind group layout serves with and without it.
pub fn placeholder_texture(
    device: &wgpu::Device,
    label: &str,
    format: wgpu::TextureFormat,
) -> wgpu::Texture {
    device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d {
            width: 1,
            height: 1,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage: wgpu::TextureUsages::TEXTURE_BINDING,
        view_formats: &[],
    })
}

/// A bind group of whole buffers and texture views, each at its binding number.
pub fn bind_group(
    device: &wgpu::Device,
    label: &str,
    layout: &wgpu::BindGroupLayout,
    buffers: &[(u32, &wgpu::Buffer)],
    views: &[(u32, &wgpu::TextureView)],
) -> wgpu::BindGroup {
    let mut entries: Vec<wgpu::BindGroupEntry> = buffers
        .iter()
        .map(|(binding, b)| wgpu::BindGroupEntry {
            binding: *binding,
            resource: b.as_entire_binding(),
        })
        .collect();
    entries.extend(views.iter().map(|(binding, v)| wgpu::BindGroupEntry {
        binding: *binding,
        resource: wgpu::BindingResource::TextureView(v),
    }));
    device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some(label),
        layout,
        entries: &entries,
    })
}

/// A compute pipeline with an automatic layout from WGSL `source`.
pub fn compute_pipeline(
    device: &wgpu::Device,
    label: &str,
    source: &str,
    entry_point: &str,
) -> wgpu::ComputePipeline {
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(label),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    });
    device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some(label),
        layout: None,
        module: &module,
        entry_point: Some(entry_point),
        compilation_options: Default::default(),
        cache: None,
    })
}

/// One compute pass, timed as `name`: `pipeline` with `groups` bound at 0, 1, ... and
/// `size` workgroups (x, y). The one way a technique records a compute pass.
pub fn timed_dispatch(
    encoder: &mut wgpu::CommandEncoder,
    timers: &Timers,
    name: &'static str,
    pipeline: &wgpu::ComputePipeline,
    groups: &[&wgpu::BindGroup],
    size: [u32; 2],
) {
    let q = timers.begin(name, encoder);
    {
        let mut cp = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some(name),
            timestamp_writes: q.compute_pass_timestamp_writes(),
        });
        cp.set_pipeline(pipeline);
        for (i, g) in groups.iter().enumerate() {
            cp.set_bind_group(i as u32, *g, &[]);
        }
        cp.dispatch_workgroups(size[0], size[1], 1);
    }
    timers.end(encoder, q);
}

/// Two of a kind that trade roles every frame (kajiya's `PingPongTemporalResource`): frame `i`
/// writes `pair[i & 1]` and reads the other, last frame's, as history. Holds textures' names,
/// bind groups, or anything made once per side.
pub struct PingPong<T> {
    pair: [T; 2],
    current: usize,
}

impl<T> PingPong<T> {
    /// Side 0 is current until [`PingPong::select`].
    pub fn new(pair: [T; 2]) -> PingPong<T> {
        PingPong { pair, current: 0 }
    }

    /// Frame `index`'s side (0 or 1) without selecting it.
    pub fn side_of(index: u32) -> usize {
        (index & 1) as usize
    }

    /// What the frame writing `side` writes and reads as history, without selecting it (for
    /// making per-side bind groups).
    pub fn at(&self, side: usize) -> (&T, &T) {
        (&self.pair[side & 1], &self.pair[1 - (side & 1)])
    }

    /// Makes frame `index`'s side current.
    pub fn select(&mut self, index: u32) {
        self.current = (index & 1) as usize;
    }

    /// The side written this frame (0 or 1).
    pub fn side(&self) -> usize {
        self.current
    }

    /// What this frame writes.
    pub fn current(&self) -> &T {
        &self.pair[self.current]
    }

    /// What this frame reads as history: the other side.
    pub fn history(&self) -> &T {
        &self.pair[1 - self.current]
    }
}
