//! The pass graph: passes declare the resources they read and write; passes whose outputs nothing
//! reads are culled, and only resources of passes that run are allocated.
//!
//! Pure bookkeeping, no GPU: techniques describe their graph here, then allocate and record what
//! the returned [`Plan`] keeps. The per-resource byte counts follow the depth-based report's
//! Tables 2 and 4 (format size times pixels times samples).

use std::collections::BTreeSet;

use tessera_results::ResourceRecord;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PassKind {
    Render,
    Compute,
    Copy,
}

impl PassKind {
    pub fn name(self) -> &'static str {
        match self {
            PassKind::Render => "render",
            PassKind::Compute => "compute",
            PassKind::Copy => "copy",
        }
    }
}

#[derive(Clone, Debug, PartialEq, Eq)]
pub struct TextureDesc {
    pub format: wgpu::TextureFormat,
    pub width: u32,
    pub height: u32,
    pub samples: u32,
    /// Array layers (1 for a plain 2D texture).
    pub layers: u32,
}

impl TextureDesc {
    pub fn bytes(&self) -> u64 {
        // Depth-stencil formats have no single copy size; none of ours is one.
        let block = self.format.block_copy_size(None).unwrap_or(4);
        block as u64
            * self.width as u64
            * self.height as u64
            * self.samples as u64
            * self.layers as u64
    }
}

/// A texture of a pass graph as a typed handle: declared once (`const COLOR: Res =
/// Res::new("color")`), then named by the graph's passes, the allocation
/// ([`kit::TextureMap`](super::kit::TextureMap)) and the recording, instead of the same string
/// written in each. Its name is what plans, results and tests call the resource.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Res(&'static str);

impl Res {
    pub const fn new(name: &'static str) -> Res {
        Res(name)
    }

    pub const fn name(self) -> &'static str {
        self.0
    }
}

/// What names a resource of a [`Graph`]: a [`Res`] handle, or its name (graphs not yet written
/// with handles).
pub trait ResourceName: Copy {
    fn resource_name(self) -> &'static str;
}

impl ResourceName for Res {
    fn resource_name(self) -> &'static str {
        self.0
    }
}

impl ResourceName for &'static str {
    fn resource_name(self) -> &'static str {
        self
    }
}

#[derive(Clone, Debug)]
pub struct Resource {
    pub name: &'static str,
    pub desc: TextureDesc,
}

#[derive(Clone, Debug)]
pub struct Pass {
    pub name: &'static str,
    pub kind: PassKind,
    pub reads: Vec<&'static str>,
    pub writes: Vec<&'static str>,
    /// Its renderer counts its pipeline statistics itself (`Renderer::own_statistics`): a pass
    /// recorded outside wgpu, which the timers' queries cannot reach. Timed like any other.
    pub self_counted: bool,
}

/// A technique's passes in submission order, its resources, and what leaves the frame.
#[derive(Clone, Debug, Default)]
pub struct Graph {
    pub resources: Vec<Resource>,
    pub passes: Vec<Pass>,
    /// Resources read after the frame (the displayed output, histories read next frame).
    pub outputs: Vec<&'static str>,
}

/// What runs: the passes kept, in order, and the resources they touch.
#[derive(Clone, Debug)]
pub struct Plan {
    pub passes: Vec<Pass>,
    pub culled: Vec<&'static str>,
    pub resources: Vec<Resource>,
}

#[derive(Debug, thiserror::Error, PartialEq, Eq)]
pub enum GraphError {
    #[error("pass `{pass}` uses resource `{resource}`, which the graph does not declare")]
    UnknownResource {
        pass: &'static str,
        resource: &'static str,
    },
    #[error("output `{0}` is not a declared resource")]
    UnknownOutput(&'static str),
}

impl Graph {
    pub fn resource(&mut self, name: impl ResourceName, desc: TextureDesc) -> &mut Self {
        self.resources.push(Resource {
            name: name.resource_name(),
            desc,
        });
        self
    }

