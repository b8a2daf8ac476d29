//! Every WGSL file under `shaders/` parses and validates with naga, without a GPU, and every one
//! of them is used by the harness (no stale shaders).

use std::path::Path;

#[test]
fn every_shader_validates() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shaders");
    let mut files: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "wgsl"))
        .map(|p| p.file_name().unwrap().to_string_lossy().into_owned())
        .collect();
    files.sort();
    let mut used: Vec<String> = Vec::new();
    for (name, source, parts) in tessera::render::technique::shader_sources() {
        let module = naga::front::wgsl::parse_str(&source)
            .unwrap_or_else(|e| panic!("{name}: {}", e.emit_to_string(&source)));
        naga::valid::Validator::new(
            naga::valid::ValidationFlags::all(),
            naga::valid::Capabilities::all(),
        )
        .validate(&module)
        .unwrap_or_else(|e| panic!("{name}: {}", e.emit_to_string(&source)));
        used.extend(parts.iter().map(|p| p.to_string()));
    }
    used.sort();
    used.dedup();
    assert_eq!(files, used, "shaders/ and the harness's shader list differ");
}
