// Textured materials, appended to scene.wgsl (its frame uniforms, lights, objects and motion
// helpers): glTF 2.0 metallic-roughness materials with base colour, metallic-roughness, normal,
// occlusion and emissive textures, alpha test (MASK) and blending (BLEND), shaded by GGX or by
// the procedural scenes' Blinn-Phong, as the material says (`harness/src/render/material.rs`).
//
// Textures are sampled with explicit gradients: d(uv)/dx and d(uv)/dy times the view's gradient
// scale (`frame.params.z`, the derivative correction of techniques that render at a reduced
// density, e.g. checkerboard's 0.5 = Intel's DDXY_BIAS) times 2^lod_bias (`frame.ground.z`, e.g.
// an upscaler's -log2(output / render)). Scaling the gradients by 2^b moves the sampled level by
// b, which is what a sampler LOD bias does (wgpu has none); anisotropic filtering follows the
// scaled footprint too.

struct Material {
    base_color: vec4<f32>,
    emissive: vec4<f32>,
    // x metallic, y roughness, z alpha cutoff, w normal scale.
    pbr: vec4<f32>,
    // x occlusion strength, y BRDF (0 Blinn-Phong, 1 GGX), z Blinn-Phong specular, w alpha mode
    // (0 opaque, 1 mask, 2 blend).
    mode: vec4<f32>,
    // Slot s (base, metallic-roughness, normal, occlusion, emissive): rows 2s and 2s + 1 of its
    // uv transform (KHR_texture_transform).
    uv: array<vec4<f32>, 10>,
}

@group(1) @binding(0) var<uniform> material: Material;
@group(1) @binding(1) var t_base: texture_2d<f32>;
@group(1) @binding(2) var t_metal_rough: texture_2d<f32>;
@group(1) @binding(3) var t_normal: texture_2d<f32>;
@group(1) @binding(4) var t_occlusion: texture_2d<f32>;
@group(1) @binding(5) var t_emissive: texture_2d<f32>;
@group(1) @binding(6) var s_base: sampler;
@group(1) @binding(7) var s_metal_rough: sampler;
@group(1) @binding(8) var s_normal: sampler;
@group(1) @binding(9) var s_occlusion: sampler;
@group(1) @binding(10) var s_emissive: sampler;

struct MaterialVs {
    @builtin(position) clip: vec4<f32>,
    @location(0) rel_pos: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) local: vec3<f32>,
    @location(3) @interpolate(flat) object: u32,
    @location(4) uv: vec2<f32>,
    @location(5) tangent: vec4<f32>,
}

// Per-sample interpolation for checkerboard's 2x MSAA sampling (see `fs_main_sample`).
struct MaterialVsSample {
    @builtin(position) clip: vec4<f32>,
    @location(0) @interpolate(perspective, sample) rel_pos: vec3<f32>,
    @location(1) @interpolate(perspective, sample) normal: vec3<f32>,
    @location(2) @interpolate(perspective, sample) local: vec3<f32>,
    @location(3) @interpolate(flat) object: u32,
    @location(4) @interpolate(perspective, sample) uv: vec2<f32>,
    @location(5) @interpolate(perspective, sample) tangent: vec4<f32>,
}

fn material_transform(
    position: vec3<f32>,
    normal: vec3<f32>,
    uv: vec2<f32>,
    tangent: vec4<f32>,
    object: u32,
) -> MaterialVs {
    let v = transform(position, normal, object);
    let t = (objects[object].model * vec4<f32>(tangent.xyz, 0.0)).xyz;
    return MaterialVs(v.clip, v.rel_pos, v.normal, v.local, object, uv, vec4<f32>(t, tangent.w));
}

@vertex
fn vs_material(
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
    @location(3) tangent: vec4<f32>,
    @builtin(instance_index) object: u32,
) -> MaterialVs {
    return material_transform(position, normal, uv, tangent, object);
}

@vertex
fn vs_material_sample(
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
    @location(3) tangent: vec4<f32>,
    @builtin(instance_index) object: u32,
) -> MaterialVsSample {
    let v = material_transform(position, normal, uv, tangent, object);
    return MaterialVsSample(v.clip, v.rel_pos, v.normal, v.local, v.object, v.uv, v.tangent);
}

// Texture coordinates and their scaled screen-space gradients.
struct Uv {
    uv: vec2<f32>,
    dx: vec2<f32>,
    dy: vec2<f32>,
}

