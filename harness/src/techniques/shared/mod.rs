//! Pieces more than one technique uses, in one place so no technique imports from a sibling's
//! folder: the Halton (2, 3) jitter and FSR 2's phase count (`jitter.rs`; `taau`, `fsr2`), and
//! FSR 1's RCAS with the perceptual encoding it works in (`rcas.rs` the pass, `rcas.wgsl` the
//! shader, `rcas_model.rs` the CPU model; `fsr1`, `taau`, `fsr2`). Motion is shared too, but
//! lives with the render infrastructure (`render/velocity.rs`), since the run loop uses it.
//!
//! Not a technique: nothing here is in the registry, and nothing here names a technique.

pub mod jitter;
pub mod rcas;
pub mod rcas_model;
