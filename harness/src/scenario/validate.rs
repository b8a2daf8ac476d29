//! Turns raw serde structs into validated domain types, collecting every problem with its key path.
//!
//! Rules are the ones `scenarios/README.md` documents: finite numbers, resolution from 1 to
//! `MAX_DIMENSION`, frames at least 1, 0 < near < far, keyframe times strictly increasing, known
//! techniques, metrics and shapes (with a suggestion for a likely typo).

use std::collections::BTreeMap;
use std::path::Path;

use glam::{DVec3, Vec3};
use toml_edit::Document;

use super::raw::*;
use super::span::{line_col, locate, KeyPath};
use super::*;
use crate::metric::cvvdp::CVVDP_MEASURES;
use crate::metric::MetricKind;
use crate::params::{closest, quoted_list, ParamValue};
use crate::techniques;
use crate::techniques::{variant_name, Variant};
use crate::timing::stop::{AutoRule, AUTO_MAX, AUTO_MIN, AUTO_TIMEOUT_S, DEFAULT_PRECISION};

/// Collects errors with their key paths; positions are resolved at the end.
struct Ctx {
    errors: Vec<(KeyPath, String)>,
}

impl Ctx {
    fn err(&mut self, path: &KeyPath, message: impl Into<String>) {
        self.errors.push((path.clone(), message.into()));
    }

    fn finite(&mut self, path: &KeyPath, v: f64) -> f32 {
        if !v.is_finite() {
            self.err(path, format!("{v} is not a finite number"));
            return 0.0;
        }
        v as f32
    }

    fn positive(&mut self, path: &KeyPath, v: f64) -> f32 {
        if !(v.is_finite() && v > 0.0) {
            self.err(
                path,
                format!("{v} is not allowed: expected a finite number > 0"),
            );
            return 1.0;
        }
        v as f32
    }

    fn non_negative(&mut self, path: &KeyPath, v: f64) -> f32 {
        if !(v.is_finite() && v >= 0.0) {
            self.err(
                path,
                format!("{v} is not allowed: expected a finite number >= 0"),
            );
            return 0.0;
        }
        v as f32
    }

    fn vec3(&mut self, path: &KeyPath, v: &[f64]) -> Vec3 {
        if v.len() != 3 {
            self.err(
                path,
                format!("expected 3 numbers [x, y, z], found {}", v.len()),
            );
            return Vec3::ZERO;
        }
        let mut out = [0.0f32; 3];
        for (i, x) in v.iter().enumerate() {
            out[i] = self.finite(&path.index(i), *x);
        }
        Vec3::from(out)
    }

    /// A position, kept in f64.
    fn dvec3(&mut self, path: &KeyPath, v: &[f64]) -> DVec3 {
        if v.len() != 3 {
            self.err(
                path,
                format!("expected 3 numbers [x, y, z], found {}", v.len()),
            );
            return DVec3::ZERO;
        }
        for (i, x) in v.iter().enumerate() {
            self.finite(&path.index(i), *x);
        }
        DVec3::new(v[0], v[1], v[2]).map(|x| if x.is_finite() { x } else { 0.0 })
    }

    fn color(&mut self, path: &KeyPath, v: &[f64]) -> Vec3 {
        let c = self.vec3(path, v);
        for (i, x) in v.iter().enumerate().take(3) {
            if *x < 0.0 {
                self.err(
                    &path.index(i),
                    format!("{x} is negative: colours are linear and >= 0"),
                );
            }
        }
        c
    }

    fn count(&mut self, path: &KeyPath, v: i64, min: i64, max: i64) -> u32 {
        if v < min || v > max {
            self.err(
                path,
                format!("{v} is out of range: expected an integer from {min} to {max}"),
            );
            return min.max(0) as u32;
        }
        v as u32
    }

    /// A string that must be one of `allowed`.
    fn choice<'a>(
        &mut self,
        path: &KeyPath,
        what: &str,
        v: &str,
        allowed: &[&'a str],
    ) -> Option<&'a str> {
        if let Some(found) = allowed.iter().find(|a| **a == v) {
            return Some(found);
        }
        let hint = closest(v, allowed)
            .map(|c| format!(" (did you mean \"{c}\"?)"))
            .unwrap_or_default();
        self.err(
            path,
            format!(
                "unknown {what} \"{v}\"{hint}: expected one of {}",
                quoted_list(allowed)
            ),
        );
        None
    }

    /// Keys set on an item that its kind does not use.
    fn unused(&mut self, path: &KeyPath, kind: &str, set: &[(&str, bool)], used: &[&str]) {
        for (key, present) in set {
            if *present && !used.contains(key) {
                self.err(
                    &path.key(key),
                    format!(
                        "`{key}` is not used by {kind}: allowed keys are {}",
                        quoted_list(used)
                    ),
                );
            }
        }
    }
}

