//! The GPU-against-model check every technique's test makes: the technique's renderer on the
//! default adapter with a scenario's scene ([`Rig`]), each frame submitted as the run loop
//! submits it and waited for, the renderer's textures read back for the CPU model, and the GPU's
//! output held against the model's at the precision of an `Rgba16Float` target ([`f16`],
//! [`close`]). What each technique's model is given and asserts stays in its own test.

use glam::Vec4;
use tessera::gpu::Gpu;
use tessera::render::readback::read_texture_layer;
use tessera::render::renderer::Renderer;
use tessera::render::scene::SceneGpu;
use tessera::render::timers::Timers;
use tessera::scenario::Scenario;

/// How a renderer names its textures (each technique's `texture` method).
pub type TextureOf<R> = for<'a> fn(&'a R, &str) -> Option<&'a wgpu::Texture>;

/// A technique's renderer on the default adapter, with the scene of a scenario and the timers
/// its frames record into.
pub struct Rig<R> {
    pub gpu: Gpu,
    pub scene: SceneGpu,
    pub renderer: R,
    timers: Timers,
    texture_of: TextureOf<R>,
}

impl<R: Renderer> Rig<R> {
    /// Opens the default adapter, puts `s`'s scene on it and builds the renderer with `build`;
    /// `texture_of` is how the renderer names its textures (`TaauGpu::texture`).
    pub fn new(s: &Scenario, build: impl FnOnce(&Gpu) -> R, texture_of: TextureOf<R>) -> Rig<R> {
        let gpu = super::gpu();
        let scene = SceneGpu::new(&gpu.device, &gpu.queue, s).unwrap();
        let renderer = build(&gpu);
        let timers = Timers::new(&gpu.device, &[]).unwrap();
        Rig {
            gpu,
            scene,
            renderer,
            timers,
            texture_of,
        }
    }

    /// Submits frame `index` of `s` as the run loop does and waits for the GPU to finish it.
    pub fn frame(&mut self, s: &Scenario, index: u32) {
        let g = &self.gpu;
        tessera::run::sequence::submit_frame(
            g,
            &mut self.scene,
            s,
            &mut self.renderer,
            &mut self.timers,
            index,
        );
        let _ = g.device.poll(wgpu::PollType::Wait {
            submission_index: None,
            timeout: None,
        });
        let _ = self.timers.try_collect(&g.queue);
    }

    /// The renderer's texture `name`, which it must have.
    pub fn texture(&self, name: &str) -> &wgpu::Texture {
        (self.texture_of)(&self.renderer, name).unwrap_or_else(|| panic!("no texture {name}"))
    }

    /// [`Rig::read`], or `None` where the renderer has no texture `name` (one a variant does not
    /// keep).
    pub fn read_if(&self, name: &str) -> Option<Vec<f32>> {
        (self.texture_of)(&self.renderer, name).map(|t| self.read_texture(t))
    }

    /// The texture `name` read back, every array layer, layer 0 first (one f32 a texel of a
    /// depth or R32Float texture, four otherwise).
    pub fn read(&self, name: &str) -> Vec<f32> {
        self.read_texture(self.texture(name))
    }

    /// One array layer of the texture `name`, read back.
    pub fn read_layer(&self, name: &str, layer: u32) -> Vec<f32> {
        read_texture_layer(&self.gpu.device, &self.gpu.queue, self.texture(name), layer)
    }

    /// [`Rig::read`] of an RGBA texture, as texels.
    pub fn read4(&self, name: &str) -> Vec<Vec4> {
        vec4s(self.read(name))
    }

    /// The renderer's output, as texels.
    pub fn output(&self) -> Vec<Vec4> {
        vec4s(self.read_texture(self.renderer.output()))
    }

    fn read_texture(&self, texture: &wgpu::Texture) -> Vec<f32> {
        (0..texture.depth_or_array_layers())
            .flat_map(|l| read_texture_layer(&self.gpu.device, &self.gpu.queue, texture, l))
            .collect()
    }
}

/// RGBA texels of four floats each.
pub fn vec4s(v: Vec<f32>) -> Vec<Vec4> {
    v.chunks_exact(4).map(Vec4::from_slice).collect()
}

/// `x` as an `Rgba16Float` target stores it: rounded to f16 and back.
pub fn f16(x: f32) -> f32 {
    half::f16::from_f32(x).to_f32()
}

/// [`f16`] of each component.
pub fn f16x4(v: Vec4) -> Vec4 {
    v.map(f16)
}

/// Whether `got` is `want` within `tolerance` of `want`'s largest magnitude (at least 1): what
/// two f32 computations stored as f16 may differ by in the last bits (2e-3: one f16 step).
pub fn close(want: Vec4, got: Vec4, tolerance: f32) -> bool {
    (want - got).abs().max_element() <= tolerance * want.abs().max_element().max(1.0)
}
