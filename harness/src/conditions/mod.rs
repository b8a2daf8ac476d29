//! The conditions of a timing: the adapter's clocks, temperature, power, energy counter and
//! throttle reasons, sampled on a thread of their own while a variant's measured frames run, and
//! summarised per result.
//!
//! Sources: NVML on NVIDIA (`nvml.rs`, `libnvidia-ml.so` loaded at run time, so the binary runs
//! where it is absent), sysfs hwmon on AMD and Intel under Linux (`hwmon.rs`), and otherwise an
//! explicit "not available" with the reason ([`open`]). This module never changes a device's
//! settings and adds nothing to the GPU's work: sensors are read on the sampling thread
//! ([`sampler`]); the figures are pure functions of the samples ([`summary`]).

pub mod hwmon;
pub mod nvml;
pub mod sampler;
pub mod summary;

use tessera_results::conditions::{Conditions, DeviceConditions};
use tessera_results::AdapterInfo;

use sampler::Sampler;

/// PCI vendor ids.
pub const VENDOR_NVIDIA: u32 = 0x10de;
pub const VENDOR_AMD: u32 = 0x1002;
pub const VENDOR_INTEL: u32 = 0x8086;

/// Period of the sampling thread. Every read of a sensor is a driver call on the CPU; 10 ms keeps
/// the thread's load small next to the frames, gives several samples per measured window (plus
/// one at each end, whatever its length), and locates the energy counter's steps to 1% over
/// the energy window.
pub const SAMPLE_INTERVAL_MS: f64 = 10.0;

/// The energy window: before the measured frames, as the end of the clock warm-up (once the clock
/// is at its top), the sequence runs with the sensors sampled, since an energy counter that steps
/// every 100 ms (an H200's, measured) cannot measure a window of a few frames. It lasts until the
/// counter has stepped [`ENERGY_STEPS`] times or for this long at most (a source without a counter, or one that does not step, runs it all and is read
/// as power times time). Sampled every [`ENERGY_SAMPLE_INTERVAL_MS`], the steps are placed to a
/// millisecond: three steps span two of the H200's intervals, 200 ms placed to 1%, reached 200 to
/// 300 ms after the window opens. Run to run on the H200 the energy per frame of 1 s windows
/// differed by 3.5% (median over 15 variants), more than that placement. Only where sensors are
/// available.
pub const ENERGY_WINDOW_MS: f64 = 500.0;

/// Counter steps that end the energy window early (see [`ENERGY_WINDOW_MS`]).
pub const ENERGY_STEPS: u32 = 3;

/// Sampling period of the energy window (the measured frames' is [`SAMPLE_INTERVAL_MS`]).
pub const ENERGY_SAMPLE_INTERVAL_MS: f64 = 1.0;

/// Why a device's clocks are limited, as NVML's clocks-event reasons name them.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum ThrottleReason {
    GpuIdle,
    ApplicationsClocksSetting,
    SwPowerCap,
    HwSlowdown,
    SyncBoost,
    SwThermalSlowdown,
    HwThermalSlowdown,
    HwPowerBrakeSlowdown,
    DisplayClockSetting,
}

impl ThrottleReason {
    /// The kebab-case name written to results.
    pub fn name(self) -> &'static str {
        match self {
            ThrottleReason::GpuIdle => "gpu-idle",
            ThrottleReason::ApplicationsClocksSetting => "applications-clocks-setting",
            ThrottleReason::SwPowerCap => "sw-power-cap",
            ThrottleReason::HwSlowdown => "hw-slowdown",
            ThrottleReason::SyncBoost => "sync-boost",
            ThrottleReason::SwThermalSlowdown => "sw-thermal-slowdown",
            ThrottleReason::HwThermalSlowdown => "hw-thermal-slowdown",
            ThrottleReason::HwPowerBrakeSlowdown => "hw-power-brake-slowdown",
            ThrottleReason::DisplayClockSetting => "display-clock-setting",
        }
    }

    /// A thermal or power limit: what flags a result as throttled whatever its clock.
    pub fn is_thermal_or_power(self) -> bool {
        matches!(
            self,
            ThrottleReason::SwPowerCap
                | ThrottleReason::HwSlowdown
                | ThrottleReason::SwThermalSlowdown
                | ThrottleReason::HwThermalSlowdown
                | ThrottleReason::HwPowerBrakeSlowdown
        )
    }
}

/// One reading of every sensor a source has; `None` where it has no such sensor or the read
/// failed.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Sample {
    /// Seconds since the sampling window began.
    pub at_s: f64,
    pub graphics_clock_mhz: Option<f64>,
    pub memory_clock_mhz: Option<f64>,
    pub temperature_c: Option<f64>,
    pub power_w: Option<f64>,
    /// The device's total-energy counter, in millijoules (any origin).
    pub energy_mj: Option<f64>,
    pub throttle_reasons: Vec<ThrottleReason>,
}

/// What a source knows of its device once, at the start of a run.
#[derive(Clone, Debug, PartialEq)]
pub struct DeviceLimits {
    pub source: &'static str,
    pub device: String,
    pub max_graphics_clock_mhz: Option<f64>,
    pub max_memory_clock_mhz: Option<f64>,
    pub energy_counter: bool,
}

impl DeviceLimits {
    /// The `run.json` record.
    pub fn record(&self) -> DeviceConditions {
        DeviceConditions::Available(tessera_results::conditions::DeviceSensors {
            source: self.source.to_string(),
            device: self.device.clone(),
            max_graphics_clock_mhz: self.max_graphics_clock_mhz,
            max_memory_clock_mhz: self.max_memory_clock_mhz,
            energy_counter: self.energy_counter,
            sample_interval_ms: SAMPLE_INTERVAL_MS,
            throttle_clock_fraction: tessera_results::conditions::THROTTLE_CLOCK_FRACTION,
        })
    }
}

