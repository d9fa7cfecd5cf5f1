//! A run of the PLC side: a client under test, with the harness playing the
//! device, the EtherCAT master and the application. The report has the same
//! shape as the device side's, with `side: plc` and the master models.

use canif_features::schedule::declined_by_client;
use canif_harness::client::master::Master;
use canif_harness::client::suite::{ClientBus, ClientKind, ClientOptions};
use canif_harness::door::Role;
use canif_harness::report::{ChoiceEntry, RunMeta, RunReport};
use canif_spec::{Catalogue, Side};

use crate::error::PlanError;
use crate::event::Observer;
use crate::{Campaign, Plan};

impl Campaign for ClientOptions {
    const UNIT: Option<&'static str> = Some("task cycles");

    fn name_of(kind: &ClientKind) -> String {
        kind.name()
    }

    fn shared(plan: &Plan<'_, Self>, _: &ClientKind) -> Option<&'static str> {
        (plan.options.bus != ClientBus::Sim).then_some(crate::socketcan::ONE_INTERFACE)
    }

    /// The client started once, and the bus the played device and the
    /// other nodes share opened once.
    #[cfg_attr(not(feature = "socketcan"), allow(unused_variables))]
    fn preflight(plan: &Plan<'_, Self>, _: &Catalogue, kind: &ClientKind) -> Result<(), PlanError> {
        if let ClientKind::Door(door) = kind {
            door.starts(Role::Client).map_err(PlanError::not_started)?;
        }
        #[cfg(feature = "socketcan")]
        if let ClientBus::SocketCan { interface, .. } = &plan.options.bus {
            crate::socketcan::opens(&format!("socketcan:{interface}"), &[interface])?;
        }
        Ok(())
    }

    /// Every profile's client run and the `@plc` Gherkin scenarios, judged and put in one report.
    fn execute(
        plan: &Plan<'_, Self>,
        catalogue: &Catalogue,
        kind: &ClientKind,
        observer: &dyn Observer,
    ) -> RunReport {
        let options = &plan.options;
        let started = std::time::Instant::now();
        let declared = options.declaration();
        let meta = RunMeta {
            side: Side::Plc,
            masters: options.masters.iter().map(|m| m.name.to_string()).collect(),
            // What the client declares: the verdicts rest on it.
            choices: ChoiceEntry::declared(&declared),
            ..RunMeta::new(kind.name(), options.bus.describe(), options.seed, catalogue)
        };
        // The Gherkin scenarios the client's declaration leaves out, with why.
        let declines = |(profile, scenario): &(String, canif_features::ScenarioInfo)| {
            let profile = plan.profiles.iter().find(|p| p.name == *profile)?;
            declined_by_client(scenario, profile, &declared)
        };
        let (gherkin, declined): (Vec<_>, Vec<_>) = plan
            .gherkin
            .iter()
            .cloned()
            .partition(|t| declines(t).is_none());
        let plan = &Plan {
            gherkin,
            ..plan.clone()
        };
        let mut lockstep = plan.run_profiles(kind, observer);
        for run in &mut lockstep {
            for target in declined.iter().filter(|(p, _)| *p == run.profile) {
                if let Some(why) = declines(target) {
                    run.reach
                        .not_served
                        .push((format!("gherkin: {}", target.1.id()), why));
                }
            }
        }
        let mut left_out = plan.left_out(&lockstep);
        if !options.counter_wrap {
            left_out.push("the 65,600-cycle counter wrap (--no-counter-wrap)".to_string());
        }
        if options.masters.len() < Master::ALL.len() {
            left_out.push("master models left out by --master".to_string());
        }
        let skip = (options.bus != ClientBus::Sim).then_some("they use the simulated bus");
        let under_test = || canif_features::UnderTest::Client(kind.clone(), declared.clone());
        let gherkin = plan.gherkin_stage(skip, under_test, &mut left_out, observer);
        // Client processes kept for the next program have none left to run.
        canif_harness::door::Door::release_idle_clients();
        plan.assemble(
            catalogue,
            (lockstep, gherkin),
            left_out,
            meta,
            (started, observer),
        )
    }
}