    pub fn pass<R: ResourceName>(
        &mut self,
        name: &'static str,
        kind: PassKind,
        reads: &[R],
        writes: &[R],
    ) -> &mut Self {
        let names = |rs: &[R]| rs.iter().map(|r| r.resource_name()).collect();
        self.passes.push(Pass {
            name,
            kind,
            reads: names(reads),
            writes: names(writes),
            self_counted: false,
        });
        self
    }

    /// Marks the pass just added as counted by its renderer ([`Pass::self_counted`]).
    pub fn self_counted(&mut self) -> &mut Self {
        if let Some(p) = self.passes.last_mut() {
            p.self_counted = true;
        }
        self
    }

    pub fn output(&mut self, name: impl ResourceName) -> &mut Self {
        self.outputs.push(name.resource_name());
        self
    }

    /// Keeps the passes that (transitively) produce an output; culls the rest and every resource
    /// only they used. A pass that writes a needed resource is kept even if it also writes others.
    pub fn plan(&self) -> Result<Plan, GraphError> {
        let known: BTreeSet<&str> = self.resources.iter().map(|r| r.name).collect();
        for p in &self.passes {
            for r in p.reads.iter().chain(&p.writes) {
                if !known.contains(r) {
                    return Err(GraphError::UnknownResource {
                        pass: p.name,
                        resource: r,
                    });
                }
            }
        }
        for o in &self.outputs {
            if !known.contains(o) {
                return Err(GraphError::UnknownOutput(o));
            }
        }
        let mut needed: BTreeSet<&str> = self.outputs.iter().copied().collect();
        let mut keep = vec![false; self.passes.len()];
        // Walk backwards: a pass is kept if it writes something needed later; its reads become needed.
        for (i, p) in self.passes.iter().enumerate().rev() {
            if p.writes.iter().any(|w| needed.contains(w)) {
                keep[i] = true;
                needed.extend(p.reads.iter().copied());
            }
        }
        let passes: Vec<Pass> = self
            .passes
            .iter()
            .zip(&keep)
            .filter(|(_, k)| **k)
            .map(|(p, _)| p.clone())
            .collect();
        let culled = self
            .passes
            .iter()
            .zip(&keep)
            .filter(|(_, k)| !**k)
            .map(|(p, _)| p.name)
            .collect();
        let used: BTreeSet<&str> = passes
            .iter()
            .flat_map(|p| p.reads.iter().chain(&p.writes).copied())
            .collect();
        let resources = self
            .resources
            .iter()
            .filter(|r| used.contains(r.name))
            .cloned()
            .collect();
        Ok(Plan {
            passes,
            culled,
            resources,
        })
    }
}

impl Plan {
    pub fn runs(&self, pass: &str) -> bool {
        self.passes.iter().any(|p| p.name == pass)
    }

    /// Whether the plan keeps `resource` (a culled pass's resources are not allocated).
    pub fn keeps(&self, resource: impl ResourceName) -> bool {
        let name = resource.resource_name();
        self.resources.iter().any(|r| r.name == name)
    }

    pub fn desc(&self, resource: &str) -> Option<&TextureDesc> {
        self.resources
            .iter()
            .find(|r| r.name == resource)
            .map(|r| &r.desc)
    }

