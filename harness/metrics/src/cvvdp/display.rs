//! Display models for ColorVideoVDP: a name, or a named base with the viewing conditions changed.
//!
//! For: turning what a scenario or `tessera diff --display` says into the `colorvideovdp` crate's
//! `DisplayModel`, with an error that names the key and what is allowed. Not for: the metric
//! itself (see `cvvdp::mod`).
//!
//! Names are the reference's `display_models.json` (26 models, `standard_4k` the default) plus
//! [`PAPER_27IN_4K`]. A custom display starts from a named one (`base`, default `standard_4k`) and
//! overrides its geometry (`pixels_per_degree`, or `diagonal_inches` with `distance_m`), its
//! resolution, peak luminance, contrast or ambient light.

use crate::MetricsError;
use colorvideovdp::{DisplayModel, Geometry, Photometry};
use serde::{Deserialize, Serialize};

/// The default display: the reference's `standard_4k` (30-inch 4K, 200 cd/m², 1000:1, 250 lux,
/// viewed from 0.7472 m: 75.4 ppd).
pub const DEFAULT_DISPLAY: &str = "standard_4k";

/// The test display of the NVIDIA content- and motion-adaptive shading paper
/// (`seeds/nvidia-adaptive-shading.txt`, section 5: "27 inch 4K display, 25 inch viewing distance,
/// leading to 76.2 PPD"). The paper gives no photometry, so it uses `standard_4k`'s (200 cd/m²,
/// contrast 1000, 250 lux). The stated 76.2 ppd is kept as stated: ColorVideoVDP's own geometry
/// would give 71.2 ppd for a 27-inch 16:9 panel at 25 inches.
pub const PAPER_27IN_4K: &str = "paper_27in_4k";

/// Pixels per degree of [`PAPER_27IN_4K`].
pub const PAPER_27IN_4K_PPD: f64 = 76.2;

/// Which display the frames are seen on: a name, or a named base with changes.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum DisplaySpec {
    Named(String),
    Custom(CustomDisplay),
}

impl Default for DisplaySpec {
    fn default() -> Self {
        Self::Named(DEFAULT_DISPLAY.to_owned())
    }
}

/// A named display with some of its viewing conditions changed. Unset fields keep the base's.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CustomDisplay {
    /// The display to start from; `standard_4k` when absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub base: Option<String>,
    /// Diagonal of the panel in inches; needs `distance_m`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub diagonal_inches: Option<f64>,
    /// Viewing distance in metres; needs `diagonal_inches`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub distance_m: Option<f64>,
    /// Pixels per visual degree, instead of a size and distance.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pixels_per_degree: Option<f64>,
    /// Native resolution `[width, height]` (the panel's, not the frames').
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub resolution: Option<[u32; 2]>,
    /// Peak luminance in cd/m².
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub peak_luminance: Option<f64>,
    /// Peak to black luminance ratio.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub contrast: Option<f64>,
    /// Ambient illuminance in lux.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ambient_lux: Option<f64>,
}

/// Every display name accepted by [`DisplaySpec::Named`].
pub fn display_names() -> Vec<String> {
    let mut names: Vec<String> = DisplayModel::names()
        .map(|n| n.into_iter().map(str::to_owned).collect())
        .unwrap_or_default();
    names.push(PAPER_27IN_4K.to_owned());
    names
}

fn named(name: &str) -> Result<DisplayModel, MetricsError> {
    let invalid = |reason: String| MetricsError::InvalidDisplay {
        spec: name.to_owned(),
        reason,
    };
    if name == PAPER_27IN_4K {
        let base = DisplayModel::from_name(DEFAULT_DISPLAY).map_err(|e| invalid(e.to_string()))?;
        let geometry = Geometry::from_ppd([3840, 2160], PAPER_27IN_4K_PPD)
            .map_err(|e| invalid(e.to_string()))?;
        return DisplayModel::new(name, base.photometry, geometry, base.color_space)
            .map_err(|e| invalid(e.to_string()));
    }
    DisplayModel::from_name(name).map_err(|_| {
        invalid(format!(
            "unknown display; known: {}",
            display_names().join(", ")
        ))
    })
}

impl DisplaySpec {
    /// Parses the command-line form: a display name, or `key=value` pairs separated by commas
    /// (`base=standard_fhd,peak_luminance=400`, `diagonal_inches=27,distance_m=0.6`,
    /// `resolution=3840x2160`), with the keys of [`CustomDisplay`].
    pub fn parse(text: &str) -> Result<Self, MetricsError> {
        let text = text.trim();
        if !text.contains('=') {
            let spec = Self::Named(text.to_owned());
            spec.model()?;
            return Ok(spec);
        }
        let mut c = CustomDisplay::default();
        for pair in text.split(',') {
            let invalid = |reason: String| MetricsError::InvalidDisplay {
                spec: text.to_owned(),
                reason,
            };
            let (key, value) = pair
                .split_once('=')
                .ok_or_else(|| invalid(format!("`{pair}` is not key=value")))?;
            let (key, value) = (key.trim(), value.trim());
            let number = || {
                value
                    .parse::<f64>()
                    .map_err(|_| invalid(format!("{key} = `{value}` is not a number")))
            };
            match key {
                "base" => c.base = Some(value.to_owned()),
                "diagonal_inches" => c.diagonal_inches = Some(number()?),
                "distance_m" => c.distance_m = Some(number()?),
                "pixels_per_degree" => c.pixels_per_degree = Some(number()?),
                "peak_luminance" => c.peak_luminance = Some(number()?),
                "contrast" => c.contrast = Some(number()?),
                "ambient_lux" => c.ambient_lux = Some(number()?),
                "resolution" => {
                    let parsed = value
                        .split_once('x')
                        .and_then(|(w, h)| Some([w.parse().ok()?, h.parse().ok()?]));
                    c.resolution = Some(parsed.ok_or_else(|| {
                        invalid(format!("resolution = `{value}` is not WIDTHxHEIGHT"))
                    })?);
                }
                other => {
                    return Err(invalid(format!(
                        "unknown key `{other}`; allowed: base, diagonal_inches, distance_m, \
                         pixels_per_degree, resolution, peak_luminance, contrast, ambient_lux"
                    )))
                }
            }
        }
        let spec = Self::Custom(c);
        spec.model()?;
        Ok(spec)
    }

