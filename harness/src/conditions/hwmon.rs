//! AMD and Intel sensors from Linux sysfs: the DRM card whose PCI ids match the adapter, and the
//! hwmon folder of its device (`/sys/class/drm/card*/device/hwmon/hwmon*`).
//!
//! Read where readable, in the kernel's units: `freq1_input` / `freq2_input` (Hz; amdgpu's
//! graphics and memory clocks), `temp1_input` (millidegrees Celsius), `power1_average` or
//! `power1_input` (microwatts), `energy1_input` (microjoules; i915 and xe), and i915's
//! `gt_act_freq_mhz`; maximum clocks from amdgpu's `pp_dpm_sclk` / `pp_dpm_mclk` (their last
//! level) or i915's `gt_RP0_freq_mhz`. The kernel reports no throttle reasons here, so hwmon
//! results are flagged on their clock alone. Nothing is written.

use std::path::{Path, PathBuf};

use super::{ConditionSource, DeviceLimits, Sample};

pub const DRM_ROOT: &str = "/sys/class/drm";

/// A sensor file and the factor that turns its integer into our unit.
#[derive(Clone, Debug)]
struct Sensor {
    path: PathBuf,
    scale: f64,
}

impl Sensor {
    fn read(&self) -> Option<f64> {
        read_number(&self.path).map(|v| v * self.scale)
    }
}

pub struct HwmonSource {
    graphics_clock: Option<Sensor>,
    memory_clock: Option<Sensor>,
    temperature: Option<Sensor>,
    power: Option<Sensor>,
    energy: Option<Sensor>,
    limits: DeviceLimits,
}

fn read_number(path: &Path) -> Option<f64> {
    let text = std::fs::read_to_string(path).ok()?;
    text.trim().parse::<f64>().ok()
}

fn read_hex(path: &Path) -> Option<u32> {
    let text = std::fs::read_to_string(path).ok()?;
    u32::from_str_radix(text.trim().trim_start_matches("0x"), 16).ok()
}

/// The highest level of an amdgpu `pp_dpm_*` table (`"1: 800Mhz *"` lines), in MHz.
fn max_dpm_level(path: &Path) -> Option<f64> {
    let text = std::fs::read_to_string(path).ok()?;
    text.lines()
        .filter_map(|l| {
            let (_, rest) = l.split_once(':')?;
            let mhz = rest.split_whitespace().next()?;
            mhz.to_ascii_lowercase()
                .trim_end_matches("mhz")
                .parse::<f64>()
                .ok()
        })
        .reduce(f64::max)
}

/// The first of `names` in `dir` that reads as a number, scaled by `scale`.
fn sensor(dir: &Path, names: &[&str], scale: f64) -> Option<Sensor> {
    names.iter().find_map(|n| {
        let path = dir.join(n);
        read_number(&path).map(|_| Sensor { path, scale })
    })
}

impl HwmonSource {
    /// Finds the card under `drm_root` with PCI ids `vendor:device` and its readable sensors.
    pub fn open(drm_root: &Path, vendor: u32, device: u32) -> Result<HwmonSource, String> {
        let entries = std::fs::read_dir(drm_root)
            .map_err(|e| format!("cannot read {}: {e}", drm_root.display()))?;
        let mut cards: Vec<PathBuf> = entries
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| {
                p.file_name()
                    .and_then(|n| n.to_str())
                    .and_then(|n| n.strip_prefix("card"))
                    .is_some_and(|n| !n.is_empty() && n.bytes().all(|b| b.is_ascii_digit()))
            })
            .collect();
        cards.sort();
        let card = cards
            .into_iter()
            .find(|c| {
                read_hex(&c.join("device/vendor")) == Some(vendor)
                    && read_hex(&c.join("device/device")) == Some(device)
            })
            .ok_or_else(|| {
                format!(
                    "no DRM card under {} has PCI ids {vendor:#06x}:{device:#06x}",
                    drm_root.display()
                )
            })?;
        let card_name = card
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        let hwmon = std::fs::read_dir(card.join("device/hwmon"))
            .ok()
            .and_then(|mut d| d.find_map(|e| e.ok().map(|e| e.path())));
        let in_hwmon =
            |names: &[&str], scale| hwmon.as_deref().and_then(|h| sensor(h, names, scale));
        let energy = in_hwmon(&["energy1_input"], 1e-3); // microjoules to millijoules
        let source = HwmonSource {
            graphics_clock: in_hwmon(&["freq1_input"], 1e-6)
                .or_else(|| sensor(&card, &["gt_act_freq_mhz"], 1.0)),
            memory_clock: in_hwmon(&["freq2_input"], 1e-6),
            temperature: in_hwmon(&["temp1_input"], 1e-3),
            power: in_hwmon(&["power1_average", "power1_input"], 1e-6),
            limits: DeviceLimits {
                source: "hwmon",
                device: card_name.clone(),
                max_graphics_clock_mhz: max_dpm_level(&card.join("device/pp_dpm_sclk"))
                    .or_else(|| read_number(&card.join("gt_RP0_freq_mhz"))),
                max_memory_clock_mhz: max_dpm_level(&card.join("device/pp_dpm_mclk")),
                energy_counter: energy.is_some(),
            },
            energy,
        };
        if source.graphics_clock.is_none()
            && source.temperature.is_none()
            && source.power.is_none()
            && source.energy.is_none()
        {
            return Err(format!(
                "{card_name} ({vendor:#06x}:{device:#06x}) has no readable clock, temperature, power or energy file"
            ));
        }
        Ok(source)
    }
}

