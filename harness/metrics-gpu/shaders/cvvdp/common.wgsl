// Shared by every ColorVideoVDP pass (colorvideovdp 0.1.1, mirrored f32 operation for f32
// operation; see src/cvvdp/). Planes are row-major f32, one buffer per plane.

// pyramid.rs: the 5-tap binomial-like kernel of the Laplacian pyramid.
const K0: f32 = 0.05;
const K1: f32 = 0.25;
const K2: f32 = 0.4;
const K3: f32 = 0.25;
const K4: f32 = 0.05;

fn kernel(k: i32) -> f32 {
    switch k {
        case 0: { return K0; }
        case 1: { return K1; }
        case 2: { return K2; }
        case 3: { return K3; }
        default: { return K4; }
    }
}

// parameters.rs: safe_pow(x, p) = (x + 1e-5)^p - 1e-5^p; `eps` is 1e-5^p as the CPU computes it.
// A square is multiplied out (the CPU's powf(x, 2) is correctly rounded, as is b * b).
fn spow(x: f32, p: f32, eps: f32) -> f32 {
    let b = x + 0.00001;
    var r: f32;
    if (p == 2.0) {
        r = b * b;
    } else {
        r = pow(b, p);
    }
    return r - eps;
}

const LOG10_2: f32 = 0.30102999566398120;
const LOG2_10: f32 = 3.32192809488736235;

fn log10_(x: f32) -> f32 {
    return log2(x) * LOG10_2;
}

fn pow10(x: f32) -> f32 {
    return exp2(x * LOG2_10);
}