pub fn parse_and_validate(path: &Path, source: &str) -> Result<Scenario, ScenarioErrors> {
    let located = |line: usize, column: usize, key: String, message: String| ScenarioError {
        file: path.to_path_buf(),
        line,
        column,
        key,
        message,
    };
    let deserializer = toml::de::Deserializer::parse(source).map_err(|e| {
        let (line, col) = e
            .span()
            .map(|s| line_col(source, s.start))
            .unwrap_or((1, 1));
        ScenarioErrors(vec![located(
            line,
            col,
            String::new(),
            first_line(e.message()),
        )])
    })?;
    let raw: RawScenario = serde_path_to_error::deserialize(deserializer).map_err(|e| {
        let key = KeyPath::parse(&e.path().to_string()).to_string();
        let inner = e.inner();
        let (line, col) = inner
            .span()
            .map(|s| line_col(source, s.start))
            .unwrap_or((1, 1));
        let key = if key == "(top level)" {
            String::new()
        } else {
            key
        };
        ScenarioErrors(vec![located(
            line,
            col,
            key,
            describe_serde(inner.message()),
        )])
    })?;

    let mut ctx = Ctx { errors: Vec::new() };
    let scenario = build(&mut ctx, path, raw);
    if ctx.errors.is_empty() {
        return Ok(scenario);
    }
    let doc: Option<Document<String>> = source.to_string().parse().ok();
    let errors = ctx
        .errors
        .into_iter()
        .map(|(key, message)| {
            let (line, col) = doc
                .as_ref()
                .and_then(|d| locate(d, &key))
                .map(|s| line_col(source, s.start))
                .unwrap_or((1, 1));
            located(line, col, key.to_string(), message)
        })
        .collect::<Vec<_>>();
    let mut errors = errors;
    errors.sort_by_key(|e| (e.line, e.column));
    Err(ScenarioErrors(errors))
}

fn first_line(s: &str) -> String {
    s.lines().next().unwrap_or(s).trim().to_string()
}

/// serde's messages name types in Rust terms; say what the TOML should hold instead.
fn describe_serde(message: &str) -> String {
    let m = first_line(message)
        .replace("invalid type: ", "wrong type: found ")
        .replace("expected a sequence", "expected an array")
        .replace("expected i64", "expected an integer")
        .replace("expected f64", "expected a number")
        .replace("expected a boolean", "expected true or false");
    if let Some(rest) = m.strip_prefix("unknown field ") {
        return format!("unknown key {rest}");
    }
    if let Some(rest) = m.strip_prefix("missing field ") {
        return format!("missing required key {rest}");
    }
    m
}

fn build(ctx: &mut Ctx, path: &Path, raw: RawScenario) -> Scenario {
    let root = KeyPath::root();
    let name = raw.name.clone().unwrap_or_else(|| {
        path.file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default()
    });
    if name.is_empty()
        || !name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || "-_.".contains(c))
    {
        ctx.err(
            &root.key("name"),
            format!("\"{name}\" is not allowed: use letters, digits, '-', '_' and '.'"),
        );
    }

    let (width, height) = resolution(ctx, &root.key("resolution"), &raw.resolution);

    let frames = root.key("frames");
    let warmup_frames = ctx.count(
        &frames.key("warmup"),
        raw.frames.warmup.unwrap_or(2),
        0,
        100_000,
    );
    let warmup_ms = raw.frames.warmup_ms;
    if let Some(ms) = warmup_ms.filter(|ms| !(ms.is_finite() && (0.0..=60_000.0).contains(ms))) {
        ctx.err(
            &frames.key("warmup_ms"),
            format!("{ms} is out of range: expected 0 to 60000 milliseconds"),
        );
    }
    let energy_window_ms = raw.frames.energy_window_ms;
    if let Some(ms) =
        energy_window_ms.filter(|ms| !(ms.is_finite() && (0.0..=60_000.0).contains(ms)))
    {
        ctx.err(
            &frames.key("energy_window_ms"),
            format!("{ms} is out of range: expected 0 to 60000 milliseconds"),
        );
    }
    let energy_steps = raw
        .frames
        .energy_steps
        .map(|n| ctx.count(&frames.key("energy_steps"), n, 2, 600));
    let (measured_frames, auto) = measured(ctx, &frames.key("measured"), &raw.frames.measured);
    let save_frames = save_frames(
        ctx,
        &frames.key("save"),
        raw.frames.save.as_deref(),
        measured_frames,
    );
    let save_worst = raw.frames.save_worst.unwrap_or(true);

    let time_step = raw.time_step.unwrap_or(1.0 / 60.0);
    ctx.positive(&root.key("time_step"), time_step);

    let reference = reference(ctx, &root.key("reference"), &raw.reference);
    let reference_noise = reference_noise(ctx, &root.key("reference"), &raw.reference, reference);
    let motion_blur = raw.reference.motion_blur.unwrap_or(false);
    if motion_blur && reference == Reference::None {
        ctx.err(
            &root.key("reference").key("motion_blur"),
            "`motion_blur` blurs the compared frames: it needs a reference (kind = \"native\" or \"ground-truth\")",
        );
    }
    let metrics = metrics(ctx, &root.key("metrics"), raw.metrics.as_deref(), reference);
    for (i, m) in metrics.iter().enumerate() {
        let min = m.def().needs.min_size;
        if width < min || height < min {
            ctx.err(
                &root.key("metrics").index(i),
                format!("{} needs at least {min}x{min} pixels (one Gaussian window); the resolution is {width}x{height}", m.name()),
            );
        }
    }
    let display = display(ctx, &root.key("display"), raw.display.as_ref(), &metrics);
    let metrics_device = raw.metrics_device.as_deref().and_then(|d| {
        tessera_metrics_gpu::Backend::parse(d)
            .map_err(|e| ctx.err(&root.key("metrics_device"), e))
            .ok()
    });
    let scene = scene(ctx, &root.key("scene"), path, &raw.scene);
    let camera = camera(ctx, &root.key("camera"), &raw.camera);
    let variants = variants(ctx, &root.key("techniques"), &raw.techniques);
    let gates = gates(ctx, &root.key("gates"), &raw.gates, &metrics);

    Scenario {
        name,
        file: path.to_path_buf(),
        description: raw.description,
        width,
        height,
        warmup_frames,
        warmup_ms,
        energy_window_ms,
        energy_steps,
        measured_frames,
        auto,
        save_frames,
        save_worst,
        motion_blur,
        time_step,
        reference,
        reference_noise,
        metrics,
        display,
        metrics_device,
        scene,
        camera,
        variants,
        gates,
        sweep: Vec::new(),
    }
}