/// A device's sensors. Implementations read, never write: the harness changes no GPU setting.
pub trait ConditionSource: Send {
    fn limits(&self) -> DeviceLimits;
    /// Reads every sensor now; `at_s` is left for the caller to set.
    fn sample(&mut self) -> Sample;
}

/// A run's sensors: a sampling thread over the adapter's source, or why there is none.
pub enum Sensors {
    Sampling(Sampler),
    NotAvailable(String),
}

impl Sensors {
    /// The adapter's source on its sampling thread, or the reason there is none.
    pub fn open(adapter: &AdapterInfo) -> Sensors {
        Sensors::from_source(open(adapter))
    }

    pub fn from_source(source: Result<Box<dyn ConditionSource>, String>) -> Sensors {
        match source {
            Ok(s) => Sensors::Sampling(Sampler::spawn(s)),
            Err(reason) => Sensors::NotAvailable(reason),
        }
    }

    pub fn sampler(&self) -> Option<&Sampler> {
        match self {
            Sensors::Sampling(s) => Some(s),
            Sensors::NotAvailable(_) => None,
        }
    }

    /// `run.json`'s `conditions`.
    pub fn device_record(&self) -> DeviceConditions {
        match self {
            Sensors::Sampling(s) => s.limits().record(),
            Sensors::NotAvailable(reason) => DeviceConditions::NotAvailable {
                reason: reason.clone(),
            },
        }
    }

    /// A result's `conditions` from the samples of its measured frames and of its energy window
    /// (samples and frames).
    pub fn result_record(
        &self,
        samples: Option<&[Sample]>,
        energy_window: Option<(&[Sample], u32)>,
    ) -> Conditions {
        match (self, samples) {
            (Sensors::Sampling(s), Some(samples)) if !samples.is_empty() => Conditions::Recorded(
                Box::new(summary::summarise(samples, s.limits(), energy_window)),
            ),
            (Sensors::Sampling(_), _) => Conditions::NotAvailable {
                reason: "the sampling thread returned no samples".into(),
            },
            (Sensors::NotAvailable(reason), _) => Conditions::NotAvailable {
                reason: reason.clone(),
            },
        }
    }
}

/// The sensor source of `adapter`, or why there is none.
pub fn open(adapter: &AdapterInfo) -> Result<Box<dyn ConditionSource>, String> {
    if adapter.device_type == "cpu" {
        return Err(format!(
            "{} is a CPU adapter: it has no GPU clocks, temperature or power sensors",
            adapter.name
        ));
    }
    if adapter.vendor == 0 || adapter.device == 0 {
        return Err(format!(
            "the {} backend gives no PCI vendor and device ids to match a sensor device with",
            adapter.backend
        ));
    }
    match adapter.vendor {
        VENDOR_NVIDIA => nvml::NvmlSource::open(adapter.device)
            .map(|s| Box::new(s) as Box<dyn ConditionSource>),
        VENDOR_AMD | VENDOR_INTEL => open_hwmon(adapter),
        other => Err(format!(
            "no sensor source for PCI vendor {other:#06x} (NVML covers NVIDIA, hwmon AMD and Intel on Linux)"
        )),
    }
}

#[cfg(target_os = "linux")]
fn open_hwmon(adapter: &AdapterInfo) -> Result<Box<dyn ConditionSource>, String> {
    hwmon::HwmonSource::open(
        std::path::Path::new(hwmon::DRM_ROOT),
        adapter.vendor,
        adapter.device,
    )
    .map(|s| Box::new(s) as Box<dyn ConditionSource>)
}

#[cfg(not(target_os = "linux"))]
fn open_hwmon(_: &AdapterInfo) -> Result<Box<dyn ConditionSource>, String> {
    Err(format!(
        "AMD and Intel sensors are read from Linux sysfs; none on {}",
        std::env::consts::OS
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn adapter(vendor: u32, device: u32, device_type: &str, backend: &str) -> AdapterInfo {
        AdapterInfo {
            name: "test adapter".into(),
            vendor,
            device,
            device_type: device_type.into(),
            driver: String::new(),
            driver_info: String::new(),
            backend: backend.into(),
            features: Default::default(),
        }
    }

    #[test]
    fn not_available_says_why() {
        let cpu = open(&adapter(0x10005, 0, "cpu", "vulkan")).err().unwrap();
        assert_eq!(
            cpu,
            "test adapter is a CPU adapter: it has no GPU clocks, temperature or power sensors"
        );
        let gl = open(&adapter(0, 0, "integrated-gpu", "gl")).err().unwrap();
        assert_eq!(
            gl,
            "the gl backend gives no PCI vendor and device ids to match a sensor device with"
        );
        let apple = open(&adapter(0x106b, 1, "integrated-gpu", "metal"))
            .err()
            .unwrap();
        assert!(
            apple.starts_with("no sensor source for PCI vendor 0x106b"),
            "{apple}"
        );
    }

    #[test]
    fn thermal_and_power_reasons() {
        assert!(ThrottleReason::SwThermalSlowdown.is_thermal_or_power());
        assert!(ThrottleReason::SwPowerCap.is_thermal_or_power());
        assert!(!ThrottleReason::GpuIdle.is_thermal_or_power());
        assert!(!ThrottleReason::ApplicationsClocksSetting.is_thermal_or_power());
        assert_eq!(
            ThrottleReason::HwThermalSlowdown.name(),
            "hw-thermal-slowdown"
        );
    }
}
