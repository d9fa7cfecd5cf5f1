//! The world a PLC-side scenario runs in: the client under test, and the
//! device, master and application the harness plays around it. The steps
//! write the life cycle down cycle by cycle; the first `Then` runs it through
//! the client rig (`canif_harness::client::rig`), with the judge on every task.

use std::cell::RefCell;

use canif_harness::client::application::{ClientScenario, Event};
use canif_harness::client::master::Master;
use canif_harness::client::rig::{self, Record};
use canif_harness::client::suite::ClientKind;
use canif_harness::ScenarioRun;
use canif_model::config::{Capabilities, FrameFormat, InterfaceConfig, QueueMode};
use canif_model::frame::{CanId, Frame};
use canif_model::image::MessageRepr;
use canif_model::timing::BitRates;

/// Who a PLC-side scenario runs against; set by the runner before each run.
#[derive(Debug, Clone)]
pub struct ClientTarget {
    pub client: ClientKind,
    /// What the client declares: its scenarios are judged by it.
    pub declared: canif_harness::client::ClientDeclaration,
    pub profile: String,
    pub caps: Capabilities,
}

thread_local! {
    static CLIENT_TARGET: RefCell<Option<ClientTarget>> = const { RefCell::new(None) };
}

pub fn set_client_target(target: ClientTarget) {
    CLIENT_TARGET.with(|t| *t.borrow_mut() = Some(target));
}

fn client_target() -> ClientTarget {
    CLIENT_TARGET
        .with(|t| t.borrow().clone())
        .unwrap_or_else(|| ClientTarget {
            client: ClientKind::Reference,
            declared: Default::default(),
            profile: "everything".into(),
            caps: Capabilities::everything(),
        })
}

/// Cycles at the end of a written life cycle for everything to arrive.
const QUIET: u64 = 40;

#[derive(cucumber::World)]
#[world(init = Self::new)]
pub struct ClientWorld {
    pub target: ClientTarget,
    pub config: InterfaceConfig,
    pub master: Master,
    /// The cycle the next event happens in.
    pub cycle: u64,
    pub events: Vec<(u64, Event)>,
    /// What the application asked to send, and what other nodes sent, in order.
    pub asked: Vec<Frame>,
    pub arrived: Vec<Frame>,
    next_id: u16,
    next_number: u16,
    /// The run, once a `Then` needed it.
    pub ran: Option<(ScenarioRun, Record)>,
}

impl std::fmt::Debug for ClientWorld {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "ClientWorld {{ client: {}, profile: {}, {:?} {:?} with {} slots under {}, cycle {}, {} events }}",
            self.target.client.name(),
            self.target.profile,
            self.config.format,
            self.config.queue,
            self.config.tx_slots,
            self.master,
            self.cycle,
            self.events.len()
        )
    }
}

impl ClientWorld {
    fn new() -> Self {
        let target = client_target();
        let config =
            canif_harness::run::interface(FrameFormat::Base11, QueueMode::Standard, &target.caps);
        ClientWorld {
            target,
            config,
            master: Master::ALL[0],
            cycle: 0,
            events: Vec::new(),
            asked: Vec::new(),
            arrived: Vec::new(),
            next_id: 0x100,
            next_number: 1,
            ran: None,
        }
    }

    /// The interface as the profile offers it and the client serves it
    /// (without the transaction numbers or time stamps it declares it does
    /// without), with `slots` slots.
    pub fn set_up(&mut self, format: FrameFormat, queue: QueueMode, slots: u8) {
        let offered = canif_harness::run::interface(format, queue, &self.target.caps);
        self.config = self.target.declared.serve(&offered).unwrap_or(offered);
        (self.config.tx_slots, self.config.rx_slots) = (slots, slots);
    }

    /// A frame the interface carries: 11-bit identifiers counting up from 0x100.
    fn next_frame(&mut self) -> Frame {
        let id = CanId::Standard(self.next_id);
        self.next_id += 1;
        let mut count = [0u8; 2];
        canif_model::image::le::write(&mut count, 0..2, self.next_id.into());
        Frame::classic(id, &count).expect("two bytes")
    }

    pub fn application_sends(&mut self, n: u32) {
        for _ in 0..n {
            let frame = self.next_frame();
            self.asked.push(frame);
            let message = MessageRepr {
                transaction_number: self.next_number,
                frame,
                time_stamp: 0,
            };
            self.next_number += 1;
            self.events.push((self.cycle, Event::Send(message)));
        }
    }

    pub fn nodes_send(&mut self, n: u32) {
        for _ in 0..n {
            let frame = self.next_frame();
            self.arrived.push(frame);
            self.events.push((self.cycle, Event::Arrive(frame)));
        }
    }

    pub fn at_this_cycle(&mut self, event: Event) {
        self.events.push((self.cycle, event));
    }

    /// Runs the life cycle written so far (once), with the judge on every task.
    pub fn run(&mut self) -> &(ScenarioRun, Record) {
        if self.ran.is_none() {
            let scenario = ClientScenario {
                name: "gherkin".into(),
                covers: Vec::new(),
                config: self.config.clone(),
                bit_rates: BitRates::classic(500_000),
                cycles: self.cycle + QUIET,
                events: self.events.clone(),
                // What the run holds it to; the rig adds what it says as it starts.
                declared: self.target.declared.clone(),
            };
            let (kind, config) = (self.target.client.clone(), self.config.clone());
            let build = move |layout| kind.build(&config, layout);
            self.ran = Some(rig::run_recorded(
                &self.target.caps,
                &scenario,
                self.master,
                &build,
                &rig::simulated,
            ));
        }
        self.ran.as_ref().expect("just ran")
    }
}