fn resolution(ctx: &mut Ctx, path: &KeyPath, v: &[i64]) -> (u32, u32) {
    if v.len() != 2 {
        ctx.err(
            path,
            format!("expected [width, height], found {} numbers", v.len()),
        );
        return (1, 1);
    }
    let w = ctx.count(&path.index(0), v[0], 1, MAX_DIMENSION as i64);
    let h = ctx.count(&path.index(1), v[1], 1, MAX_DIMENSION as i64);
    (w, h)
}

fn save_frames(ctx: &mut Ctx, path: &KeyPath, v: Option<&[i64]>, measured: u32) -> Vec<u32> {
    let Some(v) = v else {
        return vec![measured.saturating_sub(1)];
    };
    let mut out = Vec::new();
    for (i, &f) in v.iter().enumerate() {
        let index = if f < 0 { measured as i64 + f } else { f };
        if index < 0 || index >= measured as i64 {
            ctx.err(
                &path.index(i),
                format!(
                    "frame {f} does not exist: expected a measured-frame index from {} to {}",
                    -(measured as i64),
                    measured as i64 - 1
                ),
            );
        } else if !out.contains(&(index as u32)) {
            out.push(index as u32);
        }
    }
    out.sort();
    out
}

fn reference(ctx: &mut Ctx, path: &KeyPath, raw: &RawReference) -> Reference {
    let kind = raw.kind.as_deref().unwrap_or("native");
    let kind = ctx.choice(
        &path.key("kind"),
        "reference",
        kind,
        &["native", "ground-truth", "none"],
    );
    match kind {
        Some("ground-truth") => match (raw.supersample, raw.samples) {
            (Some(_), Some(_)) => {
                ctx.err(
                    &path.key("samples"),
                    "give `supersample` (an NxN supersampled render) or `samples` (jittered samples at the output resolution), not both",
                );
                Reference::Converged { samples: 32 }
            }
            (Some(n), None) => Reference::GroundTruth {
                supersample: ctx.count(&path.key("supersample"), n, 2, 8),
            },
            (None, n) => Reference::Converged {
                samples: ctx.count(&path.key("samples"), n.unwrap_or(32), 1, 1024),
            },
        },
        other => {
            for (key, given) in [
                ("supersample", raw.supersample.is_some()),
                ("samples", raw.samples.is_some()),
            ] {
                if given {
                    ctx.err(
                        &path.key(key),
                        format!("`{key}` applies only to kind = \"ground-truth\""),
                    );
                }
            }
            if other == Some("none") {
                Reference::None
            } else {
                Reference::Native
            }
        }
    }
}

/// `reference.noise_samples`: on by default for the converged reference (4 x its samples, at
/// most 1024), more samples than the reference's, and for no other kind.
fn reference_noise(
    ctx: &mut Ctx,
    path: &KeyPath,
    raw: &RawReference,
    reference: Reference,
) -> Option<u32> {
    let key = path.key("noise_samples");
    match (reference, raw.noise_samples) {
        (_, Some(0)) => None,
        (Reference::Converged { samples }, None) => {
            Some((samples * 4).min(1024)).filter(|&n| n > samples)
        }
        (Reference::Converged { samples }, Some(n)) => {
            let n = ctx.count(&key, n, 0, 4096);
            if n <= samples {
                ctx.err(
                    &key,
                    format!("the reference's noise is measured against more samples than its own {samples}: give more than {samples}, or 0 to turn it off"),
                );
                return None;
            }
            Some(n)
        }
        (_, Some(_)) => {
            ctx.err(
                &key,
                "`noise_samples` applies only to kind = \"ground-truth\" with `samples` (the converged reference)",
            );
            None
        }
        (_, None) => None,
    }
}

fn metrics(
    ctx: &mut Ctx,
    path: &KeyPath,
    v: Option<&[String]>,
    reference: Reference,
) -> Vec<MetricKind> {
    let names: Vec<&str> = MetricKind::ALL.iter().map(|m| m.name()).collect();
    let Some(v) = v else {
        return if reference == Reference::None {
            Vec::new()
        } else {
            MetricKind::DEFAULT.to_vec()
        };
    };
    if reference == Reference::None && !v.is_empty() {
        ctx.err(
            path,
            "metrics need a reference: set [reference] kind to \"native\" or \"ground-truth\"",
        );
    }
    let mut out = Vec::new();
    for (i, name) in v.iter().enumerate() {
        if let Some(found) = ctx.choice(&path.index(i), "metric", name, &names) {
            let m = MetricKind::ALL[names.iter().position(|n| *n == found).unwrap_or(0)];
            if !out.contains(&m) {
                out.push(m);
            }
        }
    }
    out
}

