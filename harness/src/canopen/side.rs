//! The CANopen node checks (002, 004) as a side of the suite, beside the
//! device and the client: the node is what is under test, the harness plays
//! the master. Selection, progress, fail-fast and the reports are the ones
//! every side has (`crate::run`).
//!
//! The checks are one script from the node's boot state, each needing the
//! state the one before left (started, heartbeat set, stopped, reset): the
//! side runs the script once per node it opens, and each case is one check
//! of it. A node that cannot be opened is an error of every case.

use std::sync::Mutex;

use canif_model::canopen::coupler::{Coupler, CouplerFault};
use canif_model::canopen::NodeId;
use canif_model::Nanos;
use canif_spec::{Profile, ReqId, Scope, Suite};

use super::checks::{check_node, NodeCheck};
use super::CanNode;
use crate::error::{IutCause, IutError, RunError};
use crate::outcome::{Failure, Outcome, ScenarioRun};
use crate::run::{Cases, Selection};
use crate::verdict::Reach;

/// The node the checks are sent to.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum NodeTarget {
    /// The model's coupler (2 digital, 4 analog channels, as the quick start
    /// has it), in virtual time, with a deliberate defect if asked.
    Simulated {
        node: NodeId,
        fault: Option<CouplerFault>,
    },
    /// A node on a SocketCAN interface, in real time.
    #[cfg(feature = "socketcan")]
    SocketCan {
        interface: String,
        node: NodeId,
        /// How long an SDO or guarding answer may take.
        answer_timeout: std::time::Duration,
    },
}

impl NodeTarget {
    pub fn node(&self) -> NodeId {
        match self {
            NodeTarget::Simulated { node, .. } => *node,
            #[cfg(feature = "socketcan")]
            NodeTarget::SocketCan { node, .. } => *node,
        }
    }

    /// What a report calls it.
    pub fn describe(&self) -> String {
        match self {
            NodeTarget::Simulated { node, fault } => format!(
                "simulated coupler, node {}{}",
                node.get(),
                fault.map_or(String::new(), |f| format!(" with {}", f.name()))
            ),
            #[cfg(feature = "socketcan")]
            NodeTarget::SocketCan {
                interface, node, ..
            } => format!("node {} on {interface}", node.get()),
        }
    }

    /// How far a heartbeat may be from its due time: nothing in virtual
    /// time; on a real bus, the poll step and scheduling jitter.
    fn tolerance(&self) -> Nanos {
        match self {
            NodeTarget::Simulated { .. } => 0,
            #[cfg(feature = "socketcan")]
            NodeTarget::SocketCan { .. } => 30_000_000,
        }
    }

    /// Whether the node can be reached at all (the interface exists, a
    /// socket opens): what a run checks once before it starts.
    pub fn reachable(&self) -> Result<(), IutError> {
        self.open().map(drop)
    }

    fn open(&self) -> Result<Box<dyn CanNode>, IutError> {
        match self {
            NodeTarget::Simulated { node, fault } => {
                let mut coupler = Coupler::new(*node, 2, 4);
                if let Some(fault) = fault {
                    coupler.inject(*fault);
                }
                Ok(Box::new(coupler))
            }
            #[cfg(feature = "socketcan")]
            NodeTarget::SocketCan {
                interface,
                node,
                answer_timeout,
            } => {
                let mut remote = super::SocketCanNode::open(interface, *node)
                    .map_err(|e| IutError::new(IutCause::NotStarted, e))?;
                remote.answer_timeout = *answer_timeout;
                Ok(Box::new(remote))
            }
        }
    }
}

/// One check of the script: its name and the requirements it exercises.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct NodeCase {
    pub name: &'static str,
    pub covers: Vec<ReqId>,
}

/// What the script found on one node: its checks, or why it could not run.
type Script = (NodeTarget, Result<Vec<NodeCheck>, IutError>);

/// The CANopen suite's side.
#[derive(Debug, Default)]
pub struct CanopenSide {
    pub selection: Selection,
    /// The run's seed, for its report (the script itself draws nothing).
    pub seed: u64,
    /// The script's checks on the node opened last, run once.
    script: Mutex<Option<Script>>,
}

impl CanopenSide {
    pub fn new(selection: Selection) -> Self {
        CanopenSide {
            selection,
            seed: 1,
            script: Mutex::new(None),
        }
    }

    /// The script's result on `target`, run at the first case that asks.
    fn checks(&self, target: &NodeTarget) -> Result<Vec<NodeCheck>, IutError> {
        let mut script = self.script.lock().unwrap_or_else(|e| e.into_inner());
        if let Some((ran_on, result)) = script.as_ref() {
            if ran_on == target {
                return result.clone();
            }
        }
        let result = target
            .open()
            .map(|mut node| check_node(node.as_mut(), target.node(), target.tolerance()));
        *script = Some((target.clone(), result.clone()));
        result
    }
}

