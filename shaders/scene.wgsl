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
    // Viewport remap applied after projection: ndc' = ndc * zw + xy. Identity is (0, 0, 1, 1).
    // Techniques use it to jitter the projection and to render a part of the frame at another
    // resolution (checkerboard's quarter-resolution targets).
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
    // x: number of lights; y, z: output width and height in pixels; w: 1 when the camera did not
    // move since the previous frame.
    counts: vec4<u32>,
    lights: array<Light, 8>,
}

struct Object {
    model: mat4x4<f32>,
    prev_model: mat4x4<f32>,
    // rgb: albedo, a: specular.
    color: vec4<f32>,
    // rgb: emitted radiance; a: 0 static object, 1 the ground, 2 dynamic (animated) object.
    emissive: vec4<f32>,
    // x: injected non-finite output (stress suite): 0 none, 1 NaN, 2 +Inf.
    flags: vec4<f32>,
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

// Per-sample interpolation for `fs_main_sample` (checkerboard's 2x MSAA sampling).
struct VsOutSample {
    @builtin(position) clip: vec4<f32>,
    @location(0) @interpolate(perspective, sample) rel_pos: vec3<f32>,
    @location(1) @interpolate(perspective, sample) normal: vec3<f32>,
    @location(2) @interpolate(perspective, sample) local: vec3<f32>,
    @location(3) @interpolate(flat) object: u32,
}

fn transform(position: vec3<f32>, normal: vec3<f32>, object: u32) -> VsOut {
    let o = objects[object];
    let world = o.model * vec4<f32>(position, 1.0);
    var clip = frame.view_proj * world;
    clip = vec4<f32>(clip.xy * frame.jitter.zw + frame.jitter.xy * clip.w, clip.zw);
    var out: VsOut;
    out.clip = clip;
    out.rel_pos = world.xyz;
    out.normal = (o.model * vec4<f32>(normal, 0.0)).xyz;
    out.local = position;
    out.object = object;
    return out;
}

@vertex
fn vs_main(
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @builtin(instance_index) object: u32,
) -> VsOut {
    return transform(position, normal, object);
}

@vertex
fn vs_main_sample(
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @builtin(instance_index) object: u32,
) -> VsOutSample {
    let v = transform(position, normal, object);
    return VsOutSample(v.clip, v.rel_pos, v.normal, v.local, v.object);
}

// Triangular wave: the integral of the square wave of the checker pattern.
fn tri(x: vec2<f32>) -> vec2<f32> {
    let h = fract(x * 0.5) - 0.5;
    return 1.0 - 2.0 * abs(h);
}

// IQ's checkersGrad: box filter over the footprint max(|ddx|, |ddy|) (+ epsilon).
fn checkers_filtered(p: vec2<f32>, footprint: vec2<f32>, epsilon: f32) -> f32 {
    let w = footprint + epsilon;
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
    return shade(in);
}

// Shaded once per sample: reading `sample_index` makes the invocation per-sample (Intel's
// SAMPLE_SHADING), and the varyings are interpolated at the sample positions.
@fragment
fn fs_main_sample(in: VsOutSample, @builtin(sample_index) sample: u32) -> @location(0) vec4<f32> {
    let c = shade(VsOut(in.clip, in.rel_pos, in.normal, in.local, in.object));
    // Keeps `sample` statically used; adds nothing visible (1e-30 underflows in Rgba16Float).
    return vec4<f32>(c.rgb, c.a + f32(sample) * 1e-30);
}

// What shading needs of a visible surface point: what the rasteriser interpolates, plus the
// ground pattern's footprint, which needs screen-space derivatives. The forward path computes it
// in the fragment shader (`shade`); adaptive shading's G-buffer stores the derivatives it is made
// from and its compute shading pass calls `shade_surface` (no derivatives in compute).
struct Surface {
    rel_pos: vec3<f32>,
    normal: vec3<f32>,
    local: vec3<f32>,
    object: u32,
    // max(|ddx|, |ddy|) of the ground pattern coordinate, gradient scale applied.
    footprint: vec2<f32>,
}

// The ground pattern coordinate (checks of size 1) of a camera-relative position.
fn ground_coord(rel_pos: vec3<f32>) -> vec2<f32> {
    return (rel_pos.xz + frame.camera_mod.xz) / frame.ground.x;
}

// The surface description of a rasterised fragment.
fn surface(in: VsOut) -> Surface {
    // Derivatives in uniform control flow, for the ground pattern.
    // One LOD policy for the ground and textures (`material.wgsl`'s `k`): derivatives times the
    // gradient scale times 2^lod_bias (exactly 1 where the bias is 0).
    let p = ground_coord(in.rel_pos);
    let k = frame.params.z * select(exp2(frame.ground.z), 1.0, frame.ground.z == 0.0);
    let ddx = dpdx(p) * k;
    let ddy = dpdy(p) * k;
    return Surface(in.rel_pos, in.normal, in.local, in.object, max(abs(ddx), abs(ddy)));
}

fn shade(in: VsOut) -> vec4<f32> {
    return shade_surface(surface(in));
}

fn shade_surface(in: Surface) -> vec4<f32> {
    let o = objects[in.object];
    let p = ground_coord(in.rel_pos);

    var albedo = o.color.rgb;
    var seed = in.local;
    if abs(o.emissive.a - 1.0) < 0.5 {
        var f = checkers_point(p);
        if frame.params.w > 0.5 {
            f = checkers_filtered(p, in.footprint, frame.ground.y);
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
    return injected(vec4<f32>(color, 1.0), o.flags.x);
}

// Stress suite: an object marked `inject` writes NaN (1) or +Inf (2) in its colour channels, so a
// run can check that no technique spreads non-finite values beyond the pixels that had them. The
// bit patterns are chosen at run time (WGSL refuses NaN and Inf in constant expressions).
fn injected(color: vec4<f32>, mode: f32) -> vec4<f32> {
    if mode < 0.5 {
        return color;
    }
    let bits = select(0x7f800000u, 0x7fc00000u, mode < 1.5);
    return vec4<f32>(vec3<f32>(bitcast<f32>(bits)), 1.0);
}

// Velocity pass (the motion provider, `render/velocity.rs`, and the `tde` metric's exact
// motion): screen motion in output pixels (y down, whatever the target's size) of the objects
// drawn, with z = 1 where the object is dynamic (moves by itself) and 0 where the camera alone
// moves it (techniques reproject those through the cameras instead), and w = the point's
// reversed-Z depth in the previous frame (disocclusion test). Cleared to 0 where nothing is
// drawn. The motion is not jittered; the raster follows the view's remap (see `vs_velocity`).
struct VelocityOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) current: vec4<f32>,
    @location(1) previous: vec4<f32>,
    @location(2) @interpolate(flat) dynamic_object: u32,
    // 1 when nothing moved (still camera, object not animated): the motion is exactly zero.
    @location(3) @interpolate(flat) still: u32,
}

@vertex
fn vs_velocity(
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @builtin(instance_index) object: u32,
) -> VelocityOut {
    let o = objects[object];
    var out: VelocityOut;
    out.current = frame.view_proj * o.model * vec4<f32>(position, 1.0);
    let still = is_still(object);
    out.previous = previous_clip(position, object, out.current, still);
    out.still = select(0u, 1u, still);
    // Rasterised through the view's remap like the scene pass (a jittered render-resolution
    // motion pass covers the same samples as the scene pass it serves, so its depth can be
    // compared with the scene's); the motion itself is the unjittered `current - previous`.
    // With the identity remap (0, 0, 1, 1) this is `current` bit for bit.
    out.clip = vec4<f32>(out.current.xy * frame.jitter.zw + frame.jitter.xy * out.current.w, out.current.zw);
    out.dynamic_object = select(0u, 1u, o.emissive.a > 1.5);
    return out;
}

@fragment
fn fs_velocity(in: VelocityOut) -> @location(0) vec4<f32> {
    let motion = screen_motion(in.current, in.previous, in.still == 1u);
    return vec4<f32>(motion, f32(in.dynamic_object), in.previous.z / in.previous.w);
}

// Motion, shared by the velocity pass and adaptive shading's G-buffer.
//
// Nothing moved (still camera, object not animated): the motion is exactly zero. Computing it
// gives rounding noise on some GPUs, even from two equal products (on an H100: between 1e-7 and
// 1e-5 px, enough to switch on checkerboard-2x2's conditional clamp, threshold 1e-7 px, in a static
// scene; the compiler may contract `(a - b) * k` into `a * k - b * k`), so it is zeroed explicitly.
fn is_still(object: u32) -> bool {
    return frame.counts.w == 1u && objects[object].emissive.a < 1.5;
}

// A vertex's clip position in the previous frame (`current` itself where nothing moved).
fn previous_clip(position: vec3<f32>, object: u32, current: vec4<f32>, still: bool) -> vec4<f32> {
    if still {
        return current;
    }
    return frame.prev_view_proj * objects[object].prev_model * vec4<f32>(position, 1.0);
}

// Screen motion in pixels (x right, y down) from the previous clip position to the current one.
fn screen_motion(current: vec4<f32>, previous: vec4<f32>, still: bool) -> vec2<f32> {
    if still {
        return vec2<f32>(0.0);
    }
    let size = frame.counts.yz;
    let ndc = current.xy / current.w;
    let prev = previous.xy / previous.w;
    return (ndc - prev) * 0.5 * vec2<f32>(f32(size.x), -f32(size.y));
}
