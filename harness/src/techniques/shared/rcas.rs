//! RCAS as a compute pass (`rcas.wgsl`, CPU model in `rcas_model.rs`): FSR 1's sharpening, run by
//! `fsr1` after EASU and by `taau` after its resolve (`fsr2` runs AMD's FSR 2 RCAS,
//! `techniques/fsr2/rcas.wgsl`). Also the one pass type of the
//! FSR 1 module (its uniforms and bindings), so `fsr1`'s EASU pass is recorded the same way.
//! Not a technique: no plan or options here, only the pass.

use crate::gpu::Gpu;
use crate::render::kit::{bind_group, compute_pipeline, timed_dispatch};
use crate::render::timers::Timers;

/// RCAS and the encoding it works in, a whole module (`fsr1` appends its EASU to it).
pub static RCAS_WGSL: &str = include_str!("rcas.wgsl");

/// The uniforms of `rcas.wgsl` (and of `fsr1.wgsl` after it).
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub struct Params {
    /// x, y: input size; z, w: output size.
    pub size: [u32; 4],
    /// x: sharpness as a linear amount; y: 1 when EASU writes perceptual values for RCAS;
    /// z: 1 when RCAS's input is linear (encoded per tap).
    pub rcas: [f32; 4],
}

/// One compute pass of the FSR 1 module (`easu` or `rcas`): its pipeline, bind group and
/// uniforms, dispatched over the output.
pub struct FsrPass {
    name: &'static str,
    pipeline: wgpu::ComputePipeline,
    bind_group: wgpu::BindGroup,
    _params: wgpu::Buffer,
    out_size: (u32, u32),
}

impl FsrPass {
    /// The pass `name` (also its entry point) of the module `source`, from `src` to `dst`.
    pub fn new(
        gpu: &Gpu,
        name: &'static str,
        source: &str,
        (src, dst): (&wgpu::TextureView, &wgpu::TextureView),
        params: Params,
    ) -> FsrPass {
        use wgpu::util::DeviceExt;
        let device = &gpu.device;
        let buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("fsr1 params"),
            contents: bytemuck::bytes_of(&params),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let pipeline = compute_pipeline(device, name, source, name);
        let bind_group = bind_group(
            device,
            name,
            &pipeline.get_bind_group_layout(0),
            &[(0, &buffer)],
            &[(1, src), (2, dst)],
        );
        FsrPass {
            name,
            pipeline,
            bind_group,
            _params: buffer,
            out_size: (params.size[2], params.size[3]),
        }
    }

    /// Records the pass, timed under its name.
    pub fn record(&self, timers: &Timers, encoder: &mut wgpu::CommandEncoder) {
        timed_dispatch(
            encoder,
            timers,
            self.name,
            &self.pipeline,
            &[&self.bind_group],
            [self.out_size.0.div_ceil(8), self.out_size.1.div_ceil(8)],
        );
    }
}

/// An RCAS pass (`rcas`) from `src` to `dst`, both `width` x `height`, at `sharpness` stops;
/// `linear_input`: `src` holds linear colour, encoded per tap (`taau`'s RCAS).
pub fn rcas_pass(
    gpu: &Gpu,
    (src, dst): (&wgpu::TextureView, &wgpu::TextureView),
    (width, height): (u32, u32),
    sharpness: f32,
    linear_input: bool,
) -> FsrPass {
    let params = Params {
        size: [width, height, width, height],
        rcas: [
            (-sharpness).exp2(),
            1.0,
            f32::from(u8::from(linear_input)),
            0.0,
        ],
    };
    FsrPass::new(gpu, "rcas", RCAS_WGSL, (src, dst), params)
}
