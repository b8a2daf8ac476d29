//! From per-tile rates to a fragment-shading-rate attachment, and how many coarse-pixel shades an
//! attachment implies: the CPU side of the hardware path (`vrs = "hardware"`), step for step with
//! `attachment.wgsl`. No GPU and no Vulkan here (that is `raw_pass.rs`).
//!
//! The mapping, in three steps:
//!
//! 1. **Code.** The rate pass writes `log2(rx) | log2(ry) << 2` per 16x16 tile (`model::encode`);
//!    VK_KHR_fragment_shading_rate's attachment texel is `log2(width) << 2 | log2(height)`.
//! 2. **Offered sizes.** A fragment size the adapter does not offer at one sample is lowered to the
//!    largest offered size no wider and no taller (most pixels per shade, then the wider): on the
//!    H200, which offers 1x1, 1x2, 2x1, 2x2, 2x4, 4x2 and 4x4 (aspect ratio at most 2), 4x1 becomes
//!    2x1 and 1x4 becomes 1x2. Never coarser than the rate pass asked for.
//! 3. **Texel size.** With a 16x16 attachment texel (the H200's only size) one texel is one tile.
//!    Where 16 is below the adapter's smallest texel size, a texel covers several tiles and takes
//!    their finest rate per axis; where 16 is above its largest, a tile's rate is repeated over the
//!    (16 / texel)^2 texels it covers.
//!
//! The shade-count model: hardware VRS shades a fragment area of `w` x `h` pixels aligned to
//! multiples of `w` and `h` in framebuffer coordinates, once per primitive that covers a sample of
//! it and passes the depth test. The hardware pass has a depth pre-pass and shades with depth test
//! EQUAL (`raw_pass.rs`), so only visible primitives are shaded. Counted per coarse pixel that holds
//! at least one covered pixel (partial coarse pixels at the image's right and bottom edges count
//! once), the model is exact at 1x1 and wherever one visible primitive fills a coarse pixel; where
//! a coarse pixel straddles a triangle edge or an object's silhouette the hardware shades it once
//! more per extra visible primitive, so the GPU count is the model's plus what edges cost.

use super::model::TILE;

/// Fragment sizes (width, height) every adapter with the extension offers.
pub const ALWAYS_OFFERED: [[u32; 2]; 1] = [[1, 1]];

/// The attachment texel of fragment size `w` x `h` (both powers of two).
pub fn vk_texel(w: u32, h: u32) -> u8 {
    ((w.trailing_zeros() << 2) | h.trailing_zeros()) as u8
}

/// Fragment size (width, height) of an attachment texel.
pub fn vk_size(texel: u8) -> [u32; 2] {
    [1 << ((texel >> 2) & 3), 1 << (texel & 3)]
}

/// The largest of `offered` no wider than `w` and no taller than `h` (most pixels, then the
/// wider); 1x1 when none fits.
pub fn clamp_to_offered(w: u32, h: u32, offered: &[[u32; 2]]) -> [u32; 2] {
    offered
        .iter()
        .copied()
        .filter(|&[ow, oh]| ow <= w && oh <= h)
        .max_by_key(|&[ow, oh]| (ow * oh, ow))
        .unwrap_or([1, 1])
}

/// Attachment texel per rate code of the rate pass (index: `log2(rx) | log2(ry) << 2`), sizes
/// lowered to what the adapter offers.
pub fn code_table(offered: &[[u32; 2]]) -> [u8; 16] {
    let mut t = [0u8; 16];
    for (code, slot) in t.iter_mut().enumerate() {
        let rx = 1u32 << (code & 3);
        let ry = 1u32 << ((code >> 2) & 3);
        let [w, h] = clamp_to_offered(rx.min(4), ry.min(4), offered);
        *slot = vk_texel(w, h);
    }
    t
}

/// The attachment's texel size: 16 where the adapter's range of power-of-two texel sizes
/// (`min`..=`max`, per axis) holds it, else the nearest end of the range (the same on both axes
/// when the adapter allows, else per axis).
pub fn texel_size(min: [u32; 2], max: [u32; 2]) -> [u32; 2] {
    [TILE.clamp(min[0], max[0]), TILE.clamp(min[1], max[1])]
}

/// An attachment: texels per axis and the texel size in pixels.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Attachment {
    pub width: u32,
    pub height: u32,
    pub texel: [u32; 2],
    /// Row-major, one byte per texel (VK_FORMAT_R8_UINT).
    pub data: Vec<u8>,
}

/// Attachment size for an image of `width` x `height` with texels of `texel` pixels.
pub fn attachment_size(width: u32, height: u32, texel: [u32; 2]) -> (u32, u32) {
    (width.div_ceil(texel[0]), height.div_ceil(texel[1]))
}

