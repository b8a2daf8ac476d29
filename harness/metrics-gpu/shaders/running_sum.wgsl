// FLIP's mean as flip-evaluator pools it, on the device: the f32 running sum of an error map in
// row-major order (NaN and negative values as 0), `s = s + v` one value after the other,
// exactly as tessera-metrics' `flip::pool::running_sum` adds them on the CPU. One workgroup per
// map (the maps of a batch are summed side by side); its threads stage tiles of the map in
// workgroup memory (the next while the last is added) and one thread adds them in order.
// Sequential by definition: the f32 rounding of each step depends on the sum before it, so no
// parallel order gives the same value.

struct Params {
    // Values per map.
    count: u32,
    // f32 words from one map to the next.
    stride: u32,
    _p0: u32,
    _p1: u32,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> maps: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read_write> sums: array<f32>;

// 2048 values per tile; two tiles (16 KiB, WebGPU's least workgroup storage), so that the next
// is loaded while the last is summed.
const TILE: u32 = 512u;
var<workgroup> tile: array<vec4<f32>, 1024>;

// Threads below this do not load: the summing thread's subgroup (32 or 64 wide) stays on its
// adds instead of waiting on its lanes' loads.
const FIRST_LOADER: u32 = 64u;

fn clean(v: f32) -> f32 {
    return select(0.0, v, v > 0.0);
}

fn load(base: u32, start: u32, len: u32, half: u32, li: u32) {
    if (li >= FIRST_LOADER) {
        for (var j = li - FIRST_LOADER; j < len; j += 256u - FIRST_LOADER) {
            tile[half * TILE + j] = maps[base + start + j];
        }
    }
}

@compute @workgroup_size(256)
fn main(
    @builtin(local_invocation_index) li: u32,
    @builtin(workgroup_id) wg: vec3<u32>,
) {
    // The stride is a multiple of 4 (maps start on 256-byte boundaries).
    let base = wg.x * (params.stride / 4u);
    let quads = params.count / 4u + select(0u, 1u, params.count % 4u != 0u);
    var s = 0.0;
    load(base, 0u, min(TILE, quads), 0u, li);
    workgroupBarrier();
    var half = 0u;
    for (var start = 0u; start < quads; start += TILE) {
        let len = min(TILE, quads - start);
        // The next tile into the other half while thread 0 adds this one.
        let next = start + TILE;
        if (next < quads) {
            load(base, next, min(TILE, quads - next), 1u - half, li);
        }
        if (li == 0u) {
            let last = start + len == quads;
            // The map's last quad may hold values past `count`: only its first `count % 4`.
            let full = select(len, len - 1u, last && params.count % 4u != 0u);
            // Four quads read before their sixteen adds: one thread's adds wait on one
            // workgroup-memory latency per sixteen values, not per four. Same order of adds.
            let at = half * TILE;
            var j = 0u;
            while (j + 4u <= full) {
                let a = tile[at + j];
                let b = tile[at + j + 1u];
                let c = tile[at + j + 2u];
                let d = tile[at + j + 3u];
                s = s + clean(a.x);
                s = s + clean(a.y);
                s = s + clean(a.z);
                s = s + clean(a.w);
                s = s + clean(b.x);
                s = s + clean(b.y);
                s = s + clean(b.z);
                s = s + clean(b.w);
                s = s + clean(c.x);
                s = s + clean(c.y);
                s = s + clean(c.z);
                s = s + clean(c.w);
                s = s + clean(d.x);
                s = s + clean(d.y);
                s = s + clean(d.z);
                s = s + clean(d.w);
                j += 4u;
            }
            while (j < full) {
                let v = tile[at + j];
                s = s + clean(v.x);
                s = s + clean(v.y);
                s = s + clean(v.z);
                s = s + clean(v.w);
                j += 1u;
            }
            if (full < len) {
                let v = tile[half * TILE + full];
                let rest = params.count % 4u;
                s = s + clean(v.x);
                if (rest > 1u) {
                    s = s + clean(v.y);
                }
                if (rest > 2u) {
                    s = s + clean(v.z);
                }
            }
        }
        workgroupBarrier();
        half = 1u - half;
    }
    if (li == 0u) {
        sums[wg.x] = s;
    }
}
