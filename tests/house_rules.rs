//! What the project's documents state about its own tree, held against the
//! tree: the counts README.md gives, the harness's module table and its
//! arrows one way, no source file over 600 lines and no function over 150,
//! no import circle in any crate, and `unsafe` only in the crates README.md
//! names. A statement that drifts fails here, not in a reader's hands.

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
    let client_faults = canif_harness::client::soft_client::ClientFault::ALL.len();
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
        ("ethercat/src/lib.rs", true),
        ("plctypes/src/lib.rs", true),
        ("runner/src/lib.rs", true),
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

/// Every crate's source folder, read from Cargo.toml's members: a new
/// crate is not missed by a rule.
fn source_dirs() -> Vec<String> {
    let manifest = read("Cargo.toml");
    let members = manifest
        .lines()
        .find_map(|l| l.strip_prefix("members = ["))
        .expect("Cargo.toml lists the workspace members");
    let dirs: Vec<String> = members
        .trim_end_matches(']')
        .split(',')
        .map(|m| format!("{}/src", m.trim().trim_matches('"')))
        .chain(["src".to_string()])
        .collect();
    assert!(dirs.len() >= 10, "{dirs:?}");
    dirs
}

#[test]
fn no_source_file_is_over_600_lines() {
    let mut long = Vec::new();
    for dir in &source_dirs() {
        for file in rust_files(&root().join(dir)) {
            let lines = std::fs::read_to_string(&file).unwrap().lines().count();
            if lines > 600 {
                long.push(format!("{} ({lines} lines)", file.display()));
            }
        }
    }
    assert!(long.is_empty(), "split by job: {long:#?}");
}

/// A transport is one module below both sides and one arm of `Door`: no
/// code outside `harness/src/door/` names a transport's types or modules,
/// so the next transport is added without touching the runner, the sides
/// or the command line (CONTRIBUTING.md, "Adding a transport").
#[test]
fn a_transport_is_named_only_inside_its_door_module() {
    const NAMES: [&str; 10] = [
        "Door::Exec",
        "Door::Lib",
        "Door::Ethercat",
        "ExecDoor",
        "LibDoor",
        "EthercatDoor",
        "EthercatLink",
        "door::exec::",
        "door::lib::",
        "door::ethercat::",
    ];
    // EtherCAT's own commands, which are no run through a door: `canif
    // device --ethercat` serves canif's terminal, `canif esi` writes its ESI.
    const OWN_COMMANDS: [&str; 2] = ["src/commands/device.rs", "src/commands/tools.rs"];
    let mut named = Vec::new();
    for dir in &source_dirs() {
        for file in rust_files(&root().join(dir)) {
            let path = file.strip_prefix(root()).unwrap().display().to_string();
            if path.starts_with("harness/src/door/") || OWN_COMMANDS.contains(&path.as_str()) {
                continue;
            }
            let text = std::fs::read_to_string(&file).unwrap();
            for (n, line) in text.lines().enumerate() {
                if let Some(name) = NAMES.iter().find(|name| line.contains(*name)) {
                    named.push(format!("{path}:{}: {name}", n + 1));
                }
            }
        }
    }
    assert!(
        named.is_empty(),
        "dispatch through Door::transport(): {named:#?}"
    );
}

/// The functions of `text` with their first line and length: from a line
/// that opens `fn NAME` to the closing brace at its own indentation.
fn functions(text: &str) -> Vec<(String, usize, usize)> {
    let lines: Vec<&str> = text.lines().collect();
    let mut found = Vec::new();
    for (at, line) in lines.iter().enumerate() {
        let body = line.trim_start();
        let indent = &line[..line.len() - body.len()];
        let words: Vec<&str> = body.split_whitespace().collect();
        let Some(fn_at) = words.iter().position(|w| *w == "fn") else {
            continue;
        };
        // Only qualifiers may stand before `fn`, and a body must follow.
        let qualifiers = [
            "pub",
            "pub(crate)",
            "pub(super)",
            "const",
            "async",
            "unsafe",
            "extern",
            "\"C\"",
        ];
        if !words[..fn_at].iter().all(|w| qualifiers.contains(w)) || body.ends_with(';') {
            continue;
        }
        let name = words
            .get(fn_at + 1)
            .map_or("", |w| w.split(['(', '<']).next().unwrap_or(w));
        let close = format!("{indent}}}");
        if let Some(end) = lines[at + 1..].iter().position(|l| *l == close) {
            found.push((name.to_string(), at + 1, end + 2));
        }
    }
    found
}

#[test]
fn no_function_is_over_150_lines() {
    let mut long = Vec::new();
    for dir in &source_dirs() {
        for file in rust_files(&root().join(dir)) {
            let text = std::fs::read_to_string(&file).unwrap();
            for (name, line, length) in functions(&text) {
                if length > 150 {
                    long.push(format!("{}:{line} {name} ({length} lines)", file.display()));
                }
            }
        }
    }
    assert!(long.is_empty(), "split by job: {long:#?}");
}