/// `display`: a ColorVideoVDP display name or a table of changes to one; only with `cvvdp`.
fn display(
    ctx: &mut Ctx,
    path: &KeyPath,
    raw: Option<&toml::Value>,
    metrics: &[MetricKind],
) -> tessera_metrics::DisplaySpec {
    use serde::Deserialize;
    use tessera_metrics::{CustomDisplay, DisplaySpec};
    let Some(raw) = raw else {
        return DisplaySpec::default();
    };
    if !metrics.contains(&MetricKind::Cvvdp) {
        ctx.err(
            path,
            "display is what cvvdp sees the frames on: add \"cvvdp\" to metrics",
        );
    }
    let spec = match raw {
        toml::Value::String(name) => DisplaySpec::Named(name.clone()),
        toml::Value::Table(_) => match CustomDisplay::deserialize(raw.clone()) {
            Ok(c) => DisplaySpec::Custom(c),
            Err(e) => {
                ctx.err(path, format!("{e}"));
                return DisplaySpec::default();
            }
        },
        other => {
            ctx.err(
                path,
                format!(
                    "expected a display name (\"standard_4k\", \"paper_27in_4k\", ...) or a table, \
                     got {}",
                    other.type_str()
                ),
            );
            return DisplaySpec::default();
        }
    };
    match spec.model() {
        Ok(_) => spec,
        Err(e) => {
            ctx.err(path, e.to_string());
            DisplaySpec::default()
        }
    }
}

fn scene(ctx: &mut Ctx, path: &KeyPath, file: &Path, raw: &RawScene) -> Scene {
    let background = raw
        .background
        .as_deref()
        .map(|c| ctx.color(&path.key("background"), c))
        .unwrap_or(Vec3::new(0.55, 0.65, 0.8));
    let ambient = ctx.non_negative(&path.key("ambient"), raw.ambient.unwrap_or(0.08));
    let shading_cost = ctx.count(
        &path.key("shading_cost"),
        raw.shading_cost.unwrap_or(0),
        0,
        100_000,
    );
    let ground = raw
        .ground
        .as_ref()
        .map(|g| ground(ctx, &path.key("ground"), g));
    let lights = raw
        .lights
        .iter()
        .enumerate()
        .map(|(i, l)| light(ctx, &path.key("lights").index(i), l))
        .collect();
    let objects = raw
        .objects
        .iter()
        .enumerate()
        .map(|(i, o)| object(ctx, &path.key("objects").index(i), file, o))
        .collect();
    let anisotropy = ctx.count(&path.key("anisotropy"), raw.anisotropy.unwrap_or(1), 1, 16) as u16;
    let city = raw.city.as_ref().map(|c| city(ctx, &path.key("city"), c));
    Scene {
        background,
        ambient,
        shading_cost,
        ground,
        lights,
        objects,
        anisotropy,
        city,
    }
}

fn city(ctx: &mut Ctx, path: &KeyPath, c: &RawCity) -> City {
    let detail = ctx.positive(&path.key("texture_detail"), c.texture_detail.unwrap_or(0.5));
    if detail > 1.0 {
        ctx.err(
            &path.key("texture_detail"),
            format!("{detail} is above 1 (the finest detail is a fraction of the texture's Nyquist frequency, in (0, 1])"),
        );
    }
    let texture_size = ctx.count(
        &path.key("texture_size"),
        c.texture_size.unwrap_or(256),
        16,
        4096,
    );
    if !texture_size.is_power_of_two() {
        ctx.err(
            &path.key("texture_size"),
            format!("{texture_size} is not a power of two (16, 32, ..., 4096)"),
        );
    }
    City {
        seed: ctx.count(&path.key("seed"), c.seed.unwrap_or(1), 0, u32::MAX as i64) as u64,
        blocks: ctx.count(&path.key("blocks"), c.blocks.unwrap_or(4), 1, 64),
        block_size: ctx.positive(&path.key("block_size"), c.block_size.unwrap_or(40.0)),
        buildings: ctx.count(&path.key("buildings"), c.buildings.unwrap_or(8), 0, 64),
        texture_size,
        texture_detail: detail,
        trees: ctx.count(&path.key("trees"), c.trees.unwrap_or(4), 0, 256),
        tree_cards: ctx.count(&path.key("tree_cards"), c.tree_cards.unwrap_or(6), 1, 64),
        poles: ctx.count(&path.key("poles"), c.poles.unwrap_or(3), 0, 64),
        parked: ctx.count(&path.key("parked"), c.parked.unwrap_or(4), 0, 64),
        moving: ctx.count(&path.key("moving"), c.moving.unwrap_or(8), 0, 4096),
        speed: ctx.non_negative(&path.key("speed"), c.speed.unwrap_or(8.0)),
    }
}

fn ground(ctx: &mut Ctx, path: &KeyPath, g: &RawGround) -> Ground {
    let colors = match g.colors.as_deref() {
        None => [Vec3::splat(0.8), Vec3::splat(0.1)],
        Some([a, b]) => [
            ctx.color(&path.key("colors").index(0), a),
            ctx.color(&path.key("colors").index(1), b),
        ],
        Some(other) => {
            ctx.err(
                &path.key("colors"),
                format!(
                    "expected two colours [[r, g, b], [r, g, b]], found {}",
                    other.len()
                ),
            );
            [Vec3::ONE, Vec3::ZERO]
        }
    };
    let filter = match ctx.choice(
        &path.key("filter"),
        "filter",
        g.filter.as_deref().unwrap_or("box"),
        &["box", "none"],
    ) {
        Some("none") => GroundFilter::None,
        _ => GroundFilter::Box,
    };
    Ground {
        size: ctx.positive(&path.key("size"), g.size.unwrap_or(200.0)),
        height: ctx.finite(&path.key("height"), g.height.unwrap_or(0.0)),
        checker_size: ctx.positive(&path.key("checker_size"), g.checker_size.unwrap_or(1.0)),
        colors,
        filter,
        filter_epsilon: ctx
            .non_negative(&path.key("filter_epsilon"), g.filter_epsilon.unwrap_or(0.0)),
    }
}