impl ConditionSource for HwmonSource {
    fn limits(&self) -> DeviceLimits {
        self.limits.clone()
    }

    fn sample(&mut self) -> Sample {
        let read = |s: &Option<Sensor>| s.as_ref().and_then(Sensor::read);
        Sample {
            at_s: 0.0,
            graphics_clock_mhz: read(&self.graphics_clock),
            memory_clock_mhz: read(&self.memory_clock),
            temperature_c: read(&self.temperature),
            power_w: read(&self.power),
            energy_mj: read(&self.energy),
            throttle_reasons: Vec::new(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn write(root: &Path, rel: &str, text: &str) {
        let p = root.join(rel);
        std::fs::create_dir_all(p.parent().unwrap()).unwrap();
        std::fs::write(p, text).unwrap();
    }

    #[test]
    fn amdgpu_card_is_found_and_read_in_our_units() {
        let dir = tempfile::tempdir().unwrap();
        let root = dir.path();
        // An Intel card first, and a connector folder that is not a card.
        write(root, "card0/device/vendor", "0x8086\n");
        write(root, "card0/device/device", "0x56a0\n");
        write(root, "card1-DP-1/status", "connected\n");
        write(root, "card1/device/vendor", "0x1002\n");
        write(root, "card1/device/device", "0x73bf\n");
        write(
            root,
            "card1/device/pp_dpm_sclk",
            "0: 500Mhz\n1: 1800Mhz *\n2: 2615Mhz\n",
        );
        write(root, "card1/device/pp_dpm_mclk", "0: 96Mhz\n1: 1000Mhz *\n");
        let h = "card1/device/hwmon/hwmon3";
        write(root, &format!("{h}/freq1_input"), "1800000000\n");
        write(root, &format!("{h}/freq2_input"), "1000000000\n");
        write(root, &format!("{h}/temp1_input"), "65000\n");
        write(root, &format!("{h}/power1_average"), "215000000\n");

        let mut s = HwmonSource::open(root, 0x1002, 0x73bf).unwrap();
        let limits = s.limits();
        assert_eq!(limits.device, "card1");
        assert_eq!(limits.max_graphics_clock_mhz, Some(2615.0));
        assert_eq!(limits.max_memory_clock_mhz, Some(1000.0));
        assert!(!limits.energy_counter);
        let sample = s.sample();
        assert_eq!(sample.graphics_clock_mhz, Some(1800.0));
        assert_eq!(sample.memory_clock_mhz, Some(1000.0));
        assert_eq!(sample.temperature_c, Some(65.0));
        assert_eq!(sample.power_w, Some(215.0));
        assert_eq!(sample.energy_mj, None);
        assert!(sample.throttle_reasons.is_empty());
    }

    #[test]
    fn intel_energy_counter_and_gt_clock() {
        let dir = tempfile::tempdir().unwrap();
        let root = dir.path();
        write(root, "card0/device/vendor", "0x8086\n");
        write(root, "card0/device/device", "0x56a0\n");
        write(root, "card0/gt_act_freq_mhz", "2050\n");
        write(root, "card0/gt_RP0_freq_mhz", "2400\n");
        write(
            root,
            "card0/device/hwmon/hwmon1/energy1_input",
            "123456789\n",
        );
        let mut s = HwmonSource::open(root, 0x8086, 0x56a0).unwrap();
        assert!(s.limits().energy_counter);
        assert_eq!(s.limits().max_graphics_clock_mhz, Some(2400.0));
        let sample = s.sample();
        assert_eq!(sample.graphics_clock_mhz, Some(2050.0));
        assert_eq!(sample.energy_mj, Some(123456.789));
    }

    #[test]
    fn unmatched_or_unreadable_cards_say_why() {
        let dir = tempfile::tempdir().unwrap();
        let root = dir.path();
        write(root, "card0/device/vendor", "0x1002\n");
        write(root, "card0/device/device", "0x73bf\n");
        let none = HwmonSource::open(root, 0x1002, 0x1234).err().unwrap();
        assert!(none.contains("no DRM card under"), "{none}");
        assert!(none.ends_with("has PCI ids 0x1002:0x1234"), "{none}");
        let empty = HwmonSource::open(root, 0x1002, 0x73bf).err().unwrap();
        assert_eq!(
            empty,
            "card0 (0x1002:0x73bf) has no readable clock, temperature, power or energy file"
        );
    }
}
