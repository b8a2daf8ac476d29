//! Which adapter a record names, in words both sides use: the one text match of `tessera run
//! --adapter` and of an expectation's `adapter` key ([`matches`]), the vendor's name of a PCI
//! vendor id ([`vendor_name`]) and the adapter class approved frames are kept per ([`class`]).
//!
//! Not for: opening adapters (the harness's `gpu/`), storing them (the dashboard's store).

use crate::AdapterInfo;

/// PCI vendor ids Tessera names (Vulkan's `VK_VENDOR_ID_MESA` for Mesa's software drivers).
pub const VENDORS: [(u32, &str); 6] = [
    (0x10de, "nvidia"),
    (0x1002, "amd"),
    (0x8086, "intel"),
    (0x106b, "apple"),
    (0x13b5, "arm"),
    (0x10005, "mesa"),
];

/// The vendor's name of a PCI vendor id (`nvidia`, `amd`, `intel`, ...); `None` for others.
pub fn vendor_name(vendor: u32) -> Option<&'static str> {
    VENDORS
        .iter()
        .find(|(id, _)| *id == vendor)
        .map(|(_, n)| *n)
}

/// Whether `wanted` names this adapter: its name, driver, driver info or backend contains it, or
/// it is the vendor's name or PCI id (`nvidia`, `0x10de`), all without regard to case. The one
/// rule of `tessera run --adapter` and of an expectation's `adapter` key.
pub fn matches(
    wanted: &str,
    name: &str,
    vendor: u32,
    driver: &str,
    driver_info: &str,
    backend: &str,
) -> bool {
    let needle = wanted.to_lowercase();
    let vendor_hex = format!("0x{vendor:04x}");
    [name, driver, driver_info, backend]
        .iter()
        .any(|s| s.to_lowercase().contains(&needle))
        || vendor_name(vendor) == Some(needle.as_str())
        || vendor_hex == needle
}

/// [`matches`] on a recorded adapter.
pub fn matches_info(wanted: &str, a: &AdapterInfo) -> bool {
    matches(
        wanted,
        &a.name,
        a.vendor,
        &a.driver,
        &a.driver_info,
        &a.backend,
    )
}

/// The adapter class of an adapter (DESIGN.md: the labels that say which adapters may stand in
/// for each other): `llvmpipe` for Mesa's CPU drivers (lavapipe, llvmpipe), else the vendor's
/// name (`nvidia`, `amd`, `intel`, ...), else `vendor-0xNNNN`.
pub fn class(a: &AdapterInfo) -> String {
    let name = a.name.to_lowercase();
    let driver = a.driver.to_lowercase();
    if ["llvmpipe", "lavapipe"]
        .iter()
        .any(|n| name.contains(n) || driver.contains(n))
    {
        return "llvmpipe".to_string();
    }
    match vendor_name(a.vendor) {
        Some(v) => v.to_string(),
        None => format!("vendor-0x{:04x}", a.vendor),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn adapter(name: &str, vendor: u32, driver: &str) -> AdapterInfo {
        AdapterInfo {
            name: name.into(),
            vendor,
            device: 0,
            device_type: "discrete-gpu".into(),
            driver: driver.into(),
            driver_info: String::new(),
            backend: "vulkan".into(),
            features: Default::default(),
        }
    }

    #[test]
    fn classes_by_vendor_and_software_driver() {
        let lavapipe = adapter("llvmpipe (LLVM 15.0.6, 256 bits)", 0x10005, "llvmpipe");
        assert_eq!(class(&lavapipe), "llvmpipe");
        assert_eq!(class(&adapter("NVIDIA H200", 0x10de, "NVIDIA")), "nvidia");
        assert_eq!(class(&adapter("Radeon", 0x1002, "radv")), "amd");
        assert_eq!(class(&adapter("Odd", 0x1234, "x")), "vendor-0x1234");
    }

    #[test]
    fn matching_reads_name_driver_backend_and_vendor() {
        let h200 = adapter("NVIDIA H200", 0x10de, "NVIDIA");
        assert!(matches_info("h200", &h200));
        assert!(matches_info("Vulkan", &h200));
        assert!(matches_info("0x10DE", &h200));
        assert!(matches_info("nvidia", &h200));
        assert!(!matches_info("amd", &h200));
        assert!(!matches_info("llvmpipe", &h200));
    }
}
