//! What a scenario draws and from where: the scene (objects, lights, ground) and the camera track,
//! as validated domain types. The renderer (`render/scene.rs`) reads these and nothing else of a
//! scenario, so rendering depends on the world, not on scenarios, variants or techniques. Not for:
//! parsing and validation (`scenario/raw.rs`, `scenario/validate.rs`, which build these).

use std::path::PathBuf;

use glam::{DMat4, DVec3, Vec3};

/// What is drawn.
#[derive(Clone, Debug)]
pub struct Scene {
    pub background: Vec3,
    pub ambient: f32,
    pub shading_cost: u32,
    pub ground: Option<Ground>,
    pub lights: Vec<Light>,
    pub objects: Vec<Object>,
    /// Maximum anisotropy of texture samplers whose filters are all linear (1: none).
    pub anisotropy: u16,
    /// A generated city (`[scene.city]`).
    pub city: Option<City>,
}

impl Scene {
    /// Whether anything moves by itself (not counting the camera).
    pub fn has_dynamic_objects(&self) -> bool {
        self.objects.iter().any(|o| o.animation.is_some())
            || self.city.as_ref().is_some_and(|c| c.moving > 0)
    }

    /// Whether a light moves or turns: the shading changes with nothing in motion.
    pub fn has_animated_lights(&self) -> bool {
        self.lights.iter().any(Light::is_animated)
    }

    /// Whether it has textured models (glTF `materials = "file"` meshes, the city): what
    /// `SceneGpu::has_materials` will say once it is on the GPU.
    pub fn has_textured_models(&self) -> bool {
        self.city.is_some()
            || self
                .objects
                .iter()
                .any(|o| matches!(o.shape, Shape::Mesh { textured: true, .. }))
    }
}

/// `[scene.city]`: a generated city, deterministic from its seed (`render/city.rs`).
#[derive(Clone, Debug, PartialEq)]
pub struct City {
    pub seed: u64,
    /// Blocks per side of the square grid.
    pub blocks: u32,
    /// Side of one block in metres (streets of 12 m between blocks).
    pub block_size: f32,
    /// Buildings per block (object count).
    pub buildings: u32,
    /// Texels per side of each generated texture (before its mip chain).
    pub texture_size: u32,
    /// Frequency of the finest texture detail as a fraction of level 0's Nyquist frequency.
    pub texture_detail: f32,
    /// Trees per block, each of `tree_cards` alpha-tested foliage cards (overdraw).
    pub trees: u32,
    pub tree_cards: u32,
    /// Poles per block side, joined by wires (thin geometry).
    pub poles: u32,
    /// Parked vehicles per block.
    pub parked: u32,
    /// Moving vehicles in the whole city, driving along the streets at `speed` m/s.
    pub moving: u32,
    pub speed: f32,
}

#[derive(Clone, Debug)]
pub struct Ground {
    pub size: f32,
    pub height: f32,
    pub checker_size: f32,
    pub colors: [Vec3; 2],
    pub filter: GroundFilter,
    pub filter_epsilon: f32,
}

/// How the ground's checkerboard is filtered (`seeds/iq-filtered-checkerboard.txt`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GroundFilter {
    /// Point-sampled: aliases at a distance.
    None,
    /// IQ's analytic box filter over the pixel footprint from screen-space gradients.
    Box,
}

#[derive(Clone, Debug)]
pub enum Light {
    Directional {
        direction: Vec3,
        color: Vec3,
        intensity: f32,
        /// `rotate` turns the direction about its axis.
        animation: Option<Animation>,
    },
    Point {
        position: Vec3,
        color: Vec3,
        intensity: f32,
        /// `translate` or `oscillate` moves the position.
        animation: Option<Animation>,
    },
}

