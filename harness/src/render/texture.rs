//! Material textures on the GPU: the wgpu sampler a [`SamplerDesc`] makes, the format an
//! [`Encoding`] is uploaded in, and the upload of an [`Image`] with a full mip chain (`mips.rs`
//! builds the levels). The images and samplers themselves are the world's (`world/texture.rs`).
//!
//! Colour textures (base colour, emissive) are `Rgba8UnormSrgb`, so sampling and the mip
//! downsample both work on linear values; data textures (metallic-roughness, normal, occlusion) are
//! `Rgba8Unorm`.

use super::mips::MipGenerator;
use crate::world::texture::{Encoding, Image, SamplerDesc, Wrap};

impl SamplerDesc {
    pub fn create(&self, device: &wgpu::Device) -> wgpu::Sampler {
        device.create_sampler(&self.descriptor())
    }

    /// The wgpu sampler this description makes (also what a pass recorded outside wgpu creates
    /// its own sampler from: `techniques/adaptive_shading/raw_material.rs`).
    pub fn descriptor(&self) -> wgpu::SamplerDescriptor<'static> {
        let wrap = |w: Wrap| match w {
            Wrap::Repeat => wgpu::AddressMode::Repeat,
            Wrap::Clamp => wgpu::AddressMode::ClampToEdge,
            Wrap::Mirror => wgpu::AddressMode::MirrorRepeat,
        };
        let filter = |linear: bool| {
            if linear {
                wgpu::FilterMode::Linear
            } else {
                wgpu::FilterMode::Nearest
            }
        };
        let mip = |linear: bool| {
            if linear {
                wgpu::MipmapFilterMode::Linear
            } else {
                wgpu::MipmapFilterMode::Nearest
            }
        };
        let all_linear = self.mag_linear && self.min_linear && self.mipmap == Some(true);
        wgpu::SamplerDescriptor {
            label: Some("material sampler"),
            address_mode_u: wrap(self.wrap_u),
            address_mode_v: wrap(self.wrap_v),
            address_mode_w: wgpu::AddressMode::Repeat,
            mag_filter: filter(self.mag_linear),
            min_filter: filter(self.min_linear),
            mipmap_filter: mip(self.mipmap.unwrap_or(false)),
            lod_min_clamp: 0.0,
            // No mip filtering in the file: level 0 only.
            lod_max_clamp: if self.mipmap.is_some() { 32.0 } else { 0.0 },
            compare: None,
            anisotropy_clamp: if all_linear {
                self.anisotropy.max(1)
            } else {
                1
            },
            border_color: None,
        }
    }
}

impl Encoding {
    pub fn format(self) -> wgpu::TextureFormat {
        match self {
            Encoding::Srgb => wgpu::TextureFormat::Rgba8UnormSrgb,
            Encoding::Linear => wgpu::TextureFormat::Rgba8Unorm,
        }
    }
}

/// Uploads `image` as a texture of `encoding` with every mip level, the levels below 0 generated
/// on the GPU by `mips` (in linear space for sRGB textures).
pub fn upload(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    mips: &mut MipGenerator,
    encoder: &mut wgpu::CommandEncoder,
    image: &Image,
    encoding: Encoding,
    label: &str,
) -> wgpu::Texture {
    let levels = image.mip_levels();
    let size = wgpu::Extent3d {
        width: image.width,
        height: image.height,
        depth_or_array_layers: 1,
    };
    let texture = device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size,
        mip_level_count: levels,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: encoding.format(),
        usage: wgpu::TextureUsages::TEXTURE_BINDING
            | wgpu::TextureUsages::COPY_DST
            | wgpu::TextureUsages::RENDER_ATTACHMENT,
        view_formats: &[],
    });
    queue.write_texture(
        wgpu::TexelCopyTextureInfo {
            texture: &texture,
            mip_level: 0,
            origin: wgpu::Origin3d::ZERO,
            aspect: wgpu::TextureAspect::All,
        },
        &image.rgba8,
        wgpu::TexelCopyBufferLayout {
            offset: 0,
            bytes_per_row: Some(4 * image.width),
            rows_per_image: Some(image.height),
        },
        size,
    );
    mips.generate(device, encoder, &texture);
    texture
}
