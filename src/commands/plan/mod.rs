//! `canif spec plan`: the test specification a certification body publishes
//! before it tests, generated from what canif runs: the catalogue (every
//! requirement, its source and rulings), the cases each side's run has on
//! each profile (lockstep scenarios, the refusal grid, the Gherkin scenarios
//! with their steps), and the faults that prove a check can fail. Written as
//! Markdown (`markdown.rs`) and as HTML rendered from it by pulldown-cmark.

mod markdown;

use std::collections::BTreeMap;
use std::path::Path;
use std::process::ExitCode;

use canif_features::ScenarioInfo;
use canif_harness::run::Cases;
use canif_spec::{Catalogue, Side as Role};

use crate::stop::{stop, Stop};
use canif_runner::Plan;

/// One case of a side's run, with the profiles it runs on.
pub(crate) struct Case {
    pub role: Role,
    /// The CAN interface's suite, or the CANopen node checks'.
    pub suite: canif_spec::Suite,
    pub name: String,
    pub covers: Vec<String>,
    pub profiles: Vec<String>,
    /// A Gherkin scenario's steps; `None` for a lockstep case.
    pub gherkin: Option<ScenarioInfo>,
}

/// Everything the plan says, gathered once.
pub(crate) struct TestPlan<'c> {
    pub catalogue: &'c Catalogue,
    pub cases: Vec<Case>,
    /// Requirement id → the faults whose runs fail it (`softdevice --fault X`, …).
    pub faults: BTreeMap<String, Vec<String>>,
}

impl<'c> TestPlan<'c> {
    pub(crate) fn gather(catalogue: &'c Catalogue) -> Result<Self, Stop> {
        let mut cases = Vec::new();
        let profiles: Vec<_> = catalogue.profiles.iter().collect();
        add_cases(
            &mut cases,
            Plan::new(
                profiles.clone(),
                canif_harness::device::Options::default(),
                None,
            )?,
        );
        add_cases(
            &mut cases,
            Plan::new(
                profiles.clone(),
                canif_harness::client::suite::ClientOptions::new(1),
                None,
            )?,
        );
        add_cases(
            &mut cases,
            Plan::new(
                profiles,
                canif_harness::canopen::side::CanopenSide::new(Default::default()),
                None,
            )?,
        );
        let mut faults: BTreeMap<String, Vec<String>> = BTreeMap::new();
        for (fault, ids) in canif_harness::device::kill_table::KILL_TABLE {
            for id in ids {
                faults
                    .entry(id.to_string())
                    .or_default()
                    .push(format!("device fault `{}`", fault.name()));
            }
        }
        for (fault, ids) in canif_harness::client::kill_table::KILL_TABLE {
            for id in *ids {
                faults
                    .entry(id.to_string())
                    .or_default()
                    .push(format!("client fault `{}`", fault.name()));
            }
        }
        Ok(TestPlan {
            catalogue,
            cases,
            faults,
        })
    }

    /// The cases that check requirement `id`.
    pub(crate) fn cases_of<'p>(&'p self, id: &'p str) -> impl Iterator<Item = &'p Case> + 'p {
        self.cases
            .iter()
            .filter(move |c| c.covers.iter().any(|c| c == id))
    }
}

/// A side's cases, each once with every profile it runs on.
fn add_cases<S: Cases>(cases: &mut Vec<Case>, plan: Plan<'_, S>) {
    let gherkin: BTreeMap<String, &ScenarioInfo> =
        plan.gherkin.iter().map(|(_, s)| (s.id(), s)).collect();
    for (profile, name, covers) in plan.candidates() {
        let (role, suite) = (S::SIDE, S::SUITE);
        match cases
            .iter_mut()
            .find(|c| c.role == role && c.suite == suite && c.name == name)
        {
            Some(case) => {
                if !case.profiles.contains(&profile) {
                    case.profiles.push(profile);
                }
                for id in covers {
                    if !case.covers.contains(&id) {
                        case.covers.push(id);
                    }
                }
            }
            None => cases.push(Case {
                role,
                suite,
                gherkin: gherkin.get(&name).map(|s| (*s).clone()),
                name,
                covers,
                profiles: vec![profile],
            }),
        }
    }
}

/// `canif spec plan --out DIR`: writes `test-plan.md` and `test-plan.html`.
pub(crate) fn write(catalogue: &Catalogue, dir: &Path, out: &mut String) -> Result<ExitCode, Stop> {
    let plan = TestPlan::gather(catalogue)?;
    let text = markdown::markdown(&plan);
    std::fs::create_dir_all(dir).map_err(|e| stop!("{}: cannot create: {e}", dir.display()))?;
    let md = dir.join("test-plan.md");
    let html = dir.join("test-plan.html");
    for (path, body) in [(&md, text.clone()), (&html, markdown::html(&text))] {
        std::fs::write(path, body).map_err(|e| stop!("{}: cannot write: {e}", path.display()))?;
    }
    outln!(
        out,
        "the test plan: {} requirements, {} cases on {} profiles\n  {}\n  {}",
        catalogue.requirements().count(),
        plan.cases.len(),
        catalogue.profiles.len(),
        md.display(),
        html.display()
    );
    Ok(ExitCode::SUCCESS)
}
