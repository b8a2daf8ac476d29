//! The generated city (`[scene.city]`): a square grid of blocks with streets between them,
//! deterministic from a seed, as one textured [`Model`] whose parts are instanced.
//!
//! What it holds, and why (the workload Bistro is to the papers, without a download):
//! - buildings (four box variants, instanced around each block's edge) with generated facade
//!   textures of known frequency content: a window grid of 4 cycles per texture plus a sinusoidal
//!   grain at `texture_detail` times level 0's Nyquist frequency (albedo, normal from the same
//!   height field, roughness), so mip selection and LOD bias decide what survives;
//! - alpha-tested foliage: trees of `tree_cards` crossed cards (MASK, cutoff 0.5), the overdraw
//!   knob;
//! - poles and wires: thin geometry (8 cm poles, 3 cm wires) that aliases and flickers;
//! - parked vehicles (static) and moving vehicles (dynamic objects driving along the streets,
//!   with motion through the velocity pass).
//!
//! Every texture is generated on the CPU at `texture_size` texels and mip-mapped on the GPU at
//! load. Not here: drawing (`render/material.rs`), the scenario keys (`scenario/`).

use glam::{DMat4, DVec3, Vec2, Vec3};

use super::material::{
    generate_tangents, AlphaMode, Brdf, Material, MaterialVertex, Model, Placement, Primitive,
    TextureRef, UvTransform,
};
use super::scene::City;
use super::texture::{Encoding, Image, SamplerDesc};

/// Street width between blocks, metres.
pub const STREET: f32 = 12.0;
/// Metres one facade texture covers (two windows across, two storeys up).
const FACADE_TILE: f32 = 6.0;
/// Metres one road texture covers.
const ROAD_TILE: f32 = 4.0;
/// Window grid of the facade texture, cycles per texture.
pub const WINDOW_CYCLES: u32 = 4;

/// One object of the city: its model matrix at time 0 and, for moving vehicles, its velocity.
#[derive(Clone, Copy, Debug)]
pub struct CityObject {
    pub base: DMat4,
    pub velocity: Option<DVec3>,
}

impl CityObject {
    pub fn model_at(&self, t: f64) -> DMat4 {
        match self.velocity {
            None => self.base,
            Some(v) => DMat4::from_translation(v * t) * self.base,
        }
    }

    pub fn is_dynamic(&self) -> bool {
        self.velocity.is_some()
    }
}

/// The city's model, its placements (objects from `first_object` on) and its objects.
pub struct Generated {
    pub model: Model,
    pub placements: Vec<Placement>,
    pub objects: Vec<CityObject>,
}

/// SplitMix64: a small deterministic generator (the same city on every machine).
struct Rng(u64);

impl Rng {
    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    fn unit(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 / (1u64 << 24) as f32
    }

    fn below(&mut self, n: u32) -> u32 {
        (self.next_u64() % n.max(1) as u64) as u32
    }
}

// Parts of the model, in order.
const BUILDING_VARIANTS: usize = 4;
const PART_ROAD: usize = BUILDING_VARIANTS;
const PART_TREE: usize = PART_ROAD + 1;
const PART_POLE: usize = PART_TREE + 1;
const PART_WIRE: usize = PART_POLE + 1;
const PART_CAR: usize = PART_WIRE + 1;
const CAR_COLOURS: usize = 3;

// Materials, in order.
const MAT_FACADE: usize = 0;
const MAT_ROOF: usize = 1;
const MAT_ROAD: usize = 2;
const MAT_FOLIAGE: usize = 3;
const MAT_BARK: usize = 4;
const MAT_METAL: usize = 5;
const MAT_CAR: usize = 6;

