//! NVIDIA sensors through NVML (the `nvml-wrapper` crate).
//!
//! `nvml-wrapper` loads `libnvidia-ml.so` with `libloading` when [`NvmlSource::open`] runs, not
//! at link time: the binary starts and runs on machines without NVIDIA's driver (lavapipe in CI),
//! where opening fails with a reason instead. It is the maintained Rust binding of the whole NVML
//! API (clocks, temperature, power, the total-energy counter, clocks-event reasons), so no FFI of
//! our own. Read-only calls only: no clock locking, no power limits.

use nvml_wrapper::bitmasks::device::ThrottleReasons;
use nvml_wrapper::enum_wrappers::device::{Clock, TemperatureSensor};
use nvml_wrapper::Nvml;

use super::{ConditionSource, DeviceLimits, Sample, ThrottleReason};

/// The names the driver installs the library under, tried in order (the unversioned name is only
/// present with development packages).
#[cfg(not(windows))]
const LIBRARIES: [&str; 2] = ["libnvidia-ml.so.1", "libnvidia-ml.so"];
#[cfg(windows)]
const LIBRARIES: [&str; 1] = ["nvml.dll"];

pub struct NvmlSource {
    nvml: Nvml,
    index: u32,
    limits: DeviceLimits,
}

impl NvmlSource {
    /// Loads NVML and finds the device whose PCI device id is `pci_device` (the first, where a
    /// host has several of one model: wgpu does not give the bus address to tell them apart).
    pub fn open(pci_device: u32) -> Result<NvmlSource, String> {
        let mut last = String::new();
        let mut nvml = None;
        for lib in LIBRARIES {
            match Nvml::builder().lib_path(lib.as_ref()).init() {
                Ok(n) => {
                    nvml = Some(n);
                    break;
                }
                Err(e) => last = format!("{lib}: {e}"),
            }
        }
        let nvml = nvml.ok_or_else(|| format!("NVML could not be loaded ({last})"))?;
        let count = nvml
            .device_count()
            .map_err(|e| format!("NVML lists no devices: {e}"))?;
        let index = (0..count)
            .find(|&i| {
                nvml.device_by_index(i)
                    .and_then(|d| d.pci_info())
                    .is_ok_and(|p| p.pci_device_id >> 16 == pci_device)
            })
            .ok_or_else(|| {
                format!("none of NVML's {count} devices has PCI device id {pci_device:#06x}")
            })?;
        let limits = {
            let device = nvml
                .device_by_index(index)
                .map_err(|e| format!("NVML device {index}: {e}"))?;
            let mhz = |c| device.max_clock_info(c).ok().map(f64::from);
            DeviceLimits {
                source: "nvml",
                device: device
                    .name()
                    .unwrap_or_else(|_| format!("NVML device {index}")),
                max_graphics_clock_mhz: mhz(Clock::Graphics),
                max_memory_clock_mhz: mhz(Clock::Memory),
                energy_counter: device.total_energy_consumption().is_ok(),
            }
        };
        Ok(NvmlSource {
            nvml,
            index,
            limits,
        })
    }
}

impl ConditionSource for NvmlSource {
    fn limits(&self) -> DeviceLimits {
        self.limits.clone()
    }

    fn sample(&mut self) -> Sample {
        let Ok(d) = self.nvml.device_by_index(self.index) else {
            return Sample::default();
        };
        Sample {
            at_s: 0.0,
            graphics_clock_mhz: d.clock_info(Clock::Graphics).ok().map(f64::from),
            memory_clock_mhz: d.clock_info(Clock::Memory).ok().map(f64::from),
            temperature_c: d.temperature(TemperatureSensor::Gpu).ok().map(f64::from),
            power_w: d.power_usage().ok().map(|mw| f64::from(mw) / 1000.0),
            energy_mj: d.total_energy_consumption().ok().map(|mj| mj as f64),
            throttle_reasons: d
                .current_throttle_reasons()
                .map(reasons)
                .unwrap_or_default(),
        }
    }
}

/// NVML's bit mask as our list.
fn reasons(bits: ThrottleReasons) -> Vec<ThrottleReason> {
    let table = [
        (ThrottleReasons::GPU_IDLE, ThrottleReason::GpuIdle),
        (
            ThrottleReasons::APPLICATIONS_CLOCKS_SETTING,
            ThrottleReason::ApplicationsClocksSetting,
        ),
        (ThrottleReasons::SW_POWER_CAP, ThrottleReason::SwPowerCap),
        (ThrottleReasons::HW_SLOWDOWN, ThrottleReason::HwSlowdown),
        (ThrottleReasons::SYNC_BOOST, ThrottleReason::SyncBoost),
        (
            ThrottleReasons::SW_THERMAL_SLOWDOWN,
            ThrottleReason::SwThermalSlowdown,
        ),
        (
            ThrottleReasons::HW_THERMAL_SLOWDOWN,
            ThrottleReason::HwThermalSlowdown,
        ),
        (
            ThrottleReasons::HW_POWER_BRAKE_SLOWDOWN,
            ThrottleReason::HwPowerBrakeSlowdown,
        ),
        (
            ThrottleReasons::DISPLAY_CLOCK_SETTING,
            ThrottleReason::DisplayClockSetting,
        ),
    ];
    table
        .into_iter()
        .filter(|(bit, _)| bits.contains(*bit))
        .map(|(_, r)| r)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bit_mask_to_reasons() {
        let bits = ThrottleReasons::SW_POWER_CAP | ThrottleReasons::HW_THERMAL_SLOWDOWN;
        assert_eq!(
            reasons(bits),
            vec![
                ThrottleReason::SwPowerCap,
                ThrottleReason::HwThermalSlowdown
            ]
        );
        assert!(reasons(ThrottleReasons::NONE).is_empty());
    }
}
