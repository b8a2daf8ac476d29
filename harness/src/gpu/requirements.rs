//! What a variant needs of an adapter, declared as data before any device is opened (wgpu's
//! `tests/src/infra/params.rs` `TestParameters` shape, STYLE.md 18): wgpu features, MSAA sample
//! counts per format, and extensions beside wgpu (VK_KHR_fragment_shading_rate). `tessera
//! validate` and the plan print them without a GPU; the run checks them on the device before the
//! variant is built, and a variant that lacks one is `skipped` with the reason.
//!
//! Not for: limits a scenario's size sets (the texture size is checked with the target), facts a
//! technique finds only by building (those stay the build's `Unsupported`).

use super::{Gpu, Unsupported};

/// An extension wgpu has no API for, reached through wgpu-hal (`gpu/vrs.rs`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Extension {
    /// VK_KHR_fragment_shading_rate with `attachmentFragmentShadingRate`: hardware variable-rate
    /// shading driven by an attachment.
    FragmentShadingRate,
}

impl Extension {
    /// The reason a variant is skipped without it (the same words on every adapter).
    pub fn needs(self) -> &'static str {
        match self {
            Extension::FragmentShadingRate => super::vrs::NEEDS,
        }
    }

    /// `None` when `gpu` offers it, else why not (the probe's words).
    fn missing(self, gpu: &Gpu) -> Option<String> {
        match self {
            Extension::FragmentShadingRate => gpu.vrs.as_ref().err().cloned(),
        }
    }
}

/// A render target format a variant multisamples, with the name its skip reason uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Msaa {
    pub samples: u32,
    pub format: wgpu::TextureFormat,
    /// `rgba16float`: how the reason names the format.
    pub name: &'static str,
}

/// Everything a variant needs of an adapter beyond what every adapter has.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Requirements {
    pub features: wgpu::Features,
    pub msaa: Vec<Msaa>,
    /// Whether 2x MSAA must have the standard sample positions (probed once per device).
    pub standard_2x_positions: bool,
    pub extensions: Vec<Extension>,
}

impl Requirements {
    /// Nothing beyond what every adapter has.
    pub fn none() -> Requirements {
        Requirements::default()
    }

    pub fn is_empty(&self) -> bool {
        *self == Requirements::default()
    }

    /// Also needs `samples`x MSAA for `format` (named `name` in the reason). 2x also needs
    /// `TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES` (wgpu offers 2x only through it) and the
    /// standard sample positions.
    pub fn msaa(mut self, samples: u32, format: wgpu::TextureFormat, name: &'static str) -> Self {
        if samples == 2 {
            self.features |= wgpu::Features::TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES;
            self.standard_2x_positions = true;
        }
        self.msaa.push(Msaa {
            samples,
            format,
            name,
        });
        self
    }

    /// Also needs `extension`.
    pub fn extension(mut self, extension: Extension) -> Self {
        self.extensions.push(extension);
        self
    }

    /// Whether no CPU adapter (lavapipe) can meet them: an extension only GPU drivers offer.
    /// `tessera validate` calls such variants hardware-only.
    pub fn hardware_only(&self) -> bool {
        !self.extensions.is_empty()
    }

    /// What they are, in words, one line each, as a skip reason says them (no GPU needed).
    pub fn describe(&self) -> Vec<String> {
        let mut out: Vec<String> = self
            .msaa
            .iter()
            .map(|m| {
                format!(
                    "needs MULTISAMPLE_X{} for {}{}",
                    m.samples,
                    m.name,
                    if m.samples == 2 {
                        " at the standard sample positions"
                    } else {
                        ""
                    }
                )
            })
            .collect();
        let extra = self.features
            - if self.msaa.iter().any(|m| m.samples == 2) {
                wgpu::Features::TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES
            } else {
                wgpu::Features::empty()
            };
        if !extra.is_empty() {
            out.push(format!("needs the wgpu features {extra:?}"));
        }
        out.extend(self.extensions.iter().map(|e| e.needs().to_string()));
        out
    }

    /// `Ok` when `gpu` meets every requirement, else the first one it lacks, in the words a
    /// `skipped` result records.
    pub fn check(&self, gpu: &Gpu) -> Result<(), Unsupported> {
        let missing = self.features - gpu.device.features();
        let msaa_feature = wgpu::Features::TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES;
        if !(missing - msaa_feature).is_empty() {
            return Err(Unsupported(format!(
                "needs the wgpu features {:?}",
                missing - msaa_feature
            )));
        }
        let twos: Vec<(wgpu::TextureFormat, &str)> = self
            .msaa
            .iter()
            .filter(|m| m.samples == 2)
            .map(|m| (m.format, m.name))
            .collect();
        if !twos.is_empty() {
            gpu.check_msaa2x(&twos)?;
        }
        for m in self.msaa.iter().filter(|m| m.samples != 2) {
            let counts = gpu
                .adapter
                .get_texture_format_features(m.format)
                .flags
                .supported_sample_counts();
            if !counts.contains(&m.samples) {
                let list: Vec<String> = counts.iter().map(|c| format!("{c}x")).collect();
                return Err(Unsupported(format!(
                    "needs MULTISAMPLE_X{} for {} (the adapter has {})",
                    m.samples,
                    m.name,
                    list.join(", ")
                )));
            }
        }
        for e in &self.extensions {
            if let Some(reason) = e.missing(gpu) {
                return Err(Unsupported(reason));
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_words_are_the_skip_reasons() {
        let r = Requirements::none()
            .msaa(2, wgpu::TextureFormat::Rgba16Float, "rgba16float")
            .extension(Extension::FragmentShadingRate);
        assert_eq!(
            r.describe(),
            [
                "needs MULTISAMPLE_X2 for rgba16float at the standard sample positions",
                "needs VK_KHR_fragment_shading_rate with attachmentFragmentShadingRate",
            ]
        );
        assert!(r.hardware_only());
        assert!(Requirements::none().is_empty());
        assert!(Requirements::none().describe().is_empty());
    }
}