fn light(ctx: &mut Ctx, path: &KeyPath, l: &RawLight) -> Light {
    let color = l
        .color
        .as_deref()
        .map(|c| ctx.color(&path.key("color"), c))
        .unwrap_or(Vec3::ONE);
    let intensity = ctx.non_negative(&path.key("intensity"), l.intensity.unwrap_or(1.0));
    let set = [
        ("direction", l.direction.is_some()),
        ("position", l.position.is_some()),
    ];
    let apath = path.key("animation");
    let anim = l.animation.as_ref().map(|a| animation(ctx, &apath, a));
    let moves = |a: &Option<Animation>| {
        matches!(
            a,
            Some(Animation::Translate { .. } | Animation::Oscillate { .. })
        )
    };
    match ctx.choice(
        &path.key("type"),
        "light type",
        &l.kind,
        &["directional", "point"],
    ) {
        Some("point") => {
            ctx.unused(path, "a point light", &set, &["position"]);
            let Some(p) = l.position.as_deref() else {
                ctx.err(path, "a point light needs `position`");
                return Light::Point {
                    position: Vec3::ZERO,
                    color,
                    intensity,
                    animation: None,
                };
            };
            if anim.is_some() && !moves(&anim) {
                ctx.err(
                    &apath.key("kind"),
                    "a point light's animation is `translate` or `oscillate` (`rotate` turns a directional light)",
                );
            }
            Light::Point {
                position: ctx.vec3(&path.key("position"), p),
                color,
                intensity,
                animation: anim,
            }
        }
        _ => {
            ctx.unused(path, "a directional light", &set, &["direction"]);
            let d = l
                .direction
                .as_deref()
                .map(|d| ctx.vec3(&path.key("direction"), d))
                .unwrap_or(Vec3::new(-0.4, -1.0, -0.3));
            if d.length_squared() == 0.0 {
                ctx.err(&path.key("direction"), "the direction must not be zero");
            }
            if moves(&anim) {
                ctx.err(
                    &apath.key("kind"),
                    "a directional light's animation is `rotate` (it turns the direction; `translate` and `oscillate` move a point light)",
                );
            }
            Light::Directional {
                direction: d.normalize_or(Vec3::NEG_Y),
                color,
                intensity,
                animation: anim,
            }
        }
    }
}

fn object(ctx: &mut Ctx, path: &KeyPath, file: &Path, o: &RawObject) -> Object {
    let set = [
        ("size", o.size.is_some()),
        ("radius", o.radius.is_some()),
        ("height", o.height.is_some()),
        ("end", o.end.is_some()),
        ("posts", o.posts.is_some()),
        ("rails", o.rails.is_some()),
        ("thickness", o.thickness.is_some()),
        ("path", o.path.is_some()),
        ("scale", o.scale.is_some()),
        ("materials", o.materials.is_some()),
    ];
    let shapes = ["box", "sphere", "pole", "fence", "mesh"];
    let shape_name = ctx.choice(&path.key("shape"), "shape", &o.shape, &shapes);
    let shape = match shape_name {
        Some("box") => {
            ctx.unused(path, "shape \"box\"", &set, &["size"]);
            let size = o
                .size
                .as_deref()
                .map(|s| ctx.vec3(&path.key("size"), s))
                .unwrap_or(Vec3::ONE);
            if size.min_element() <= 0.0 {
                ctx.err(&path.key("size"), "every extent must be > 0");
            }
            Shape::Box { size }
        }
        Some("sphere") => {
            ctx.unused(path, "shape \"sphere\"", &set, &["radius"]);
            Shape::Sphere {
                radius: ctx.positive(&path.key("radius"), o.radius.unwrap_or(0.5)),
            }
        }
        Some("pole") => {
            ctx.unused(path, "shape \"pole\"", &set, &["radius", "height"]);
            Shape::Pole {
                radius: ctx.positive(&path.key("radius"), o.radius.unwrap_or(0.02)),
                height: ctx.positive(&path.key("height"), o.height.unwrap_or(2.0)),
            }
        }
        Some("fence") => {
            ctx.unused(
                path,
                "shape \"fence\"",
                &set,
                &["end", "height", "posts", "rails", "thickness"],
            );
            let end = match o.end.as_deref() {
                Some(e) => ctx.vec3(&path.key("end"), e),
                None => {
                    ctx.err(path, "a fence needs `end` (its near end is `position`)");
                    Vec3::X
                }
            };
            Shape::Fence {
                end,
                height: ctx.positive(&path.key("height"), o.height.unwrap_or(1.0)),
                posts: ctx.count(&path.key("posts"), o.posts.unwrap_or(10), 2, 10_000),
                rails: ctx.count(&path.key("rails"), o.rails.unwrap_or(2), 0, 100),
                thickness: ctx.positive(&path.key("thickness"), o.thickness.unwrap_or(0.03)),
            }
        }
        Some("mesh") => {
            ctx.unused(
                path,
                "shape \"mesh\"",
                &set,
                &["path", "scale", "materials"],
            );
            let rel = match &o.path {
                Some(p) => p.clone(),
                None => {
                    ctx.err(path, "a mesh needs `path` (a .glb or .gltf file)");
                    String::new()
                }
            };
            let resolved = file.parent().unwrap_or(Path::new(".")).join(&rel);
            if !rel.is_empty() && !resolved.is_file() {
                ctx.err(
                    &path.key("path"),
                    format!(
                        "no such file: {} (run ci/setup.sh to install the test models)",
                        resolved.display()
                    ),
                );
            }
            // A file with materials is drawn with them unless the scenario asks for "color".
            let default = if file_has_materials(&resolved) {
                "file"
            } else {
                "color"
            };
            let textured = ctx.choice(
                &path.key("materials"),
                "materials",
                o.materials.as_deref().unwrap_or(default),
                &["color", "file"],
            ) == Some("file");
            Shape::Mesh {
                path: resolved,
                scale: ctx.positive(&path.key("scale"), o.scale.unwrap_or(1.0)),
                textured,
            }
        }
        _ => Shape::Sphere { radius: 1.0 },
    };
    let animation = o
        .animation
        .as_ref()
        .map(|a| animation(ctx, &path.key("animation"), a));
    Object {
        shape,
        position: o
            .position
            .as_deref()
            .map(|p| ctx.dvec3(&path.key("position"), p))
            .unwrap_or(DVec3::ZERO),
        yaw_degrees: ctx.finite(&path.key("yaw"), o.yaw.unwrap_or(0.0)),
        color: o
            .color
            .as_deref()
            .map(|c| ctx.color(&path.key("color"), c))
            .unwrap_or(Vec3::splat(0.7)),
        emissive: o
            .emissive
            .as_deref()
            .map(|c| ctx.color(&path.key("emissive"), c))
            .unwrap_or(Vec3::ZERO),
        specular: ctx.non_negative(&path.key("specular"), o.specular.unwrap_or(0.25)),
        animation,
        inject: o.inject.as_deref().and_then(|v| {
            match ctx.choice(&path.key("inject"), "injected value", v, &["nan", "inf"]) {
                Some("nan") => Some(Inject::Nan),
                Some(_) => Some(Inject::Inf),
                None => None,
            }
        }),
    }
}