pub fn generate(c: &City, first_object: u32) -> Generated {
    let mut rng = Rng(c.seed ^ 0x7e55_e7a0);
    let mut model = Model {
        name: format!("city (seed {})", c.seed),
        images: textures(c.texture_size, c.texture_detail, c.seed),
        ..Default::default()
    };
    model.materials = materials();
    let extent = c.blocks as f32 * (c.block_size + STREET) + STREET;

    let building_sizes: Vec<Vec3> = (0..BUILDING_VARIANTS)
        .map(|i| {
            Vec3::new(
                10.0 + 2.0 * i as f32,
                12.0 + 9.0 * ((i * 3) % 4) as f32,
                10.0 + (i % 2) as f32 * 4.0,
            )
        })
        .collect();
    for size in &building_sizes {
        let mut b = Builder::default();
        b.box_uv(Vec3::new(0.0, size.y * 0.5, 0.0), *size, FACADE_TILE, false);
        let walls = b.finish(&mut model, MAT_FACADE);
        let mut r = Builder::default();
        r.roof(*size);
        let roof = r.finish(&mut model, MAT_ROOF);
        model.parts.push(vec![walls, roof]);
    }
    let mut road = Builder::default();
    road.quad_xz(extent * 0.5 + 20.0, ROAD_TILE);
    let road = road.finish(&mut model, MAT_ROAD);
    model.parts.push(vec![road]);

    let mut cards = Builder::default();
    for k in 0..c.tree_cards {
        let angle = std::f32::consts::PI * k as f32 / c.tree_cards as f32;
        cards.card(angle, 4.0, 5.0, 2.0);
    }
    let cards = cards.finish(&mut model, MAT_FOLIAGE);
    let mut trunk = Builder::default();
    trunk.cylinder(0.15, 2.5, 8);
    let trunk = trunk.finish(&mut model, MAT_BARK);
    model.parts.push(vec![cards, trunk]);

    let mut pole = Builder::default();
    pole.cylinder(0.08, 7.0, 8);
    let pole = pole.finish(&mut model, MAT_METAL);
    model.parts.push(vec![pole]);

    let spacing = (c.block_size - 1.0) / c.poles.max(1) as f32;
    let mut wire = Builder::default();
    wire.box_uv(
        Vec3::new(spacing * 0.5, 0.0, 0.0),
        Vec3::new(spacing, 0.03, 0.03),
        1.0,
        true,
    );
    let wire = wire.finish(&mut model, MAT_METAL);
    model.parts.push(vec![wire]);

    for k in 0..CAR_COLOURS {
        let mut body = Builder::default();
        body.box_uv(
            Vec3::new(0.0, 0.55, 0.0),
            Vec3::new(4.2, 0.8, 1.8),
            1.0,
            true,
        );
        body.box_uv(
            Vec3::new(-0.3, 1.25, 0.0),
            Vec3::new(2.2, 0.6, 1.6),
            1.0,
            true,
        );
        let body = body.finish(&mut model, MAT_CAR + k);
        model.parts.push(vec![body]);
    }

    // Objects, grouped by part so that each part's instances are consecutive.
    let mut by_part: Vec<Vec<CityObject>> = vec![Vec::new(); model.parts.len()];
    let still = |m: DMat4| CityObject {
        base: m,
        velocity: None,
    };
    by_part[PART_ROAD].push(still(DMat4::IDENTITY));
    let origin = -(extent as f64) * 0.5 + STREET as f64;
    let bs = c.block_size as f64;
    for bx in 0..c.blocks {
        for bz in 0..c.blocks {
            let x0 = origin + bx as f64 * (bs + STREET as f64);
            let z0 = origin + bz as f64 * (bs + STREET as f64);
            // Along the block's edge, counter-clockwise: position and outward yaw at t in [0, 4).
            let edge = |t: f64, inset: f64| -> (DVec3, f64) {
                let side = (t.floor() as i64).rem_euclid(4);
                let f = t - t.floor();
                let (a, b) = (inset, bs - inset);
                let l = b - a;
                match side {
                    0 => (
                        DVec3::new(x0 + a + f * l, 0.0, z0 + a),
                        std::f64::consts::PI,
                    ),
                    1 => (
                        DVec3::new(x0 + b, 0.0, z0 + a + f * l),
                        std::f64::consts::FRAC_PI_2,
                    ),
                    2 => (DVec3::new(x0 + b - f * l, 0.0, z0 + b), 0.0),
                    _ => (
                        DVec3::new(x0 + a, 0.0, z0 + b - f * l),
                        -std::f64::consts::FRAC_PI_2,
                    ),
                }
            };
            let place =
                |p: DVec3, yaw: f64| DMat4::from_translation(p) * DMat4::from_rotation_y(yaw);
            for i in 0..c.buildings {
                let t = 4.0 * (i as f64 + 0.5) / c.buildings as f64;
                let v = rng.below(BUILDING_VARIANTS as u32) as usize;
                let inset = building_sizes[v].z as f64 * 0.5 + 4.0;
                let (p, yaw) = edge(t, inset.min(bs * 0.25));
                by_part[v].push(still(place(p, yaw)));
            }
            for i in 0..c.trees {
                let t = 4.0 * (i as f64 + 0.25 + 0.5 * rng.unit() as f64) / c.trees as f64;
                let (p, _) = edge(t, 1.5);
                let yaw = rng.unit() as f64 * std::f64::consts::TAU;
                by_part[PART_TREE].push(still(place(p, yaw)));
            }
            if c.poles > 0 {
                for side in 0..4 {
                    for k in 0..c.poles {
                        let t = side as f64 + k as f64 / c.poles as f64;
                        let (p, yaw) = edge(t, 0.5);
                        by_part[PART_POLE].push(still(place(p, 0.0)));
                        // The wire runs to the next pole along the edge, at 6.5 m.
                        let along = yaw - std::f64::consts::PI;
                        by_part[PART_WIRE].push(still(place(p + DVec3::Y * 6.5, along)));
                    }
                }
            }
            for i in 0..c.parked {
                let t = 4.0 * (i as f64 + 0.5 * rng.unit() as f64) / c.parked as f64;
                let (p, yaw) = edge(t, -2.0);
                let car = PART_CAR + rng.below(CAR_COLOURS as u32) as usize;
                by_part[car].push(still(place(p, yaw - std::f64::consts::PI)));
            }
        }
    }
    // Moving vehicles: along the streets parallel to x, both directions, spread over the city.
    let streets = c.blocks + 1;
    for i in 0..c.moving {
        let street = rng.below(streets) as f64;
        let z = origin - STREET as f64 * 0.5 + street * (bs + STREET as f64);
        let dir = if i % 2 == 0 { 1.0 } else { -1.0 };
        let x = (rng.unit() as f64 - 0.5) * extent as f64;
        let p = DVec3::new(x, 0.0, z + dir * 2.5);
        let car = PART_CAR + rng.below(CAR_COLOURS as u32) as usize;
        let yaw = if dir > 0.0 { 0.0 } else { std::f64::consts::PI };
        by_part[car].push(CityObject {
            base: DMat4::from_translation(p) * DMat4::from_rotation_y(yaw),
            velocity: Some(DVec3::X * dir * c.speed as f64),
        });
    }

    let mut placements = Vec::new();
    let mut objects = Vec::new();
    for (part, list) in by_part.into_iter().enumerate() {
        if list.is_empty() {
            continue;
        }
        placements.push(Placement {
            part,
            first_object: first_object + objects.len() as u32,
            count: list.len() as u32,
        });
        objects.extend(list);
    }
    Generated {
        model,
        placements,
        objects,
    }
}

