//! Technique `upscale`: render at a scale factor, then upscale to the output with a bilinear or
//! nearest filter (a compute pass): what a user would pick instead of a technique.

use super::definition::{BuildContext, Definition, Shader, Target};
use super::native::gpu::{forward_graph, Forward, MakeResample, Resample};
use crate::gpu::Gpu;
use crate::render::graph::Plan;
use crate::render::kit::compute_pipeline;
use crate::render::renderer::{Renderer, Unsupported};

pub static UPSCALE_WGSL: &str = include_str!("upscale.wgsl");

crate::choice! {
    /// The upscaling filter.
    pub enum Filter {
        Bilinear = "bilinear",
        Nearest = "nearest",
    }
}

crate::options! {
    /// A variant's options, typed.
    #[derive(Clone, Copy, Debug, PartialEq)]
    pub struct Options {
        scale: f64 = float(
            (0.0, false, 1.0),
            0.5,
            "render width and height as a fraction of the output resolution",
        ),
        filter: Filter = choice(
            Filter::Bilinear,
            "upscaling filter (compute pass at output resolution)",
        ),
    }
}

pub struct Upscale;

/// Render size and the upscale pass of a variant at `target`.
fn setup(options: &Options, target: Target) -> (u32, u32, Resample, Filter) {
    let s = options.scale;
    let lw = ((target.width as f64 * s).round() as u32).max(1);
    let lh = ((target.height as f64 * s).round() as u32).max(1);
    let resample = Resample {
        pass: "upscale",
        color: "color_low",
        depth: "depth_low",
        width: target.width,
        height: target.height,
    };
    (lw, lh, resample, options.filter)
}

impl Definition for Upscale {
    type Options = Options;

    fn name(&self) -> &'static str {
        "upscale"
    }

    fn summary(&self) -> &'static str {
        "render at a fraction of the output resolution, then upscale"
    }

    fn plan(&self, options: &Options, target: Target) -> Plan {
        let (w, h, resample, _) = setup(options, target);
        forward_graph(w, h, Some(&resample))
    }

    fn build(
        &self,
        options: &Options,
        cx: &BuildContext<'_>,
    ) -> Result<Box<dyn Renderer>, Unsupported> {
        let (w, h, resample, filter) = setup(options, cx.target);
        let filter = match filter {
            Filter::Bilinear => wgpu::FilterMode::Linear,
            Filter::Nearest => wgpu::FilterMode::Nearest,
        };
        let make: MakeResample =
            Box::new(move |gpu, src, dst| upscale_pipeline(gpu, src, dst, filter));
        // Textures and the ground sampled as at the output resolution (the LOD policy of the
        // parameter table: mip bias log2(render / output)).
        let lod_bias = -(cx.target.width as f32 / w as f32).log2();
        Ok(Box::new(
            Forward::new(cx.gpu, w, h, Some((resample, make))).with_lod_bias(lod_bias),
        ))
    }

    fn shaders(&self) -> Vec<Shader> {
        vec![Shader::file("upscale/upscale.wgsl", UPSCALE_WGSL)]
    }
}

fn upscale_pipeline(
    gpu: &Gpu,
    src: &wgpu::Texture,
    dst: &wgpu::Texture,
    filter: wgpu::FilterMode,
) -> (wgpu::ComputePipeline, wgpu::BindGroup) {
    let device = &gpu.device;
    let pipeline = compute_pipeline(device, "upscale", UPSCALE_WGSL, "main");
    let sampler = device.create_sampler(&wgpu::SamplerDescriptor {
        label: Some("upscale"),
        mag_filter: filter,
        min_filter: filter,
        address_mode_u: wgpu::AddressMode::ClampToEdge,
        address_mode_v: wgpu::AddressMode::ClampToEdge,
        ..Default::default()
    });
    let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("upscale"),
        layout: &pipeline.get_bind_group_layout(0),
        entries: &[
            wgpu::BindGroupEntry {
                binding: 0,
                resource: wgpu::BindingResource::TextureView(&src.create_view(&Default::default())),
            },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: wgpu::BindingResource::Sampler(&sampler),
            },
            wgpu::BindGroupEntry {
                binding: 2,
                resource: wgpu::BindingResource::TextureView(&dst.create_view(&Default::default())),
            },
        ],
    });
    (pipeline, bind_group)
}
