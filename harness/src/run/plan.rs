//! A scenario's plan, computed once before anything renders: where its metrics run, what each
//! render keeps of its frames (on the CPU, linear, on the device), which measured frames start a
//! shot, whether the reference is rendered apart or is the native variant's own frames, and in
//! which order the variants render. The stages (render, evaluate, save, report) read the plan
//! instead of asking the `Scenario` again.
//!
//! For: decisions that follow from the scenario and the adapter alone. Not for: rendering,
//! metrics or records.

use super::rendered::Keep;
use super::sequence::history_valid;
use crate::gpu::Gpu;
use crate::metric::Needs;
use crate::metrics_device::Backend;
use crate::scenario::{Reference, Scenario};
use crate::techniques::{self, Variant};

/// What a scenario's run does, decided once.
#[derive(Clone)]
pub struct Plan<'a> {
    pub scenario: &'a Scenario,
    /// Where the metrics run: `metrics_device` (the scenario's, `--metrics-device`), else by
    /// adapter.
    pub backend: Backend,
    /// With the GPU's metrics, frames stay on the device (they fit its buffers).
    pub on_gpu: bool,
    /// Some variant is diffed against a reference.
    pub needs_reference: bool,
    /// The reference renders apart (ground truth, converged, or native when the native variant
    /// is not in the scenario); otherwise the native variant's frames are the reference.
    pub separate_reference: bool,
    /// Linear frames are kept: for a metric that needs them (HDR-FLIP), and for one that reads
    /// frames as the display takes them (`cvvdp`) on an HDR display.
    pub keep_hdr: bool,
    /// A metric reads the frames on the CPU as the display model takes them (`cvvdp`).
    pub display_frames: bool,
    /// ...and the display takes linear frames (it is HDR).
    pub display_linear: bool,
    /// The renderer's exact motion is captured (for `tde`).
    pub motion: bool,
    /// Measured frames where a new camera shot starts (history is dropped there), the first
    /// measured frame included when a cut falls on it.
    pub cuts: Vec<u32>,
    /// The variants in render order: the native reference first, then the others as declared.
    pub order: Vec<&'a Variant>,
}

impl<'a> Plan<'a> {
    /// The plan of `scenario` on `gpu`.
    pub fn new(gpu: &Gpu, scenario: &'a Scenario) -> Plan<'a> {
        let needs = |f: fn(&Needs) -> bool| scenario.metrics.iter().any(|m| f(&m.def().needs));
        let display_frames = needs(|n| n.display);
        let display_linear = display_frames && crate::metric::cvvdp::uses_linear(&scenario.display);
        let keep_hdr = needs(|n| n.linear) || display_linear;
        let backend = crate::metrics_device::chosen(scenario, gpu);
        let on_gpu = backend == Backend::Gpu
            && gpu
                .metrics()
                .frame_fits(scenario.width, scenario.height, keep_hdr)
                .is_ok();
        let needs_reference = scenario.needs_reference();
        let mut plan = Plan {
            scenario,
            backend,
            on_gpu,
            needs_reference,
            separate_reference: scenario.needs_separate_reference(),
            keep_hdr,
            display_frames,
            display_linear,
            motion: needs_reference && needs(|n| n.motion),
            cuts: cut_frames(scenario),
            order: Vec::new(),
        };
        plan.order = scenario
            .variants
            .iter()
            .filter(|v| plan.is_native_reference(v))
            .chain(
                scenario
                    .variants
                    .iter()
                    .filter(|v| !plan.is_native_reference(v)),
            )
            .collect();
        plan
    }

    /// The same plan with the metrics on the CPU, every frame read back to it.
    pub fn on_cpu(&self) -> Plan<'a> {
        Plan {
            backend: Backend::Cpu,
            on_gpu: false,
            ..self.clone()
        }
    }

    /// Whether `variant` is the native variant and the scenario's reference is native.
    pub fn is_native_reference(&self, variant: &Variant) -> bool {
        techniques::is_reference(variant) && self.scenario.reference == Reference::Native
    }

    /// What a render keeps of its frames for the metrics, on the device (the GPU metrics) or on
    /// the CPU; `reference`: the render is the reference. Without a reference nothing is kept but
    /// the saved frames' images. With the GPU metrics the CPU keeps only what the CPU still
    /// reads: the 8-bit frames for ColorVideoVDP, linear frames for ColorVideoVDP on an HDR
    /// display and, of the reference, for HDR-FLIP's exposure ranges.
    pub fn keep(&self, reference: bool) -> Keep {
        if !self.needs_reference {
            return Keep::default();
        }
        if !self.on_gpu {
            return Keep::cpu(self.keep_hdr);
        }
        Keep {
            frames: self.display_frames,
            hdr: self.display_linear || (reference && self.keep_hdr),
            gpu: true,
            gpu_hdr: self.keep_hdr,
        }
    }

    /// The cuts as ColorVideoVDP takes them: measured frames after the first that start a shot.
    pub fn cvvdp_cuts(&self) -> Vec<usize> {
        self.cuts
            .iter()
            .filter(|&&c| c > 0)
            .map(|&c| c as usize)
            .collect()
    }
}

/// Measured-frame indices where a new camera shot starts (history is dropped there).
fn cut_frames(scenario: &Scenario) -> Vec<u32> {
    (0..scenario.measured_frames)
        .filter(|&m| {
            let index = scenario.warmup_frames + m;
            index > 0 && !history_valid(scenario, index)
        })
        .collect()
}
