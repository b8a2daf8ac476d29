//! The textured materials of the raw Vulkan passes (`raw_pass.rs`): group 1 of
//! `shaders/material/material.wgsl` as a raw descriptor set layout, one descriptor set per
//! material bind group of the scene's [`MaterialGpu`](crate::render::material::MaterialGpu)
//! (its uniform buffer, five texture views, five samplers), and the textured draws, so that
//! `adaptive-shading`'s hardware path and `native-vrs` draw glTF models and the city as `native`
//! does.
//!
//! What the descriptors point at:
//! - buffers and texture views: wgpu's, by their raw handles (`as_hal`), kept alive by clones
//!   held here;
//! - samplers: our own `VkSampler`s (wgpu-hal gives no raw sampler handle), made from the same
//!   [`SamplerDesc::descriptor`] as wgpu's, mapped as wgpu-core and wgpu-hal map it
//!   (`wgpu-core` `Device::create_sampler`: anisotropy only where the adapter has
//!   `ANISOTROPIC_FILTERING`, clamped to 16; `wgpu-hal` `vulkan::Device::create_sampler`: filters,
//!   mipmap mode, address modes, LOD clamp, anisotropy when the clamp is not 1);
//! - image layouts: the sets say SHADER_READ_ONLY_OPTIMAL, the layout wgpu-hal's Vulkan backend
//!   gives `TextureUses::RESOURCE` on colour formats (`conv::derive_image_layout`).
//!   [`RawMaterialSets::transition`] moves every sampled texture into that state with
//!   `CommandEncoder::transition_resources` before each raw pass (their mip levels were last
//!   written as render targets by the mip generator, so they may be in another layout).
//!
//! Not here: pipelines and drawing (`raw_pass.rs`), the shader (`vrs_material.wgsl`).

use ash::vk;
use wgpu::hal::api::Vulkan;

use crate::render::material::{Class, RawMaterialDraw, RawMaterials};

/// Group 1 of `material.wgsl`: binding, descriptor type. Binding 0 the material uniform, 1..=5
/// the textures of `material::SLOTS`, 6..=10 their samplers (checked against the shader by
/// `tests/vrs.rs`, which reflects the naga module).
pub fn bindings() -> Vec<(u32, vk::DescriptorType)> {
    let mut b = vec![(0, vk::DescriptorType::UNIFORM_BUFFER)];
    b.extend((1..=5).map(|i| (i, vk::DescriptorType::SAMPLED_IMAGE)));
    b.extend((6..=10).map(|i| (i, vk::DescriptorType::SAMPLER)));
    b
}

/// Descriptor pool sizes for `sets` material sets: per type, its bindings times `sets`.
pub fn pool_sizes(sets: u32) -> Vec<vk::DescriptorPoolSize> {
    let b = bindings();
    let mut out: Vec<vk::DescriptorPoolSize> = Vec::new();
    for (_, ty) in b {
        match out.iter_mut().find(|p| p.ty == ty) {
            Some(p) => p.descriptor_count += sets,
            None => out.push(vk::DescriptorPoolSize {
                ty,
                descriptor_count: sets,
            }),
        }
    }
    out
}