fn animation(ctx: &mut Ctx, path: &KeyPath, a: &RawAnimation) -> Animation {
    let set = [
        ("axis", a.axis.is_some()),
        ("degrees_per_second", a.degrees_per_second.is_some()),
        ("velocity", a.velocity.is_some()),
        ("amplitude", a.amplitude.is_some()),
        ("period", a.period.is_some()),
    ];
    match ctx.choice(
        &path.key("kind"),
        "animation",
        &a.kind,
        &["rotate", "translate", "oscillate"],
    ) {
        Some("translate") => {
            ctx.unused(path, "a translate animation", &set, &["velocity"]);
            let v = a
                .velocity
                .as_deref()
                .map(|v| ctx.vec3(&path.key("velocity"), v))
                .unwrap_or(Vec3::X);
            Animation::Translate { velocity: v }
        }
        Some("oscillate") => {
            ctx.unused(
                path,
                "an oscillate animation",
                &set,
                &["amplitude", "period"],
            );
            let amp = a
                .amplitude
                .as_deref()
                .map(|v| ctx.vec3(&path.key("amplitude"), v))
                .unwrap_or(Vec3::X);
            Animation::Oscillate {
                amplitude: amp,
                period: ctx.positive(&path.key("period"), a.period.unwrap_or(2.0)),
            }
        }
        _ => {
            ctx.unused(
                path,
                "a rotate animation",
                &set,
                &["axis", "degrees_per_second"],
            );
            let axis = a
                .axis
                .as_deref()
                .map(|v| ctx.vec3(&path.key("axis"), v))
                .unwrap_or(Vec3::Y);
            if axis.length_squared() == 0.0 {
                ctx.err(&path.key("axis"), "the axis must not be zero");
            }
            Animation::Rotate {
                axis: axis.normalize_or(Vec3::Y),
                degrees_per_second: ctx.finite(
                    &path.key("degrees_per_second"),
                    a.degrees_per_second.unwrap_or(90.0),
                ),
            }
        }
    }
}

fn camera(ctx: &mut Ctx, path: &KeyPath, raw: &RawCamera) -> CameraTrack {
    let near = raw.near.unwrap_or(0.1);
    let far = raw.far.unwrap_or(1000.0);
    let near_ok = near.is_finite() && near > 0.0;
    if !near_ok {
        ctx.err(
            &path.key("near"),
            format!("{near} is not allowed: expected 0 < near < far"),
        );
    }
    if !(far.is_finite() && (!near_ok || far > near)) {
        ctx.err(
            &path.key("far"),
            format!("{far} is not allowed: expected 0 < near < far (near = {near})"),
        );
    }
    let interpolation = match ctx.choice(
        &path.key("interpolation"),
        "interpolation",
        raw.interpolation.as_deref().unwrap_or("linear"),
        &["linear", "smooth"],
    ) {
        Some("smooth") => Interpolation::Smooth,
        _ => Interpolation::Linear,
    };
    let kpath = path.key("keyframes");
    if raw.keyframes.is_empty() {
        ctx.err(&kpath, "at least one keyframe is needed");
    }
    let mut keyframes: Vec<Keyframe> = Vec::new();
    for (i, k) in raw.keyframes.iter().enumerate() {
        let p = kpath.index(i);
        let time = ctx.non_negative(&p.key("time"), k.time) as f64;
        if let Some(prev) = keyframes.last() {
            if k.time <= prev.time {
                ctx.err(&p.key("time"), format!("{} is not after the previous keyframe's time {}: keyframe times must increase", k.time, prev.time));
            }
        }
        let position = ctx.dvec3(&p.key("position"), &k.position);
        let target = ctx.dvec3(&p.key("target"), &k.target);
        if (target - position).length_squared() == 0.0 {
            ctx.err(&p.key("target"), "the target must differ from the position");
        }
        let fov = k.fov.unwrap_or(60.0);
        if !(fov.is_finite() && fov > 0.0 && fov < 180.0) {
            ctx.err(&p.key("fov"), format!("{fov} is not allowed: expected a vertical field of view in degrees, 0 < fov < 180"));
        }
        if k.cut && i == 0 {
            ctx.err(&p.key("cut"), "the first keyframe cannot be a cut");
        }
        keyframes.push(Keyframe {
            time: if time.is_finite() { k.time } else { 0.0 },
            position,
            target,
            fov_degrees: fov as f32,
            cut: k.cut,
        });
    }
    if keyframes.is_empty() {
        keyframes.push(Keyframe {
            time: 0.0,
            position: DVec3::new(0.0, 1.0, 5.0),
            target: DVec3::ZERO,
            fov_degrees: 60.0,
            cut: false,
        });
    }
    CameraTrack {
        near: near as f32,
        far: far as f32,
        interpolation,
        keyframes,
    }
}