/// The checks' names and requirements, as the script on a simulated coupler
/// lists them (the script is the same on every node).
fn script_cases() -> Vec<NodeCase> {
    let node = NodeId::new(5).expect("5 is a node id");
    check_node(&mut Coupler::new(node, 2, 4), node, 0)
        .into_iter()
        .map(|check| NodeCase {
            name: check.name,
            covers: check.requirements.iter().map(|id| ReqId::new(id)).collect(),
        })
        .collect()
}

impl Cases for CanopenSide {
    type UnderTest = NodeTarget;
    type Case = NodeCase;
    const UNDER_TEST: &'static str = "the node";
    const SIDE: canif_spec::Side = canif_spec::Side::Device;
    /// Nothing carries from one case to the next: each starts afresh.
    type Learned = ();

    fn choices((): ()) -> Vec<crate::declare::ChoiceEntry> {
        Vec::new()
    }
    const SUITE: Suite = Suite::Canopen;

    fn cases(&self, _: &Profile) -> Vec<NodeCase> {
        script_cases()
    }

    fn name(case: &NodeCase) -> String {
        case.name.to_string()
    }

    fn covers(case: &NodeCase) -> &[ReqId] {
        &case.covers
    }

    fn run(&self, target: &NodeTarget, _: &Profile, case: NodeCase, (): &mut ()) -> ScenarioRun {
        let outcome = match self.checks(target) {
            Err(error) => Outcome::Error(RunError::Iut(error)),
            Ok(checks) => match checks.iter().find(|check| check.name == case.name) {
                None => Outcome::Error(RunError::Iut(IutError::new(
                    IutCause::HarnessBug,
                    format!("the script ran no check `{}`", case.name),
                ))),
                Some(check) => match &check.outcome {
                    Ok(()) => Outcome::Pass,
                    Err(why) => Outcome::Fail(Box::new(Failure::stopped(
                        (
                            check.blamed.iter().map(|id| ReqId::new(id)).collect(),
                            case.name.to_string(),
                        ),
                        "the node's answer".into(),
                        ("what 002 and 004 say a node answers".into(), why.clone()),
                    ))),
                },
            },
        };
        ScenarioRun::ended(case.name.to_string(), case.covers, outcome)
    }

    fn selection(&self) -> &Selection {
        &self.selection
    }

    fn fail_fast(&self) -> bool {
        true
    }

    fn reach(&self, _: &Profile, _: &[ScenarioRun]) -> Reach {
        Reach {
            scope: Scope {
                side: canif_spec::Side::Device,
                suite: Suite::Canopen,
            },
            here: super::node_check_ids()
                .iter()
                .map(|id| id.to_string())
                .collect(),
            left_out: self.selection.not_run(),
            ..Reach::default()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::run::run_profile;

    fn profile() -> Profile {
        canif_spec::Catalogue::embedded().unwrap().profiles[0].clone()
    }

    fn simulated(fault: Option<CouplerFault>) -> NodeTarget {
        NodeTarget::Simulated {
            node: NodeId::new(5).unwrap(),
            fault,
        }
    }

    #[test]
    fn the_coupler_passes_every_check_and_a_faulty_one_fails_the_ones_it_breaks() {
        let side = CanopenSide::default();
        let good = run_profile(&profile(), &simulated(None), &side, |_| {});
        assert!(!good.runs.is_empty());
        assert!(
            good.runs.iter().all(|r| r.outcome == Outcome::Pass),
            "{:?}",
            good.runs
        );
        let side = CanopenSide::default();
        let faulty = run_profile(
            &profile(),
            &simulated(Some(CouplerFault::NoAbort)),
            &side,
            |_| {},
        );
        let failed: Vec<_> = faulty
            .runs
            .iter()
            .filter(|r| matches!(r.outcome, Outcome::Fail(_)))
            .collect();
        assert!(!failed.is_empty(), "a coupler that never aborts passed");
        assert!(
            failed
                .iter()
                .all(|r| r.covers.iter().any(|id| id.as_str() == "SDO-007")),
            "{failed:?}"
        );
    }

    #[test]
    fn the_selection_runs_only_the_checks_it_names() {
        let side = CanopenSide::new(Selection {
            scenarios: vec!["heartbeat".into()],
            requirements: Vec::new(),
            shard: None,
        });
        let run = run_profile(&profile(), &simulated(None), &side, |_| {});
        assert!(!run.runs.is_empty());
        assert!(run.runs.iter().all(|r| r.scenario.contains("heartbeat")));
    }
}
