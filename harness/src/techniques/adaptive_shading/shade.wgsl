// Adaptive shading's deferred path, appended to scene.wgsl: the G-buffer pass (what `shade_surface`
// needs per pixel, plus per-pixel motion for the rate pass) and the compute shading pass, which
// emulates variable-rate shading in software (wgpu has no VRS; Call of Duty's software VRS packs
// coarse pixels for compute the same way, notes/techniques.md "Other sources").
//
// Shading pass: one 16x16 workgroup per 16x16 tile, whose rate (rx x ry pixels per shade) is
// uniform over the workgroup. As hardware VRS does, each coarse pixel is shaded once per object it
// covers, at the coarse pixel's centre for that object (the mean of the G-buffer attributes of the
// object's pixels in it) with derivatives across the coarse pixel (the ground filter's footprint
// scaled by rx and ry), and the result is written to all its pixels of that object: object edges
// stay sharp. With `coarse_sample = "pixel"` it is shaded at its shading pixel's own sample
// instead (the centre pixel, or the object's first pixel in it). At 1x1 this is exactly the forward path's shading. The shades are packed into the
// first threads of the workgroup, so coarse tiles leave whole SIMD groups idle.

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
    let previous = previous_clip(position, object, v.clip, is_still(object));
    return GBufferVs(v.clip, v.rel_pos, v.normal, v.local, v.object, v.clip, previous);
}

// The ground is shaded from its pattern coordinate and footprint, every other object from its
// object-space position: one target holds whichever the object needs.
fn is_ground(object: u32) -> bool {
    return abs(objects[object].emissive.a - 1.0) < 0.5;
}

struct GBuffer {
    // xyz: camera-relative position; w: object + 1 (0 where nothing is drawn).
    @location(0) position: vec4<f32>,
    // xyz: interpolated normal.
    @location(1) normal: vec4<f32>,
    // The ground: screen-space derivatives of its pattern coordinate, gradient scale applied (xy
    // d/dx, zw d/dy; `surface` in scene.wgsl takes the footprint from them). Other objects: xyz
    // object-space position (the detail seed).
    @location(2) detail: vec4<f32>,
}

fn gbuffer(in: GBufferVs) -> GBuffer {
    let p = ground_coord(in.rel_pos);
    let ddx = dpdx(p) * frame.params.z;
    let ddy = dpdy(p) * frame.params.z;
    var detail = vec4<f32>(in.local, 0.0);
    if is_ground(in.object) {
        detail = vec4<f32>(ddx, ddy);
    }
    return GBuffer(
        vec4<f32>(in.rel_pos, f32(in.object + 1u)),
        vec4<f32>(in.normal, 0.0),
        detail,
    );
}

@fragment
fn fs_gbuffer(in: GBufferVs) -> GBuffer {
    return gbuffer(in);
}

struct GBufferMotion {
    @location(0) position: vec4<f32>,
    @location(1) normal: vec4<f32>,
    @location(2) detail: vec4<f32>,
    // xy: screen motion in pixels (current - previous, y down); z: the previous frame's depth
    // of this surface point; w: 1 (covered).
    @location(3) motion: vec4<f32>,
}

@fragment
fn fs_gbuffer_motion(in: GBufferVs) -> GBufferMotion {
    let g = gbuffer(in);
    let motion = screen_motion(in.current, in.previous, is_still(in.object));
    return GBufferMotion(
        g.position,
        g.normal,
        g.detail,
        vec4<f32>(motion, in.previous.z / in.previous.w, 1.0),
    );
}

struct ShadeParams {
    // x, y: output size; z: 1 to shade every tile at 1x1 (native-deferred), ignoring `rates`;
    // w: where a coarse pixel is shaded: 0 at its centre with derivatives across it (hardware
    // VRS), 1 at its shading pixel with that pixel's own attributes (a native sample, replicated).
    size: vec4<u32>,
}

@group(1) @binding(0) var<uniform> sp: ShadeParams;
@group(1) @binding(1) var g_position: texture_2d<f32>;
@group(1) @binding(2) var g_normal: texture_2d<f32>;
@group(1) @binding(3) var g_detail: texture_2d<f32>;
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

// Shades object `o` over the coarse pixel of `r` pixels at `block` (tile-local): the mean of the
// object's attributes there, the ground's derivatives of pixel `at` scaled to the coarse pixel.
fn shade_coarse(origin: vec2<i32>, block: vec2<u32>, r: vec2<u32>, o: u32, at: u32) -> vec4<f32> {
    let object = o - 1u;
    let pixel = origin + vec2<i32>(vec2<u32>(at % 16u, at / 16u));
    var scale = vec2<f32>(r);
    var rel_pos = textureLoad(g_position, pixel, 0).xyz;
    var normal = textureLoad(g_normal, pixel, 0).xyz;
    var detail = textureLoad(g_detail, pixel, 0);
    if sp.size.w == 1u {
        scale = vec2<f32>(1.0);
    } else {
        rel_pos = vec3<f32>(0.0);
        normal = vec3<f32>(0.0);
        var local = vec3<f32>(0.0);
        var n = 0.0;
        for (var y = 0u; y < r.y; y = y + 1u) {
            for (var x = 0u; x < r.x; x = x + 1u) {
                let q = block + vec2<u32>(x, y);
                if obj[q.y * 16u + q.x] == o {
                    let p = origin + vec2<i32>(q);
                    rel_pos = rel_pos + textureLoad(g_position, p, 0).xyz;
                    normal = normal + textureLoad(g_normal, p, 0).xyz;
                    local = local + textureLoad(g_detail, p, 0).xyz;
                    n = n + 1.0;
                }
            }
        }
        rel_pos = rel_pos / n;
        normal = normal / n;
        if !is_ground(object) {
            detail = vec4<f32>(local / n, 0.0);
        }
    }
    // Only the ground reads the footprint, only other objects the object-space position.
    var local = detail.xyz;
    var footprint = vec2<f32>(0.0);
    if is_ground(object) {
        local = vec3<f32>(0.0);
        footprint = max(abs(detail.xy * scale.x), abs(detail.zw * scale.y));
    }
    return shade_surface(Surface(rel_pos, normal, local, object, footprint));
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
        let q = vec2<u32>(j % 16u, j / 16u);
        col[j] = shade_coarse(origin, (q / r) * r, r, obj[j], j);
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
