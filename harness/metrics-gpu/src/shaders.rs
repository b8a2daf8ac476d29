//! The WGSL sources and the pipelines made from them, once per device.
//!
//! For: composing shader sources (FLIP's constants are written in as the exact f32 values the
//! CPU port computes) and creating the compute pipelines. Not for: recording work (see `pair`,
//! `temporal`, `frame`).

/// Every pipeline of the GPU metrics.
pub(crate) struct Pipelines {
    pub pixel: wgpu::ComputePipeline,
    pub ssim: wgpu::ComputePipeline,
    pub planes_ldr: wgpu::ComputePipeline,
    pub planes_hdr: wgpu::ComputePipeline,
    pub vertical: wgpu::ComputePipeline,
    pub horizontal: wgpu::ComputePipeline,
    pub reduce: wgpu::ComputePipeline,
    pub heatmap: wgpu::ComputePipeline,
    pub tde: wgpu::ComputePipeline,
    /// One per readable frame texture format, made on first use.
    pub encode: std::collections::HashMap<wgpu::TextureFormat, wgpu::ComputePipeline>,
}

pub(crate) const PIXEL: &str = include_str!("../shaders/pixel.wgsl");
pub(crate) const SSIM: &str = include_str!("../shaders/ssim.wgsl");
pub(crate) const FLIP_COMMON: &str = include_str!("../shaders/flip_common.wgsl");
pub(crate) const FLIP_PLANES_LDR: &str = include_str!("../shaders/flip_planes_ldr.wgsl");
pub(crate) const FLIP_PLANES_HDR: &str = include_str!("../shaders/flip_planes_hdr.wgsl");
pub(crate) const FLIP_VERTICAL: &str = include_str!("../shaders/flip_vertical.wgsl");
pub(crate) const FLIP_HORIZONTAL: &str = include_str!("../shaders/flip_horizontal.wgsl");
pub(crate) const REDUCE: &str = include_str!("../shaders/reduce.wgsl");
pub(crate) const HEATMAP: &str = include_str!("../shaders/heatmap.wgsl");
pub(crate) const TDE: &str = include_str!("../shaders/tde.wgsl");
pub(crate) const ENCODE: &str = include_str!("../shaders/encode.wgsl");
pub(crate) const RUNNING_SUM: &str = include_str!("../shaders/running_sum.wgsl");

/// An f32 as a WGSL literal that parses back to the same value.
fn lit(v: f32) -> String {
    format!("{v:e}f")
}

/// FLIP's constants, computed in f32 operation for operation as tessera-metrics' `flip/color.rs`
/// (from `FLIP.h`) computes them, as WGSL `const`s: WGSL would fold `a / b` in higher precision.
#[allow(clippy::excessive_precision)]
pub(crate) fn flip_constants() -> String {
    let d = 24577794.0f32;
    let e = 12288897.0f32;
    let f = 73733382.0f32;
    let delta = 6.0f32 / 29.0f32;
    let delta_square = delta * delta;
    let values: &[(&str, f32)] = &[
        ("A11", 10135552.0f32 / d),
        ("A12", 8788810.0f32 / d),
        ("A13", 4435075.0f32 / d),
        ("A21", 2613072.0f32 / e),
        ("A22", 8788810.0f32 / e),
        ("A23", 887015.0f32 / e),
        ("A31", 1425312.0f32 / f),
        ("A32", 8788810.0f32 / f),
        ("A33", 70074185.0f32 / f),
        ("B11", 3.241003275),
        ("B12", -1.537398934),
        ("B13", -0.498615861),
        ("B21", -0.969224334),
        ("B22", 1.875930071),
        ("B23", 0.041554224),
        ("B31", 0.055639423),
        ("B32", -0.204011202),
        ("B33", 1.057148933),
        ("ILL_X", 0.950428545),
        ("ILL_Y", 1.0),
        ("ILL_Z", 1.088900371),
        ("INV_ILL_X", 1.052156925),
        ("INV_ILL_Y", 1.0),
        ("INV_ILL_Z", 0.918357670),
        ("DELTA_CUBE", delta * delta_square),
        ("LAB_FACTOR", 1.0f32 / (3.0f32 * delta_square)),
        ("LAB_TERM", 4.0f32 / 29.0f32),
        ("ONE_THIRD", 1.0f32 / 3.0f32),
        ("ONE_OVER_116", 1.0f32 / 116.0f32),
        ("SIXTEEN_OVER_116", 16.0f32 / 116.0f32),
        ("QC", tessera_metrics::port::FLIP_QC),
        ("PT", tessera_metrics::port::FLIP_PT),
        ("NORMALIZATION", 1.0f32 / 2.0f32.sqrt()),
    ];
    let mut s = String::new();
    for &(name, v) in values {
        s.push_str(&format!("const C_{name}: f32 = {};\n", lit(v)));
    }
    s
}

