//! The one list of techniques. Everything that enumerates techniques (validation and its
//! messages, plan and build, the shader test, the speedup baselines, the parameter table of
//! `scenarios/README.md`) reads it.

use super::adaptive_shading::{AdaptiveShading, NativeDeferred, NativeVrs};
use super::checkerboard::Checkerboard;
use super::checkerboard_2x2::Checkerboard2x2;
use super::definition::Technique;
use super::fsr1::Fsr1;
use super::fsr2::Fsr2;
use super::interlace::Interlace;
use super::native::Native;
use super::taau::Taau;
use super::upscale::Upscale;

/// Every technique, in the order the docs and error messages list them.
pub static ALL: &[&dyn Technique] = &[
    &Native,
    &Upscale,
    &Fsr1,
    &Taau,
    &Fsr2,
    &Checkerboard,
    &Checkerboard2x2,
    &AdaptiveShading,
    &NativeDeferred,
    &NativeVrs,
    &Interlace,
];

/// The technique called `name`.
pub fn by_name(name: &str) -> Option<&'static dyn Technique> {
    ALL.iter().copied().find(|t| t.name() == name)
}

/// Names of every technique, for error messages.
pub fn names() -> Vec<&'static str> {
    ALL.iter().map(|t| t.name()).collect()
}