    /// A short label: the name, or the base's name with `(custom)`.
    pub fn label(&self) -> String {
        match self {
            Self::Named(n) => n.clone(),
            Self::Custom(c) => format!("{} (custom)", c.base.as_deref().unwrap_or(DEFAULT_DISPLAY)),
        }
    }

    /// The `colorvideovdp` display model.
    pub fn model(&self) -> Result<DisplayModel, MetricsError> {
        let c = match self {
            Self::Named(name) => return named(name),
            Self::Custom(c) => c,
        };
        let base_name = c.base.as_deref().unwrap_or(DEFAULT_DISPLAY);
        let invalid = |reason: String| MetricsError::InvalidDisplay {
            spec: format!("{c:?}"),
            reason,
        };
        let base = named(base_name)?;
        let [bw, bh] = base.geometry.resolution();
        let resolution = c
            .resolution
            .map_or([bw, bh], |[w, h]| [w as usize, h as usize]);
        let geometry = match (c.pixels_per_degree, c.diagonal_inches, c.distance_m) {
            (Some(_), Some(_), _) | (Some(_), _, Some(_)) => {
                return Err(invalid(
                    "give pixels_per_degree or diagonal_inches with distance_m, not both".into(),
                ))
            }
            (Some(ppd), None, None) => Geometry::from_ppd(resolution, ppd),
            (None, Some(d), Some(m)) => Geometry::from_diagonal(resolution, d, m),
            (None, Some(_), None) | (None, None, Some(_)) => {
                return Err(invalid(
                    "diagonal_inches and distance_m must be given together".into(),
                ))
            }
            (None, None, None) if c.resolution.is_some() => {
                return Err(invalid(
                    "a new resolution needs pixels_per_degree or diagonal_inches with distance_m"
                        .into(),
                ))
            }
            (None, None, None) => Ok(base.geometry.clone()),
        }
        .map_err(|e| invalid(e.to_string()))?;
        let p = &base.photometry;
        let photometry = Photometry::new(
            c.peak_luminance.unwrap_or(p.peak_luminance),
            c.contrast.unwrap_or(p.contrast),
            c.ambient_lux.unwrap_or(p.ambient_illuminance),
            p.reflectivity,
            p.exposure,
        )
        .map_err(|e| invalid(e.to_string()))?;
        DisplayModel::new(self.label(), photometry, geometry, base.color_space.clone())
            .map_err(|e| invalid(e.to_string()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn standard_4k_is_the_reference_geometry() {
        let m = DisplaySpec::default().model().unwrap();
        // 30-inch 16:9 at 0.7472 m, by the reference's vvdp_display_geometry.
        assert!((m.geometry.pixels_per_degree() - 75.4).abs() < 0.1);
        assert_eq!(m.photometry.peak_luminance, 200.0);
    }

    #[test]
    fn paper_display_has_its_stated_ppd() {
        let m = DisplaySpec::Named(PAPER_27IN_4K.into()).model().unwrap();
        assert_eq!(m.geometry.pixels_per_degree(), 76.2);
        assert_eq!(m.geometry.resolution(), [3840, 2160]);
    }

    #[test]
    fn custom_overrides_size_distance_and_peak() {
        let spec =
            DisplaySpec::parse("diagonal_inches=27,distance_m=0.635,peak_luminance=400").unwrap();
        let m = spec.model().unwrap();
        assert!((m.geometry.pixels_per_degree() - 71.2).abs() < 0.1);
        assert_eq!(m.photometry.peak_luminance, 400.0);
        assert_eq!(m.photometry.contrast, 1000.0);
    }

    #[test]
    fn bad_specs_name_what_is_wrong() {
        let e = DisplaySpec::parse("standard_5k").unwrap_err().to_string();
        assert!(
            e.contains("unknown display") && e.contains("standard_fhd"),
            "{e}"
        );
        let e = DisplaySpec::parse("diagonal_inches=27")
            .unwrap_err()
            .to_string();
        assert!(e.contains("together"), "{e}");
        let e = DisplaySpec::parse("peak=400").unwrap_err().to_string();
        assert!(e.contains("unknown key `peak`"), "{e}");
        let e = DisplaySpec::parse("peak_luminance=-3")
            .unwrap_err()
            .to_string();
        assert!(e.contains("photometry"), "{e}");
        let e = DisplaySpec::parse("resolution=12").unwrap_err().to_string();
        assert!(e.contains("WIDTHxHEIGHT"), "{e}");
    }

    #[test]
    fn toml_like_forms_deserialize() {
        let named: DisplaySpec = serde_json::from_str("\"standard_fhd\"").unwrap();
        assert_eq!(named, DisplaySpec::Named("standard_fhd".into()));
        let custom: DisplaySpec =
            serde_json::from_str(r#"{"pixels_per_degree": 60, "peak_luminance": 300}"#).unwrap();
        assert!(custom.model().is_ok());
        assert!(serde_json::from_str::<DisplaySpec>(r#"{"peak": 300}"#).is_err());
    }
}