/// Geometry of one primitive, before it joins the model.
#[derive(Default)]
struct Builder {
    vertices: Vec<MaterialVertex>,
    indices: Vec<u32>,
}

impl Builder {
    fn quad(&mut self, corners: [Vec3; 4], uvs: [Vec2; 4], normal: Vec3) {
        let base = self.vertices.len() as u32;
        for (p, uv) in corners.iter().zip(uvs) {
            self.vertices.push(MaterialVertex {
                position: (*p).into(),
                normal: normal.into(),
                uv: uv.into(),
                tangent: [0.0; 4],
            });
        }
        self.indices
            .extend([base, base + 1, base + 2, base, base + 2, base + 3]);
    }

    /// A box centred on `center` of full extents `size`, side faces textured in `tile`-metre
    /// repeats (u along the face, v down); `caps` adds top and bottom.
    fn box_uv(&mut self, center: Vec3, size: Vec3, tile: f32, caps: bool) {
        let h = size * 0.5;
        let sides = [
            (Vec3::Z, Vec3::X, size.x),
            (Vec3::NEG_Z, Vec3::NEG_X, size.x),
            (Vec3::X, Vec3::NEG_Z, size.z),
            (Vec3::NEG_X, Vec3::Z, size.z),
        ];
        for (n, u, width) in sides {
            let c = center + n * h;
            let du = u * (width * 0.5);
            let dv = Vec3::Y * h.y;
            let (uw, vh) = (width / tile, size.y / tile);
            self.quad(
                [c - du - dv, c + du - dv, c + du + dv, c - du + dv],
                [
                    Vec2::new(0.0, vh),
                    Vec2::new(uw, vh),
                    Vec2::new(uw, 0.0),
                    Vec2::ZERO,
                ],
                n,
            );
        }
        if caps {
            for n in [Vec3::Y, Vec3::NEG_Y] {
                let c = center + n * h.y;
                let (du, dv) = (Vec3::X * h.x, Vec3::Z * h.z * n.y);
                self.quad(
                    [c - du + dv, c + du + dv, c + du - dv, c - du - dv],
                    [Vec2::ZERO, Vec2::X, Vec2::ONE, Vec2::Y],
                    n,
                );
            }
        }
    }

