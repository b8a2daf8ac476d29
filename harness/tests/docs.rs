//! The parameter table in `scenarios/README.md` is the registry's (`techniques::docs`): this test
//! fails on any drift; `TESSERA_BLESS=1` rewrites the README's copy.

use std::path::Path;

use tessera::techniques::docs::{parameter_table, BEGIN, END};

#[test]
fn the_readme_parameter_table_is_the_registrys() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenarios/README.md");
    let readme = std::fs::read_to_string(&path).unwrap();
    let start = readme
        .find(BEGIN)
        .unwrap_or_else(|| panic!("{} lacks the marker {BEGIN}", path.display()))
        + BEGIN.len();
    let end = start
        + readme[start..]
            .find(END)
            .unwrap_or_else(|| panic!("{} lacks the marker {END}", path.display()));
    let want = format!("\n{}", parameter_table());
    if readme[start..end] == want {
        return;
    }
    if std::env::var_os("TESSERA_BLESS").is_some() {
        let updated = format!("{}{want}{}", &readme[..start], &readme[end..]);
        std::fs::write(&path, updated).unwrap();
        return;
    }
    panic!(
        "the parameter table in {} differs from the registry; run \
         `TESSERA_BLESS=1 cargo test -p tessera --test docs` and review the diff. Expected:\n{want}",
        path.display()
    );
}