/// The raw sampler create-info of a wgpu sampler descriptor, as wgpu-core and wgpu-hal make it
/// (`anisotropic`: the adapter has `DownlevelFlags::ANISOTROPIC_FILTERING`).
pub fn sampler_info(
    desc: &wgpu::SamplerDescriptor<'_>,
    anisotropic: bool,
) -> vk::SamplerCreateInfo<'static> {
    let filter = |f: wgpu::FilterMode| match f {
        wgpu::FilterMode::Nearest => vk::Filter::NEAREST,
        wgpu::FilterMode::Linear => vk::Filter::LINEAR,
    };
    let address = |a: wgpu::AddressMode| match a {
        wgpu::AddressMode::ClampToEdge => vk::SamplerAddressMode::CLAMP_TO_EDGE,
        wgpu::AddressMode::Repeat => vk::SamplerAddressMode::REPEAT,
        wgpu::AddressMode::MirrorRepeat => vk::SamplerAddressMode::MIRRORED_REPEAT,
        wgpu::AddressMode::ClampToBorder => vk::SamplerAddressMode::CLAMP_TO_BORDER,
    };
    let mut info = vk::SamplerCreateInfo::default()
        .mag_filter(filter(desc.mag_filter))
        .min_filter(filter(desc.min_filter))
        .mipmap_mode(match desc.mipmap_filter {
            wgpu::MipmapFilterMode::Nearest => vk::SamplerMipmapMode::NEAREST,
            wgpu::MipmapFilterMode::Linear => vk::SamplerMipmapMode::LINEAR,
        })
        .address_mode_u(address(desc.address_mode_u))
        .address_mode_v(address(desc.address_mode_v))
        .address_mode_w(address(desc.address_mode_w))
        .min_lod(desc.lod_min_clamp)
        .max_lod(desc.lod_max_clamp);
    let clamp = if anisotropic {
        desc.anisotropy_clamp.min(16)
    } else {
        1
    };
    if clamp != 1 {
        info = info.anisotropy_enable(true).max_anisotropy(clamp as f32);
    }
    info
}

/// The raw descriptor sets of the scene's materials and its textured draws.
pub struct RawMaterialSets {
    device: ash::Device,
    /// Group 1's layout (set 1 of the material pipelines).
    pub layout: vk::DescriptorSetLayout,
    pool: vk::DescriptorPool,
    /// One per material bind group, in [`RawMaterials::materials`]' order.
    pub sets: Vec<vk::DescriptorSet>,
    samplers: Vec<vk::Sampler>,
    pub vertex: vk::Buffer,
    pub index: vk::Buffer,
    pub vertex_stride: u32,
    pub draws: Vec<RawMaterialDraw>,
    /// Every texture the sets sample (moved into the shader-read state before each pass).
    textures: Vec<wgpu::Texture>,
    /// wgpu objects the raw handles point into, kept alive as long as the sets.
    _keep_buffers: Vec<wgpu::Buffer>,
    _keep_views: Vec<wgpu::TextureView>,
}

fn vk_err(what: &'static str) -> impl Fn(vk::Result) -> String {
    move |e| format!("{what}: {e}")
}