    fn roof(&mut self, size: Vec3) {
        let h = size * 0.5;
        let y = size.y;
        let t = FACADE_TILE;
        self.quad(
            [
                Vec3::new(-h.x, y, h.z),
                Vec3::new(h.x, y, h.z),
                Vec3::new(h.x, y, -h.z),
                Vec3::new(-h.x, y, -h.z),
            ],
            [
                Vec2::ZERO,
                Vec2::new(size.x / t, 0.0),
                Vec2::new(size.x / t, size.z / t),
                Vec2::new(0.0, size.z / t),
            ],
            Vec3::Y,
        );
    }

    fn quad_xz(&mut self, half: f32, tile: f32) {
        let r = 2.0 * half / tile;
        self.quad(
            [
                Vec3::new(-half, 0.0, half),
                Vec3::new(half, 0.0, half),
                Vec3::new(half, 0.0, -half),
                Vec3::new(-half, 0.0, -half),
            ],
            [
                Vec2::ZERO,
                Vec2::new(r, 0.0),
                Vec2::new(r, r),
                Vec2::new(0.0, r),
            ],
            Vec3::Y,
        );
    }

    /// A vertical foliage card rotated `angle` about y: `width` x `height`, its foot at `base`.
    fn card(&mut self, angle: f32, width: f32, height: f32, base: f32) {
        let u = Vec3::new(angle.cos(), 0.0, angle.sin()) * (width * 0.5);
        let n = Vec3::new(-angle.sin(), 0.0, angle.cos());
        let (b, t) = (Vec3::Y * base, Vec3::Y * (base + height));
        self.quad(
            [b - u, b + u, t + u, t - u],
            [Vec2::Y, Vec2::ONE, Vec2::X, Vec2::ZERO],
            n,
        );
    }