impl Light {
    /// The light at scene time `t` (seconds): its animation applied, as objects' are
    /// ([`Object::model_at`]); the light itself when it has none.
    pub fn at(&self, t: f64) -> Light {
        let mut l = self.clone();
        match &mut l {
            Light::Directional {
                direction,
                animation:
                    Some(Animation::Rotate {
                        axis,
                        degrees_per_second,
                    }),
                ..
            } => {
                let angle = (*degrees_per_second as f64 * t).to_radians();
                let turn = glam::DQuat::from_axis_angle(axis.as_dvec3().normalize(), angle);
                *direction = (turn * direction.as_dvec3()).as_vec3();
            }
            Light::Point {
                position,
                animation: Some(a),
                ..
            } => {
                let offset = match a {
                    Animation::Translate { velocity } => velocity.as_dvec3() * t,
                    Animation::Oscillate { amplitude, period } => {
                        amplitude.as_dvec3() * (std::f64::consts::TAU * t / *period as f64).sin()
                    }
                    Animation::Rotate { .. } => DVec3::ZERO,
                };
                *position = (position.as_dvec3() + offset).as_vec3();
            }
            _ => {}
        }
        l
    }

    /// Whether it has an animation.
    pub fn is_animated(&self) -> bool {
        match self {
            Light::Directional { animation, .. } | Light::Point { animation, .. } => {
                animation.is_some()
            }
        }
    }
}

#[derive(Clone, Debug)]
pub struct Object {
    pub shape: Shape,
    /// f64: a scene far from the origin keeps its precision (stress suite).
    pub position: DVec3,
    pub yaw_degrees: f32,
    pub color: Vec3,
    pub emissive: Vec3,
    pub specular: f32,
    pub animation: Option<Animation>,
    /// Stress suite: the object's pixels are written non-finite, to check that a technique does
    /// not spread them (issue 8).
    pub inject: Option<Inject>,
}

/// A non-finite value an object's shader writes instead of its colour.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Inject {
    Nan,
    Inf,
}

impl Inject {
    /// The value the scene shader reads (`Object.flags.x`).
    pub fn code(self) -> f32 {
        match self {
            Inject::Nan => 1.0,
            Inject::Inf => 2.0,
        }
    }
}

#[derive(Clone, Debug)]
pub enum Shape {
    /// Full extents.
    Box {
        size: Vec3,
    },
    Sphere {
        radius: f32,
    },
    /// A thin vertical cylinder standing on `position`.
    Pole {
        radius: f32,
        height: f32,
    },
    /// Posts from `position` to `end` with horizontal rails.
    Fence {
        end: Vec3,
        height: f32,
        posts: u32,
        rails: u32,
        thickness: f32,
    },
    /// A glTF 2.0 file, resolved against the scenario's folder.
    Mesh {
        path: PathBuf,
        scale: f32,
        /// `materials = "file"`: the file's textured PBR materials; otherwise the object's
        /// `color` (untextured Blinn-Phong, as procedural shapes).
        textured: bool,
    },
}

impl Shape {
    pub fn name(&self) -> &'static str {
        match self {
            Shape::Box { .. } => "box",
            Shape::Sphere { .. } => "sphere",
            Shape::Pole { .. } => "pole",
            Shape::Fence { .. } => "fence",
            Shape::Mesh { .. } => "mesh",
        }
    }
}

#[derive(Clone, Debug)]
pub enum Animation {
    Rotate { axis: Vec3, degrees_per_second: f32 },
    Translate { velocity: Vec3 },
    Oscillate { amplitude: Vec3, period: f32 },
}

impl Object {
    /// World-space model matrix at scene time `t` (seconds), in f64 so that objects far from the
    /// origin keep their precision once made camera-relative.
    pub fn model_at(&self, t: f64) -> DMat4 {
        let base = DMat4::from_translation(self.position)
            * DMat4::from_rotation_y((self.yaw_degrees as f64).to_radians());
        match &self.animation {
            None => base,
            Some(Animation::Rotate {
                axis,
                degrees_per_second,
            }) => {
                let angle = (*degrees_per_second as f64 * t).to_radians();
                base * DMat4::from_axis_angle(axis.as_dvec3().normalize(), angle)
            }
            Some(Animation::Translate { velocity }) => {
                DMat4::from_translation(velocity.as_dvec3() * t) * base
            }
            Some(Animation::Oscillate { amplitude, period }) => {
                let phase = (std::f64::consts::TAU * t / *period as f64).sin();
                DMat4::from_translation(amplitude.as_dvec3() * phase) * base
            }
        }
    }
}

