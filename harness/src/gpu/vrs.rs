//! Hardware variable-rate shading (VK_KHR_fragment_shading_rate) at the device level: whether an
//! adapter offers it ([`probe`]) and a device opened with it turned on ([`open`]). wgpu 30 has no
//! VRS API; this module reaches wgpu-hal's Vulkan objects (`as_hal`).
//!
//! Not here: the raw Vulkan pass drawn with a fragment-shading-rate attachment (a technique's, in
//! `techniques/adaptive_shading/raw_pass.rs`), which rates (the rate pass and the CPU model,
//! `techniques/adaptive_shading/`), timing (wgpu-profiler timestamps around the encoder).

use std::ffi::CStr;

use ash::vk;
use wgpu::hal::api::Vulkan;

/// Why a hardware-VRS variant is skipped on an adapter that cannot run it.
pub const NEEDS: &str = "needs VK_KHR_fragment_shading_rate with attachmentFragmentShadingRate";

const EXTENSION: &CStr = ash::khr::fragment_shading_rate::NAME;

/// What the adapter offers of VK_KHR_fragment_shading_rate.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct VrsCaps {
    /// Smallest and largest attachment texel size (width, height) in pixels; powers of two.
    pub texel_min: [u32; 2],
    pub texel_max: [u32; 2],
    /// Fragment sizes (width, height) offered at one sample per pixel.
    pub fragment_sizes: Vec<[u32; 2]>,
}

/// Whether `adapter` can run attachment-driven VRS: the caps, or the reason it cannot.
pub fn probe(adapter: &wgpu::Adapter) -> Result<VrsCaps, String> {
    // SAFETY: the guard only reads the adapter's immutable hal object; we neither destroy nor
    // keep anything it returns beyond this function.
    let hal = unsafe { adapter.as_hal::<Vulkan>() }
        .ok_or_else(|| format!("{NEEDS} (not a Vulkan adapter)"))?;
    let caps = hal.physical_device_capabilities();
    if !caps.supports_extension(EXTENSION) {
        return Err(format!("{NEEDS} (the driver does not offer the extension)"));
    }
    if caps.properties().api_version < vk::API_VERSION_1_2
        || hal.shared_instance().instance_api_version() < vk::API_VERSION_1_2
    {
        return Err(format!("{NEEDS} (and Vulkan 1.2)"));
    }
    let instance = hal.shared_instance().raw_instance();
    let physical = hal.raw_physical_device();
    let mut features = vk::PhysicalDeviceFragmentShadingRateFeaturesKHR::default();
    let mut props = vk::PhysicalDeviceFragmentShadingRatePropertiesKHR::default();
    // SAFETY: `physical` belongs to `instance` (both from the same hal adapter), the instance is
    // Vulkan 1.2 (checked above), and each output chain holds one extension struct that lives
    // across the call.
    unsafe {
        let mut f2 = vk::PhysicalDeviceFeatures2::default().push_next(&mut features);
        instance.get_physical_device_features2(physical, &mut f2);
        let mut p2 = vk::PhysicalDeviceProperties2::default().push_next(&mut props);
        instance.get_physical_device_properties2(physical, &mut p2);
    }
    if features.attachment_fragment_shading_rate != vk::TRUE {
        return Err(format!(
            "{NEEDS} (the extension is there, the attachment feature is not)"
        ));
    }
    let ext =
        ash::khr::fragment_shading_rate::Instance::new(hal.shared_instance().entry(), instance);
    let get = ext.fp().get_physical_device_fragment_shading_rates_khr;
    let mut n = 0u32;
    // SAFETY: the two-call idiom of vkGetPhysicalDeviceFragmentShadingRatesKHR: a count, then an
    // array of that many default-initialised structs (sType set by `default`).
    let rates = unsafe {
        get(physical, &mut n, std::ptr::null_mut())
            .result()
            .map_err(|e| format!("{NEEDS} (listing fragment sizes failed: {e})"))?;
        let mut rates = vec![vk::PhysicalDeviceFragmentShadingRateKHR::default(); n as usize];
        get(physical, &mut n, rates.as_mut_ptr())
            .result()
            .map_err(|e| format!("{NEEDS} (listing fragment sizes failed: {e})"))?;
        rates.truncate(n as usize);
        rates
    };
    let mut fragment_sizes: Vec<[u32; 2]> = rates
        .iter()
        .filter(|r| r.sample_counts.contains(vk::SampleCountFlags::TYPE_1))
        .map(|r| [r.fragment_size.width, r.fragment_size.height])
        .collect();
    fragment_sizes.sort_unstable();
    let e = |x: vk::Extent2D| [x.width, x.height];
    Ok(VrsCaps {
        texel_min: e(props.min_fragment_shading_rate_attachment_texel_size),
        texel_max: e(props.max_fragment_shading_rate_attachment_texel_size),
        fragment_sizes,
    })
}

/// Opens a device on `adapter` as `request_device` would, with VK_KHR_fragment_shading_rate and
/// its pipeline and attachment features turned on (the caller checked [`probe`]).
pub fn open(
    adapter: &wgpu::Adapter,
    desc: &wgpu::DeviceDescriptor<'_>,
) -> Result<(wgpu::Device, wgpu::Queue), String> {
    let mut features = vk::PhysicalDeviceFragmentShadingRateFeaturesKHR::default()
        .pipeline_fragment_shading_rate(true)
        .attachment_fragment_shading_rate(true);
    let features_ptr: *mut vk::PhysicalDeviceFragmentShadingRateFeaturesKHR<'static> =
        &mut features;
    let callback: Box<wgpu::hal::vulkan::CreateDeviceCallback<'_>> = Box::new(move |args| {
        args.extensions.push(EXTENSION);
        // SAFETY: `features` lives on this function's stack until after vkCreateDevice returns;
        // it is spliced in front of whatever chain the create-info holds, which wgpu-hal extends
        // afterwards without dropping it.
        unsafe {
            (*features_ptr).p_next = args.create_info.p_next as *mut std::ffi::c_void;
        }
        args.create_info.p_next = features_ptr as *const std::ffi::c_void;
    });
    let open = {
        // SAFETY: the hal adapter is only used to open a device on itself; the callback adds one
        // extension the probe found supported and turns two of its features on (nothing removed),
        // and the feature struct outlives device creation (it lives in this function).
        let hal = unsafe { adapter.as_hal::<Vulkan>() }.ok_or("not a Vulkan adapter")?;
        unsafe {
            hal.open_with_callback(
                desc.required_features,
                &desc.required_limits,
                &desc.memory_hints,
                Some(callback),
            )
        }
        .map_err(|e| format!("creating a Vulkan device with {EXTENSION:?} failed: {e}"))?
    };
    // SAFETY: `open` was created from this adapter's hal object just above with exactly
    // `desc.required_features`.
    unsafe { adapter.create_device_from_hal(open, desc) }.map_err(|e| e.to_string())
}
