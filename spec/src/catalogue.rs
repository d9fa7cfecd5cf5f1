//! Loading and validating the catalogue.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

use serde::Deserialize;

use crate::error::{SpecError, SpecErrors};
use crate::lines::{line_of, LineIndex};
use crate::profile::Profile;
use crate::scope::{Side, Suite};
pub use crate::source::Source;

/// How firmly a requirement is grounded (see shared/RULINGS.md).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Status {
    /// A document says it.
    Normative,
    /// Follows from what a document says, or from the standard it cites.
    Derived,
    /// We decided; the decision is written down.
    Assumption,
}

/// How a requirement is checked.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Verification {
    /// By tests, scenarios or properties that name its id.
    #[default]
    Test,
    /// Not by running anything; `reason` says why.
    Inspection,
    /// By the reference model's own tests and `@model` scenarios: a statement
    /// of the documents' tables, formulas or samples that no implementation's
    /// images or bus show; `reason` says what it is.
    Model,
}

/// One testable statement.
#[derive(Debug, Clone, PartialEq, Eq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Requirement {
    pub id: String,
    pub statement: String,
    pub source: Source,
    pub status: Status,
    #[serde(default)]
    pub capabilities: Vec<String>,
    #[serde(default)]
    pub rulings: Vec<String>,
    #[serde(default)]
    pub related: Vec<String>,
    #[serde(default)]
    pub notes: Option<String>,
    #[serde(default)]
    pub verification: Verification,
    /// Why it is not checked by a test (with `verification: inspection`).
    #[serde(default)]
    pub reason: Option<String>,
    /// Errata: what the document prints.
    #[serde(default)]
    pub document_says: Option<String>,
    /// Errata: the behaviour the model implements instead.
    #[serde(default)]
    pub corrected: Option<String>,
    /// Which file it was loaded from (not in the YAML).
    #[serde(skip)]
    pub file: String,
    /// The side its area binds (not in the requirement's YAML: the area's `side`).
    #[serde(skip)]
    pub side: Side,
    /// The suite that judges it (the area's `suite`).
    #[serde(skip)]
    pub suite: Suite,
    /// The line of its `id:` (not in the YAML).
    #[serde(skip)]
    pub line: usize,
}

impl Requirement {
    /// Must a test, scenario or property name this requirement?
    pub fn needs_coverage(&self) -> bool {
        self.verification == Verification::Test
            && matches!(self.status, Status::Normative | Status::Derived)
    }

    pub fn is_erratum(&self) -> bool {
        self.document_says.is_some()
    }
}

/// One requirements file: an area of the interface.
#[derive(Debug, Clone, PartialEq, Eq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Area {
    pub area: String,
    pub title: String,
    /// The side the area's requirements bind; `device` when left out.
    #[serde(default)]
    pub side: Side,
    /// The suite that judges them; `interface` when left out.
    #[serde(default)]
    pub suite: Suite,
    pub requirements: Vec<Requirement>,
    #[serde(skip)]
    pub file: String,
}

#[derive(Debug, Clone, PartialEq, Eq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SourceDocument {
    pub file: String,
    pub title: String,
    /// Which document wins where this one and another say different things.
    #[serde(default)]
    pub precedence: Option<String>,
}

#[derive(Debug, Clone, PartialEq, Eq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Capability {
    pub name: String,
    pub description: String,
}

#[derive(Debug, Clone, PartialEq, Eq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Ruling {
    pub id: String,
    pub title: String,
    /// The ruling as `shared/RULINGS.md` words it (what the documents say, the decision).
    #[serde(default)]
    pub text: Option<String>,
}

/// The whole catalogue, validated.
#[derive(Debug, Clone)]
pub struct Catalogue {
    pub sources: Vec<SourceDocument>,
    pub capabilities: Vec<Capability>,
    pub rulings: Vec<Ruling>,
    pub areas: Vec<Area>,
    pub profiles: Vec<Profile>,
    /// SHA-256 (hex) over the files this catalogue was read from, each named
    /// as in `spec/` (`sources.yaml`, `requirements/…`): the same files give
    /// the same hash whether embedded or read with `--spec`.
    pub sha256: String,
}

