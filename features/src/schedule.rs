//! Which Gherkin scenario runs on which profile, for either side, and one
//! run of it as the harness reports it. The command line and the test
//! target both schedule through here.

use canif_harness::client::suite::ClientKind;
use canif_harness::client::ClientDeclaration;
use canif_harness::declare::choices::Declared;
use canif_harness::declare::client::Application;
use canif_harness::device::refusals::OFFERED_REFUSED;
use canif_harness::device::{blame, IutKind};
use canif_harness::verdict::{NotRunReason, Rest};
use canif_harness::{GherkinOutcome, GherkinRun};
use canif_model::config::{FrameFormat, QueueMode};
use canif_spec::{Profile, Side};

use crate::{
    run_client_scenario, run_scenario, ClientTarget, ScenarioInfo, ScenarioOutcome, Target,
};

/// What a Gherkin scenario runs against.
#[derive(Debug, Clone)]
pub enum UnderTest {
    /// A device, and what it declares (the command line's over its kind's).
    Device(IutKind, Declared),
    /// A client, and what it declares (the command line's and its own).
    Client(ClientKind, ClientDeclaration),
}

impl UnderTest {
    pub fn side(&self) -> Side {
        match self {
            UnderTest::Device(..) => Side::Device,
            UnderTest::Client(..) => Side::Plc,
        }
    }
}

/// Each scenario of `side` on each profile that offers what it needs, as
/// (profile, scenario): once per profile whose capabilities it needs, a
/// `@once` scenario on the profile it names. The manual's tables (`@model`)
/// check the model, not an implementation: `cargo test` runs them.
pub fn targets(
    scenarios: &[ScenarioInfo],
    profiles: &[&Profile],
    side: Side,
) -> Vec<(String, ScenarioInfo)> {
    let mut targets = Vec::new();
    for scenario in scenarios.iter().filter(|s| s.side == side && !s.model_only) {
        let offers = |p: &&&Profile| p.lacks(&scenario.capabilities).is_empty();
        if scenario.once {
            let named = profiles
                .iter()
                .find(|p| scenario.profile.as_deref().is_none_or(|n| n == p.name));
            if let Some(profile) = named {
                targets.push((profile.name.clone(), scenario.clone()));
            }
        } else {
            for profile in profiles.iter().filter(offers) {
                targets.push((profile.name.clone(), scenario.clone()));
            }
        }
    }
    targets
}

/// Why a client declaring `declared` does not meet a `@plc` scenario on
/// `profile`, if it does not: the interface its steps set up (format, queue,
/// slots, and the profile's transaction numbers) or the traffic they make.
pub fn declined_by_client(
    scenario: &ScenarioInfo,
    profile: &Profile,
    declared: &ClientDeclaration,
) -> Option<String> {
    if let Some(why) = scenario
        .capabilities
        .iter()
        .find_map(|capability| declared.declined_capability(capability))
    {
        return Some(why);
    }
    let caps = profile.model_capabilities();
    let (mut format, mut queue, mut slots) = (FrameFormat::Base11, QueueMode::Standard, 0u8);
    let count = |text: &str| text.split(' ').find_map(|w| w.parse::<u8>().ok());
    for step in &scenario.steps {
        if let Some(rest) = step.strip_prefix("the client's interface is set up for ") {
            format = match rest {
                r if r.starts_with("29-bit") => FrameFormat::Extended29,
                r if r.starts_with("CAN FD") => FrameFormat::Fd,
                _ => FrameFormat::Base11,
            };
            slots = count(rest).unwrap_or(slots);
        } else if let Some(rest) =
            step.strip_prefix("the client's interface uses the Fast CAN Queue")
        {
            queue = QueueMode::Fast;
            slots = count(rest).unwrap_or(slots);
        } else if step.ends_with("once and in order")
            && declared.application() != Application::OneStream
        {
            // One stream's order, frame by frame: what a client with
            // several streams, or one that cuts bytes its own way, need not keep.
            return Some(declared.declined_application());
        } else {
            let sends = step.starts_with("the application asks the client to send");
            let receives = step.starts_with("other nodes send");
            let direction = declared.direction();
            if (sends && !direction.sends()) || (receives && !direction.receives()) {
                return Some(declared.declined_direction());
            }
        }
    }
    let config = canif_harness::run::interface(format, queue, &caps);
    if let Err(why) = declared.serve(&config) {
        return Some(why);
    }
    // The scenarios set up one count for both directions.
    (!declared.serves_slots(slots, slots)).then(|| {
        format!(
            "{}; the scenario's interface has {slots} each way",
            declared.declined_geometry()
        )
    })
}

