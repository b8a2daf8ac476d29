//! Opening a device for the GPU metrics when the caller has none (the bench, the tests,
//! `tessera diff --gpu`); a run passes the device that rendered its frames instead.
//!
//! For: choosing an adapter by a name filter and opening it with its real limits. Not for:
//! anything the harness's `gpu` module does for rendering (features, VRS, probes).

use crate::error::GpuMetricsError;

/// An opened device and its adapter.
pub struct MetricsDevice {
    pub adapter: wgpu::Adapter,
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
}

/// The adapter whose name, driver or backend contains `wanted` (case-insensitive), or the first
/// discrete, then integrated, then any adapter; Vulkan, Metal and DX12 (`WGPU_BACKEND` overrides).
pub fn select_adapter(wanted: Option<&str>) -> Result<wgpu::Adapter, GpuMetricsError> {
    let backends = wgpu::Backends::from_env().unwrap_or(wgpu::Backends::PRIMARY);
    let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
    desc.backends = backends;
    let mut adapters = pollster::block_on(wgpu::Instance::new(desc).enumerate_adapters(backends));
    let available = adapters
        .iter()
        .map(|a| {
            let i = a.get_info();
            format!("{} ({})", i.name, i.backend.to_str())
        })
        .collect::<Vec<_>>()
        .join(", ");
    let position = match wanted {
        Some(w) => {
            let needle = w.to_lowercase();
            adapters.iter().position(|a| {
                let i = a.get_info();
                [&i.name, &i.driver, &i.driver_info, i.backend.to_str()]
                    .iter()
                    .any(|s| s.to_lowercase().contains(&needle))
            })
        }
        None => {
            adapters.sort_by_key(|a| match a.get_info().device_type {
                wgpu::DeviceType::DiscreteGpu => 0,
                wgpu::DeviceType::IntegratedGpu => 1,
                wgpu::DeviceType::VirtualGpu | wgpu::DeviceType::Other => 2,
                wgpu::DeviceType::Cpu => 3,
            });
            (!adapters.is_empty()).then_some(0)
        }
    };
    match position {
        Some(i) => Ok(adapters.swap_remove(i)),
        None => Err(GpuMetricsError::NoAdapter {
            wanted: wanted.map(str::to_string),
            available: if available.is_empty() {
                "none (on a machine without a GPU, run ci/setup.sh to install lavapipe)".into()
            } else {
                available
            },
        }),
    }
}

/// Opens `adapter` with its own limits (large frames need more than the defaults) and timestamp
/// queries where offered.
pub fn open(adapter: wgpu::Adapter) -> Result<MetricsDevice, GpuMetricsError> {
    let features = adapter.features() & wgpu::Features::TIMESTAMP_QUERY;
    let desc = wgpu::DeviceDescriptor {
        label: Some("tessera metrics"),
        required_features: features,
        required_limits: adapter.limits(),
        experimental_features: wgpu::ExperimentalFeatures::disabled(),
        memory_hints: wgpu::MemoryHints::Performance,
        trace: wgpu::Trace::Off,
    };
    let (device, queue) = pollster::block_on(adapter.request_device(&desc)).map_err(|source| {
        GpuMetricsError::RequestDevice {
            adapter: adapter.get_info().name,
            source,
        }
    })?;
    Ok(MetricsDevice {
        adapter,
        device,
        queue,
    })
}