/// The attachment of per-tile rate `codes` (`tiles_x` x `tiles_y` tiles of 16x16 pixels) for an
/// image of `width` x `height`.
pub fn attachment(
    codes: &[u32],
    tiles_x: u32,
    tiles_y: u32,
    width: u32,
    height: u32,
    texel: [u32; 2],
    table: &[u8; 16],
) -> Attachment {
    let (aw, ah) = attachment_size(width, height, texel);
    let mut data = Vec::with_capacity((aw * ah) as usize);
    for ay in 0..ah {
        for ax in 0..aw {
            data.push(texel_at(codes, tiles_x, tiles_y, ax, ay, texel, table));
        }
    }
    Attachment {
        width: aw,
        height: ah,
        texel,
        data,
    }
}

/// Texel (`ax`, `ay`): the finest rate per axis of the tiles it overlaps (one tile when the texel
/// is 16 or smaller).
fn texel_at(
    codes: &[u32],
    tiles_x: u32,
    tiles_y: u32,
    ax: u32,
    ay: u32,
    texel: [u32; 2],
    table: &[u8; 16],
) -> u8 {
    let t0 = [ax * texel[0] / TILE, ay * texel[1] / TILE];
    let t1 = [
        ((ax + 1) * texel[0])
            .div_ceil(TILE)
            .min(tiles_x)
            .max(t0[0] + 1),
        ((ay + 1) * texel[1])
            .div_ceil(TILE)
            .min(tiles_y)
            .max(t0[1] + 1),
    ];
    let (mut lx, mut ly) = (3u32, 3u32);
    for ty in t0[1]..t1[1] {
        for tx in t0[0]..t1[0] {
            let c = codes
                .get((ty * tiles_x + tx) as usize)
                .copied()
                .unwrap_or(0);
            lx = lx.min(c & 3);
            ly = ly.min((c >> 2) & 3);
        }
    }
    table[(lx | (ly << 2)) as usize]
}

/// Every tile at one rate (`fixed-rate` variants): the attachment of `rx` x `ry` everywhere.
pub fn uniform(
    width: u32,
    height: u32,
    texel: [u32; 2],
    rx: u32,
    ry: u32,
    table: &[u8; 16],
) -> Attachment {
    let (aw, ah) = attachment_size(width, height, texel);
    let code = rx.trailing_zeros() | (ry.trailing_zeros() << 2);
    Attachment {
        width: aw,
        height: ah,
        texel,
        data: vec![table[code as usize]; (aw * ah) as usize],
    }
}

/// Coarse-pixel shades the attachment implies over an image of `width` x `height`: per fragment
/// area (aligned to its size) with at least one pixel where `covered(x, y)`.
pub fn shades(
    a: &Attachment,
    width: u32,
    height: u32,
    covered: &(dyn Fn(u32, u32) -> bool + Sync),
) -> u64 {
    // One attachment row of texels: the shades of its fragment areas.
    let row = |ay: u32| {
        let mut n = 0u64;
        for ax in 0..a.width {
            let [w, h] = vk_size(a.data[(ay * a.width + ax) as usize]);
            let x0 = ax * a.texel[0];
            let y0 = ay * a.texel[1];
            let x1 = (x0 + a.texel[0]).min(width);
            let y1 = (y0 + a.texel[1]).min(height);
            // Texel sizes are multiples of every fragment size, so areas never cross texels.
            let mut cy = y0;
            while cy < y1 {
                let mut cx = x0;
                while cx < x1 {
                    let any = (cy..(cy + h).min(y1))
                        .any(|y| (cx..(cx + w).min(x1)).any(|x| covered(x, y)));
                    n += u64::from(any);
                    cx += w;
                }
                cy += h;
            }
        }
        n
    };
    // Rows counted on every core (a 4K frame is 8.3M coverage reads per captured frame); the
    // count is a sum of integers, the same in any order.
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get()) as u32;
    let band = a.height.div_ceil(threads.max(1)).max(1);
    std::thread::scope(|scope| {
        let handles: Vec<_> = (0..a.height)
            .step_by(band as usize)
            .map(|start| {
                let row = &row;
                scope.spawn(move || (start..(start + band).min(a.height)).map(row).sum::<u64>())
            })
            .collect();
        handles
            .into_iter()
            .map(|h| h.join().unwrap_or_else(|e| std::panic::resume_unwind(e)))
            .sum()
    })
}

/// Shades over covered pixels (1 where nothing is covered): the average shading rate as the
/// software path reports it.
pub fn rate(shades: u64, covered: u64) -> f64 {
    if covered == 0 {
        1.0
    } else {
        shades as f64 / covered as f64
    }
}

#[cfg(test)]
mod tests {
    use super::super::model::encode;
    use super::*;

    const H200: [[u32; 2]; 7] = [[1, 1], [1, 2], [2, 1], [2, 2], [2, 4], [4, 2], [4, 4]];

