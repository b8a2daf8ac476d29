// `checkerboard` technique, pass `reconstruct`: one invocation per full-resolution pixel rebuilds
// the frame from this frame's and the previous frame's quarter-resolution samples.
//
// Sources: Intel's CheckerboardColorResolveCS.hlsl (quadrant map, missing-shading rules, CSO/ASO)
// and mosaiikki's ReconstructionShader.frag (order of the steps, velocity buffer, clamp,
// confidence, reversible tonemap, differential blend); ../shared/notes/techniques.md sections 1a,
// 1b. Pixel coordinates are y-down: quadrant 0 = top-left, 1 = top-right, 2 = bottom-left,
// 3 = bottom-right of a 2x2 block. Even frames shade quadrants {0, 3}, odd frames {1, 2}.
// The sample accessors `load_color` / `load_depth` come from a prelude (two-pass or 2x MSAA).
// The CPU model in model.rs beside this file mirrors it step by step.

struct Params {
    // Previous frame's full-resolution NDC (unjittered) to current clip space.
    reproject: mat4x4<f32>,
    // xy: full resolution; zw: quarter-resolution texture size.
    size: vec4<u32>,
    // x: parity (0 even, 1 odd), y: reset history, z: occlusion (0 cso, 1 aso),
    // w: fill (0 plain, 1 tonemapped, 2 differential).
    mode: vec4<u32>,
    // x: clamp (0 none, 1 min-max, 2 min-max with depth confidence), y: velocity buffer present,
    // z: it holds the dynamic objects only (test its depth for static occluders), w: ASO's motion
    // rule (1 more than a quarter-resolution texel, Intel; 0 another 2x2 block, mosaiikki).
    mode2: vec4<u32>,
    // x: depth tolerance (view units), y: near, z: far.
    depth: vec4<f32>,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(9) var velocity: texture_2d<f32>;
// The velocity pass's depth (reversed-Z, 0 where it drew nothing); read when mode2.z is set.
@group(0) @binding(11) var velocity_depth: texture_depth_2d;
@group(0) @binding(10) var output: texture_storage_2d<rgba16float, write>;

// Which set of samples holds quadrant `q`: the current frame's if this frame shaded it.
fn is_current(q: u32) -> bool {
    let even_quadrant = q == 0u || q == 3u;
    return even_quadrant == (params.mode.x == 0u);
}

// Intel's readFromQuadrant: quadrant q of block b, from the frame that shaded it.
// Returns the quarter-resolution pixel and the sample index.
fn quadrant_source(b: vec2<i32>, q: u32) -> vec3<i32> {
    switch q {
        case 0u: { return vec3<i32>(b, 1); }
        case 1u: { return vec3<i32>(b + vec2<i32>(1, 0), 1); }
        case 2u: { return vec3<i32>(b, 0); }
        default: { return vec3<i32>(b, 0); }
    }
}

fn color_at(pixel: vec2<i32>) -> vec4<f32> {
    let q = u32(pixel.x & 1) + 2u * u32(pixel.y & 1);
    let s = quadrant_source(pixel >> vec2<u32>(1u), q);
    return load_color(!is_current(q), s.xy, u32(s.z));
}

fn depth_at(pixel: vec2<i32>) -> f32 {
    let q = u32(pixel.x & 1) + 2u * u32(pixel.y & 1);
    let s = quadrant_source(pixel >> vec2<u32>(1u), q);
    return load_depth(!is_current(q), s.xy, u32(s.z));
}

// View-space distance from reversed-Z depth (near -> 1, far -> 0).
fn linear_depth(d: f32) -> f32 {
    let near = params.depth.y;
    let far = params.depth.z;
    return near * far / (d * (far - near) + near);
}

// AMD's reversible tonemapper (mosaiikki): c / (1 + max(r, g, b)).
fn tonemap(c: vec3<f32>) -> vec3<f32> {
    return c / (1.0 + max(c.r, max(c.g, c.b)));
}

fn untonemap(c: vec3<f32>) -> vec3<f32> {
    return c / max(1.0 - max(c.r, max(c.g, c.b)), 1e-6);
}

const OFFSETS = array<vec2<i32>, 4>(vec2<i32>(0, -1), vec2<i32>(0, 1), vec2<i32>(-1, 0), vec2<i32>(1, 0));

fn inside(p: vec2<i32>) -> bool {
    return all(p >= vec2<i32>(0)) && all(p < vec2<i32>(params.size.xy));
}

// NaN and ±Inf, by their bits: a fast-math compiler may fold `x != x` away.
fn finite(c: vec3<f32>) -> bool {
    let e = bitcast<vec3<u32>>(c) & vec3<u32>(0x7f800000u);
    return all(e != vec3<u32>(0x7f800000u));
}

struct Neighbourhood {
    // Up, down, left, right (tonemapped when the fill or clamp needs it).
    c: array<vec3<f32>, 4>,
    // On screen and finite.
    valid: array<bool, 4>,
    count: f32,
    lo: vec3<f32>,
    hi: vec3<f32>,
    // A non-finite neighbour's colour (untonemapped), when one was left out.
    non_finite: vec3<f32>,
    has_non_finite: bool,
}

// The 4 cardinal neighbours' colours. Loaded only when a fill or a clamp needs them: on the
// history path without a clamp nothing here is read (CPU adapters pay for every load).
fn neighbourhood(pixel: vec2<i32>, tonemapped: bool) -> Neighbourhood {
    var n: Neighbourhood;
    n.has_non_finite = false;
    n.non_finite = vec3<f32>(0.0);
    n.lo = vec3<f32>(3.0e38);
    n.hi = vec3<f32>(-3.0e38);
    n.count = 0.0;
    for (var i = 0; i < 4; i = i + 1) {
        let p = pixel + OFFSETS[i];
        n.valid[i] = inside(p);
        n.c[i] = vec3<f32>(0.0);
        if n.valid[i] {
            var c = color_at(p).rgb;
            // Stability (issue 8, not in the sources): a non-finite neighbour is left out of the
            // fill and the clamp, so NaN or Inf never spreads into a finite pixel; a pixel whose
            // neighbours are all non-finite is inside such a region and stays non-finite.
            if !finite(c) {
                n.valid[i] = false;
                n.non_finite = c;
                n.has_non_finite = true;
                continue;
            }
            if tonemapped {
                c = tonemap(c);
            }
            n.c[i] = c;
            n.lo = min(n.lo, c);
            n.hi = max(n.hi, c);
            n.count = n.count + 1.0;
        }
    }
    return n;
}

// Mean view depth of the 4 cardinal neighbours (this frame's samples).
fn neighbour_depth(pixel: vec2<i32>) -> f32 {
    var sum = 0.0;
    var count = 0.0;
    for (var i = 0; i < 4; i = i + 1) {
        let p = pixel + OFFSETS[i];
        if inside(p) {
            sum = sum + linear_depth(depth_at(p));
            count = count + 1.0;
        }
    }
    return sum / max(count, 1.0);
}

// The spatial fill of a missing pixel, in the neighbourhood's space (tonemapped or not).
fn fill(n: Neighbourhood) -> vec3<f32> {
    if params.mode.w == 2u && n.valid[0] && n.valid[1] && n.valid[2] && n.valid[3] {
        // Differential blend (mosaiikki after Wihlidal/Jimenez): favour the smoother pair.
        let wv = 1.0 / max(length(n.c[0] - n.c[1]), 0.001);
        let wh = 1.0 / max(length(n.c[2] - n.c[3]), 0.001);
        return 0.5 * (wv * (n.c[0] + n.c[1]) + wh * (n.c[2] + n.c[3])) / (wv + wh);
    }
    var sum = vec3<f32>(0.0);
    for (var i = 0; i < 4; i = i + 1) {
        if n.valid[i] {
            sum = sum + n.c[i];
        }
    }
    return sum / max(n.count, 1.0);
}

fn finish(c: vec3<f32>, tonemapped: bool) -> vec4<f32> {
    if tonemapped {
        return vec4<f32>(untonemap(c), 1.0);
    }
    return vec4<f32>(c, 1.0);
}

fn reconstruct(pixel: vec2<i32>) -> vec4<f32> {
    let q = u32(pixel.x & 1) + 2u * u32(pixel.y & 1);
    // 1. Shaded this frame: take it.
    if is_current(q) {
        return color_at(pixel);
    }
    // Decide between history and a spatial fill first, then load the neighbourhood at one place
    // only: SIMD hardware and CPU rasterisers run every branch some lane takes.
    var use_history = false;
    var prev_pixel = pixel;
    var deviation = 0.0;
    let confidence_clamp = params.mode2.x == 2u;
    // 2. No usable history (first frame, camera cut, resolution change): spatial fill.
    if params.mode.y == 0u {
        // 3. Where was this pixel last frame? Dynamic pixels: the velocity buffer. Static
        //    pixels: the previous frame's sample here, unprojected with the previous camera and
        //    projected with the current one (Intel; mosaiikki unprojects with the current inverse).
        let size = vec2<f32>(params.size.xy);
        let centre = vec2<f32>(pixel) + 0.5;
        var prev_pos: vec2<f32>;
        var v = vec4<f32>(0.0);
        if params.mode2.y != 0u {
            v = textureLoad(velocity, pixel, 0);
        }
        // Static occluders (mode2.z: the velocity pass drew the dynamic objects only, as
        // mosaiikki's "Overview" 1, "Only dynamic objects; for static objects camera reprojection
        // is used in the reconstruction pass"). mosaiikki needs no test, every object of its scene
        // moves; here a static object in front of a moving one is not in the buffer, which then
        // says "dynamic, motion m" where the pixel shows the static object. This frame's
        // neighbours show what is in front: where the dynamic surface lies behind their mean
        // view depth by the tolerance or more, the pixel is taken as static (camera reprojection,
        // the path mosaiikki's "Reconstruction shader" 2 gives static objects). A plane or a
        // convex surface never is behind its own neighbours' mean (view depth is convex along a
        // screen line), so an unoccluded dynamic surface keeps its velocity; at an occluder's
        // edge the mean mixes both and the rule may pick either.
        if v.z > 0.5 && params.mode2.z != 0u {
            let behind = linear_depth(textureLoad(velocity_depth, pixel, 0)) - neighbour_depth(pixel);
            if behind >= params.depth.x {
                v.z = 0.0;
            }
        }
        if v.z > 0.5 {
            prev_pos = centre - v.xy;
        } else {
            let d = depth_at(pixel);
            let ndc = vec4<f32>(centre.x / size.x * 2.0 - 1.0, 1.0 - centre.y / size.y * 2.0, d, 1.0);
            let now = params.reproject * ndc;
            let now_px = vec2<f32>((now.x / now.w * 0.5 + 0.5) * size.x, (0.5 - now.y / now.w * 0.5) * size.y);
            prev_pos = centre - (now_px - centre);
        }
        prev_pixel = vec2<i32>(floor(prev_pos));
        // 4. Off screen last frame; 5. the motion cancelled the jitter (last frame did not shade
        //    that quadrant): both fill.
        let q_prev = u32(prev_pixel.x & 1) + 2u * u32(prev_pixel.y & 1);
        if inside(prev_pixel) && !is_current(q_prev) {
            // 6. Moved to another 2x2 block: possibly occluded. ASO assumes so; CSO compares
            //    the old sample's view depth with the mean of the current neighbours'.
            let moved_block = any((prev_pixel >> vec2<u32>(1u)) != (pixel >> vec2<u32>(1u)));
            if (moved_block && params.mode.z == 0u) || confidence_clamp {
                deviation = abs(neighbour_depth(pixel) - linear_depth(depth_at(prev_pixel)));
            }
            if params.mode.z == 1u {
                // ASO: moved more than a quarter-resolution texel (2 px; Intel's white paper,
                // "Assume Shading Occluded") or, as mosaiikki, to another 2x2 block (mode2.w 0).
                let moved_far = length(prev_pos - centre) > 2.0;
                use_history = !select(moved_block, moved_far, params.mode2.w == 1u);
            } else {
                use_history = !(moved_block && deviation >= params.depth.x);
            }
        }
    }
    // A non-finite history sample is not used (stability, as the neighbours above).
    var history = vec4<f32>(0.0);
    if use_history {
        history = color_at(prev_pixel);
        use_history = finite(history.rgb);
    }
    // 7. History, unclamped (Intel) ...
    if use_history && params.mode2.x == 0u {
        return history;
    }
    let tonemapped = params.mode.w != 0u;
    let n = neighbourhood(pixel, tonemapped);
    if !use_history {
        if n.count == 0.0 && n.has_non_finite {
            return vec4<f32>(n.non_finite, 1.0);
        }
        return finish(fill(n), tonemapped);
    }
    if n.count == 0.0 {
        return history;
    }
    // ... or clamped to the neighbourhood (mosaiikki after El Mansouri), optionally blended back
    // by depth confidence (a large deviation means small-scale detail: trust the history).
    var h = history.rgb;
    if tonemapped {
        h = tonemap(h);
    }
    let clamped = clamp(h, n.lo, n.hi);
    if confidence_clamp {
        let d = deviation - params.depth.x;
        h = mix(clamped, h, clamp(d * d, 0.0, 1.0));
    } else {
        h = clamped;
    }
    return finish(h, tonemapped);
}

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= params.size.x || id.y >= params.size.y {
        return;
    }
    textureStore(output, id.xy, reconstruct(vec2<i32>(id.xy)));
}
