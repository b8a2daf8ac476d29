// FLIP's colour spaces in f32 (tessera-metrics `flip/color.rs`, from `FLIP.h`); the constants
// (`C_*`) are prepended by `flip.rs` as the exact f32 values the CPU port uses.

fn linear_rgb_to_xyz(c: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(
        C_A11 * c.x + C_A12 * c.y + C_A13 * c.z,
        C_A21 * c.x + C_A22 * c.y + C_A23 * c.z,
        C_A31 * c.x + C_A32 * c.y + C_A33 * c.z,
    );
}

fn xyz_to_linear_rgb(c: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(
        C_B11 * c.x + C_B12 * c.y + C_B13 * c.z,
        C_B21 * c.x + C_B22 * c.y + C_B23 * c.z,
        C_B31 * c.x + C_B32 * c.y + C_B33 * c.z,
    );
}

fn xyz_to_ycxcz(c: vec3<f32>) -> vec3<f32> {
    let x = c.x * C_INV_ILL_X;
    let y = c.y * C_INV_ILL_Y;
    let z = c.z * C_INV_ILL_Z;
    return vec3<f32>(116.0 * y - 16.0, 500.0 * (x - y), 200.0 * (y - z));
}

fn ycxcz_to_xyz(yy: f32, cx: f32, cz: f32) -> vec3<f32> {
    let y = (yy + 16.0) / 116.0;
    let x = y + cx / 500.0;
    let z = y - cz / 200.0;
    return vec3<f32>(x * C_ILL_X, y * C_ILL_Y, z * C_ILL_Z);
}

// x^y for x >= 0 with the CPU port's edge cases: 0^0 = 1, 0^y = 0.
fn pow0(x: f32, y: f32) -> f32 {
    if (x == 0.0) {
        return select(0.0, 1.0, y == 0.0);
    }
    return pow(x, y);
}

fn lab_f(v: f32) -> f32 {
    if (v > C_DELTA_CUBE) {
        return pow0(v, C_ONE_THIRD);
    }
    return C_LAB_FACTOR * v + C_LAB_TERM;
}

fn clamped_rgb_to_hunt_lab(rgb: vec3<f32>) -> vec3<f32> {
    let c = clamp(rgb, vec3<f32>(0.0), vec3<f32>(1.0));
    let xyz = linear_rgb_to_xyz(c);
    let x = lab_f(xyz.x * C_INV_ILL_X);
    let y = lab_f(xyz.y * C_INV_ILL_Y);
    let z = lab_f(xyz.z * C_INV_ILL_Z);
    let l = 116.0 * y - 16.0;
    let la = 500.0 * (x - y);
    let lb = 200.0 * (y - z);
    return vec3<f32>(l, 0.01 * l * la, 0.01 * l * lb);
}

fn hyab(a: vec3<f32>, b: vec3<f32>) -> f32 {
    let dl = abs(a.x - b.x);
    let da = a.y - b.y;
    let db = a.z - b.z;
    return dl + sqrt(da * da + db * db);
}

// The YCxCz planes of one pixel of linear RGB in [0,1]: (Y, Cx, Cz, feature gray).
fn planes_of(c: vec3<f32>) -> vec4<f32> {
    let v = xyz_to_ycxcz(linear_rgb_to_xyz(c));
    return vec4<f32>(v, v.x * C_ONE_OVER_116 + C_SIXTEEN_OVER_116);
}