    #[test]
    fn codes_swap_axes_and_lower_unoffered_sizes() {
        let t = code_table(&H200);
        // 1x1 -> 0; 2x1 (rx = 2) -> width 2: (1 << 2) | 0 = 4; 1x2 -> 1; 2x2 -> 5.
        assert_eq!(t[encode(1, 1) as usize], 0);
        assert_eq!(t[encode(2, 1) as usize], 4);
        assert_eq!(t[encode(1, 2) as usize], 1);
        assert_eq!(t[encode(2, 2) as usize], 5);
        // 4x2 -> (2 << 2) | 1 = 9; 4x4 -> 10.
        assert_eq!(t[encode(4, 2) as usize], 9);
        assert_eq!(t[encode(4, 4) as usize], 10);
        // 4x1 and 1x4 are not offered on the H200: 2x1 and 1x2.
        assert_eq!(t[encode(4, 1) as usize], 4);
        assert_eq!(t[encode(1, 4) as usize], 1);
        // Only 1x1 offered: everything 1x1.
        assert!(code_table(&ALWAYS_OFFERED).iter().all(|&c| c == 0));
        for c in 0..16u8 {
            assert_eq!(vk_texel(vk_size(c)[0], vk_size(c)[1]), c & 0b1111);
        }
    }

    #[test]
    fn texel_size_prefers_16_and_clamps_to_the_range() {
        assert_eq!(texel_size([16, 16], [16, 16]), [16, 16]);
        assert_eq!(texel_size([8, 8], [32, 32]), [16, 16]);
        assert_eq!(texel_size([4, 4], [8, 8]), [8, 8]);
        assert_eq!(texel_size([32, 32], [64, 64]), [32, 32]);
    }

    #[test]
    fn sixteen_pixel_texels_are_the_tiles() {
        let t = code_table(&H200);
        // 40x20 pixels: 3x2 tiles, the last column and row partial.
        let codes = [
            encode(1, 1),
            encode(2, 2),
            encode(4, 2),
            encode(2, 1),
            encode(1, 2),
            encode(4, 4),
        ];
        let a = attachment(&codes, 3, 2, 40, 20, [16, 16], &t);
        assert_eq!((a.width, a.height), (3, 2));
        let want: Vec<u8> = codes.iter().map(|&c| t[c as usize]).collect();
        assert_eq!(a.data, want);
    }

    #[test]
    fn small_texels_repeat_a_tile_and_large_ones_take_the_finest() {
        let t = code_table(&H200);
        let codes = [encode(2, 2), encode(4, 2), encode(1, 2), encode(2, 1)];
        // 8x8 texels: each tile's rate over 2x2 texels.
        let a = attachment(&codes, 2, 2, 32, 32, [8, 8], &t);
        assert_eq!((a.width, a.height), (4, 4));
        assert_eq!(a.data[0], t[encode(2, 2) as usize]);
        assert_eq!(a.data[5], t[encode(2, 2) as usize]);
        assert_eq!(a.data[2], t[encode(4, 2) as usize]);
        assert_eq!(a.data[15], t[encode(2, 1) as usize]);
        // One 32x32 texel over all four: finest per axis is 1 x 1.
        let b = attachment(&codes, 2, 2, 32, 32, [32, 32], &t);
        assert_eq!(b.data, vec![0]);
        // Over the first row only (2x2 and 4x2): 2 x 2.
        let c = attachment(&codes[..2], 2, 1, 32, 16, [32, 32], &t);
        assert_eq!(c.data, vec![t[encode(2, 2) as usize]]);
    }

    #[test]
    fn shade_count_of_full_and_partial_tiles() {
        let t = code_table(&H200);
        let all = |_: u32, _: u32| true;
        // 1x1 everywhere: one shade per pixel.
        let a = uniform(37, 21, [16, 16], 1, 1, &t);
        assert_eq!(shades(&a, 37, 21, &all), 37 * 21);
        // 2x2: ceil(37/2) x ceil(21/2) — partial coarse pixels at the right and bottom edges count.
        let b = uniform(37, 21, [16, 16], 2, 2, &t);
        assert_eq!(shades(&b, 37, 21, &all), 19 * 11);
        // 4x4 over 32x32: 64 shades.
        let c = uniform(32, 32, [16, 16], 4, 4, &t);
        assert_eq!(shades(&c, 32, 32, &all), 64);
        // Coverage: only the pixel (5, 5) drawn -> one shade at any rate.
        let one = |x: u32, y: u32| x == 5 && y == 5;
        assert_eq!(shades(&c, 32, 32, &one), 1);
        assert_eq!(shades(&a, 37, 21, &one), 1);
        assert_eq!(rate(shades(&c, 32, 32, &all), 32 * 32), 1.0 / 16.0);
    }
}
