//! Raw serde structs mirroring the scenario TOML one to one.
//!
//! Unknown keys are rejected here; values are checked in `validate.rs`, which turns these structs into
//! the domain types of `mod.rs`. Every key is documented in `scenarios/README.md`.

use std::collections::BTreeMap;

use serde::Deserialize;

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawScenario {
    /// Defaults to the file stem.
    pub name: Option<String>,
    #[serde(default)]
    pub description: String,
    /// `[width, height]` in pixels.
    pub resolution: Vec<i64>,
    /// Seconds of scene time per frame (fixed step, so runs are deterministic). Default 1/60.
    pub time_step: Option<f64>,
    /// Image metrics computed against the reference. Default `["psnr", "psnr-luma", "max-abs-error"]`
    /// when there is a reference.
    pub metrics: Option<Vec<String>>,
    /// The display `cvvdp` sees the frames on: a name (default `standard_4k`) or a table
    /// (`base`, `diagonal_inches`, `distance_m`, `pixels_per_degree`, `resolution`,
    /// `peak_luminance`, `contrast`, `ambient_lux`).
    pub display: Option<toml::Value>,
    /// Where the metrics are computed: `"gpu"` (the device that rendered the frames) or `"cpu"`
    /// (the reference implementations). Default: GPU unless the adapter is a CPU (lavapipe).
    pub metrics_device: Option<String>,
    #[serde(default)]
    pub frames: RawFrames,
    #[serde(default)]
    pub reference: RawReference,
    #[serde(default)]
    pub scene: RawScene,
    pub camera: RawCamera,
    #[serde(default)]
    pub techniques: Vec<RawTechnique>,
    #[serde(default)]
    pub gates: Vec<RawGate>,
    /// `[sweep]`: dotted keys and the values to run each at (`sweep.rs` expands the file before
    /// it is parsed here; the values the file itself holds are the first scenario's defaults).
    #[allow(dead_code)]
    pub sweep: Option<toml::Value>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawFrames {
    /// Frames rendered before measuring; excluded from timings and metrics. Default 2.
    pub warmup: Option<i64>,
    /// Clock warm-up: frame 0 repeated for at least this long before timing. Default 100.
    pub warmup_ms: Option<f64>,
    /// Energy window after the timed frames, where sensors exist; 0 turns it off.
    pub energy_window_ms: Option<f64>,
    /// Energy counter steps that end the energy window (default 3).
    pub energy_steps: Option<i64>,
    /// Frames timed and compared (an integer, default 8), or `"auto"` / `{ min, max, precision }`.
    pub measured: Option<RawMeasured>,
    /// Measured-frame indices saved as PNG; negative counts from the end. Default `[-1]`.
    pub save: Option<Vec<i64>>,
    /// Also save each metric's worst frame (beside `save`). Default `true`.
    pub save_worst: Option<bool>,
}

/// `frames.measured`: a count, `"auto"`, or a table of the auto rule's bounds.
#[derive(Debug)]
pub enum RawMeasured {
    Count(i64),
    /// Any string: validation accepts only `"auto"` and says so.
    Word(String),
    Auto(RawAuto),
}

/// `frames.measured = { min, max, precision }`: each defaults as `"auto"` does.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawAuto {
    pub min: Option<i64>,
    pub max: Option<i64>,
    pub precision: Option<f64>,
    pub timeout_s: Option<f64>,
}