    fn cylinder(&mut self, radius: f32, height: f32, segments: u32) {
        for s in 0..segments {
            let a0 = std::f32::consts::TAU * s as f32 / segments as f32;
            let a1 = std::f32::consts::TAU * (s + 1) as f32 / segments as f32;
            let d0 = Vec3::new(a0.cos(), 0.0, a0.sin());
            let d1 = Vec3::new(a1.cos(), 0.0, a1.sin());
            let base = self.vertices.len() as u32;
            for (d, y, u) in [
                (d0, 0.0, 0.0),
                (d1, 0.0, 1.0),
                (d1, height, 1.0),
                (d0, height, 0.0),
            ] {
                self.vertices.push(MaterialVertex {
                    position: (d * radius + Vec3::Y * y).into(),
                    normal: d.into(),
                    uv: [u, y],
                    tangent: [0.0; 4],
                });
            }
            self.indices
                .extend([base, base + 2, base + 1, base, base + 3, base + 2]);
        }
    }

    /// Appends to `model` as one primitive of `material`.
    fn finish(mut self, model: &mut Model, material: usize) -> Primitive {
        generate_tangents(&mut self.vertices, &self.indices);
        let base = model.vertices.len() as u32;
        let first_index = model.indices.len() as u32;
        let (mut lo, mut hi) = (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN));
        for v in &self.vertices {
            lo = lo.min(Vec3::from(v.position));
            hi = hi.max(Vec3::from(v.position));
        }
        model.vertices.extend(self.vertices);
        model.indices.extend(self.indices.iter().map(|i| i + base));
        Primitive {
            first_index,
            index_count: self.indices.len() as u32,
            material,
            center: (lo + hi) * 0.5,
        }
    }
}

// Images, in order: facade albedo, normal, metallic-roughness; road albedo, metallic-roughness;
// foliage albedo (alpha = cut-out).
const IMG_FACADE: usize = 0;
const IMG_FACADE_NORMAL: usize = 1;
const IMG_FACADE_MR: usize = 2;
const IMG_ROAD: usize = 3;
const IMG_ROAD_MR: usize = 4;
const IMG_FOLIAGE: usize = 5;

fn linear_to_srgb8(v: f32) -> u8 {
    let v = v.clamp(0.0, 1.0);
    let s = if v <= 0.003_130_8 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    };
    (s * 255.0 + 0.5) as u8
}

fn unorm8(v: f32) -> u8 {
    (v.clamp(0.0, 1.0) * 255.0 + 0.5) as u8
}

/// The grain: a product of sinusoids at `cycles` per texture along u and v, in [0, 1].
fn grain(x: f32, y: f32, cycles: f32) -> f32 {
    let tau = std::f32::consts::TAU;
    0.5 + 0.5 * (tau * cycles * x).sin() * (tau * cycles * y).sin()
}

/// Whether texture coordinate (x, y) in [0, 1) is inside a window of the facade grid.
fn window(x: f32, y: f32) -> bool {
    let (fx, fy) = (
        (x * WINDOW_CYCLES as f32).fract(),
        (y * WINDOW_CYCLES as f32).fract(),
    );
    (0.2..0.8).contains(&fx) && (0.25..0.85).contains(&fy)
}