impl RawMaterialSets {
    /// The sets of `materials` on `device` (the raw device of the wgpu device that made them);
    /// `anisotropic` as [`sampler_info`] takes it. `None` when there is no material.
    pub fn new(
        device: &ash::Device,
        materials: &RawMaterials<'_>,
        anisotropic: bool,
    ) -> Result<Option<RawMaterialSets>, String> {
        if materials.materials.is_empty() {
            return Ok(None);
        }
        // The buffers are kept clones.
        let buffer_of = raw_buffer;
        let view_of = |v: &wgpu::TextureView| -> Result<vk::ImageView, String> {
            // SAFETY: the handle is only used while `v` (a kept clone) is alive.
            unsafe { v.as_hal::<Vulkan>().map(|h| h.raw_handle()) }
                .ok_or_else(|| "texture view is not a Vulkan view".to_string())
        };
        let mut out = RawMaterialSets {
            device: device.clone(),
            layout: vk::DescriptorSetLayout::null(),
            pool: vk::DescriptorPool::null(),
            sets: Vec::new(),
            samplers: Vec::new(),
            vertex: buffer_of(materials.vertex)?,
            index: buffer_of(materials.index)?,
            vertex_stride: materials.vertex_stride,
            draws: materials.draws.clone(),
            textures: materials.textures.iter().map(|&t| t.clone()).collect(),
            _keep_buffers: vec![materials.vertex.clone(), materials.index.clone()],
            _keep_views: Vec::new(),
        };
        let d = device;
        let layout_bindings: Vec<vk::DescriptorSetLayoutBinding> = bindings()
            .into_iter()
            .map(|(binding, ty)| {
                vk::DescriptorSetLayoutBinding::default()
                    .binding(binding)
                    .descriptor_type(ty)
                    .descriptor_count(1)
                    .stage_flags(vk::ShaderStageFlags::FRAGMENT)
            })
            .collect();
        let n = materials.materials.len() as u32;
        let sizes = pool_sizes(n);
        // Samplers: one per distinct description.
        let mut sampler_of: Vec<(crate::world::texture::SamplerDesc, vk::Sampler)> = Vec::new();
        // SAFETY: every create-info outlives its call; each object is stored in `out` as soon as
        // it exists, so `Drop` destroys exactly what was made, also when a later step fails.
        unsafe {
            out.layout = d
                .create_descriptor_set_layout(
                    &vk::DescriptorSetLayoutCreateInfo::default().bindings(&layout_bindings),
                    None,
                )
                .map_err(vk_err("material descriptor set layout"))?;
            out.pool = d
                .create_descriptor_pool(
                    &vk::DescriptorPoolCreateInfo::default()
                        .max_sets(n)
                        .pool_sizes(&sizes),
                    None,
                )
                .map_err(vk_err("material descriptor pool"))?;
            let layouts = vec![out.layout; n as usize];
            out.sets = d
                .allocate_descriptor_sets(
                    &vk::DescriptorSetAllocateInfo::default()
                        .descriptor_pool(out.pool)
                        .set_layouts(&layouts),
                )
                .map_err(vk_err("material descriptor sets"))?;
            for m in &materials.materials {
                for desc in m.samplers {
                    if sampler_of.iter().all(|(s, _)| *s != desc) {
                        let info = sampler_info(&desc.descriptor(), anisotropic);
                        let s = d
                            .create_sampler(&info, None)
                            .map_err(vk_err("material sampler"))?;
                        out.samplers.push(s);
                        sampler_of.push((desc, s));
                    }
                }
            }
        }
        for (set, m) in out.sets.clone().into_iter().zip(&materials.materials) {
            if m.views.len() != 5 {
                return Err(format!(
                    "a material binds {} texture views, the shader 5",
                    m.views.len()
                ));
            }
            let buffer = [vk::DescriptorBufferInfo {
                buffer: buffer_of(m.uniform)?,
                offset: 0,
                range: materials.uniform_size,
            }];
            let mut images = Vec::with_capacity(5);
            for v in &m.views {
                images.push([vk::DescriptorImageInfo {
                    sampler: vk::Sampler::null(),
                    image_view: view_of(v)?,
                    image_layout: vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
                }]);
            }
            let samplers: Vec<[vk::DescriptorImageInfo; 1]> = m
                .samplers
                .iter()
                .map(|desc| {
                    let s = sampler_of.iter().find(|(x, _)| x == desc).map(|(_, s)| *s);
                    [vk::DescriptorImageInfo {
                        sampler: s.unwrap_or_default(),
                        image_view: vk::ImageView::null(),
                        image_layout: vk::ImageLayout::UNDEFINED,
                    }]
                })
                .collect();
            let mut writes = vec![vk::WriteDescriptorSet::default()
                .dst_set(set)
                .dst_binding(0)
                .descriptor_type(vk::DescriptorType::UNIFORM_BUFFER)
                .buffer_info(&buffer)];
            for (i, info) in images.iter().enumerate() {
                writes.push(
                    vk::WriteDescriptorSet::default()
                        .dst_set(set)
                        .dst_binding(1 + i as u32)
                        .descriptor_type(vk::DescriptorType::SAMPLED_IMAGE)
                        .image_info(info),
                );
            }
            for (i, info) in samplers.iter().enumerate() {
                writes.push(
                    vk::WriteDescriptorSet::default()
                        .dst_set(set)
                        .dst_binding(6 + i as u32)
                        .descriptor_type(vk::DescriptorType::SAMPLER)
                        .image_info(info),
                );
            }
            // SAFETY: the set is ours and not in use; the buffer, views and samplers are alive
            // (kept clones, our samplers) and match the layout's types.
            unsafe { d.update_descriptor_sets(&writes, &[]) };
            out._keep_buffers.push(m.uniform.clone());
            out._keep_views.extend(m.views.iter().map(|&v| v.clone()));
        }
        Ok(Some(out))
    }

