//! The parameter table of `scenarios/README.md`, generated from the registry: `tests/docs.rs`
//! fails when the README's copy differs (and rewrites it with `TESSERA_BLESS=1`).

use crate::params::{DefaultValue, ParamKind, ParamSpec};

/// Where the generated table starts and ends in `scenarios/README.md`.
pub const BEGIN: &str = "<!-- parameters: generated from harness/src/techniques (tests/docs.rs; TESSERA_BLESS=1 cargo test -p tessera --test docs rewrites it) -->";
pub const END: &str = "<!-- end of parameters -->";

/// The one level-of-detail policy of every technique that renders below the output's sample
/// density, stated once above the table.
pub const LOD_POLICY: &str = "**LOD policy.** Every technique that renders below the output's sample density samples textures and the procedural ground alike as at the output's density: the screen-space derivatives of both (the ground filter's width, texture gradients) are multiplied by the render's sample spacing in output pixels, i.e. a mip bias of log2(render / output) per axis: `upscale` and `fsr1` at `scale` (AMD's FSR 1 modes: -0.38 / -0.58 / -0.79 / -1.0), `checkerboard` at its `gradient_scale` (Intel's DDXY_BIAS 0.5: quarter-resolution raster, full-resolution samples), `interlace` at its `gradient_scale`. A temporal upscaler whose source asks for more adds it on top: `taau`'s `mip_bias` and `fsr2` always (FSR 2's guide: log2(render / display) - 1, since accumulation resolves detail finer than one frame's samples). `native` and the references use 1.";

/// The Markdown table of every technique and parameter, in registry order.
pub fn parameter_table() -> String {
    let mut out = format!("{LOD_POLICY}\n\n");
    out.push_str(
        "| technique | parameter | allowed | default | meaning |\n|---|---|---|---|---|\n",
    );
    for t in super::ALL {
        out.push_str(&format!(
            "| `{}` | – | | | {} |\n",
            t.name(),
            cell(t.summary())
        ));
        for p in t.params() {
            out.push_str(&row(p));
        }
    }
    out
}

fn row(p: &ParamSpec) -> String {
    format!(
        "| | `{}` | {} | `{}` | {} |\n",
        p.name,
        allowed(&p.kind),
        default(&p.default),
        cell(p.doc)
    )
}

fn allowed(kind: &ParamKind) -> String {
    match kind {
        ParamKind::Float {
            min,
            min_inclusive,
            max,
        } => {
            if *max >= 1.0e9 {
                let op = if *min_inclusive { "≥" } else { ">" };
                format!("number {op} {min}")
            } else {
                let open = if *min_inclusive { "[" } else { "(" };
                format!("number in {open}{min}, {max}]")
            }
        }
        ParamKind::Int { min, max } => format!("integer {min}–{max}"),
        ParamKind::Choice(options) => options
            .iter()
            .map(|o| format!("`\"{o}\"`"))
            .collect::<Vec<_>>()
            .join(", "),
        ParamKind::Bool => "bool".to_string(),
    }
}

fn default(d: &DefaultValue) -> String {
    match d {
        DefaultValue::Float(v) => format!("{v}"),
        DefaultValue::Int(v) => format!("{v}"),
        DefaultValue::Str(v) => format!("\"{v}\""),
        DefaultValue::Bool(v) => format!("{v}"),
    }
}

/// Text safe inside a table cell.
fn cell(s: &str) -> String {
    s.replace('|', "\\|").replace('\n', " ")
}