#[test]
fn the_function_rule_sees_functions() {
    let text = "pub(crate) fn short() {\n    a();\n}\n\nimpl A {\n    fn inner(&self) -> u8 {\n        1\n    }\n    fn declared(&self);\n}\n";
    assert_eq!(
        functions(text),
        vec![("short".to_string(), 1, 3), ("inner".to_string(), 6, 3)]
    );
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
    let mut done = BTreeSet::new();
    for module in arrows.keys() {
        if let Some(cycle) = find_cycle(module, &arrows, &mut Vec::new(), &mut done) {
            panic!("module cycle: {}", cycle.join(" → "));
        }
    }
    // The sides stand beside each other on what both share: `run` (one
    // profile's run) and `door` (how an implementation is reached), and
    // neither of those reaches up into a side.
    for (from, to) in [
        ("device", "client"),
        ("client", "device"),
        ("run", "device"),
        ("run", "client"),
        ("door", "device"),
        ("door", "client"),
        ("door", "run"),
    ] {
        assert!(!arrows[from].contains(to), "`{from}` uses `{to}`");
    }
}

/// A Rust source file's module path below its crate root
/// (`door/exec/mod.rs` is `door::exec`).
fn module_path(src: &Path, file: &Path) -> Vec<String> {
    let relative = file.strip_prefix(src).unwrap().with_extension("");
    let mut parts: Vec<String> = relative
        .components()
        .map(|c| c.as_os_str().to_string_lossy().into_owned())
        .collect();
    if matches!(
        parts.last().map(String::as_str),
        Some("mod" | "lib" | "main")
    ) {
        parts.pop();
    }
    parts
}

/// The paths a line names through `crate::` or `super::`, as module paths
/// of the crate (unresolved: the longest known prefix is taken later).
fn named_paths(line: &str, from: &[String]) -> Vec<Vec<String>> {
    let ident = |rest: &str| -> Vec<String> {
        let mut parts = Vec::new();
        let mut rest = rest;
        loop {
            let name: String = rest
                .chars()
                .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
                .collect();
            if name.is_empty() {
                break;
            }
            rest = &rest[name.len()..];
            parts.push(name);
            match rest.strip_prefix("::") {
                Some(next) => rest = next,
                None => break,
            }
        }
        parts
    };
    let mut paths = Vec::new();
    for (at, _) in line.match_indices("crate::") {
        // `canif_harness::x` is no `crate::` path of this crate, nor is `$crate::`.
        let before = line[..at].chars().last();
        if before.is_some_and(|c| c.is_ascii_alphanumeric() || c == '_' || c == '$') {
            continue;
        }
        paths.push(ident(&line[at + 7..]));
    }
    let mut rest = line;
    while let Some(at) = rest.find("super::") {
        let before = rest[..at].chars().last();
        let mut tail = &rest[at..];
        let mut ups = 0;
        while let Some(next) = tail.strip_prefix("super::") {
            ups += 1;
            tail = next;
        }
        rest = tail;
        if before.is_some_and(|c| c.is_ascii_alphanumeric() || c == '_' || c == ':') {
            continue;
        }
        // A file `a/b.rs` is module `a::b`, and a `mod.rs` its folder's
        // module: either way its `super` is one up.
        let base = from.len().saturating_sub(ups);
        let mut path = from[..base].to_vec();
        path.extend(ident(tail));
        paths.push(path);
    }
    paths
}

/// Every crate's modules at every level: no two siblings use each other,
/// directly or around a circle (a child using its parent, or a parent its
/// child, is not a circle between siblings).
#[test]
fn no_module_at_any_level_imports_one_that_imports_it_back() {
    let mut circles = Vec::new();
    for src in source_dirs() {
        let src = root().join(src);
        let files = rust_files(&src);
        let modules: BTreeSet<Vec<String>> = files.iter().map(|f| module_path(&src, f)).collect();
        // Arrows between siblings, keyed by their parent.
        let mut arrows: BTreeMap<Vec<String>, BTreeMap<String, BTreeSet<String>>> = BTreeMap::new();
        for file in &files {
            let from = module_path(&src, file);
            let text = std::fs::read_to_string(file).unwrap();
            for line in text.lines().filter(|l| !l.trim_start().starts_with("//")) {
                for named in named_paths(line, &from) {
                    let Some(to) = (0..=named.len())
                        .rev()
                        .map(|n| named[..n].to_vec())
                        .find(|prefix| modules.contains(prefix))
                    else {
                        continue;
                    };
                    let common = from.iter().zip(&to).take_while(|(a, b)| a == b).count();
                    if common == from.len() || common == to.len() {
                        continue; // one contains the other
                    }
                    arrows
                        .entry(from[..common].to_vec())
                        .or_default()
                        .entry(from[common].clone())
                        .or_default()
                        .insert(to[common].clone());
                }
            }
        }
        for (parent, level) in &arrows {
            let mut done = BTreeSet::new();
            for start in level.keys() {
                let mut path = Vec::new();
                if let Some(cycle) = find_cycle(start, level, &mut path, &mut done) {
                    circles.push(format!(
                        "{}: in `{}`: {}",
                        src.strip_prefix(root()).unwrap().display(),
                        parent.join("::"),
                        cycle.join(" → ")
                    ));
                }
            }
        }
    }
    assert!(circles.is_empty(), "import circles: {circles:#?}");
}

fn find_cycle(
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
    for next in arrows.get(module).into_iter().flatten() {
        if let Some(cycle) = find_cycle(next, arrows, path, done) {
            return Some(cycle);
        }
    }
    path.pop();
    done.insert(module.to_string());
    None
}