// Derivatives in uniform control flow, before any discard.
fn uv_gradients(uv: vec2<f32>) -> Uv {
    let k = frame.params.z * exp2(frame.ground.z);
    return Uv(uv, dpdx(uv) * k, dpdy(uv) * k);
}

fn sample_slot(t: texture_2d<f32>, s: sampler, slot: u32, g: Uv) -> vec4<f32> {
    let r0 = material.uv[2u * slot];
    let r1 = material.uv[2u * slot + 1u];
    let uv = vec2<f32>(dot(r0.xy, g.uv) + r0.z, dot(r1.xy, g.uv) + r1.z);
    let dx = vec2<f32>(dot(r0.xy, g.dx), dot(r1.xy, g.dx));
    let dy = vec2<f32>(dot(r0.xy, g.dy), dot(r1.xy, g.dy));
    return textureSampleGrad(t, s, uv, dx, dy);
}

// Base colour times factor; alpha as the material's mode uses it.
fn base_color(g: Uv) -> vec4<f32> {
    return sample_slot(t_base, s_base, 0u, g) * material.base_color;
}

const PI: f32 = 3.14159265358979;

// The direction to light `i` from `rel_pos` and its radiance there.
fn light_at(i: u32, rel_pos: vec3<f32>) -> vec4<f32> {
    let light = frame.lights[i];
    if light.position_or_direction.w > 0.5 {
        let d = light.position_or_direction.xyz - rel_pos;
        let dist2 = max(dot(d, d), 1e-4);
        return vec4<f32>(d * inverseSqrt(dist2), 1.0 / dist2);
    }
    return vec4<f32>(-normalize(light.position_or_direction.xyz), 1.0);
}

fn shade_material(
    rel_pos: vec3<f32>,
    normal: vec3<f32>,
    local: vec3<f32>,
    object: u32,
    tangent: vec4<f32>,
    g: Uv,
    base: vec4<f32>,
) -> vec4<f32> {
    let o = objects[object];
    let albedo = base.rgb * detail(local, u32(frame.params.y));
    let mr = sample_slot(t_metal_rough, s_metal_rough, 1u, g);
    let metallic = clamp(material.pbr.x * mr.b, 0.0, 1.0);
    let roughness = clamp(material.pbr.y * mr.g, 0.03, 1.0);
    let occ = 1.0 + material.mode.x * (sample_slot(t_occlusion, s_occlusion, 3u, g).r - 1.0);
    let emissive = material.emissive.rgb * sample_slot(t_emissive, s_emissive, 4u, g).rgb;

    let view = normalize(-rel_pos);
    var n = normalize(normal);
    // Two-sided: thin geometry (foliage cards, wires) is seen from both sides.
    if dot(n, view) < 0.0 {
        n = -n;
    }
    if dot(tangent.xyz, tangent.xyz) > 0.0 {
        let t = normalize(tangent.xyz - n * dot(n, tangent.xyz));
        let b = cross(n, t) * tangent.w;
        var m = sample_slot(t_normal, s_normal, 2u, g).xyz * 2.0 - 1.0;
        m = vec3<f32>(m.xy * material.pbr.w, m.z);
        n = normalize(t * m.x + b * m.y + n * max(m.z, 0.0));
    }

    var color = albedo * frame.params.x * occ;
    let ggx = material.mode.y > 0.5;
    let f0 = mix(vec3<f32>(0.04), albedo, metallic);
    let diffuse = albedo * (1.0 - metallic);
    let a = roughness * roughness;
    let a2 = a * a;
    let ndv = max(dot(n, view), 1e-4);
    for (var i = 0u; i < frame.counts.x; i = i + 1u) {
        let la = light_at(i, rel_pos);
        let l = la.xyz;
        let radiance = frame.lights[i].radiance.rgb * la.w;
        let ndl = max(dot(n, l), 0.0);
        let h = normalize(l + view);
        let ndh = max(dot(n, h), 0.0);
        if ggx {
            // glTF 2.0 appendix B; multiplied by pi so that a white Lambert surface facing a
            // light of radiance L is lit L, as in the Blinn-Phong path.
            let vdh = max(dot(view, h), 0.0);
            let f = f0 + (1.0 - f0) * pow(1.0 - vdh, 5.0);
            let dd = ndh * ndh * (a2 - 1.0) + 1.0;
            let d = a2 / (PI * dd * dd);
            let vis = 0.5 / max(
                ndl * sqrt(ndv * ndv * (1.0 - a2) + a2) + ndv * sqrt(ndl * ndl * (1.0 - a2) + a2),
                1e-6,
            );
            color = color + ((1.0 - f) * diffuse + PI * f * d * vis) * radiance * ndl;
        } else {
            let spec = material.mode.z * pow(ndh, 48.0) * f32(ndl > 0.0);
            color = color + (albedo * ndl + vec3<f32>(spec)) * radiance;
        }
    }
    color = color + emissive + o.emissive.rgb;
    let alpha = select(1.0, base.a, material.mode.w > 1.5);
    return injected(vec4<f32>(color, alpha), o.flags.x);
}

