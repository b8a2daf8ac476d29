//! Branch-free `pow` for FLIP's per-pixel exponents, evaluated in f64 so the f32 result matches
//! libm's `powf` to within an ulp, written so the compiler can vectorise it over a row.
//!
//! For: `x^(1/3)` in CIELAB, `HyAB^0.7` and the final `colour^(1 - feature)`, which with libm
//! took about a third of FLIP's time. Not for: general use (x must be finite and >= 0, y
//! finite; `pow(0, 0) = 1` and `pow(0, y > 0) = 0` as libm gives).
//!
//! `log2(m)` for the mantissa in [sqrt(1/2), sqrt(2)) uses the atanh series
//! `2/ln 2 * (s + s^3/3 + ... + s^13/13)`, `s = (m - 1)/(m + 1)`, |s| < 0.172 (error < 1e-13);
//! `2^f` for f in [-0.5, 0.5] uses the Taylor series of `e^(f ln 2)` to degree 11 (< 1e-14).

const LN2: f64 = std::f64::consts::LN_2;

#[inline(always)]
fn log2(x: f64) -> f64 {
    let bits = x.to_bits();
    let mut e = ((bits >> 52) & 0x7ff) as i32 - 1023;
    let mut m = f64::from_bits((bits & 0x000f_ffff_ffff_ffff) | 0x3ff0_0000_0000_0000);
    let big = m > std::f64::consts::SQRT_2;
    m = if big { m * 0.5 } else { m };
    e += big as i32;
    let s = (m - 1.0) / (m + 1.0);
    let s2 = s * s;
    let p = 1.0
        + s2 * (1.0 / 3.0
            + s2 * (1.0 / 5.0
                + s2 * (1.0 / 7.0 + s2 * (1.0 / 9.0 + s2 * (1.0 / 11.0 + s2 * (1.0 / 13.0))))));
    e as f64 + (2.0 / LN2) * s * p
}

#[inline(always)]
fn exp2(t: f64) -> f64 {
    // Clamp to a range where 2^t is a normal f64 and the f32 result is 0 or finite.
    let t = t.clamp(-1000.0, 1000.0);
    // Round to nearest with the 1.5 * 2^52 trick: `f64::round` is a libm call without SSE4.1.
    const MAGIC: f64 = 6_755_399_441_055_744.0;
    let n = (t + MAGIC) - MAGIC;
    let u = (t - n) * LN2;
    // Horner form of sum_{k=0}^{11} u^k / k!: 1 + u/1 (1 + u/2 (1 + ... (1 + u/11))).
    let mut p = 1.0;
    for inv_k in INV_K.iter().rev() {
        p = 1.0 + p * u * inv_k;
    }
    p * f64::from_bits(((n as i64 + 1023) as u64) << 52)
}

/// 1/1 .. 1/11.
const INV_K: [f64; 11] = [
    1.0,
    1.0 / 2.0,
    1.0 / 3.0,
    1.0 / 4.0,
    1.0 / 5.0,
    1.0 / 6.0,
    1.0 / 7.0,
    1.0 / 8.0,
    1.0 / 9.0,
    1.0 / 10.0,
    1.0 / 11.0,
];

/// `x^y` for finite `x >= 0` and finite `y`, rounded to f32.
#[inline(always)]
pub(crate) fn pow(x: f32, y: f32) -> f32 {
    let r = exp2(y as f64 * log2(x as f64)) as f32;
    if x == 0.0 {
        if y == 0.0 {
            1.0
        } else {
            0.0
        }
    } else {
        r
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn agrees_with_libm_to_an_ulp() {
        let mut worst = 0.0f32;
        let mut s = 7u32;
        for _ in 0..200_000 {
            s = s.wrapping_mul(1664525).wrapping_add(1013904223);
            let x = (s >> 8) as f32 / (1u32 << 24) as f32 * 120.0;
            s = s.wrapping_mul(1664525).wrapping_add(1013904223);
            let y = (s >> 8) as f32 / (1u32 << 24) as f32;
            for (x, y) in [(x, y), (x, 0.7), (x / 100.0, 1.0 / 3.0)] {
                let (a, b) = (pow(x, y), x.powf(y));
                let ulps = (a - b).abs() / (b.abs() * f32::EPSILON).max(f32::MIN_POSITIVE);
                worst = worst.max(ulps);
            }
        }
        assert!(worst <= 1.0, "worst {worst} ulp");
    }

    #[test]
    fn edge_cases() {
        assert_eq!(pow(0.0, 0.0), 1.0);
        assert_eq!(pow(0.0, 0.5), 0.0);
        assert_eq!(pow(1.0, 0.7), 1.0);
        assert_eq!(pow(8.0, 1.0 / 3.0), 2.0);
        assert_eq!(pow(1e-30, 1.0), 1e-30);
    }
}
