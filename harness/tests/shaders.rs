//! Every WGSL module of every technique in the registry parses and validates with naga, without a
//! GPU, and every WGSL file is used by one (no stale shaders): the shared ones in `shaders/`
//! (`scene.wgsl`, the adapter probe's) and each technique's in its own folder under
//! `harness/src/techniques/` (named `<folder>/<file>.wgsl`, e.g. `interlace/reconstruct.wgsl`).

use std::path::Path;

fn wgsl_files(dir: &Path, prefix: &str, out: &mut Vec<String>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        if path.is_dir() {
            wgsl_files(&path, &format!("{prefix}{name}/"), out);
        } else if path.extension().is_some_and(|e| e == "wgsl") {
            out.push(format!("{prefix}{name}"));
        }
    }
}

#[test]
fn every_shader_validates() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut files: Vec<String> = Vec::new();
    wgsl_files(&root.join("../shaders"), "", &mut files);
    wgsl_files(&root.join("src/techniques"), "", &mut files);
    files.sort();
    let mut used: Vec<String> = Vec::new();
    for shader in tessera::techniques::shaders() {
        let source = &shader.source;
        let module = naga::front::wgsl::parse_str(source)
            .unwrap_or_else(|e| panic!("{}: {}", shader.name, e.emit_to_string(source)));
        naga::valid::Validator::new(
            naga::valid::ValidationFlags::all(),
            naga::valid::Capabilities::all(),
        )
        .validate(&module)
        .unwrap_or_else(|e| panic!("{}: {}", shader.name, e.emit_to_string(source)));
        used.extend(shader.files.iter().map(|p| p.to_string()));
    }
    used.sort();
    used.dedup();
    assert_eq!(
        files, used,
        "the WGSL files (shaders/, src/techniques/<folder>/) and the techniques' shader lists differ"
    );
}

/// Each technique declares its own modules: a technique whose `shaders()` is empty would escape
/// the check above.
#[test]
fn every_technique_declares_its_shaders() {
    for t in tessera::techniques::ALL {
        assert!(!t.shaders().is_empty(), "{} declares no shader", t.name());
    }
}
