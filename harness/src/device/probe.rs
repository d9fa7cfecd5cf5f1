//! `canif probe`: which of the documented choices a device takes, found by
//! running the scenarios that tell them apart once under each choice. What
//! it finds is a declaration `canif run --declare @FILE` takes; for a
//! terminal nobody has measured yet it is the first command a lab runs.

use canif_model::config::TxQueueAccounting;
use canif_spec::Profile;

use super::choices::{Declared, TX_QUEUE_ACCOUNTING_SETTLED_BY};
use super::iut_kind::IutKind;
use super::suite::{DeviceCase, Options};
use crate::outcome::Outcome;
use crate::run::Side;

/// One scenario that tells the send queue's accountings apart, on one profile.
#[derive(Debug, Clone)]
pub struct Probed {
    pub profile: String,
    pub scenario: String,
    /// The accountings the device passed the scenario under.
    pub passes: Vec<TxQueueAccounting>,
    /// Why a run under some accounting neither passed nor failed (the IUT
    /// broke, refused the interface, …): then nothing is concluded from it.
    pub errors: Vec<String>,
}

/// What the probes of a device show.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Finding {
    /// Every probe passed under exactly this choice, and none contradicts it.
    Takes(TxQueueAccounting),
    /// No probe told the choices apart (each passed under both, or none ran).
    Undecided,
    /// Some probe passed under none of the choices: the device breaks the
    /// requirement whichever way it is read.
    Neither,
    /// The probes disagree: one passed only under one choice, another only
    /// under the other.
    Inconsistent,
}

/// Runs each scenario of `profile` that tells the accountings apart under
/// each of them, with `options` (its selection and declarations ignored).
pub fn probe(kind: &IutKind, profile: &Profile, options: &Options) -> Vec<Probed> {
    let settling = |case: &DeviceCase| matches!(case, DeviceCase::Scenario(s) if s.covers.contains(&TX_QUEUE_ACCOUNTING_SETTLED_BY));
    options
        .cases(profile)
        .into_iter()
        .filter(settling)
        .map(|case| {
            let scenario = Options::name(&case);
            let mut probed = Probed {
                profile: profile.name.clone(),
                scenario,
                passes: Vec::new(),
                errors: Vec::new(),
            };
            for accounting in TxQueueAccounting::ALL {
                let under = Options {
                    declared: Declared {
                        tx_queue_accounting: Some(accounting),
                        ..options.declared
                    },
                    observed: Default::default(),
                    ..options.clone()
                };
                match under.run(kind, profile, case.clone()).outcome {
                    Outcome::Pass => probed.passes.push(accounting),
                    Outcome::Fail(_) => {}
                    Outcome::Error(error) => probed
                        .errors
                        .push(format!("under {}: {error}", accounting.name())),
                }
            }
            probed
        })
        .collect()
}

/// What `probes` show together.
pub fn finding(probes: &[Probed]) -> Finding {
    let decided: Vec<TxQueueAccounting> = probes
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
        Some((first, rest)) if rest.iter().all(|a| a == first) => Finding::Takes(*first),
        Some(_) => Finding::Inconsistent,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use TxQueueAccounting::{WireInQueue, WireOutsideQueue};

    fn probed(passes: &[TxQueueAccounting]) -> Probed {
        Probed {
            profile: "p".into(),
            scenario: "s".into(),
            passes: passes.to_vec(),
            errors: Vec::new(),
        }
    }

    #[test]
    fn a_finding_needs_a_probe_that_tells_the_choices_apart_and_none_against_it() {
        assert_eq!(finding(&[]), Finding::Undecided);
        let both = probed(&[WireOutsideQueue, WireInQueue]);
        assert_eq!(finding(std::slice::from_ref(&both)), Finding::Undecided);
        let inside = probed(&[WireInQueue]);
        assert_eq!(
            finding(&[both, inside.clone()]),
            Finding::Takes(WireInQueue)
        );
        let outside = probed(&[WireOutsideQueue]);
        assert_eq!(finding(&[inside.clone(), outside]), Finding::Inconsistent);
        assert_eq!(finding(&[inside.clone(), probed(&[])]), Finding::Neither);
        let broke = Probed {
            errors: vec!["under wire-in-queue: the IUT broke".into()],
            ..probed(&[])
        };
        assert_eq!(finding(&[inside, broke]), Finding::Takes(WireInQueue));
    }
}
