// Section 5.4's neighbour filter of adaptive shading's rates (Yang et al. 2019): per axis, a tile's
// rate is at most twice the lowest among its eight neighbours. Appended to the modules that filter
// (`rate.wgsl`'s `filter_rates`, `attachment.wgsl`), which declare `rates_in`, the unfiltered
// codes (log2(rx) | log2(ry) << 2). CPU model: `model::neighbour_filter`.

// The loads have no branches (coordinates clamped, neighbours outside the grid not taken), so
// the nine can be in flight together.
fn filtered_code(t: vec2<i32>, tiles: vec2<i32>) -> u32 {
    let c = textureLoad(rates_in, t, 0).x;
    var lx = c & 3u;
    var ly = (c >> 2u) & 3u;
    for (var dy = -1; dy <= 1; dy = dy + 1) {
        for (var dx = -1; dx <= 1; dx = dx + 1) {
            let n = t + vec2<i32>(dx, dy);
            let taken = all(n >= vec2<i32>(0)) && all(n < tiles);
            let nc = textureLoad(rates_in, clamp(n, vec2<i32>(0), tiles - 1), 0).x;
            lx = select(lx, min(lx, (nc & 3u) + 1u), taken);
            ly = select(ly, min(ly, ((nc >> 2u) & 3u) + 1u), taken);
        }
    }
    return lx | (ly << 2u);
}
