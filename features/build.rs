//! Embeds every `.feature` file, so `canif run` has the scenarios wherever it runs.

use std::fmt::Write as _;
use std::path::Path;

fn main() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    println!("cargo:rerun-if-changed=.");
    let mut names: Vec<String> = std::fs::read_dir(root)
        .expect("features folder")
        .filter_map(|e| e.ok())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".feature"))
        .collect();
    names.sort();
    let mut code = String::from("pub(crate) const EMBEDDED: &[(&str, &str)] = &[\n");
    for name in names {
        println!("cargo:rerun-if-changed={name}");
        let path = root.join(&name);
        writeln!(
            code,
            "    (\"features/{name}\", include_str!({:?})),",
            path.display().to_string()
        )
        .unwrap();
    }
    code.push_str("];\n");
    std::fs::write(
        Path::new(&std::env::var("OUT_DIR").unwrap()).join("features.rs"),
        code,
    )
    .unwrap();
}
