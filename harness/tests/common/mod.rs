//! Shared helpers for the GPU tests: open the default adapter (lavapipe in CI) once per test.
// Each test crate uses a subset of these helpers.
#![allow(dead_code)]

pub mod check;

use std::path::Path;

use tessera::gpu::{self, Gpu};
use tessera::params::ParamValue;
use tessera::scenario::{self, Scenario};
use tessera::techniques::Variant;

/// Opens the adapter the harness would pick. CI installs lavapipe (ci/setup.sh), so a missing
/// adapter is a failure, not a skip.
pub fn gpu() -> Gpu {
    // As `tessera` does: keep libwayland's XDG_RUNTIME_DIR complaint out of test output. Set once,
    // before any test of this binary touches the GPU (every GPU test comes through here first).
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        if std::env::var_os("XDG_RUNTIME_DIR").is_none() {
            let dir = std::env::temp_dir().join("tessera-runtime");
            if std::fs::create_dir_all(&dir).is_ok() {
                std::env::set_var("XDG_RUNTIME_DIR", &dir);
            }
        }
    });
    let adapter = gpu::select(None).expect("no GPU adapter: run ci/setup.sh to install lavapipe");
    gpu::open(adapter).expect("cannot open a device")
}

pub fn scenario(src: &str) -> Scenario {
    scenario::parse(Path::new("test.toml"), src).unwrap_or_else(|e| panic!("{e}"))
}

/// A variant of the technique named `technique` with its defaults and `params` set.
pub fn variant(technique: &str, params: &[(&str, ParamValue)]) -> Variant {
    let technique = tessera::techniques::by_name(technique)
        .unwrap_or_else(|| panic!("no technique {technique}"));
    let mut v = Variant::with_defaults(technique);
    for (k, value) in params {
        assert!(
            v.params.contains_key(*k),
            "{technique:?} has no parameter {k}"
        );
        v.params.insert(k.to_string(), value.clone());
    }
    v
}

/// A small scene with every procedural shape, a light and a moving object.
pub const TINY: &str = r#"
resolution = [48, 32]
[frames]
warmup = 1
measured = 2
[scene]
shading_cost = 4
[scene.ground]
checker_size = 0.5
[[scene.lights]]
type = "directional"
direction = [-0.4, -1.0, -0.3]
intensity = 2.0
[[scene.objects]]
shape = "box"
position = [0, 0.5, 0]
color = [0.8, 0.3, 0.2]
animation = { kind = "rotate", degrees_per_second = 90 }
[[scene.objects]]
shape = "sphere"
position = [1.2, 0.5, 0]
radius = 0.5
[[scene.objects]]
shape = "pole"
position = [-1.0, 0, 0]
[[scene.objects]]
shape = "fence"
position = [-2, 0, -1]
end = [2, 0, -1]
[camera]
[[camera.keyframes]]
time = 0
position = [0, 1.5, 4]
target = [0, 0.4, 0]
[[camera.keyframes]]
time = 1
position = [0.5, 1.5, 4]
target = [0, 0.4, 0]
[[techniques]]
technique = "native"
"#;

/// Writes `src` as `name` in a temporary folder, runs it (as [`run_file`]) and returns its result,
/// asserting exit code 0.
pub fn run_ok(src: &str, name: &str) -> tessera_results::ScenarioResult {
    let dir = tempfile::tempdir().unwrap();
    let f = dir.path().join(name);
    std::fs::write(&f, src).unwrap();
    let (code, result, stdout) = run_file(&f);
    assert_eq!(code, 0, "{stdout}");
    result
}

/// Runs `tessera run FILE --quiet` into a temporary folder: the exit code, the scenario's result
/// file and stdout.
pub fn run_file(file: &Path) -> (i32, tessera_results::ScenarioResult, String) {
    let out = tempfile::tempdir().unwrap();
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_tessera"))
        .args(["run", file.to_str().unwrap(), "--quiet", "--out"])
        .arg(out.path())
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&o.stdout).into_owned();
    let run_dir = std::fs::read_dir(out.path())
        .unwrap()
        .next()
        .unwrap_or_else(|| panic!("no run folder: {stdout}"))
        .unwrap()
        .path();
    let files = tessera_results::layout::scenario_files(&run_dir).unwrap();
    let text = std::fs::read_to_string(&files[0]).unwrap();
    (
        o.status.code().unwrap_or(-1),
        serde_json::from_str(&text).unwrap(),
        stdout,
    )
}

/// A `w` x `h` depth texture (the harness's `DEPTH_FORMAT`) holding `data` (one per texel, rows
/// unpadded): WebGPU cannot copy into a depth texture, so a full-screen pass writes `frag_depth`
/// from a storage buffer.
pub fn depth_texture(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    (w, h): (u32, u32),
    data: &[f32],
) -> wgpu::Texture {
    use wgpu::util::DeviceExt;
    const WGSL: &str = r#"
@group(0) @binding(0) var<storage, read> depths: array<f32>;
@group(0) @binding(1) var<uniform> width: vec4<u32>;
@vertex
fn vs(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let uv = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4<f32>(uv * 2.0 - 1.0, 0.0, 1.0);
}
@fragment
fn fs(@builtin(position) p: vec4<f32>) -> @builtin(frag_depth) f32 {
    let q = vec2<u32>(p.xy);
    return depths[q.y * width.x + q.x];
}
"#;
    let t = device.create_texture(&wgpu::TextureDescriptor {
        label: Some("synthetic depth"),
        size: wgpu::Extent3d {
            width: w,
            height: h,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: tessera::render::scene::DEPTH_FORMAT,
        usage: wgpu::TextureUsages::TEXTURE_BINDING
            | wgpu::TextureUsages::RENDER_ATTACHMENT
            | wgpu::TextureUsages::COPY_SRC,
        view_formats: &[],
    });
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("depth writer"),
        source: wgpu::ShaderSource::Wgsl(WGSL.into()),
    });
    let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some("depth writer"),
        layout: None,
        vertex: wgpu::VertexState {
            module: &module,
            entry_point: Some("vs"),
            compilation_options: Default::default(),
            buffers: &[],
        },
        fragment: Some(wgpu::FragmentState {
            module: &module,
            entry_point: Some("fs"),
            compilation_options: Default::default(),
            targets: &[],
        }),
        primitive: Default::default(),
        depth_stencil: Some(wgpu::DepthStencilState {
            format: tessera::render::scene::DEPTH_FORMAT,
            depth_write_enabled: Some(true),
            depth_compare: Some(wgpu::CompareFunction::Always),
            stencil: Default::default(),
            bias: Default::default(),
        }),
        multisample: Default::default(),
        multiview_mask: None,
        cache: None,
    });
    let depths = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("depths"),
        contents: bytemuck::cast_slice(data),
        usage: wgpu::BufferUsages::STORAGE,
    });
    let width = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("width"),
        contents: bytemuck::cast_slice(&[w, 0, 0, 0]),
        usage: wgpu::BufferUsages::UNIFORM,
    });
    let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("depth writer"),
        layout: &pipeline.get_bind_group_layout(0),
        entries: &[
            wgpu::BindGroupEntry {
                binding: 0,
                resource: depths.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: width.as_entire_binding(),
            },
        ],
    });
    let view = t.create_view(&Default::default());
    let mut encoder = device.create_command_encoder(&Default::default());
    {
        let mut rp = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("depth writer"),
            color_attachments: &[],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &view,
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
        rp.set_pipeline(&pipeline);
        rp.set_bind_group(0, &bind_group, &[]);
        rp.draw(0..3, 0..1);
    }
    queue.submit([encoder.finish()]);
    t
}