fn module(device: &wgpu::Device, label: &str, source: &str) -> wgpu::ShaderModule {
    device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(label),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    })
}

pub(crate) fn pipeline(device: &wgpu::Device, label: &str, source: &str) -> wgpu::ComputePipeline {
    device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some(label),
        layout: None,
        module: &module(device, label, source),
        entry_point: Some("main"),
        compilation_options: Default::default(),
        cache: None,
    })
}

/// The full source of a FLIP pass: constants, colour functions, the pass.
pub(crate) fn flip_source(pass: &str) -> String {
    format!("{}\n{FLIP_COMMON}\n{pass}", flip_constants())
}

impl Pipelines {
    pub fn new(device: &wgpu::Device) -> Pipelines {
        Pipelines {
            pixel: pipeline(device, "metrics pixel", PIXEL),
            ssim: pipeline(device, "metrics ssim", SSIM),
            planes_ldr: pipeline(device, "flip planes ldr", &flip_source(FLIP_PLANES_LDR)),
            planes_hdr: pipeline(device, "flip planes hdr", &flip_source(FLIP_PLANES_HDR)),
            vertical: pipeline(device, "flip vertical", &flip_source(FLIP_VERTICAL)),
            horizontal: pipeline(device, "flip horizontal", &flip_source(FLIP_HORIZONTAL)),
            reduce: pipeline(device, "metrics reduce", REDUCE),
            heatmap: pipeline(device, "flip heatmap", HEATMAP),
            tde: pipeline(device, "metrics tde", TDE),
            encode: Default::default(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every shader parses and validates with naga, without a GPU (STYLE.md 6).
    #[test]
    fn shaders_validate() {
        let sources = [
            PIXEL.to_string(),
            SSIM.to_string(),
            flip_source(FLIP_PLANES_LDR),
            flip_source(FLIP_PLANES_HDR),
            flip_source(FLIP_VERTICAL),
            flip_source(FLIP_HORIZONTAL),
            REDUCE.to_string(),
            HEATMAP.to_string(),
            TDE.to_string(),
            ENCODE.to_string(),
            RUNNING_SUM.to_string(),
        ];
        let cvvdp = crate::cvvdp::sources().into_iter().map(|(_, s)| s);
        for s in sources.into_iter().chain(cvvdp) {
            let m = naga::front::wgsl::parse_str(&s)
                .unwrap_or_else(|e| panic!("{}", e.emit_to_string(&s)));
            naga::valid::Validator::new(
                naga::valid::ValidationFlags::all(),
                naga::valid::Capabilities::empty(),
            )
            .validate(&m)
            .unwrap_or_else(|e| panic!("{e:?}"));
        }
    }

    #[test]
    fn literals_round_trip() {
        for v in [0.41238656f32, 1.0 / 3.0, -1.537_399, 1e-7, 0.0] {
            let s = lit(v);
            assert_eq!(s[..s.len() - 1].parse::<f32>().unwrap(), v);
        }
    }
}