fn textures(size: u32, detail: f32, seed: u64) -> Vec<(Image, Encoding)> {
    let n = size as usize;
    // The grain's frequency: `detail` times Nyquist (size / 2 cycles), rounded to whole cycles so
    // that the texture tiles.
    let cycles = (detail * size as f32 * 0.5).round().max(1.0);
    let img = |f: &mut dyn FnMut(f32, f32) -> [u8; 4]| {
        let mut rgba8 = Vec::with_capacity(4 * n * n);
        for j in 0..n {
            for i in 0..n {
                let (x, y) = ((i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32);
                rgba8.extend(f(x, y));
            }
        }
        Image {
            width: size,
            height: size,
            rgba8,
        }
    };
    let wall = Vec3::new(0.55, 0.42, 0.33);
    let glass = Vec3::new(0.04, 0.05, 0.07);
    let facade = img(&mut |x, y| {
        let c = if window(x, y) {
            glass
        } else {
            wall * (0.7 + 0.3 * grain(x, y, cycles))
        };
        [
            linear_to_srgb8(c.x),
            linear_to_srgb8(c.y),
            linear_to_srgb8(c.z),
            255,
        ]
    });
    // Height: windows recessed, the grain as relief; the normal is its central difference.
    let height = |x: f32, y: f32| -> f32 {
        let w = if window(x.rem_euclid(1.0), y.rem_euclid(1.0)) {
            -1.0
        } else {
            0.0
        };
        w * 0.02 + 0.004 * grain(x, y, cycles)
    };
    let texel = 1.0 / size as f32;
    let facade_normal = img(&mut |x, y| {
        // Slopes per texture-space unit scaled to metres of the facade tile.
        let dx = (height(x + texel, y) - height(x - texel, y)) / (2.0 * texel * FACADE_TILE);
        let dy = (height(x, y + texel) - height(x, y - texel)) / (2.0 * texel * FACADE_TILE);
        // +y of the normal map points up the image (decreasing v).
        let n = Vec3::new(-dx, dy, 1.0).normalize();
        [
            unorm8(n.x * 0.5 + 0.5),
            unorm8(n.y * 0.5 + 0.5),
            unorm8(n.z * 0.5 + 0.5),
            255,
        ]
    });
    let facade_mr = img(&mut |x, y| {
        let (rough, metal) = if window(x, y) {
            (0.08, 0.0)
        } else {
            (0.55 + 0.4 * grain(x, y, cycles), 0.0)
        };
        [255, unorm8(rough), unorm8(metal), 255]
    });
    let mut rng = Rng(seed ^ 0x00a5_fa17);
    let speckle: Vec<f32> = (0..n * n).map(|_| rng.unit()).collect();
    let road = img(&mut |x, y| {
        let (i, j) = ((x * n as f32) as usize, (y * n as f32) as usize);
        let v = 0.06 + 0.03 * grain(x, y, cycles) + 0.02 * speckle[j * n + i];
        let c = linear_to_srgb8(v);
        [c, c, c, 255]
    });
    let road_mr = img(&mut |x, y| [255, unorm8(0.75 + 0.2 * grain(x, y, cycles)), 0, 255]);
    // Foliage: discs on an 8x8 jittered grid inside an ellipse; alpha is the cut-out.
    let cells = 8usize;
    let mut rng = Rng(seed ^ 0x0f01_1a6e);
    let centres: Vec<Vec2> = (0..cells * cells)
        .map(|_| Vec2::new(rng.unit(), rng.unit()) * 0.6 + 0.2)
        .collect();
    let foliage = img(&mut |x, y| {
        let (ci, cj) = (
            ((x * cells as f32) as usize).min(cells - 1),
            ((y * cells as f32) as usize).min(cells - 1),
        );
        let local = Vec2::new(x * cells as f32 - ci as f32, y * cells as f32 - cj as f32);
        let leaf = local.distance(centres[cj * cells + ci]) < 0.42;
        let e = Vec2::new((x - 0.5) / 0.5, (y - 0.55) / 0.45);
        let inside = e.length_squared() < 1.0 && leaf;
        let g = 0.6 + 0.4 * grain(x, y, cycles);
        let c = Vec3::new(0.10, 0.28, 0.06) * g;
        [
            linear_to_srgb8(c.x),
            linear_to_srgb8(c.y),
            linear_to_srgb8(c.z),
            if inside { 255 } else { 0 },
        ]
    });
    vec![
        (facade, Encoding::Srgb),
        (facade_normal, Encoding::Linear),
        (facade_mr, Encoding::Linear),
        (road, Encoding::Srgb),
        (road_mr, Encoding::Linear),
        (foliage, Encoding::Srgb),
    ]
}

fn materials() -> Vec<Material> {
    let tex = |image: usize| {
        Some(TextureRef {
            image,
            sampler: SamplerDesc::DEFAULT,
            transform: UvTransform::IDENTITY,
        })
    };
    let plain = |name: &str, color: Vec3, metallic: f32, roughness: f32| Material {
        name: name.into(),
        base_color: color.extend(1.0),
        metallic,
        roughness,
        ..Material::gltf_default()
    };
    let mut facade = plain("facade", Vec3::ONE, 1.0, 1.0);
    facade.textures = [
        tex(IMG_FACADE),
        tex(IMG_FACADE_MR),
        tex(IMG_FACADE_NORMAL),
        None,
        None,
    ];
    let mut roof = plain("roof", Vec3::splat(0.8), 1.0, 1.0);
    roof.textures = [tex(IMG_ROAD), tex(IMG_ROAD_MR), None, None, None];
    let mut road = plain("road", Vec3::ONE, 1.0, 1.0);
    road.textures = [tex(IMG_ROAD), tex(IMG_ROAD_MR), None, None, None];
    let mut foliage = plain("foliage", Vec3::ONE, 0.0, 0.8);
    foliage.alpha = AlphaMode::Mask { cutoff: 0.5 };
    foliage.textures = [tex(IMG_FOLIAGE), None, None, None, None];
    let mut out = vec![
        facade,
        roof,
        road,
        foliage,
        plain("bark", Vec3::new(0.2, 0.12, 0.07), 0.0, 0.9),
        plain("metal", Vec3::splat(0.6), 1.0, 0.4),
    ];
    for c in [
        Vec3::new(0.6, 0.05, 0.04),
        Vec3::new(0.05, 0.12, 0.5),
        Vec3::splat(0.8),
    ] {
        out.push(Material {
            brdf: Brdf::Ggx,
            ..plain("car paint", c, 0.5, 0.3)
        });
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn city() -> City {
        City {
            seed: 7,
            blocks: 2,
            block_size: 30.0,
            buildings: 4,
            texture_size: 32,
            texture_detail: 0.5,
            trees: 2,
            tree_cards: 3,
            poles: 2,
            parked: 2,
            moving: 3,
            speed: 5.0,
        }
    }

    #[test]
    fn the_city_is_deterministic_and_its_parts_are_instanced_contiguously() {
        let a = generate(&city(), 5);
        let b = generate(&city(), 5);
        assert_eq!(a.objects.len(), b.objects.len());
        for (x, y) in a.objects.iter().zip(&b.objects) {
            assert_eq!(x.base, y.base);
        }
        // 4 blocks: 16 buildings, 8 trees, 32 poles and wires, 8 parked + 3 moving cars, 1 road.
        assert_eq!(a.objects.len(), 16 + 8 + 32 + 32 + 11 + 1);
        assert_eq!(a.objects.iter().filter(|o| o.is_dynamic()).count(), 3);
        let mut next = 5;
        for p in &a.placements {
            assert_eq!(p.first_object, next);
            next += p.count;
        }
        assert_eq!(next as usize, 5 + a.objects.len());
        assert_eq!(a.model.indices.len() % 3, 0);
        assert!(a
            .model
            .indices
            .iter()
            .all(|&i| (i as usize) < a.model.vertices.len()));
        let other = generate(&City { seed: 8, ..city() }, 5);
        assert!(a
            .objects
            .iter()
            .zip(&other.objects)
            .any(|(x, y)| x.base != y.base));
    }

    #[test]
    fn the_facade_grain_has_the_asked_frequency() {
        // At detail 0.5 of a 32-texel texture the grain has 8 cycles: its period is 4 texels.
        let images = textures(32, 0.5, 1);
        let (facade, _) = &images[IMG_FACADE_MR];
        let rough = |i: usize, j: usize| facade.rgba8[4 * (j * 32 + i) + 1];
        // A row of wall (no windows at v in the first 0.25 of a window cycle).
        let j = 0;
        for i in 0..28 {
            if !window((i as f32 + 0.5) / 32.0, 0.5 / 32.0)
                && !window((i as f32 + 4.5) / 32.0, 0.5 / 32.0)
            {
                assert_eq!(rough(i, j), rough(i + 4, j), "texel {i}");
            }
        }
    }
}
