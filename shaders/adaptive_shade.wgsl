// Adaptive shading's deferred path, appended to scene.wgsl: the G-buffer pass (what `shade_surface`
// needs per pixel, plus per-pixel motion for the rate pass) and the compute shading pass, which
// emulates variable-rate shading in software (wgpu has no VRS; Call of Duty's software VRS packs
// coarse pixels for compute the same way, notes/techniques.md "Other sources").
//
// Shading pass: one 16x16 workgroup per 16x16 tile, whose rate (rx x ry pixels per shade) is
// uniform over the workgroup. Each coarse pixel is shaded once per object it covers, at its centre
// pixel ((rx - 1) / 2, (ry - 1) / 2) when that pixel shows the object, else at the object's first
// pixel in row order; the result is written to all its pixels of that object. So object edges stay
// sharp, as with hardware VRS, whose coarse pixels are shaded per primitive. The shades are packed
// into the first threads of the workgroup, so coarse tiles leave whole SIMD groups idle.

struct GBufferVs {
    @builtin(position) clip: vec4<f32>,
    @location(0) rel_pos: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) local: vec3<f32>,
    @location(3) @interpolate(flat) object: u32,
    @location(4) current: vec4<f32>,
    @location(5) previous: vec4<f32>,
}

@vertex
fn vs_gbuffer(
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @builtin(instance_index) object: u32,
) -> GBufferVs {
    let v = transform(position, normal, object);
    let o = objects[object];
    let previous = frame.prev_view_proj * o.prev_model * vec4<f32>(position, 1.0);
    return GBufferVs(v.clip, v.rel_pos, v.normal, v.local, v.object, v.clip, previous);
}

struct GBuffer {
    // xyz: camera-relative position; w: object + 1 (0 where nothing is drawn).
    @location(0) position: vec4<f32>,
    // xyz: interpolated normal; w: ground footprint x.
    @location(1) normal: vec4<f32>,
    // xyz: object-space position; w: ground footprint y.
    @location(2) local: vec4<f32>,
}

fn gbuffer(in: GBufferVs) -> GBuffer {
    let s = surface(VsOut(in.clip, in.rel_pos, in.normal, in.local, in.object));
    return GBuffer(
        vec4<f32>(s.rel_pos, f32(s.object + 1u)),
        vec4<f32>(s.normal, s.footprint.x),
        vec4<f32>(s.local, s.footprint.y),
    );
}

@fragment
fn fs_gbuffer(in: GBufferVs) -> GBuffer {
    return gbuffer(in);
}

struct GBufferMotion {
    @location(0) position: vec4<f32>,
    @location(1) normal: vec4<f32>,
    @location(2) local: vec4<f32>,
    // xy: screen motion in pixels (current - previous, y down); z: the previous frame's depth
    // of this surface point; w: 1 (covered).
    @location(3) motion: vec4<f32>,
}

@fragment
fn fs_gbuffer_motion(in: GBufferVs) -> GBufferMotion {
    let g = gbuffer(in);
    let size = frame.counts.yz;
    let ndc = in.current.xy / in.current.w;
    let prev = in.previous.xy / in.previous.w;
    let motion = (ndc - prev) * 0.5 * vec2<f32>(f32(size.x), -f32(size.y));
    return GBufferMotion(
        g.position,
        g.normal,
        g.local,
        vec4<f32>(motion, in.previous.z / in.previous.w, 1.0),
    );
}

struct ShadeParams {
    // x, y: output size; z: 1 to shade every tile at 1x1 (native-deferred), ignoring `rates`.
    size: vec4<u32>,
}

@group(1) @binding(0) var<uniform> sp: ShadeParams;
@group(1) @binding(1) var g_position: texture_2d<f32>;
@group(1) @binding(2) var g_normal: texture_2d<f32>;
@group(1) @binding(3) var g_local: texture_2d<f32>;
@group(1) @binding(4) var rates: texture_2d<u32>;
@group(1) @binding(5) var shaded: texture_storage_2d<rgba16float, write>;
// [0]: shades, [1]: covered pixels, summed over the frame.
@group(1) @binding(6) var<storage, read_write> counters: array<atomic<u32>, 2>;

var<workgroup> obj: array<u32, 256>;
var<workgroup> rep: array<u32, 256>;
var<workgroup> tasks: array<u32, 256>;
var<workgroup> col: array<vec4<f32>, 256>;
var<workgroup> task_count: atomic<u32>;
var<workgroup> covered: atomic<u32>;

fn shade_pixel(p: vec2<i32>) -> vec4<f32> {
    let a = textureLoad(g_position, p, 0);
    let b = textureLoad(g_normal, p, 0);
    let c = textureLoad(g_local, p, 0);
    return shade_surface(Surface(a.xyz, b.xyz, c.xyz, u32(a.w) - 1u, vec2<f32>(b.w, c.w)));
}

@compute @workgroup_size(16, 16)
fn shade_main(
    @builtin(workgroup_id) tile: vec3<u32>,
    @builtin(local_invocation_id) lid: vec3<u32>,
    @builtin(local_invocation_index) i: u32,
) {
    let size = vec2<i32>(sp.size.xy);
    let origin = vec2<i32>(tile.xy * 16u);
    let p = origin + vec2<i32>(lid.xy);
    let inside = all(p < size);
    if i == 0u {
        atomicStore(&task_count, 0u);
        atomicStore(&covered, 0u);
    }
    var o = 0u;
    if inside {
        o = u32(textureLoad(g_position, p, 0).w);
    }
    obj[i] = o;
    var code = 0u;
    if sp.size.z == 0u {
        code = textureLoad(rates, vec2<i32>(tile.xy), 0).x;
    }
    let r = vec2<u32>(1u << (code & 3u), 1u << ((code >> 2u) & 3u));
    workgroupBarrier();
    // The coarse pixel (block) of this pixel, and who shades for it.
    let b = (lid.xy / r) * r;
    let centre = b + (r - 1u) / 2u;
    var me = centre.y * 16u + centre.x;
    if o != 0u && obj[me] != o {
        me = 256u;
        for (var y = 0u; y < r.y; y = y + 1u) {
            for (var x = 0u; x < r.x; x = x + 1u) {
                let j = (b.y + y) * 16u + b.x + x;
                if me == 256u && obj[j] == o {
                    me = j;
                }
            }
        }
    }
    rep[i] = me;
    if o != 0u {
        atomicAdd(&covered, 1u);
        if me == i {
            tasks[atomicAdd(&task_count, 1u)] = i;
        }
    }
    workgroupBarrier();
    // Packed: threads 0..n shade, one coarse pixel (and object) each.
    let n = atomicLoad(&task_count);
    if i < n {
        let j = tasks[i];
        col[j] = shade_pixel(origin + vec2<i32>(vec2<u32>(j % 16u, j / 16u)));
    }
    workgroupBarrier();
    if inside {
        var c = vec4<f32>(frame.background.rgb, 1.0);
        if o != 0u {
            c = col[rep[i]];
        }
        textureStore(shaded, p, c);
    }
    if i == 0u {
        atomicAdd(&counters[0], n);
        atomicAdd(&counters[1], atomicLoad(&covered));
    }
}