fn variants(ctx: &mut Ctx, path: &KeyPath, raw: &[RawTechnique]) -> Vec<Variant> {
    let mut out: Vec<Variant> = Vec::new();
    if raw.is_empty() {
        ctx.err(
            path,
            format!(
                "at least one [[techniques]] entry is needed; known techniques: {}",
                quoted_list(&techniques::names())
            ),
        );
    }
    for (i, t) in raw.iter().enumerate() {
        let p = path.index(i);
        let known = techniques::names();
        let Some(kind) = techniques::by_name(&t.technique) else {
            let hint = closest(&t.technique, &known)
                .map(|c| format!(" (did you mean \"{c}\"?)"))
                .unwrap_or_default();
            ctx.err(
                &p.key("technique"),
                format!(
                    "unknown technique \"{}\"{hint}: known techniques are {}",
                    t.technique,
                    quoted_list(&known)
                ),
            );
            continue;
        };
        let specs = kind.params();
        let allowed: Vec<&str> = specs.iter().map(|s| s.name).collect();
        // Each parameter's list of values; a list of more than one is a sweep.
        let mut axes: Vec<(String, Vec<ParamValue>, bool)> = Vec::new();
        for (key, value) in &t.params {
            let Some(spec) = specs.iter().find(|s| s.name == key) else {
                let what = if allowed.is_empty() {
                    format!("technique \"{kind}\" takes no parameters")
                } else {
                    let hint = closest(key, &allowed)
                        .map(|c| format!(" (did you mean \"{c}\"?)"))
                        .unwrap_or_default();
                    format!(
                        "unknown parameter{hint}: technique \"{kind}\" takes {}",
                        quoted_list(&allowed)
                    )
                };
                ctx.err(&p.key(key), what);
                continue;
            };
            let values: Vec<(KeyPath, &toml::Value)> = match value {
                toml::Value::Array(items) => {
                    if items.is_empty() {
                        ctx.err(&p.key(key), "an empty sweep: give at least one value");
                    }
                    items
                        .iter()
                        .enumerate()
                        .map(|(j, v)| (p.key(key).index(j), v))
                        .collect()
                }
                v => vec![(p.key(key), v)],
            };
            let mut checked = Vec::new();
            for (vp, v) in values {
                match spec.kind.check(v) {
                    Ok(pv) => checked.push(pv),
                    Err(msg) => ctx.err(&vp, msg),
                }
            }
            // Named in the variant: swept parameters, and single values that differ from the default.
            let named =
                checked.len() > 1 || checked.first().is_some_and(|v| *v != spec.default.value());
            axes.push((key.clone(), checked, named));
        }
        let swept = axes.iter().any(|(_, v, _)| v.len() > 1);
        if swept && t.label.is_some() {
            ctx.err(
                &p.key("label"),
                "`label` names one variant: it cannot be used with a sweep",
            );
        }
        for combo in cartesian(&axes) {
            let mut params: BTreeMap<String, ParamValue> = specs
                .iter()
                .map(|s| (s.name.to_string(), s.default.value()))
                .collect();
            for (k, v) in &combo {
                params.insert(k.clone(), v.clone());
            }
            let shown: Vec<(String, ParamValue)> = combo
                .iter()
                .filter(|(k, _)| axes.iter().any(|(a, _, named)| a == k && *named))
                .cloned()
                .collect();
            let name = t
                .label
                .clone()
                .unwrap_or_else(|| variant_name(kind, &shown));
            if out.iter().any(|v| v.name == name) {
                ctx.err(
                    &p,
                    format!(
                        "variant \"{name}\" appears twice: give one of them a different `label`"
                    ),
                );
            }
            let variant = Variant {
                name,
                technique: kind,
                params,
            };
            if let Err(why) = kind.check(&variant) {
                ctx.err(&p, format!("variant \"{}\": {why}", variant.name));
            }
            out.push(variant);
        }
    }
    out
}

/// Every combination of one value per axis, in declaration order.
fn cartesian(axes: &[(String, Vec<ParamValue>, bool)]) -> Vec<Vec<(String, ParamValue)>> {
    let mut combos: Vec<Vec<(String, ParamValue)>> = vec![Vec::new()];
    for (key, values, _) in axes {
        if values.is_empty() {
            return vec![Vec::new()];
        }
        combos = combos
            .into_iter()
            .flat_map(|c| {
                values.iter().map(move |v| {
                    let mut c = c.clone();
                    c.push((key.clone(), v.clone()));
                    c
                })
            })
            .collect();
    }
    combos
}