fn alpha_discarded(base: vec4<f32>) -> bool {
    return material.mode.w > 0.5 && material.mode.w < 1.5 && base.a < material.pbr.z;
}

@fragment
fn fs_material(in: MaterialVs) -> @location(0) vec4<f32> {
    let g = uv_gradients(in.uv);
    let base = base_color(g);
    return shade_material(in.rel_pos, in.normal, in.local, in.object, in.tangent, g, base);
}

// Alpha-tested and blended materials (a separate entry point: a shader that can discard costs
// opaque draws their early depth test).
@fragment
fn fs_material_alpha(in: MaterialVs) -> @location(0) vec4<f32> {
    let g = uv_gradients(in.uv);
    let base = base_color(g);
    if alpha_discarded(base) {
        discard;
    }
    return shade_material(in.rel_pos, in.normal, in.local, in.object, in.tangent, g, base);
}

@fragment
fn fs_material_sample(
    in: MaterialVsSample,
    @builtin(sample_index) sample: u32,
) -> @location(0) vec4<f32> {
    let g = uv_gradients(in.uv);
    let base = base_color(g);
    let c = shade_material(in.rel_pos, in.normal, in.local, in.object, in.tangent, g, base);
    return vec4<f32>(c.rgb, c.a + f32(sample) * 1e-30);
}

@fragment
fn fs_material_sample_alpha(
    in: MaterialVsSample,
    @builtin(sample_index) sample: u32,
) -> @location(0) vec4<f32> {
    let g = uv_gradients(in.uv);
    let base = base_color(g);
    if alpha_discarded(base) {
        discard;
    }
    let c = shade_material(in.rel_pos, in.normal, in.local, in.object, in.tangent, g, base);
    return vec4<f32>(c.rgb, c.a + f32(sample) * 1e-30);
}

// Velocity pass of textured objects: as `vs_velocity` / `fs_velocity`, with the alpha test, so
// a foliage card's cut-outs show the motion of what is behind them.
struct MaterialVelocityOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) current: vec4<f32>,
    @location(1) previous: vec4<f32>,
    @location(2) @interpolate(flat) dynamic_object: u32,
    @location(3) @interpolate(flat) still: u32,
    @location(4) uv: vec2<f32>,
}

@vertex
fn vs_material_velocity(
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
    @location(3) tangent: vec4<f32>,
    @builtin(instance_index) object: u32,
) -> MaterialVelocityOut {
    let o = objects[object];
    let current = frame.view_proj * o.model * vec4<f32>(position, 1.0);
    let still = is_still(object);
    // The raster follows the view's remap as `vs_velocity`'s does (bit for bit `current` with
    // the identity remap); the motion stays unjittered.
    let clip = vec4<f32>(current.xy * frame.jitter.zw + frame.jitter.xy * current.w, current.zw);
    return MaterialVelocityOut(
        clip,
        current,
        previous_clip(position, object, current, still),
        select(0u, 1u, o.emissive.a > 1.5),
        select(0u, 1u, still),
        uv,
    );
}

fn material_motion(in: MaterialVelocityOut) -> vec4<f32> {
    let motion = screen_motion(in.current, in.previous, in.still == 1u);
    return vec4<f32>(motion, f32(in.dynamic_object), in.previous.z / in.previous.w);
}

@fragment
fn fs_material_velocity(in: MaterialVelocityOut) -> @location(0) vec4<f32> {
    return material_motion(in);
}

@fragment
fn fs_material_velocity_mask(in: MaterialVelocityOut) -> @location(0) vec4<f32> {
    let g = uv_gradients(in.uv);
    if alpha_discarded(base_color(g)) {
        discard;
    }
    return material_motion(in);
}
