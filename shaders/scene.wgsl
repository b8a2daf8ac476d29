// Forward shading of a Tessera scene: the `scene` pass of every technique.
//
// Positions are camera-relative (the CPU subtracts the camera position in f64), so scenes far from
// the origin keep their precision. Depth is reversed-Z (near = 1, far = 0, compare Greater).
// The ground's checkerboard is IQ's analytically box-filtered pattern
// (seeds/iq-filtered-checkerboard.txt, "checkersGrad"), its epsilon a parameter.

struct Light {
    // xyz: direction the light travels (w = 0) or camera-relative position (w = 1).
    position_or_direction: vec4<f32>,
    // rgb: colour times intensity.
    radiance: vec4<f32>,
}

struct Frame {
    view_proj: mat4x4<f32>,
    // Previous frame's camera, applied to current camera-relative positions.
    prev_view_proj: mat4x4<f32>,
    // xy: offset added to clip-space xy / w (NDC), for techniques that jitter the projection.
    jitter: vec4<f32>,
    // xz: camera position modulo twice the checker size (f64 on the CPU), for the ground pattern.
    camera_mod: vec4<f32>,
    background: vec4<f32>,
    // x: ambient, y: shading cost (iterations), z: gradient scale, w: ground filter (0 none, 1 box).
    params: vec4<f32>,
    // x: checker size, y: filter epsilon.
    ground: vec4<f32>,
    ground_a: vec4<f32>,
    ground_b: vec4<f32>,
    // x: number of lights.
    counts: vec4<u32>,
    lights: array<Light, 8>,
}

struct Object {
    model: mat4x4<f32>,
    prev_model: mat4x4<f32>,
    // rgb: albedo, a: specular.
    color: vec4<f32>,
    // rgb: emitted radiance, a: 1 for the ground.
    emissive: vec4<f32>,
}

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<storage, read> objects: array<Object>;

struct VsOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) rel_pos: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) local: vec3<f32>,
    @location(3) @interpolate(flat) object: u32,
}

@vertex
fn vs_main(
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @builtin(instance_index) object: u32,
) -> VsOut {
    let o = objects[object];
    let world = o.model * vec4<f32>(position, 1.0);
    var clip = frame.view_proj * world;
    clip = vec4<f32>(clip.xy + frame.jitter.xy * clip.w, clip.zw);
    var out: VsOut;
    out.clip = clip;
    out.rel_pos = world.xyz;
    out.normal = (o.model * vec4<f32>(normal, 0.0)).xyz;
    out.local = position;
    out.object = object;
    return out;
}

// Triangular wave: the integral of the square wave of the checker pattern.
fn tri(x: vec2<f32>) -> vec2<f32> {
    let h = fract(x * 0.5) - 0.5;
    return 1.0 - 2.0 * abs(h);
}

// IQ's checkersGrad: box filter over the footprint max(|ddx|, |ddy|) (+ epsilon).
fn checkers_filtered(p: vec2<f32>, ddx: vec2<f32>, ddy: vec2<f32>, epsilon: f32) -> f32 {
    let w = max(abs(ddx), abs(ddy)) + epsilon;
    let i = (tri(p + 0.5 * w) - tri(p - 0.5 * w)) / w;
    // A zero footprint (epsilon 0, no derivative) falls back to point sampling.
    let safe = select(i, sign(fract(p * 0.5) - 0.5), w <= vec2<f32>(0.0));
    return 0.5 - 0.5 * safe.x * safe.y;
}

fn checkers_point(p: vec2<f32>) -> f32 {
    let s = sign(fract(p * 0.5) - 0.5);
    return 0.5 - 0.5 * s.x * s.y;
}

// Deterministic ALU work that makes fragment shading expensive: `cost` rounds of sin/cos.
// Its result modulates the albedo slightly, so the compiler cannot drop it.
fn detail(seed: vec3<f32>, cost: u32) -> f32 {
    if cost == 0u {
        return 1.0;
    }
    var q = seed * 4.0 + vec3<f32>(0.37, 0.11, 0.73);
    var acc = 0.0;
    for (var i = 0u; i < cost; i = i + 1u) {
        q = vec3<f32>(
            sin(q.y * 1.31 + q.z * 0.7),
            cos(q.z * 1.17 - q.x * 0.5),
            sin(q.x * 1.23 + 0.1 * f32(i)),
        );
        acc = acc + q.x * q.y;
    }
    return 0.94 + 0.06 * (0.5 + 0.5 * sin(acc));
}

@fragment
fn fs_main(in: VsOut) -> @location(0) vec4<f32> {
    let o = objects[in.object];
    // Derivatives in uniform control flow, for the ground pattern.
    let p = (in.rel_pos.xz + frame.camera_mod.xz) / frame.ground.x;
    let ddx = dpdx(p) * frame.params.z;
    let ddy = dpdy(p) * frame.params.z;

    var albedo = o.color.rgb;
    var seed = in.local;
    if o.emissive.a > 0.5 {
        var f = checkers_point(p);
        if frame.params.w > 0.5 {
            f = checkers_filtered(p, ddx, ddy, frame.ground.y);
        }
        albedo = mix(frame.ground_a.rgb, frame.ground_b.rgb, f);
        seed = vec3<f32>(fract(p * 0.125), 0.0);
    }
    albedo = albedo * detail(seed, u32(frame.params.y));

    let view = normalize(-in.rel_pos);
    var n = normalize(in.normal);
    // Two-sided: thin geometry is seen from both sides.
    if dot(n, view) < 0.0 {
        n = -n;
    }
    var color = albedo * frame.params.x;
    for (var i = 0u; i < frame.counts.x; i = i + 1u) {
        let light = frame.lights[i];
        var l: vec3<f32>;
        var radiance = light.radiance.rgb;
        if light.position_or_direction.w > 0.5 {
            let d = light.position_or_direction.xyz - in.rel_pos;
            let dist2 = max(dot(d, d), 1e-4);
            l = d * inverseSqrt(dist2);
            radiance = radiance / dist2;
        } else {
            l = -normalize(light.position_or_direction.xyz);
        }
        let ndl = max(dot(n, l), 0.0);
        let h = normalize(l + view);
        let spec = o.color.a * pow(max(dot(n, h), 0.0), 48.0) * f32(ndl > 0.0);
        color = color + (albedo * ndl + vec3<f32>(spec)) * radiance;
    }
    color = color + o.emissive.rgb;
    return vec4<f32>(color, 1.0);
}
