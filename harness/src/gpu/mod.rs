//! Adapters and devices: listing, choosing, and opening one with its real limits.
//!
//! Only this module talks to `wgpu::Instance`. It does not render; `render/` does. What an
//! adapter can do beyond its limits and features is probed in `probe.rs`; what a variant needs of
//! it is declared as `requirements.rs`' data.

mod probe;
pub mod requirements;
pub mod vrs;

pub use probe::{PROBE_WGSL, STANDARD_2X};
pub use requirements::{Extension, Requirements};

use std::collections::BTreeMap;

use tessera_results::{AdapterFeatures, AdapterInfo};

/// Formats whose MSAA support `tessera adapters` reports (the ones the techniques render to).
pub const REPORTED_FORMATS: [(wgpu::TextureFormat, &str); 4] = [
    (wgpu::TextureFormat::Rgba16Float, "rgba16float"),
    (wgpu::TextureFormat::Rgba8Unorm, "rgba8unorm"),
    (wgpu::TextureFormat::Depth32Float, "depth32float"),
    (wgpu::TextureFormat::Rg16Float, "rg16float"),
];

#[derive(Debug, thiserror::Error)]
pub enum GpuError {
    #[error("no GPU adapter was found (on a machine without a GPU, run ci/setup.sh to install lavapipe)")]
    NoAdapter,
    #[error("no adapter matches \"{wanted}\"; available: {available}")]
    NoMatch { wanted: String, available: String },
    #[error("cannot open a device on {adapter}: {source}")]
    RequestDevice {
        adapter: String,
        source: wgpu::RequestDeviceError,
    },
}

/// An opened device and what Tessera knows about its adapter.
pub struct Gpu {
    pub adapter: wgpu::Adapter,
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    pub info: AdapterInfo,
    /// 2x MSAA sample positions, probed on first use by `checkerboard` with `sampling = "msaa2x"`.
    pub msaa2x_positions: std::sync::OnceLock<Result<[[f32; 2]; 2], String>>,
    /// Hardware variable-rate shading (VK_KHR_fragment_shading_rate, turned on at device
    /// creation where offered): what the adapter offers, or why the hardware variants are skipped.
    pub vrs: Result<vrs::VrsCaps, String>,
    /// The GPU metrics back end on this device, made on first use (`crate::metrics_device`).
    pub metrics: std::sync::OnceLock<std::sync::Mutex<tessera_metrics_gpu::GpuMetrics>>,
    /// The frame-check pipelines, made on first use by the module that owns them (the frame
    /// checks of render/, `Gpu::frame_check`); type-erased so that gpu/ does not import render/.
    pub frame_check: std::sync::OnceLock<Box<dyn std::any::Any + Send + Sync>>,
}

impl Gpu {
    pub fn has(&self, feature: wgpu::Features) -> bool {
        self.device.features().contains(feature)
    }

    pub fn max_dimension(&self) -> u32 {
        self.device.limits().max_texture_dimension_2d
    }

    /// Unsupported when `width` x `height` exceeds the adapter's texture size.
    pub fn check_size(&self, width: u32, height: u32) -> Result<(), Unsupported> {
        let max = self.max_dimension();
        if width > max || height > max {
            return Err(Unsupported(format!(
                "{width}x{height} exceeds the adapter's maximum texture size {max}"
            )));
        }
        Ok(())
    }
}

/// Why a variant cannot run on this adapter: reported as status `skipped`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Unsupported(pub String);

/// Backends searched: `WGPU_BACKEND` if set (e.g. `vulkan`, `gl`), else `default`.
fn backends(default: wgpu::Backends) -> wgpu::Backends {
    wgpu::Backends::from_env().unwrap_or(default)
}

fn enumerate_backends(backends: wgpu::Backends) -> Vec<wgpu::Adapter> {
    let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
    desc.backends = backends;
    pollster::block_on(wgpu::Instance::new(desc).enumerate_adapters(backends))
}

/// Every adapter of every backend (GL included), in the order wgpu enumerates them.
pub fn enumerate() -> Vec<wgpu::Adapter> {
    enumerate_backends(backends(wgpu::Backends::all()))
}

/// Describes an adapter: identity, driver and the features that matter here.
pub fn describe(adapter: &wgpu::Adapter) -> AdapterInfo {
    let info = adapter.get_info();
    let features = adapter.features();
    let mut msaa = BTreeMap::new();
    for (format, name) in REPORTED_FORMATS {
        let f = adapter.get_texture_format_features(format);
        msaa.insert(name.to_string(), f.flags.supported_sample_counts());
    }
    AdapterInfo {
        name: info.name.clone(),
        vendor: info.vendor,
        device: info.device,
        device_type: device_type_name(info.device_type).to_string(),
        driver: info.driver.clone(),
        driver_info: info.driver_info.clone(),
        backend: info.backend.to_str().to_string(),
        features: AdapterFeatures {
            timestamps: features.contains(wgpu::Features::TIMESTAMP_QUERY),
            timestamps_inside_passes: features
                .contains(wgpu::Features::TIMESTAMP_QUERY_INSIDE_PASSES),
            timestamp_period_ns: None,
            pipeline_statistics: features.contains(wgpu::Features::PIPELINE_STATISTICS_QUERY),
            shader_f16: features.contains(wgpu::Features::SHADER_F16),
            msaa,
            max_texture_dimension_2d: adapter.limits().max_texture_dimension_2d,
        },
    }
}

