//! `canif probe`: which of the documented choices a device takes, found by
//! running the scenarios that tell them apart once under each value. What
//! it finds is a declaration `canif run --declare @FILE` takes; for a
//! terminal nobody has measured yet it is the first command a lab runs.

use canif_spec::Profile;

use super::iut_kind::IutKind;
use super::scenario::Scenario;
use super::suite::{DeviceCase, Options};
use crate::declare::choices::{Choice, Declared};
use crate::declare::Declaration;
use crate::error::RunError;
use crate::outcome::Outcome;
use crate::run::Cases;

/// One scenario that tells a choice's values apart, on one profile.
#[derive(Debug, Clone)]
pub struct Probed {
    pub choice: Choice,
    pub profile: String,
    pub scenario: String,
    /// The values the device passed the scenario under.
    pub passes: Vec<&'static str>,
    /// Why a run under some value neither passed nor failed (the IUT
    /// broke, refused the interface, …): then nothing is concluded from it.
    pub errors: Vec<String>,
    /// Of those, where the IUT itself broke (it exited, hung, answered
    /// garbage) or the bus did: nothing can be concluded from the whole probe.
    pub broke: Vec<String>,
}

/// What the probes of one choice show.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Finding {
    /// Every probe passed under exactly this value, and none contradicts it.
    Takes(&'static str),
    /// No probe told the values apart (each passed under every one, or none ran).
    Undecided,
    /// Some probe passed under none of the values: the device breaks the
    /// requirement whichever way it is read.
    Neither,
    /// The probes disagree: one passed only under one value, another only
    /// under another.
    Inconsistent,
}

/// Runs each scenario of `profile` that tells a choice's values apart under
/// each of them, with `options` (its selection ignored; the choice probed is
/// declared, the others as `options` declare them).
pub fn probe(kind: &IutKind, profile: &Profile, options: &Options) -> Vec<Probed> {
    let cases = options.cases(profile);
    let mut probes = Vec::new();
    for choice in Choice::ALL {
        let Some(settled_by) = choice.settled_by() else {
            continue;
        };
        // What is declared is judged as declared, not probed.
        if options.declared.value(choice).is_some() {
            continue;
        }
        let settling = cases.iter().filter(|case| match case {
            DeviceCase::Scenario(s) => tells_apart(choice, settled_by, s),
            DeviceCase::Refusals => false,
        });
        for case in settling {
            let mut probed = Probed {
                choice,
                profile: profile.name.clone(),
                scenario: Options::name(case),
                passes: Vec::new(),
                errors: Vec::new(),
                broke: Vec::new(),
            };
            for value in choice.named_values() {
                let mut declared = options.declared;
                declared
                    .declare(&format!("{choice}={value}"))
                    .expect("a choice's own value");
                let under = Options {
                    declared,
                    ..options.clone()
                };
                // Each value tried afresh: nothing learned under another.
                let learned = &mut Default::default();
                match under.run(kind, profile, case.clone(), learned).outcome {
                    Outcome::Pass => probed.passes.push(value),
                    Outcome::Fail(_) => {}
                    Outcome::Error(error) => {
                        if matches!(
                            error,
                            RunError::Iut(_)
                                | RunError::Bus(_)
                                | RunError::Harness(_)
                                | RunError::Skipped(_)
                        ) {
                            probed.broke.push(error.to_string());
                        }
                        probed.errors.push(format!("under {value}: {error}"));
                    }
                }
            }
            probes.push(probed);
        }
    }
    probes
}

/// Whether `scenario` shows which value of `choice` a device takes: it
/// covers the choice's requirement, or, for what a buffered delivery leaves
/// (judged only where declared, so covered only then), it delivers.
fn tells_apart(choice: Choice, settled_by: canif_spec::ReqId, scenario: &Scenario) -> bool {
    match choice {
        Choice::RxIdleCount | Choice::StaleRxSlots => scenario.delivers_buffered(),
        _ => scenario.covers.contains(&settled_by),
    }
}

/// What `probes` show of `choice` together.
pub fn finding(probes: &[Probed], choice: Choice) -> Finding {
    let probes: Vec<&Probed> = probes.iter().filter(|p| p.choice == choice).collect();
    let decided: Vec<&'static str> = probes
        .iter()
        .filter(|p| p.errors.is_empty())
        .filter_map(|p| match p.passes.as_slice() {
            [only] => Some(*only),
            _ => None,
        })
        .collect();
    if probes
        .iter()
        .any(|p| p.errors.is_empty() && p.passes.is_empty())
    {
        return Finding::Neither;
    }
    match decided.split_first() {
        None => Finding::Undecided,
        Some((first, rest)) if rest.iter().all(|a| a == first) => Finding::Takes(first),
        Some(_) => Finding::Inconsistent,
    }
}

/// The declaration the findings make, choice by choice.
pub fn declaration(probes: &[Probed]) -> Declared {
    let mut declared = Declared::default();
    for choice in Choice::ALL {
        if let Finding::Takes(value) = finding(probes, choice) {
            declared
                .declare(&format!("{choice}={value}"))
                .expect("a choice's own value");
        }
    }
    declared
}

#[cfg(test)]
mod tests {
    use super::*;
    const WIRE_IN: &str = "wire-in-queue";
    const WIRE_OUT: &str = "wire-outside-queue";

    fn probed(passes: &[&'static str]) -> Probed {
        Probed {
            choice: Choice::TxQueueAccounting,
            profile: "p".into(),
            scenario: "s".into(),
            passes: passes.to_vec(),
            errors: Vec::new(),
            broke: Vec::new(),
        }
    }

    #[test]
    fn a_finding_needs_a_probe_that_tells_the_choices_apart_and_none_against_it() {
        assert_eq!(finding(&[], Choice::TxQueueAccounting), Finding::Undecided);
        let both = probed(&[WIRE_OUT, WIRE_IN]);
        assert_eq!(
            finding(std::slice::from_ref(&both), Choice::TxQueueAccounting),
            Finding::Undecided
        );
        let inside = probed(&[WIRE_IN]);
        assert_eq!(
            finding(&[both, inside.clone()], Choice::TxQueueAccounting),
            Finding::Takes(WIRE_IN)
        );
        let outside = probed(&[WIRE_OUT]);
        assert_eq!(
            finding(&[inside.clone(), outside], Choice::TxQueueAccounting),
            Finding::Inconsistent
        );
        assert_eq!(
            finding(&[inside.clone(), probed(&[])], Choice::TxQueueAccounting),
            Finding::Neither
        );
        let broke = Probed {
            errors: vec!["under wire-in-queue: the IUT broke".into()],
            ..probed(&[])
        };
        assert_eq!(
            finding(&[inside.clone(), broke], Choice::TxQueueAccounting),
            Finding::Takes(WIRE_IN)
        );
        // Another choice's probes say nothing of this one.
        let dropped = Probed {
            choice: Choice::OversizeBatch,
            ..probed(&["drops-the-batch"])
        };
        assert_eq!(
            finding(std::slice::from_ref(&dropped), Choice::TxQueueAccounting),
            Finding::Undecided
        );
        let declared = declaration(&[inside, dropped]);
        assert_eq!(
            declared.lines(),
            [
                "tx-queue-accounting=wire-in-queue",
                "oversize-batch=drops-the-batch"
            ]
        );
    }
}