    pub fn records(&self) -> Vec<ResourceRecord> {
        self.resources
            .iter()
            .map(|r| ResourceRecord {
                name: r.name.to_string(),
                kind: "texture".to_string(),
                format: format_name(r.desc.format),
                width: r.desc.width,
                height: r.desc.height,
                samples: r.desc.samples,
                bytes: r.desc.bytes(),
            })
            .collect()
    }
}

/// `Rgba16Float` → `rgba16float`, as WGSL and WebGPU spell formats.
pub fn format_name(format: wgpu::TextureFormat) -> String {
    format!("{format:?}").to_lowercase()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tex(w: u32) -> TextureDesc {
        TextureDesc {
            format: wgpu::TextureFormat::Rgba16Float,
            width: w,
            height: w,
            samples: 1,
            layers: 1,
        }
    }

    fn graph(outputs: &[&'static str]) -> Graph {
        let mut g = Graph::default();
        g.resource("color", tex(4))
            .resource(
                "depth",
                TextureDesc {
                    format: wgpu::TextureFormat::Depth32Float,
                    width: 4,
                    height: 4,
                    samples: 1,
                    layers: 1,
                },
            )
            .resource("velocity", tex(4))
            .resource("resolved", tex(4))
            .pass("scene", PassKind::Render, &[], &["color", "depth"])
            .pass("velocity", PassKind::Render, &["depth"], &["velocity"])
            .pass(
                "resolve",
                PassKind::Compute,
                &["color", "velocity"],
                &["resolved"],
            );
        for o in outputs {
            g.output(*o);
        }
        g
    }

    #[test]
    fn passes_nothing_reads_are_culled_with_their_resources() {
        let plan = graph(&["color"]).plan().unwrap();
        assert_eq!(
            plan.passes.iter().map(|p| p.name).collect::<Vec<_>>(),
            ["scene"]
        );
        assert_eq!(plan.culled, ["velocity", "resolve"]);
        let names: Vec<&str> = plan.resources.iter().map(|r| r.name).collect();
        assert_eq!(names, ["color", "depth"]);
        // 4x4 Rgba16Float (8 B) + 4x4 Depth32Float (4 B).
        assert_eq!(
            plan.records().iter().map(|r| r.bytes).sum::<u64>(),
            16 * 8 + 16 * 4
        );
    }

    #[test]
    fn reads_pull_in_their_producers_in_order() {
        let plan = graph(&["resolved"]).plan().unwrap();
        assert_eq!(
            plan.passes.iter().map(|p| p.name).collect::<Vec<_>>(),
            ["scene", "velocity", "resolve"]
        );
        assert!(plan.culled.is_empty());
        assert_eq!(plan.resources.len(), 4);
    }

    #[test]
    fn undeclared_resources_are_errors() {
        let mut g = Graph::default();
        g.resource("color", tex(1))
            .pass("scene", PassKind::Render, &["history"], &["color"])
            .output("color");
        assert_eq!(
            g.plan().unwrap_err(),
            GraphError::UnknownResource {
                pass: "scene",
                resource: "history"
            }
        );
        let mut g = Graph::default();
        g.resource("color", tex(1)).output("colour");
        assert_eq!(g.plan().unwrap_err(), GraphError::UnknownOutput("colour"));
    }

    #[test]
    fn handles_name_the_same_resources_as_strings() {
        const COLOR: Res = Res::new("color");
        const OUT: Res = Res::new("out");
        let mut g = Graph::default();
        g.resource(COLOR, tex(2))
            .resource(OUT, tex(2))
            .resource("unused", tex(2))
            .pass("scene", PassKind::Render, &[], &[COLOR])
            .pass("copy", PassKind::Copy, &[COLOR], &[OUT])
            .pass("spare", PassKind::Render, &[], &["unused"])
            .output(OUT);
        let plan = g.plan().unwrap();
        assert_eq!(plan.passes[1].reads, ["color"]);
        assert!(plan.keeps(COLOR) && plan.keeps("out") && !plan.keeps("unused"));
        assert_eq!(plan.culled, ["spare"]);
    }

    #[test]
    fn multisampled_bytes_count_samples() {
        let d = TextureDesc {
            format: wgpu::TextureFormat::Rgba8Unorm,
            width: 1280,
            height: 720,
            samples: 2,
            layers: 1,
        };
        assert_eq!(d.bytes(), 1280 * 720 * 4 * 2);
    }
}