/// Runs one scenario on `profile` and says how it ended, blamed the way its side blames.
pub fn run(profile: &Profile, scenario: &ScenarioInfo, under_test: &UnderTest) -> GherkinRun {
    let started = std::time::Instant::now();
    let (caps, name) = (profile.model_capabilities(), profile.name.clone());
    let outcome = match under_test {
        UnderTest::Device(iut, declared) => {
            // Judged by what the device declares where the documents leave a choice.
            let caps = declared.apply(&caps);
            run_scenario(
                &scenario.file,
                scenario.line,
                Target {
                    iut: iut.for_profile(profile),
                    profile: name,
                    caps,
                    declared: *declared,
                },
            )
        }
        UnderTest::Client(client, declared) => run_client_scenario(
            &scenario.file,
            scenario.line,
            ClientTarget {
                client: client.clone(),
                declared: declared.clone(),
                profile: name,
                caps,
            },
        ),
    };
    let outcome = match outcome {
        ScenarioOutcome::Passed => GherkinOutcome::Pass,
        ScenarioOutcome::Failed { report, witness } => GherkinOutcome::Fail {
            step: failing_step(&report),
            blamed: match under_test {
                // A device step names the families of the field it read:
                // the scenario's tags of those families are blamed.
                UnderTest::Device(..) => blame::narrow_tags(&scenario.requirements, &witness),
                // The client judge names exactly what a client broke,
                // whatever the scenario is tagged with.
                UnderTest::Client(..) if witness.is_empty() => scenario.requirements.clone(),
                UnderTest::Client(..) => witness.iter().map(|id| id.to_string()).collect(),
            },
            report,
            rest: Rest::Stopped,
        },
        ScenarioOutcome::Error(report) => GherkinOutcome::Error(report),
        // Refusing an interface the profile offers is the device's failure;
        // what the scenario needed the interface for is not run.
        ScenarioOutcome::Refused { interface, reason } => GherkinOutcome::Fail {
            step: format!("the IUT refuses {interface}, which the profile offers: {reason}"),
            report: String::new(),
            blamed: OFFERED_REFUSED.iter().map(|id| id.to_string()).collect(),
            rest: Rest::NotRun(NotRunReason::Refused { interface, reason }),
        },
    };
    GherkinRun {
        id: scenario.id(),
        file: scenario.file.clone(),
        line: scenario.line,
        requirements: scenario.requirements.clone(),
        outcome,
        elapsed: started.elapsed(),
    }
}

/// The failing step of cucumber's report and what it said, in one line:
/// `✘ And the bytes after the first 10 are 00: padding is not 00: FF FF`.
pub fn failing_step(report: &str) -> String {
    let mut lines = report.lines().map(str::trim).filter(|l| !l.is_empty());
    let Some(step) = lines.find(|l| l.contains('✘')) else {
        return report
            .lines()
            .next()
            .unwrap_or("the scenario failed")
            .trim()
            .to_string();
    };
    let said = lines
        .take_while(|l| !l.contains('✘') && !l.contains('✔') && !l.starts_with('['))
        .find_map(|l| {
            l.strip_prefix("Step panicked. Captured output:")
                .or_else(|| {
                    (!l.starts_with("Step failed")
                        && !l.starts_with("Defined:")
                        && !l.starts_with("Matched:"))
                    .then_some(l)
                })
        });
    match said {
        Some(said) => format!("{step}: {}", said.trim()),
        None => step.to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use canif_harness::declare::Declaration;

    fn plc(name: &str) -> ScenarioInfo {
        crate::scenarios()
            .unwrap()
            .into_iter()
            .find(|s| s.side == Side::Plc && s.name.starts_with(name))
            .unwrap_or_else(|| panic!("no @plc scenario {name}"))
    }

    fn declined(scenario: &str, lines: &[&str]) -> Option<String> {
        let catalogue = canif_spec::Catalogue::embedded().unwrap();
        let declared = ClientDeclaration::parse(lines).unwrap();
        declined_by_client(
            &plc(scenario),
            catalogue.profile("fc510x").unwrap(),
            &declared,
        )
    }

    #[test]
    fn a_declaration_leaves_out_the_scenarios_it_does_not_serve_and_says_why() {
        let reads = "The client reads exactly NoOfRxMessages";
        let sends = "The device sends every message the application asked for";
        assert_eq!(declined(reads, &[]), None);
        assert_eq!(
            declined(reads, &["direction=tx"]).as_deref(),
            Some("the client declares direction=tx")
        );
        assert_eq!(declined(sends, &["direction=tx"]), None);
        assert_eq!(
            declined(sends, &["slots=10"]).as_deref(),
            Some("the client declares slots=10; the scenario's interface has 4 each way")
        );
        assert_eq!(declined(sends, &["slots=1..8"]), None);
        assert_eq!(
            declined("Transaction numbers tell", &["formats=11-bit"]).as_deref(),
            Some("the client declares formats=11-bit")
        );
        assert_eq!(
            declined("With the Fast CAN Queue", &["queues=standard"]).as_deref(),
            Some("the client declares queues=standard")
        );
        assert_eq!(
            declined(sends, &["application=streams"]).as_deref(),
            Some("the client declares application=streams")
        );
    }
}
