//! The scenarios of the embedded feature files, one entry per scenario or
//! Examples row, with their tags.

use canif_spec::Side;
use cucumber::gherkin::{Feature, GherkinEnv};

/// One runnable scenario (an outline's Examples row counts once).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ScenarioInfo {
    pub file: String,
    pub feature: String,
    pub name: String,
    /// The line cucumber filters on (an Examples row's line for outlines).
    pub line: usize,
    /// Requirement ids and capabilities from the feature's and scenario's tags.
    pub requirements: Vec<String>,
    pub capabilities: Vec<String>,
    /// Runs without an implementation under test (the manual's tables).
    pub model_only: bool,
    /// Runs once against the soft device; the scenario names its profile.
    pub once: bool,
    /// The profile a `Given the device profile …` step names (outline values filled in).
    pub profile: Option<String>,
    /// An Examples row's values, `column=value, …`.
    pub example: Option<String>,
    /// The side under test: `@plc` features judge a client, the others a device.
    pub side: Side,
    /// Its steps' text, without the keywords (what a client's declaration is
    /// matched against: the interface set up, the traffic made).
    pub steps: Vec<String>,
    /// Its steps as written, keyword first (`Given …`, `And …`), and whether
    /// each is an expected result (a `Then` step or one continuing it), for
    /// the test plan.
    pub written: Vec<(String, bool)>,
}

impl ScenarioInfo {
    /// `feature file: scenario name [row values]`: what reports call it, stable
    /// while lines move.
    pub fn id(&self) -> String {
        match &self.example {
            Some(row) => format!("{}: {} [{row}]", self.file, self.name),
            None => format!("{}: {}", self.file, self.name),
        }
    }
}

/// One runnable row: its line, its tags, the profile it names and its Examples values.
type Row<'a> = (usize, Vec<&'a String>, Option<String>, Option<String>);

/// The profile a scenario's `Given the device profile X` step names, with an
/// outline's `<column>` taken from the row.
fn named_profile(
    scenario: &cucumber::gherkin::Scenario,
    header: Option<&Vec<String>>,
    row: Option<&Vec<String>>,
) -> Option<String> {
    let step = scenario
        .steps
        .iter()
        .find_map(|s| s.value.strip_prefix("the device profile "))?
        .trim();
    match step.strip_prefix('<').and_then(|s| s.strip_suffix('>')) {
        Some(column) => {
            let index = header?.iter().position(|h| h == column)?;
            row?.get(index).cloned()
        }
        None => Some(step.to_string()),
    }
}

/// The embedded catalogue, read once; `None` if it does not load (its own
/// tests say why).
fn embedded_catalogue() -> Option<&'static canif_spec::Catalogue> {
    static CATALOGUE: std::sync::OnceLock<Option<canif_spec::Catalogue>> =
        std::sync::OnceLock::new();
    CATALOGUE
        .get_or_init(|| canif_spec::Catalogue::embedded().ok())
        .as_ref()
}

/// The capabilities a tag can name: those of the catalogue (`spec/capabilities.yaml`).
fn is_capability(tag: &str) -> bool {
    embedded_catalogue().is_some_and(|c| c.capabilities.iter().any(|cap| cap.name == tag))
}

/// The capabilities every requirement in `ids` needs: on a profile without
/// one of them a scenario tagged with `ids` judges nothing it names, so it
/// does not run there (issue 36: fc510x ran the EL6751's PDX scenarios).
fn needed_by_every_requirement(ids: &[String]) -> Vec<String> {
    let Some(catalogue) = embedded_catalogue() else {
        return Vec::new();
    };
    let mut needs = ids
        .iter()
        .filter_map(|id| catalogue.requirement(id))
        .map(|r| r.capabilities.clone());
    let first = needs.next().unwrap_or_default();
    needs.fold(first, |common, caps| {
        common.into_iter().filter(|c| caps.contains(c)).collect()
    })
}

/// The embedded feature parsed, by file name.
pub fn feature(file: &str) -> Option<Feature> {
    let (path, text) = crate::embedded::EMBEDDED
        .iter()
        .find(|(path, _)| *path == file)?;
    let mut feature = Feature::parse(text, GherkinEnv::default()).ok()?;
    feature.path = Some(path.into());
    Some(feature)
}