/// Timed keyframes of the camera, with cuts.
#[derive(Clone, Debug)]
pub struct CameraTrack {
    pub near: f32,
    pub far: f32,
    pub interpolation: Interpolation,
    pub keyframes: Vec<Keyframe>,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Interpolation {
    Linear,
    /// Catmull-Rom through the keyframe positions and targets.
    Smooth,
}

#[derive(Clone, Debug)]
pub struct Keyframe {
    pub time: f64,
    pub position: DVec3,
    pub target: DVec3,
    pub fov_degrees: f32,
    pub cut: bool,
}

/// The camera at one instant.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraPose {
    /// f64 and interpolated in f64: in f32 a camera 1e6 units from the origin moves in 1/16-unit
    /// steps (found by scenarios/stress/far-from-origin.toml).
    pub position: DVec3,
    pub target: DVec3,
    pub fov_degrees: f32,
    /// Index of the segment (between cuts) the pose belongs to: history is invalid across a change.
    pub segment: usize,
}

impl CameraTrack {
    /// The pose at scene time `t`. Before the first keyframe the camera holds it; after the last, too.
    /// A cut keyframe is not interpolated towards: the camera holds the previous pose until the cut.
    pub fn pose_at(&self, t: f64) -> CameraPose {
        let k = &self.keyframes;
        let segment_of = |i: usize| k[..=i].iter().filter(|f| f.cut).count();
        let hold = |i: usize| CameraPose {
            position: k[i].position,
            target: k[i].target,
            fov_degrees: k[i].fov_degrees,
            segment: segment_of(i),
        };
        if t <= k[0].time {
            return hold(0);
        }
        let Some(next) = k.iter().position(|f| f.time > t) else {
            return hold(k.len() - 1);
        };
        let prev = next - 1;
        if k[next].cut {
            return hold(prev);
        }
        let span = k[next].time - k[prev].time;
        let s = (t - k[prev].time) / span;
        let (position, target) = match self.interpolation {
            Interpolation::Linear => (
                k[prev].position.lerp(k[next].position, s),
                k[prev].target.lerp(k[next].target, s),
            ),
            Interpolation::Smooth => {
                // Neighbours across a cut do not shape the curve.
                let before = if prev > 0 && !k[prev].cut {
                    prev - 1
                } else {
                    prev
                };
                let after = if next + 1 < k.len() && !k[next + 1].cut {
                    next + 1
                } else {
                    next
                };
                (
                    catmull_rom(
                        k[before].position,
                        k[prev].position,
                        k[next].position,
                        k[after].position,
                        s,
                    ),
                    catmull_rom(
                        k[before].target,
                        k[prev].target,
                        k[next].target,
                        k[after].target,
                        s,
                    ),
                )
            }
        };
        CameraPose {
            position,
            target,
            fov_degrees: k[prev].fov_degrees
                + (k[next].fov_degrees - k[prev].fov_degrees) * s as f32,
            segment: segment_of(prev),
        }
    }
}

fn catmull_rom(p0: DVec3, p1: DVec3, p2: DVec3, p3: DVec3, t: f64) -> DVec3 {
    let t2 = t * t;
    let t3 = t2 * t;
    0.5 * ((2.0 * p1)
        + (-p0 + p2) * t
        + (2.0 * p0 - 5.0 * p1 + 4.0 * p2 - p3) * t2
        + (-p0 + 3.0 * p1 - 3.0 * p2 + p3) * t3)
}

/// What the renderer needs of a scenario: its scene, camera track and output size (a copy, so
/// the GPU scene outlives no scenario).
#[derive(Clone, Debug)]
pub struct Stage {
    pub width: u32,
    pub height: u32,
    pub scene: Scene,
    pub camera: CameraTrack,
}