fn device_type_name(t: wgpu::DeviceType) -> &'static str {
    match t {
        wgpu::DeviceType::DiscreteGpu => "discrete-gpu",
        wgpu::DeviceType::IntegratedGpu => "integrated-gpu",
        wgpu::DeviceType::VirtualGpu => "virtual-gpu",
        wgpu::DeviceType::Cpu => "cpu",
        wgpu::DeviceType::Other => "other",
    }
}

/// Preference for the default choice: a real GPU first, Vulkan before the other backends (GL is
/// not supported: see DESIGN.md), lavapipe last.
fn rank(info: &wgpu::AdapterInfo) -> (u8, u8) {
    let kind = match info.device_type {
        wgpu::DeviceType::DiscreteGpu => 0,
        wgpu::DeviceType::IntegratedGpu => 1,
        wgpu::DeviceType::VirtualGpu => 2,
        wgpu::DeviceType::Other => 3,
        wgpu::DeviceType::Cpu => 4,
    };
    let backend = match info.backend {
        wgpu::Backend::Vulkan => 0,
        wgpu::Backend::Metal | wgpu::Backend::Dx12 => 1,
        _ => 2,
    };
    (backend, kind)
}

/// Picks an adapter: the first that `wanted` names ([`tessera_results::adapter::matches`]: its
/// name, driver or backend contains it, or it is the vendor, case-insensitive), or by default the
/// best-ranked one.
///
/// Runs search Vulkan, Metal and DX12 only, unless `WGPU_BACKEND` says otherwise: the GL backend
/// mis-times render passes and cannot read multisampled textures in compute (DESIGN.md).
pub fn select(wanted: Option<&str>) -> Result<wgpu::Adapter, GpuError> {
    let mut adapters = enumerate_backends(backends(wgpu::Backends::PRIMARY));
    if adapters.is_empty() {
        return Err(GpuError::NoAdapter);
    }
    match wanted {
        Some(w) => {
            // The one matching rule, shared with expectations' `adapter` key.
            let found = adapters.iter().position(|a| {
                let i = a.get_info();
                tessera_results::adapter::matches(
                    w,
                    &i.name,
                    i.vendor,
                    &i.driver,
                    &i.driver_info,
                    i.backend.to_str(),
                )
            });
            match found {
                Some(i) => Ok(adapters.swap_remove(i)),
                None => Err(GpuError::NoMatch {
                    wanted: w.to_string(),
                    available: adapters
                        .iter()
                        .map(|a| {
                            let i = a.get_info();
                            format!("{} ({})", i.name, i.backend.to_str())
                        })
                        .collect::<Vec<_>>()
                        .join(", "),
                }),
            }
        }
        None => {
            adapters.sort_by_key(|a| rank(&a.get_info()));
            Ok(adapters.swap_remove(0))
        }
    }
}

/// Features Tessera uses when the adapter has them; none is required.
pub fn wanted_features() -> wgpu::Features {
    wgpu::Features::TIMESTAMP_QUERY
        | wgpu::Features::TIMESTAMP_QUERY_INSIDE_PASSES
        | wgpu::Features::TIMESTAMP_QUERY_INSIDE_ENCODERS
        | wgpu::Features::PIPELINE_STATISTICS_QUERY
        | wgpu::Features::TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES
        | wgpu::Features::SHADER_F16
        | wgpu::Features::SUBGROUP
}

/// Opens a device with the adapter's real limits (not the downlevel defaults, which cap textures
/// at 2048) and every wanted feature it has.
pub fn open(adapter: wgpu::Adapter) -> Result<Gpu, GpuError> {
    let mut info = describe(&adapter);
    let features = adapter.features() & wanted_features();
    let desc = wgpu::DeviceDescriptor {
        label: Some("tessera"),
        required_features: features,
        required_limits: adapter.limits(),
        experimental_features: wgpu::ExperimentalFeatures::disabled(),
        memory_hints: wgpu::MemoryHints::Performance,
        trace: wgpu::Trace::Off,
    };
    // With hardware VRS where the adapter offers it (through wgpu-hal, `vrs.rs`); a device that
    // cannot be opened that way is opened as usual, and the VRS variants are skipped.
    let mut vrs = vrs::probe(&adapter);
    let opened = match &vrs {
        Ok(_) => match vrs::open(&adapter, &desc) {
            Ok(dq) => Some(dq),
            Err(e) => {
                vrs = Err(format!(
                    "{} (device creation with it failed: {e})",
                    vrs::NEEDS
                ));
                None
            }
        },
        Err(_) => None,
    };
    let (device, queue) = match opened {
        Some(dq) => dq,
        None => pollster::block_on(adapter.request_device(&desc)).map_err(|source| {
            GpuError::RequestDevice {
                adapter: info.name.clone(),
                source,
            }
        })?,
    };
    if features.contains(wgpu::Features::TIMESTAMP_QUERY) {
        info.features.timestamp_period_ns = Some(queue.get_timestamp_period());
    }
    Ok(Gpu {
        adapter,
        device,
        queue,
        info,
        msaa2x_positions: std::sync::OnceLock::new(),
        vrs,
        metrics: std::sync::OnceLock::new(),
        frame_check: std::sync::OnceLock::new(),
    })
}
