//! What the project's documents state about its own tree, held against the
//! tree: the counts README.md gives, the harness's module table and its
//! arrows one way, no source file over 600 lines, and `unsafe` only in the
//! crates README.md names. A statement that drifts fails here, not in a
//! reader's hands.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn read(path: &str) -> String {
    std::fs::read_to_string(root().join(path)).unwrap_or_else(|e| panic!("{path}: {e}"))
}

fn rust_files(dir: &Path) -> Vec<PathBuf> {
    let mut files = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(&dir).unwrap().map(Result::unwrap) {
            let path = entry.path();
            if path.is_dir() {
                stack.push(path);
            } else if path.extension().is_some_and(|e| e == "rs") {
                files.push(path);
            }
        }
    }
    files.sort();
    files
}

/// The number README.md writes right before `words` (e.g. `183 statements`).
fn stated(readme: &str, words: &str) -> usize {
    let at = readme
        .find(words)
        .unwrap_or_else(|| panic!("README.md no longer says `{words}`"));
    let number: String = readme[..at]
        .trim_end()
        .chars()
        .rev()
        .take_while(char::is_ascii_digit)
        .collect::<Vec<_>>()
        .into_iter()
        .rev()
        .collect();
    number
        .parse()
        .unwrap_or_else(|_| panic!("README.md: no number before `{words}`"))
}

#[test]
fn the_counts_readme_states_are_the_trees() {
    let readme = read("README.md");
    let catalogue = canif_spec::Catalogue::embedded().unwrap();
    let features = std::fs::read_dir(root().join("features"))
        .unwrap()
        .filter(|e| {
            e.as_ref()
                .unwrap()
                .path()
                .extension()
                .is_some_and(|x| x == "feature")
        })
        .count();
    let device_faults = canif_softdevice::Fault::ALL.len();
    let client_faults = canif_harness::client::faulty::ClientFault::ALL.len();
    for (words, actual) in [
        (
            "statements of the five source documents",
            catalogue.requirements().count(),
        ),
        ("device profiles", catalogue.profiles.len()),
        ("switchable faults", device_faults),
        ("feature files", features),
        ("device faults and each of the", device_faults),
        ("client faults", client_faults),
    ] {
        assert_eq!(stated(&readme, words), actual, "README.md: `{words}`");
    }
}

/// Every crate root forbids `unsafe` but the ones README.md names, and those
/// two are the ones that use it.
#[test]
fn unsafe_is_only_where_readme_says() {
    let readme = read("README.md");
    assert!(readme.contains("`canif-kernel` and `canif-cabi` are the only crates with `unsafe`"));
    let roots = [
        ("spec/src/lib.rs", true),
        ("model/src/lib.rs", true),
        ("softdevice/src/lib.rs", true),
        ("harness/src/lib.rs", true),
        ("features/src/lib.rs", true),
        ("src/main.rs", true),
        ("kernel/src/lib.rs", false),
        ("cabi/src/lib.rs", false),
    ];
    for (path, forbids) in roots {
        let text = read(path);
        assert_eq!(
            text.contains("#![forbid(unsafe_code)]"),
            forbids,
            "{path}: forbid(unsafe_code)"
        );
        if !forbids {
            assert!(
                text.contains("unsafe"),
                "{path} is named for unsafe and has none"
            );
        }
    }
}

#[test]
fn no_source_file_is_over_600_lines() {
    let mut long = Vec::new();
    for dir in [
        "harness/src",
        "features/src",
        "src",
        "model/src",
        "softdevice/src",
    ] {
        for file in rust_files(&root().join(dir)) {
            let lines = std::fs::read_to_string(&file).unwrap().lines().count();
            if lines > 600 {
                long.push(format!("{} ({lines} lines)", file.display()));
            }
        }
    }
    assert!(long.is_empty(), "split by job: {long:#?}");
}

/// The harness's top-level modules, as `harness/src/lib.rs` declares them.
fn harness_modules() -> BTreeSet<String> {
    read("harness/src/lib.rs")
        .lines()
        .filter_map(|l| {
            let l = l.trim();
            l.strip_prefix("pub mod ")
                .or_else(|| l.strip_prefix("mod "))
        })
        .map(|m| m.trim_end_matches(';').to_string())
        .collect()
}

#[test]
fn the_harness_module_table_is_the_tree() {
    let table: BTreeSet<String> = read("harness/README.md")
        .lines()
        .filter_map(|l| l.strip_prefix("| `"))
        .filter_map(|l| l.split('`').next())
        .map(str::to_string)
        .collect();
    assert_eq!(table, harness_modules(), "harness/README.md's module table");
}

/// The top-level modules each one uses (`crate::x` outside comments).
fn harness_arrows() -> BTreeMap<String, BTreeSet<String>> {
    let modules = harness_modules();
    let src = root().join("harness/src");
    modules
        .iter()
        .map(|module| {
            let dir = src.join(module);
            let files = if dir.is_dir() {
                rust_files(&dir)
            } else {
                vec![src.join(format!("{module}.rs"))]
            };
            let uses = files
                .iter()
                .flat_map(|f| {
                    let text = std::fs::read_to_string(f).unwrap();
                    text.lines()
                        .filter(|l| !l.trim_start().starts_with("//"))
                        .flat_map(|l| {
                            l.match_indices("crate::")
                                .map(|(at, _)| {
                                    l[at + 7..]
                                        .chars()
                                        .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
                                        .collect::<String>()
                                })
                                .collect::<Vec<_>>()
                        })
                        .collect::<Vec<_>>()
                })
                .filter(|used| used != module && modules.contains(used))
                .collect();
            (module.clone(), uses)
        })
        .collect()
}

#[test]
fn no_harness_module_imports_one_that_imports_it_back() {
    let arrows = harness_arrows();
    // Depth-first search for a cycle, naming it.
    fn visit(
        module: &str,
        arrows: &BTreeMap<String, BTreeSet<String>>,
        path: &mut Vec<String>,
        done: &mut BTreeSet<String>,
    ) -> Option<Vec<String>> {
        if let Some(at) = path.iter().position(|m| m == module) {
            let mut cycle = path[at..].to_vec();
            cycle.push(module.to_string());
            return Some(cycle);
        }
        if done.contains(module) {
            return None;
        }
        path.push(module.to_string());
        for next in &arrows[module] {
            if let Some(cycle) = visit(next, arrows, path, done) {
                return Some(cycle);
            }
        }
        path.pop();
        done.insert(module.to_string());
        None
    }
    let mut done = BTreeSet::new();
    for module in arrows.keys() {
        if let Some(cycle) = visit(module, &arrows, &mut Vec::new(), &mut done) {
            panic!("module cycle: {}", cycle.join(" → "));
        }
    }
    // The sides: the client side may use the device side's pieces, never the reverse.
    assert!(!arrows["device"].contains("client"));
    assert!(!arrows["run"].contains("device") && !arrows["run"].contains("client"));
}