impl<'de> Deserialize<'de> for RawMeasured {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct Visitor;
        impl<'de> serde::de::Visitor<'de> for Visitor {
            type Value = RawMeasured;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("an integer, \"auto\" or a table { min, max, precision, timeout_s }")
            }
            fn visit_i64<E: serde::de::Error>(self, v: i64) -> Result<RawMeasured, E> {
                Ok(RawMeasured::Count(v))
            }
            fn visit_u64<E: serde::de::Error>(self, v: u64) -> Result<RawMeasured, E> {
                Ok(RawMeasured::Count(i64::try_from(v).unwrap_or(i64::MAX)))
            }
            fn visit_str<E: serde::de::Error>(self, v: &str) -> Result<RawMeasured, E> {
                Ok(RawMeasured::Word(v.to_string()))
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(
                self,
                map: A,
            ) -> Result<RawMeasured, A::Error> {
                RawAuto::deserialize(serde::de::value::MapAccessDeserializer::new(map))
                    .map(RawMeasured::Auto)
            }
        }
        d.deserialize_any(Visitor)
    }
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawReference {
    /// `native` (default), `ground-truth` or `none`.
    pub kind: Option<String>,
    /// Ground truth: samples per axis per pixel (NxN, box-downsampled).
    pub supersample: Option<i64>,
    /// Ground truth: jittered samples per pixel at the output resolution (the converged
    /// reference). Default 32 when `supersample` is not given.
    pub samples: Option<i64>,
    /// Ground truth with `samples`: samples per pixel of the denser reference the reference is
    /// measured against on its first compared frame (its own noise, a result's
    /// `reference_noise`). Default 4 x `samples` (at most 1024); 0 turns it off.
    pub noise_samples: Option<i64>,
    /// Compare after motion blur: reference and variants filtered by a box along each pixel's
    /// motion (NVIDIA adaptive shading, section 4 and Fig. 9). Default false.
    pub motion_blur: Option<bool>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawScene {
    pub background: Option<Vec<f64>>,
    pub ambient: Option<f64>,
    /// Extra deterministic ALU iterations per fragment: makes a scene shading-bound.
    pub shading_cost: Option<i64>,
    pub ground: Option<RawGround>,
    #[serde(default)]
    pub lights: Vec<RawLight>,
    #[serde(default)]
    pub objects: Vec<RawObject>,
    /// Maximum sampler anisotropy for textured materials (1..=16). Default 1.
    pub anisotropy: Option<i64>,
    /// A generated city.
    pub city: Option<RawCity>,
}

/// `[scene.city]`: every key optional; see `scenarios/README.md`.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawCity {
    pub seed: Option<i64>,
    pub blocks: Option<i64>,
    pub block_size: Option<f64>,
    pub buildings: Option<i64>,
    pub texture_size: Option<i64>,
    pub texture_detail: Option<f64>,
    pub trees: Option<i64>,
    pub tree_cards: Option<i64>,
    pub poles: Option<i64>,
    pub parked: Option<i64>,
    pub moving: Option<i64>,
    pub speed: Option<f64>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawGround {
    pub size: Option<f64>,
    pub height: Option<f64>,
    pub checker_size: Option<f64>,
    pub colors: Option<Vec<Vec<f64>>>,
    /// `box` (IQ's analytic box filter, default) or `none`.
    pub filter: Option<String>,
    /// IQ's Shadertoy copies add 0.01 to the filter width; default 0.
    pub filter_epsilon: Option<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawLight {
    /// `directional` or `point`.
    #[serde(rename = "type")]
    pub kind: String,
    pub direction: Option<Vec<f64>>,
    pub position: Option<Vec<f64>>,
    pub color: Option<Vec<f64>>,
    pub intensity: Option<f64>,
    /// The same inline table as objects': `translate` and `oscillate` move a point light,
    /// `rotate` turns a directional light's direction.
    pub animation: Option<RawAnimation>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawObject {
    /// `box`, `sphere`, `pole`, `fence` or `mesh`.
    pub shape: String,
    pub position: Option<Vec<f64>>,
    pub size: Option<Vec<f64>>,
    pub radius: Option<f64>,
    pub height: Option<f64>,
    /// Fence: the far end (the near end is `position`).
    pub end: Option<Vec<f64>>,
    /// Fence: number of posts.
    pub posts: Option<i64>,
    /// Fence: number of horizontal rails.
    pub rails: Option<i64>,
    /// Fence: thickness of posts and rails.
    pub thickness: Option<f64>,
    /// Mesh: glTF 2.0 file (`.glb` or `.gltf`), relative to the scenario file.
    pub path: Option<String>,
    /// Mesh: uniform scale.
    pub scale: Option<f64>,
    /// Mesh: `color` (default: the object's colour, untextured) or `file` (the file's textured
    /// PBR materials).
    pub materials: Option<String>,
    /// Degrees about the y axis.
    pub yaw: Option<f64>,
    pub color: Option<Vec<f64>>,
    /// Linear radiance added to the shaded colour (HDR highlights).
    pub emissive: Option<Vec<f64>>,
    pub specular: Option<f64>,
    pub animation: Option<RawAnimation>,
    /// Stress: `nan` or `inf`, the object's shader output in every channel.
    pub inject: Option<String>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawAnimation {
    /// `rotate`, `translate` or `oscillate`.
    pub kind: String,
    pub axis: Option<Vec<f64>>,
    pub degrees_per_second: Option<f64>,
    pub velocity: Option<Vec<f64>>,
    pub amplitude: Option<Vec<f64>>,
    pub period: Option<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawCamera {
    pub near: Option<f64>,
    pub far: Option<f64>,
    /// `linear` (default) or `smooth` (Catmull-Rom).
    pub interpolation: Option<String>,
    pub keyframes: Vec<RawKeyframe>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawKeyframe {
    pub time: f64,
    pub position: Vec<f64>,
    pub target: Vec<f64>,
    /// Vertical field of view in degrees. Default 60.
    pub fov: Option<f64>,
    /// The camera jumps to this keyframe at its time instead of moving towards it.
    #[serde(default)]
    pub cut: bool,
}

/// A technique entry; its parameters are checked against the technique's own parameter list.
#[derive(Debug, Deserialize)]
pub struct RawTechnique {
    pub technique: String,
    /// Overrides the generated variant name (only without sweeps).
    pub label: Option<String>,
    #[serde(flatten)]
    pub params: BTreeMap<String, toml::Value>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawGate {
    /// A metric name, or `gpu_ms`, `cpu_ms`, `speedup`.
    pub measure: String,
    /// Variant name pattern (`*` matches any run of characters). Default: every variant but the
    /// reference.
    pub variants: Option<String>,
    pub warn_below: Option<f64>,
    pub fail_below: Option<f64>,
    pub warn_above: Option<f64>,
    pub fail_above: Option<f64>,
}