/// `frames.measured`: the compared (and, when fixed, timed) frame count, and the auto rule. Under
/// `auto` the compared frames are the rule's `min`.
fn measured(ctx: &mut Ctx, path: &KeyPath, raw: &Option<RawMeasured>) -> (u32, Option<AutoRule>) {
    const MAX: i64 = 100_000;
    let auto = match raw {
        None => return (8, None),
        Some(RawMeasured::Count(n)) => return (ctx.count(path, *n, 1, MAX), None),
        Some(RawMeasured::Word(w)) if w == "auto" => RawAuto::default(),
        Some(RawMeasured::Word(w)) => {
            ctx.err(
                path,
                format!("\"{w}\" is not allowed: expected an integer from 1 to {MAX}, \"auto\" or a table {{ min, max, precision, timeout_s }}"),
            );
            return (8, None);
        }
        Some(RawMeasured::Auto(a)) => RawAuto {
            min: a.min,
            max: a.max,
            precision: a.precision,
            timeout_s: a.timeout_s,
        },
    };
    let min = ctx.count(&path.key("min"), auto.min.unwrap_or(AUTO_MIN), 1, MAX);
    let max = ctx.count(&path.key("max"), auto.max.unwrap_or(AUTO_MAX), 1, MAX);
    if min > max {
        ctx.err(
            &path.key("max"),
            format!("{max} is below min ({min}): expected min <= max"),
        );
    }
    let precision = auto.precision.unwrap_or(DEFAULT_PRECISION);
    if !(precision.is_finite() && precision > 0.0 && precision < 1.0) {
        ctx.err(
            &path.key("precision"),
            format!("{precision} is out of range: expected a relative precision above 0 and below 1 (0.005 = 0.5%)"),
        );
    }
    let timeout_s = auto.timeout_s.unwrap_or(AUTO_TIMEOUT_S);
    if !(timeout_s.is_finite() && timeout_s > 0.0 && timeout_s <= 3600.0) {
        ctx.err(
            &path.key("timeout_s"),
            format!("{timeout_s} is out of range: expected seconds above 0, at most 3600"),
        );
    }
    (
        min,
        Some(AutoRule {
            min,
            max: max.max(min),
            precision,
            timeout_s,
        }),
    )
}

/// The canonical name of a gate's measure: itself, an older spelling's (`non-finite` is
/// `non_finite_values`), or a summarised measure's for `<name>.median`; `None` when it names no
/// single value of the measure table.
fn gate_measure_name(name: &str) -> Option<&'static str> {
    let key = tessera_results::measure::Key::parse(name)?;
    let single = key.pass.is_none()
        && key.baseline.is_none()
        && matches!(key.statistic, None | Some("median"));
    single.then(|| key.measure.name())
}

fn gates(ctx: &mut Ctx, path: &KeyPath, raw: &[RawGate], metrics: &[MetricKind]) -> Vec<Gate> {
    let mut out = Vec::new();
    for (i, g) in raw.iter().enumerate() {
        let p = path.index(i);
        let mut allowed: Vec<&str> = metrics.iter().map(|m| m.name()).collect();
        allowed.extend(record_gate_measures());
        if metrics.contains(&MetricKind::Cvvdp) {
            allowed.extend(CVVDP_MEASURES.map(Measure::name));
        }
        // An older spelling (`non-finite`) or `<name>.median` names the same measure.
        let canonical = gate_measure_name(&g.measure);
        let measure = canonical.unwrap_or(g.measure.as_str());
        if !allowed.contains(&measure) {
            let known_metric = MetricKind::ALL.iter().any(|m| m.name() == measure);
            if known_metric {
                ctx.err(
                    &p.key("measure"),
                    format!(
                        "metric \"{}\" is not computed by this scenario: add it to `metrics`",
                        g.measure
                    ),
                );
            } else {
                ctx.choice(&p.key("measure"), "measure", &g.measure, &allowed);
            }
        }
        let bounds = [
            ("warn_below", g.warn_below),
            ("fail_below", g.fail_below),
            ("warn_above", g.warn_above),
            ("fail_above", g.fail_above),
        ];
        if bounds.iter().all(|(_, v)| v.is_none()) {
            ctx.err(
                &p,
                "a gate needs at least one of warn_below, fail_below, warn_above, fail_above",
            );
        }
        for (key, v) in bounds {
            if let Some(v) = v {
                ctx.finite(&p.key(key), v);
            }
        }
        if let (Some(w), Some(f)) = (g.warn_below, g.fail_below) {
            if f > w {
                ctx.err(&p.key("fail_below"), format!("fail_below ({f}) is above warn_below ({w}): failing must be the stricter level"));
            }
        }
        if let (Some(w), Some(f)) = (g.warn_above, g.fail_above) {
            if f < w {
                ctx.err(&p.key("fail_above"), format!("fail_above ({f}) is below warn_above ({w}): failing must be the stricter level"));
            }
        }
        out.push(Gate {
            measure: measure.to_string(),
            variants: g.variants.clone(),
            warn_below: g.warn_below,
            fail_below: g.fail_below,
            warn_above: g.warn_above,
            fail_above: g.fail_above,
        });
    }
    out
}

/// Whether the glTF file at `path` declares materials (its JSON only: no buffers or images are
/// read). False for a file that cannot be read or parsed: loading it reports that.
fn file_has_materials(path: &Path) -> bool {
    gltf::Gltf::open(path).is_ok_and(|g| g.materials().len() > 0)
}