/// A file's name as in `spec/`, wherever it was read from.
fn spec_name(path: &str) -> String {
    let parts: Vec<&str> = path.rsplit(['/', '\\']).take(2).collect();
    match parts.as_slice() {
        [name, dir] if *dir == "requirements" || *dir == "profiles" => format!("{dir}/{name}"),
        [name, ..] => name.to_string(),
        [] => path.to_string(),
    }
}

fn files_sha256(files: &[(String, String)]) -> String {
    use sha2::{Digest, Sha256};
    let mut named: Vec<(String, &str)> = files
        .iter()
        .map(|(path, text)| (spec_name(path), text.as_str()))
        .collect();
    named.sort();
    let mut hasher = Sha256::new();
    for (name, text) in named {
        hasher.update(name.as_bytes());
        hasher.update([0]);
        hasher.update(text.as_bytes());
        hasher.update([0]);
    }
    hasher
        .finalize()
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

/// The most a catalogue file may hold: far above any real one (the embedded
/// catalogue's largest file is under 30 KB), far below what exhausts memory.
pub(crate) const MAX_FILE_BYTES: u64 = 16 << 20;

/// How deeply flow collections (`[…]`, `{…}`) may nest.
const MAX_FLOW_DEPTH: usize = 64;

/// Checks a file's text before the YAML parser sees it: nesting the parser
/// would take quadratic time over, and anchors, whose aliases multiply text.
fn precheck(text: &str) -> Result<(), (usize, String)> {
    let (mut depth, mut line) = (0usize, 1usize);
    let mut quote: Option<char> = None;
    // Where a node may begin: after `: `, a `- ` item, `[`, `{` or `,`; an
    // `&` or `*` there is an anchor or an alias, anywhere else it is text.
    let (mut node_start, mut line_start, mut previous) = (true, true, '\n');
    for c in text.chars() {
        if c == '\n' {
            line += 1;
            (node_start, line_start, previous) = (true, true, c);
            if quote == Some('#') {
                quote = None;
            }
            continue;
        }
        if let Some(q) = quote {
            if q != '#' && c == q {
                quote = None;
                node_start = false;
            }
            previous = c;
            continue;
        }
        match c {
            ' ' | '\t' => {
                if previous == ':' || (previous == '-' && line_start) {
                    node_start = true;
                }
                previous = c;
                continue;
            }
            '#' if previous.is_whitespace() => quote = Some('#'),
            '"' | '\'' if node_start => quote = Some(c),
            '[' | '{' => {
                depth += 1;
                if depth > MAX_FLOW_DEPTH {
                    return Err((line, format!("collections nest deeper than {MAX_FLOW_DEPTH} levels")));
                }
                (node_start, previous) = (true, c);
                continue;
            }
            ']' | '}' => depth = depth.saturating_sub(1),
            ',' if depth > 0 => {
                (node_start, previous) = (true, c);
                continue;
            }
            '&' | '*' if node_start => {
                return Err((
                    line,
                    "anchors and aliases (& and *) are not allowed in the catalogue: an alias repeats text without bound"
                        .into(),
                ))
            }
            '-' if line_start => {
                previous = c;
                continue;
            }
            _ => {}
        }
        node_start = false;
        line_start = false;
        previous = c;
    }
    Ok(())
}

fn parse<T: for<'de> Deserialize<'de>>(
    file: &str,
    text: &str,
    errors: &mut Vec<SpecError>,
) -> Option<T> {
    if let Err((line, message)) = precheck(text) {
        errors.push(SpecError {
            file: file.to_string(),
            line: Some(line),
            field: String::new(),
            message,
        });
        return None;
    }
    match serde_yaml::from_str(text) {
        Ok(value) => Some(value),
        Err(error) => {
            let line = error.location().map(|location| location.line());
            // serde_yaml puts the field path in front: "requirements[2].status: unknown variant …"
            let text = error.to_string();
            let text = text.split(" at line ").next().unwrap_or(&text).to_string();
            let (mut field, message) = match text.split_once(": ") {
                Some((path, rest)) if !path.contains(' ') => (path.to_string(), rest.to_string()),
                _ => (String::new(), text),
            };
            // A top-level unknown key has no path in front: name the key itself.
            if let Some(key) = message
                .strip_prefix("unknown field `")
                .and_then(|rest| rest.split('`').next())
            {
                field = if field.is_empty() {
                    key.to_string()
                } else {
                    format!("{field}.{key}")
                };
            }
            errors.push(SpecError {
                file: file.to_string(),
                line,
                field,
                message,
            });
            None
        }
    }
}

/// A catalogue file's text: a regular file (not a FIFO or a device, which
/// could block for ever) of at most [`MAX_FILE_BYTES`], UTF-8, a leading BOM
/// dropped.
fn read_file(path: &Path) -> Result<String, String> {
    let metadata = std::fs::metadata(path).map_err(|e| format!("cannot read: {e}"))?;
    if !metadata.is_file() {
        return Err("not a regular file (a FIFO, device or folder is not read)".into());
    }
    if metadata.len() > MAX_FILE_BYTES {
        return Err(format!(
            "{} bytes: a catalogue file holds at most {MAX_FILE_BYTES}",
            metadata.len()
        ));
    }
    let bytes = std::fs::read(path).map_err(|e| format!("cannot read: {e}"))?;
    let text = String::from_utf8(bytes)
        .map_err(|e| format!("not UTF-8 (at byte {})", e.utf8_error().valid_up_to()))?;
    Ok(match text.strip_prefix('\u{FEFF}') {
        Some(rest) => rest.to_string(),
        None => text,
    })
}

impl Catalogue {
    /// The catalogue built into this binary.
    pub fn embedded() -> Result<Self, SpecErrors> {
        let files: Vec<(String, String)> = crate::embedded::EMBEDDED
            .iter()
            .map(|(path, text)| (path.to_string(), text.to_string()))
            .collect();
        Self::from_files(&files)
    }

    /// A catalogue folder of the same shape as `spec/`: `sources.yaml`,
    /// `capabilities.yaml`, `rulings.yaml`, `requirements/*.yaml`, `profiles/*.yaml`.
    pub fn load_dir(dir: &Path) -> Result<Self, SpecErrors> {
        let mut files = Vec::new();
        let mut errors = Vec::new();
        let mut read = |path: &Path, files: &mut Vec<(String, String)>| match read_file(path) {
            Ok(text) => files.push((path.display().to_string(), text)),
            Err(message) => errors.push(SpecError {
                file: path.display().to_string(),
                line: None,
                field: String::new(),
                message,
            }),
        };
        for name in ["sources.yaml", "capabilities.yaml", "rulings.yaml"] {
            read(&dir.join(name), &mut files);
        }
        for sub in ["requirements", "profiles"] {
            let mut paths: Vec<_> = match std::fs::read_dir(dir.join(sub)) {
                Ok(entries) => entries
                    .filter_map(|entry| entry.ok().map(|entry| entry.path()))
                    .filter(|path| path.extension().is_some_and(|ext| ext == "yaml"))
                    .collect(),
                Err(error) => {
                    read(&dir.join(sub), &mut Vec::new());
                    let _ = error;
                    Vec::new()
                }
            };
            paths.sort();
            for path in paths {
                read(&path, &mut files);
            }
        }
        if !errors.is_empty() {
            return Err(SpecErrors(errors));
        }
        Self::from_files(&files)
    }

    /// Parses and validates files given as (path, text). Paths decide the kind:
    /// `…sources.yaml`, `…capabilities.yaml`, `…rulings.yaml`, `…requirements/…`,
    /// `…profiles/…`.
    pub fn from_files(files: &[(String, String)]) -> Result<Self, SpecErrors> {
        let mut errors = Vec::new();
        let mut sources = Vec::new();
        let mut capabilities = Vec::new();
        let mut rulings = Vec::new();
        let mut areas = Vec::new();
        let mut profiles = Vec::new();
        let mut texts = BTreeMap::new();
        for (path, text) in files {
            texts.insert(path.clone(), text.clone());
            let unix = path.replace('\\', "/");
            if unix.ends_with("sources.yaml") {
                sources.extend(
                    parse::<Vec<SourceDocument>>(path, text, &mut errors).unwrap_or_default(),
                );
            } else if unix.ends_with("capabilities.yaml") {
                capabilities
                    .extend(parse::<Vec<Capability>>(path, text, &mut errors).unwrap_or_default());
            } else if unix.ends_with("rulings.yaml") {
                rulings.extend(parse::<Vec<Ruling>>(path, text, &mut errors).unwrap_or_default());
            } else if unix.contains("requirements/") {
                if let Some(mut area) = parse::<Area>(path, text, &mut errors) {
                    area.file = path.clone();
                    let lines = LineIndex::new(text);
                    let mut from = 1;
                    for requirement in &mut area.requirements {
                        requirement.file = path.clone();
                        requirement.side = area.side;
                        requirement.suite = area.suite;
                        requirement.line = lines
                            .find(&format!("id: {}", requirement.id), from)
                            .unwrap_or(0);
                        from = requirement.line.max(1) + 1;
                    }
                    areas.push(area);
                }
            } else if unix.contains("profiles/") {
                if let Some(mut profile) = parse::<Profile>(path, text, &mut errors) {
                    profile.file = path.clone();
                    profiles.push(profile);
                }
            } else {
                errors.push(SpecError {
                    file: path.clone(),
                    line: None,
                    field: String::new(),
                    message: "not a catalogue file (expected sources, capabilities, rulings, requirements/ or profiles/)".into(),
                });
            }
        }
        let catalogue = Catalogue {
            sources,
            capabilities,
            rulings,
            areas,
            profiles,
            sha256: files_sha256(files),
        };
        catalogue.validate(&texts, &mut errors);
        if errors.is_empty() {
            Ok(catalogue)
        } else {
            Err(SpecErrors(errors))
        }
    }

    fn validate(&self, texts: &BTreeMap<String, String>, errors: &mut Vec<SpecError>) {
        let known_sources: BTreeSet<&str> = self.sources.iter().map(|s| s.file.as_str()).collect();
        let known_capabilities: BTreeSet<&str> =
            self.capabilities.iter().map(|c| c.name.as_str()).collect();
        let known_rulings: BTreeSet<&str> = self.rulings.iter().map(|r| r.id.as_str()).collect();
        let all_ids: BTreeSet<&str> = self.requirements().map(|r| r.id.as_str()).collect();
        let mut first_seen: BTreeMap<&str, &Requirement> = BTreeMap::new();
        let lines: BTreeMap<&str, LineIndex> = texts
            .iter()
            .map(|(file, text)| (file.as_str(), LineIndex::new(text)))
            .collect();
        let nowhere = LineIndex::new("");

        for requirement in self.requirements() {
            let index = lines.get(requirement.file.as_str()).unwrap_or(&nowhere);
            let mut error = |field: &str, needle: &str, message: String| {
                let line = index
                    .find(needle, requirement.line)
                    .or(Some(requirement.line).filter(|&l| l > 0));
                errors.push(SpecError {
                    file: requirement.file.clone(),
                    line,
                    field: format!("{}.{field}", requirement.id),
                    message,
                });
            };
            if !valid_id(&requirement.id) {
                error("id", &requirement.id, format!("`{}` is not an id (upper-case words and digits joined by '-', e.g. HS-TX-003)", requirement.id));
            }
            if let Some(first) = first_seen.insert(&requirement.id, requirement) {
                error(
                    "id",
                    &requirement.id,
                    format!("duplicate id, first at {}:{}", first.file, first.line),
                );
            }
            if requirement.statement.trim().is_empty() {
                error("statement", "statement:", "is empty".into());
            }
            if !known_sources.contains(requirement.source.file.as_str()) {
                error(
                    "source.file",
                    &requirement.source.file,
                    format!("`{}` is not in sources.yaml", requirement.source.file),
                );
            }
            for capability in &requirement.capabilities {
                if !known_capabilities.contains(capability.as_str()) {
                    error(
                        "capabilities",
                        capability,
                        format!("unknown capability `{capability}` (see capabilities.yaml)"),
                    );
                }
            }
            for ruling in &requirement.rulings {
                if !known_rulings.contains(ruling.as_str()) {
                    error(
                        "rulings",
                        ruling,
                        format!("unknown ruling `{ruling}` (see rulings.yaml)"),
                    );
                }
            }
            for related in &requirement.related {
                if !all_ids.contains(related.as_str()) {
                    error(
                        "related",
                        related,
                        format!("`{related}` names no requirement"),
                    );
                }
            }
            match (requirement.verification, &requirement.reason) {
                (Verification::Inspection | Verification::Model, None) => error(
                    "reason",
                    "verification:",
                    "inspection and model verification need a reason".into(),
                ),
                (Verification::Test, Some(_)) => error(
                    "reason",
                    "reason:",
                    "a reason belongs to `verification: inspection` or `model`".into(),
                ),
                _ => {}
            }
            if requirement.document_says.is_some() != requirement.corrected.is_some() {
                error(
                    "corrected",
                    "document_says:",
                    "an erratum names both `document_says` and `corrected`".into(),
                );
            }
        }
        for area in &self.areas {
            if area.requirements.is_empty() {
                errors.push(SpecError {
                    file: area.file.clone(),
                    line: Some(1),
                    field: "requirements".into(),
                    message: "no requirements".into(),
                });
            }
        }
        let mut profile_names = BTreeMap::new();
        for profile in &self.profiles {
            let text = texts.get(&profile.file).map(String::as_str).unwrap_or("");
            if let Some(first) = profile_names.insert(profile.name.as_str(), &profile.file) {
                errors.push(SpecError {
                    file: profile.file.clone(),
                    line: line_of(text, "name:", 1),
                    field: "name".into(),
                    message: format!(
                        "duplicate profile name `{}`, first in {first}",
                        profile.name
                    ),
                });
            }
            profile.validate(text, &known_capabilities, &known_sources, errors);
        }
    }

    /// Every requirement, in file order.
    pub fn requirements(&self) -> impl Iterator<Item = &Requirement> {
        self.areas.iter().flat_map(|area| area.requirements.iter())
    }

    pub fn requirement(&self, id: &str) -> Option<&Requirement> {
        self.requirements().find(|r| r.id == id)
    }

    pub fn profile(&self, name: &str) -> Option<&Profile> {
        self.profiles.iter().find(|p| p.name == name)
    }

    /// The names of the profiles that are EtherCAT terminals.
    pub fn terminal_names(&self) -> Vec<&str> {
        let terminals = self.profiles.iter().filter(|p| p.ethercat.is_some());
        terminals.map(|p| p.name.as_str()).collect()
    }
}

fn valid_id(id: &str) -> bool {
    !id.is_empty()
        && id.split('-').all(|part| {
            !part.is_empty()
                && part
                    .chars()
                    .all(|c| c.is_ascii_uppercase() || c.is_ascii_digit())
        })
        && id.starts_with(|c: char| c.is_ascii_uppercase())
}