    /// Moves every sampled texture into `TextureUses::RESOURCE` (SHADER_READ_ONLY_OPTIMAL, what
    /// the sets say), in `encoder`, which must be submitted before the raw pass reading them.
    pub fn transition(&self, encoder: &mut wgpu::CommandEncoder) {
        encoder.transition_resources(
            std::iter::empty(),
            self.textures.iter().map(|texture| wgpu::TextureTransition {
                texture,
                selector: None,
                state: wgpu::TextureUses::RESOURCE,
            }),
        );
    }

    /// Whether any draw is of `class`.
    pub fn has(&self, class: Class) -> bool {
        self.draws.iter().any(|d| d.class == class)
    }
}

impl Drop for RawMaterialSets {
    fn drop(&mut self) {
        let d = &self.device;
        // SAFETY: after the device is idle no submitted command buffer uses the sets or the
        // samplers; each was created on `d` by `new` (null handles of a `new` that failed
        // part-way are ignored by the destroy calls; freeing the pool frees its sets).
        unsafe {
            let _ = d.device_wait_idle();
            for &s in &self.samplers {
                d.destroy_sampler(s, None);
            }
            d.destroy_descriptor_pool(self.pool, None);
            d.destroy_descriptor_set_layout(self.layout, None);
        }
    }
}

/// The raw handle of a wgpu buffer on Vulkan. The caller keeps `b` (a clone) alive as long as the
/// handle is used.
pub(super) fn raw_buffer(b: &wgpu::Buffer) -> Result<vk::Buffer, String> {
    // SAFETY: only the handle is read; its lifetime is the caller's clone's.
    unsafe { b.as_hal::<Vulkan>().map(|h| h.raw_handle()) }
        .ok_or_else(|| "buffer is not a Vulkan buffer".to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pool_sizes_cover_every_binding_of_every_set() {
        let sizes = pool_sizes(3);
        let count = |ty| {
            sizes
                .iter()
                .find(|p| p.ty == ty)
                .map_or(0, |p| p.descriptor_count)
        };
        assert_eq!(count(vk::DescriptorType::UNIFORM_BUFFER), 3);
        assert_eq!(count(vk::DescriptorType::SAMPLED_IMAGE), 15);
        assert_eq!(count(vk::DescriptorType::SAMPLER), 15);
        assert_eq!(sizes.len(), 3);
    }

    #[test]
    fn samplers_map_as_wgpu_does() {
        let trilinear = crate::world::texture::SamplerDesc {
            anisotropy: 8,
            ..crate::world::texture::SamplerDesc::DEFAULT
        };
        let info = sampler_info(&trilinear.descriptor(), true);
        assert_eq!(info.min_filter, vk::Filter::LINEAR);
        assert_eq!(info.mipmap_mode, vk::SamplerMipmapMode::LINEAR);
        assert_eq!(info.address_mode_u, vk::SamplerAddressMode::REPEAT);
        assert_eq!(
            (info.anisotropy_enable, info.max_anisotropy),
            (vk::TRUE, 8.0)
        );
        assert_eq!((info.min_lod, info.max_lod), (0.0, 32.0));
        // Without the adapter's anisotropic filtering wgpu-core sets the clamp to 1.
        assert_eq!(
            sampler_info(&trilinear.descriptor(), false).anisotropy_enable,
            vk::FALSE
        );
        // No mip filtering in the file: level 0 only, no anisotropy (not every filter linear).
        let nearest = crate::world::texture::SamplerDesc {
            mipmap: None,
            mag_linear: false,
            ..trilinear
        };
        let info = sampler_info(&nearest.descriptor(), true);
        assert_eq!(info.mag_filter, vk::Filter::NEAREST);
        assert_eq!(info.max_lod, 0.0);
        assert_eq!(info.anisotropy_enable, vk::FALSE);
    }
}
