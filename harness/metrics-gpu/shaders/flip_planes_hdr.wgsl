// FLIP planes of a linear frame at one HDR-FLIP exposure: multiply by 2^exposure, ACES with
// FLIP's 0.6 pre-exposure cancellation, clamp to [0,1] (tessera-metrics `flip/hdr.rs`), then
// YCxCz and the feature channel.

struct Params {
    count: u32,
    groups_x: u32,
    multiplier: f32,
    _p0: u32,
    t012: vec4<f32>,
    t345: vec4<f32>,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> src: array<f32>;
@group(0) @binding(2) var<storage, read_write> planes: array<vec4<f32>>;

fn tone(v: f32) -> f32 {
    let c = v * params.multiplier;
    let t = ((c * c) * params.t012.x + c * params.t012.y + params.t012.z)
        / (c * c * params.t345.x + c * params.t345.y + params.t345.z);
    return clamp(t, 0.0, 1.0);
}

@compute @workgroup_size(256)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x + gid.y * params.groups_x * 256u;
    if (i >= params.count) {
        return;
    }
    let c = vec3<f32>(tone(src[3u * i]), tone(src[3u * i + 1u]), tone(src[3u * i + 2u]));
    planes[i] = planes_of(c);
}