/// Every scenario of every embedded feature; a feature that does not parse is an error naming it.
pub fn scenarios() -> Result<Vec<ScenarioInfo>, String> {
    let mut list = Vec::new();
    for (path, text) in crate::embedded::EMBEDDED {
        let feature =
            Feature::parse(text, GherkinEnv::default()).map_err(|e| format!("{path}: {e}"))?;
        for scenario in &feature.scenarios {
            let base: Vec<&String> = feature.tags.iter().chain(&scenario.tags).collect();
            // Each runnable row with the tags that apply to it (an Examples block may add its own).
            let mut rows: Vec<Row> = Vec::new();
            for examples in &scenario.examples {
                let tags: Vec<&String> = base.iter().copied().chain(&examples.tags).collect();
                if let Some(table) = &examples.table {
                    rows.extend((1..table.rows.len()).map(|i| {
                        let profile =
                            named_profile(scenario, table.rows.first(), table.rows.get(i));
                        let example = table.rows.first().zip(table.rows.get(i)).map(|(h, r)| {
                            h.iter()
                                .zip(r)
                                .map(|(h, v)| format!("{h}={v}"))
                                .collect::<Vec<_>>()
                                .join(", ")
                        });
                        (table.position.line + i, tags.clone(), profile, example)
                    }));
                }
            }
            if scenario.examples.is_empty() {
                rows.push((
                    scenario.position.line,
                    base.clone(),
                    named_profile(scenario, None, None),
                    None,
                ));
            }
            for (line, tags, profile, example) in rows {
                let requirements: Vec<String> = tags
                    .iter()
                    .filter(|t| t.contains('-'))
                    .map(|t| t.to_string())
                    .collect();
                let mut capabilities: Vec<String> = tags
                    .iter()
                    .filter(|t| is_capability(t))
                    .map(|t| t.to_string())
                    .collect();
                for needed in needed_by_every_requirement(&requirements) {
                    if !capabilities.contains(&needed) {
                        capabilities.push(needed);
                    }
                }
                list.push(ScenarioInfo {
                    file: path.to_string(),
                    feature: feature.name.clone(),
                    name: scenario.name.clone(),
                    line,
                    requirements,
                    capabilities,
                    model_only: tags.iter().any(|t| *t == "model"),
                    once: tags.iter().any(|t| *t == "once"),
                    profile,
                    example,
                    side: if tags.iter().any(|t| *t == "plc") {
                        Side::Plc
                    } else {
                        Side::Device
                    },
                    steps: scenario.steps.iter().map(|s| s.value.clone()).collect(),
                    written: scenario
                        .steps
                        .iter()
                        .map(|s| {
                            (
                                format!("{} {}", s.keyword.trim(), s.value),
                                s.ty == cucumber::gherkin::StepType::Then,
                            )
                        })
                        .collect(),
                });
            }
        }
    }
    Ok(list)
}

/// The feature cut down to the scenario at `line`; for an outline, to the one
/// Examples row at `line`. Cucumber filters before it expands outlines, so a
/// single row is chosen here.
pub fn only(mut feature: Feature, line: usize) -> Option<Feature> {
    feature.rules.clear();
    feature.scenarios.retain(|scenario| {
        scenario.position.line == line
            || scenario.examples.iter().any(|e| {
                e.table.as_ref().is_some_and(|t| {
                    (t.position.line + 1..t.position.line + t.rows.len()).contains(&line)
                })
            })
    });
    let scenario = feature.scenarios.first_mut()?;
    for examples in &mut scenario.examples {
        if let Some(table) = &mut examples.table {
            let first = table.position.line;
            let keep: Vec<Vec<String>> = table
                .rows
                .iter()
                .enumerate()
                .filter(|(i, _)| *i == 0 || first + *i == line)
                .map(|(_, row)| row.clone())
                .collect();
            table.rows = keep;
        }
    }
    scenario
        .examples
        .retain(|e| e.table.as_ref().is_some_and(|t| t.rows.len() > 1));
    Some(feature)
}
