//! One client scenario, driven task by task: the single place where the
//! device side, the master, the application and the client under test meet.
//! Every task is judged as it ends; the first breach ends the scenario.

use std::panic::{catch_unwind, AssertUnwindSafe};

use canif_model::config::{Capabilities, InterfaceConfig, Synchronization};
use canif_model::frame::Frame;
use canif_model::image::{
    ImageLayout, InputHeader, InputImage, MessageRepr, OutputHeader, OutputImage,
};
use canif_model::timing::BitRates;
use canif_model::Nanos;

use super::application::{ClientScenario, Event};
use super::judge::{self, Breach, Judge, TaskSeen, SENT_REPORTS, TRANSACTION_NUMBERS};
use super::master::{Master, MasterRun};
use super::{Client, ClientDeclaration, IutError, TaskIo};
use crate::client::played_device::{DeviceSide, Ended, PlayedDevice};
use crate::declare::Declares;
use crate::door::iut::BuildError;
use crate::error::{HarnessError, IutCause, Refusal, RunError};
use crate::outcome::{BusFrame, Failure, Outcome, ScenarioRun, TaskView, Timeline};
use crate::run::Ring;

/// The CAN interface cycle of every client scenario.
pub const CYCLE: Nanos = 1_000_000;

/// Builds a fresh client for an image (at the start and at each PLC restart).
pub type BuildClient<'a> = dyn Fn(ImageLayout) -> Result<Box<dyn Client>, BuildError> + 'a;

/// Opens the device the harness plays, on the bus of the run.
pub type OpenDevice<'a> = dyn Fn(&Capabilities, InterfaceConfig, BitRates) -> Result<Box<dyn PlayedDevice>, RunError>
    + 'a;

/// The device on the simulated bus.
pub fn simulated(
    caps: &Capabilities,
    config: InterfaceConfig,
    bit_rates: BitRates,
) -> Result<Box<dyn PlayedDevice>, RunError> {
    DeviceSide::new(caps, config, bit_rates)
        .map(|d| Box::new(d) as Box<dyn PlayedDevice>)
        .map_err(|e| RunError::Configuration(Refusal::Model(e)))
}

/// A line of a failure's history, kept as data: most runs pass, and a
/// counter wrap is 65,600 tasks, so text is made only for a failure.
enum Note {
    Task {
        task: u64,
        inputs: InputHeader,
        outputs: OutputHeader,
        delivered: usize,
    },
    Restart {
        task: u64,
        what: &'static str,
    },
    Overrun(u64),
}

impl std::fmt::Display for Note {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Note::Task {
                task,
                inputs,
                outputs,
                delivered,
            } => write!(
                f,
                "task {task}: inputs Tx {} Rx {} n {} | outputs Tx {} Rx {} n {} | delivered {delivered}",
                inputs.tx_counter,
                inputs.rx_counter,
                inputs.no_of_rx_messages,
                outputs.tx_counter,
                outputs.rx_counter,
                outputs.no_of_tx_messages,
            ),
            Note::Restart { task, what } => write!(f, "task {task}: the {what} restarts"),
            Note::Overrun(task) => write!(f, "task {task}: overrun, the client does not run"),
        }
    }
}

/// Where a run is, for the failure it may end in.
struct Tracker {
    task: u64,
    time: Nanos,
    context: Ring<Note>,
    /// The same tasks as data, for the report's timing diagram: the inputs
    /// each was handed, the outputs it left, its application's requests and
    /// deliveries, and the frames that ended since the task before.
    timeline: Ring<(TaskView, Vec<Ended>)>,
    /// Frames that ended since the last task.
    frames: Vec<Ended>,
    /// The scenario's name, for its failures.
    scenario: String,
    /// Each distinct breach so far, at its first task: judging goes on after
    /// one, so one defect does not hide the next.
    breaches: Vec<Failure>,
}

impl Tracker {
    /// Records a breach the first time its requirements are breached.
    fn breached(&mut self, judged: Result<(), Breach>) {
        let Err(breach) = judged else {
            return;
        };
        if self
            .breaches
            .iter()
            .any(|f| f.requirements == breach.requirements)
        {
            return;
        }
        let failure = self.failure(&self.scenario, breach);
        self.breaches.push(failure);
    }

    fn failure(&self, scenario: &str, breach: Breach) -> Failure {
        let bus_frame = |e: &Ended| BusFrame {
            end: e.end,
            from_iut: e.from_device,
            text: e.frame.to_string(),
        };
        Failure {
            requirements: breach.requirements.to_vec(),
            scenario: scenario.to_string(),
            cycle: self.task,
            time: self.time,
            what: breach.what,
            expected: breach.expected,
            actual: breach.actual,
            context: self.context.iter().map(Note::to_string).collect(),
            timeline: Timeline::Tasks {
                tasks: self
                    .timeline
                    .iter()
                    .map(|(view, frames)| TaskView {
                        frames: frames.iter().map(bus_frame).collect(),
                        ..view.clone()
                    })
                    .collect(),
                row: judge::row_of(breach.requirements),
            },
            frames: None,
            images: None,
            rest: crate::verdict::Rest::Stopped,
            further: Vec::new(),
        }
    }

    fn note(&mut self, note: Note) {
        self.context.push(note);
    }

    /// The task just run: its images for the timeline and the history.
    fn task_ran(
        &mut self,
        layout: ImageLayout,
        (inputs, outputs): (&[u8], &[u8]),
        (requests, delivered): (usize, usize),
    ) {
        let inputs = InputImage::new_checked(&inputs[..layout.input_size()], layout);
        let outputs = OutputImage::new_checked(&outputs[..layout.output_size()], layout);
        let (Ok(inputs), Ok(outputs)) = (inputs, outputs) else {
            return;
        };
        let (seen, written) = (InputHeader::parse(&inputs), OutputHeader::parse(&outputs));
        let view = TaskView {
            task: self.task,
            time: self.time,
            inputs: seen,
            outputs: written,
            requests,
            delivered,
            frames: Vec::new(),
        };
        self.timeline.push((view, std::mem::take(&mut self.frames)));
        self.note(Note::Task {
            task: self.task,
            inputs: seen,
            outputs: written,
            delivered,
        });
    }
}

/// What a run saw, for checks beyond the judge's (the Gherkin steps).
#[derive(Debug, Clone, Default)]
pub struct Record {
    pub tasks: u64,
    pub frames_checked: u64,
    /// The frames the device sent on the bus, in order.
    pub sent: Vec<Frame>,
    /// The messages the client delivered to its application, in order.
    pub delivered: Vec<MessageRepr>,
    /// The transaction numbers the client told its application were sent.
    pub told_sent: Vec<u16>,
    /// What the client was held to: the run's declaration and its own.
    pub declared: ClientDeclaration,
    /// Batches, batches of nothing and request-to-bus latency (never judged).
    pub advisories: crate::advisory::Advisories,
    /// Keep `sent` and `delivered` (a counter wrap is 65,600 of each, and
    /// only the Gherkin steps read them).
    keep_frames: bool,
}

/// What ended a run early.
enum Stop {
    Breach(Breach),
    Error(RunError),
}

impl From<Breach> for Stop {
    fn from(breach: Breach) -> Self {
        Stop::Breach(breach)
    }
}

/// Runs `scenario` under `master` against the clients `build` makes.
pub fn run(
    caps: &Capabilities,
    scenario: &ClientScenario,
    master: Master,
    build: &BuildClient<'_>,
    open: &OpenDevice<'_>,
) -> ScenarioRun {
    run_with(caps, scenario, master, (build, open), Record::default()).0
}

/// [`run`], and what the run saw.
pub fn run_recorded(
    caps: &Capabilities,
    scenario: &ClientScenario,
    master: Master,
    build: &BuildClient<'_>,
    open: &OpenDevice<'_>,
) -> (ScenarioRun, Record) {
    let record = Record {
        keep_frames: true,
        ..Record::default()
    };
    run_with(caps, scenario, master, (build, open), record)
}

fn run_with(
    caps: &Capabilities,
    scenario: &ClientScenario,
    master: Master,
    (build, open): (&BuildClient<'_>, &OpenDevice<'_>),
    mut record: Record,
) -> (ScenarioRun, Record) {
    let started = std::time::Instant::now();
    let name = format!("{} under {}", scenario.name, master.name);
    let mut tracker = Tracker {
        task: 0,
        time: 0,
        context: Ring::context(),
        timeline: Ring::context(),
        frames: Vec::new(),
        scenario: name.clone(),
        breaches: Vec::new(),
    };
    let result = drive(
        caps,
        scenario,
        master,
        (build, open),
        &mut tracker,
        &mut record,
    );
    let error = match result {
        Ok(()) => None,
        // A breach that stopped the run (its client is gone) comes last.
        Err(Stop::Breach(breach)) => {
            let failure = tracker.failure(&name, breach);
            tracker.breaches.push(failure);
            None
        }
        Err(Stop::Error(error)) => Some(error),
    };
    let mut breaches = std::mem::take(&mut tracker.breaches).into_iter();
    let outcome = match (error, breaches.next()) {
        (Some(error), _) => Outcome::Error(error),
        (None, None) => Outcome::Pass,
        (None, Some(first)) => Outcome::Fail(Box::new(Failure {
            further: breaches.collect(),
            ..first
        })),
    };
    // A client that tells its application nothing of what was sent gives
    // CL-TN-002 nothing to judge: no evidence of a pass.
    // A client that declares it tells nothing is judged on neither.
    let covers = scenario
        .covers
        .iter()
        .filter(|id| !record.told_sent.is_empty() || !SENT_REPORTS.contains(id))
        .filter(|id| record.declared.tells_sent != Some(false) || !TRANSACTION_NUMBERS.contains(id))
        .cloned()
        .collect();
    let run = ScenarioRun {
        iut_declares: Declares::Client(record.declared.clone()),
        advisories: record.advisories,
        cycles: record.tasks,
        frames_checked: record.frames_checked,
        elapsed: started.elapsed(),
        ..ScenarioRun::ended(name, covers, outcome)
    };
    (run, record)
}

fn drive(
    caps: &Capabilities,
    scenario: &ClientScenario,
    master: Master,
    (build, open): (&BuildClient<'_>, &OpenDevice<'_>),
    tracker: &mut Tracker,
    record: &mut Record,
) -> Result<(), Stop> {
    let mut config = scenario.config.clone();
    if master.distributed_clocks {
        config.synchronization = Synchronization::DistributedClocks {
            sync1_shift: CYCLE / 2,
        };
    }
    let configuration = |e: canif_model::config::ConfigError| {
        Stop::Error(RunError::Configuration(Refusal::Model(e)))
    };
    let mut device = open(caps, config.clone(), scenario.bit_rates).map_err(Stop::Error)?;
    let layout = device.layout();
    let built = |layout| {
        build(layout).map_err(|e| {
            Stop::Error(match e {
                BuildError::Failed(error) => RunError::Iut(error),
                BuildError::Refused(reason) => RunError::Configuration(Refusal::Iut(reason)),
            })
        })
    };
    let mut client = built(layout)?;
    record.declared = declared(&scenario.declared, client.as_ref())?;
    let mut exchange = MasterRun::new(master, layout);
    let mut judge = Judge::new(layout, config.queue, &record.declared);
    let per_cycle = master.tasks_per_cycle();
    let period = CYCLE / per_cycle;
    let deadline = 2 * per_cycle + 2 * master.confirmation_tasks();
    let mut events = scenario.events.iter().peekable();
    let mut requests: Vec<MessageRepr> = Vec::new();
    // The application's requests not yet on the bus, and when each was made.
    let mut requested: std::collections::VecDeque<(Frame, Nanos)> = Default::default();
    let (mut overstate, mut device_saw) = (false, 0u16);
    for task in 0..scenario.cycles * per_cycle {
        let time = task * period;
        (tracker.task, tracker.time) = (task, time);
        while let Some((_, event)) = events.next_if(|(cycle, _)| cycle * per_cycle <= task) {
            match event {
                Event::Send(message) => {
                    requests.push(*message);
                    requested.push_back((message.frame, time));
                }
                Event::Arrive(frame) => device.schedule(time + period / 4, *frame),
                Event::OverstateRxCount => overstate = true,
                Event::PlcRestart => {
                    end_program(&mut client);
                    client = built(layout)?;
                    declared(&record.declared, client.as_ref())?;
                    exchange.client_restarted();
                    judge.plc_restarted(device_saw);
                    tracker.note(Note::Restart { task, what: "PLC" });
                }
                // The master runs on: its buffers keep what the old program
                // wrote, and the new one's first tasks are handed those.
                Event::ModuleRestart => {
                    end_program(&mut client);
                    client = built(layout)?;
                    declared(&record.declared, client.as_ref())?;
                    judge.plc_restarted(device_saw);
                    tracker.note(Note::Restart {
                        task,
                        what: "client module",
                    });
                }
                Event::DeviceRestart => {
                    device.restart().map_err(configuration)?;
                    exchange.device_restarted();
                    let visible = InputImage::new_checked(exchange.task_input_image(), layout)
                        .map_or(0, |i| i.rx_counter());
                    judge.device_restarted(task, exchange.device_outputs(), visible);
                    tracker.note(Note::Restart {
                        task,
                        what: "device",
                    });
                }
            }
        }
        let ended = device
            .run_until(time)
            .map_err(|e| Stop::Error(RunError::Bus(e)))?;
        bus_frames_ended(ended, &mut requested, (tracker, &mut judge, record));
        if exchange.client_runs() {
            let asked = std::mem::take(&mut requests);
            client_task(
                client.as_mut(),
                &asked,
                &mut exchange,
                (task, deadline),
                (tracker, &mut judge, record),
            )?;
        } else {
            tracker.note(Note::Overrun(task));
        }
        exchange.end_task(|outputs| -> Result<Vec<u8>, Stop> {
            device_saw = OutputImage::new_checked(outputs, layout).map_or(0, |o| o.tx_counter());
            judge.device_saw(device_saw);
            let mut inputs = device
                .cycle(outputs)
                .map_err(|e| Stop::Error(RunError::Harness(HarnessError::Model(e.to_string()))))?;
            if overstate && overstated(&mut inputs, layout, judge.device_rx_counter()) {
                overstate = false;
            }
            judge.device_cycle(&inputs);
            Ok(inputs)
        })?;
        record.tasks += 1;
    }
    // What never arrived is the consequence of any breach before: judged
    // only in a run that had none.
    if tracker.breaches.is_empty() {
        tracker.breached(judge.finish(device.queued_rx()));
    }
    Ok(())
}

/// The frames that ended on the bus up to a task's time: each kept for the
/// trace, and those the device sent judged, counted, and matched with the
/// application's request they answer (for the advisories).
fn bus_frames_ended(
    ended: Vec<Ended>,
    requested: &mut std::collections::VecDeque<(Frame, Nanos)>,
    (tracker, judge, record): (&mut Tracker, &mut Judge, &mut Record),
) {
    for ended in ended {
        tracker.frames.push(ended);
        if ended.from_device {
            if record.keep_frames {
                record.sent.push(ended.frame);
            }
            tracker.breached(judge.device_sent(&ended.frame));
            record.frames_checked += 1;
            if let Some(at) = requested.iter().position(|(f, _)| *f == ended.frame) {
                let (_, asked) = requested.remove(at).expect("found");
                record.advisories.frame_sent(asked, ended.end);
            }
        }
    }
}

/// One task of the client's program: it reads the inputs the master gave
/// it and fills the output buffer, with the application's requests `asked`;
/// what it did is judged, and what it wrote handed to the master.
fn client_task(
    client: &mut dyn Client,
    asked: &[MessageRepr],
    exchange: &mut MasterRun,
    (task, deadline): (u64, u64),
    (tracker, judge, record): (&mut Tracker, &mut Judge, &mut Record),
) -> Result<(), Stop> {
    let layout = exchange.layout();
    let mut buffer = exchange.output_buffer();
    let inputs = exchange.task_inputs().to_vec();
    let answer = catch_unwind(AssertUnwindSafe(|| {
        client.task(TaskIo {
            inputs: &inputs,
            outputs: &mut buffer,
            requests: asked,
        })
    }))
    .unwrap_or_else(|panic| Err(IutError::new(IutCause::Panicked, panic_message(&panic))))
    .map_err(|e| match e.cause {
        // Stopped at an image's end by its host: what it did, judged.
        IutCause::OutsideImage => Stop::Breach(judge::outside_image(&e.what)),
        _ => Stop::Error(RunError::Iut(e)),
    })?;
    let accepted: Vec<MessageRepr> = asked
        .iter()
        .enumerate()
        .filter(|(i, _)| !answer.refused.contains(i))
        .map(|(_, m)| *m)
        .collect();
    tracker.task_ran(
        layout,
        (&inputs, &buffer),
        (asked.len(), answer.delivered.len()),
    );
    let breaches = judge.task(
        task,
        TaskSeen {
            inputs: exchange.task_input_image(),
            before: exchange.device_outputs(),
            after: &buffer,
            accepted: &accepted,
            delivered: &answer.delivered,
            not_frames: &answer.not_frames,
            sent: &answer.sent,
        },
        deadline,
    );
    for breach in breaches {
        tracker.breached(Err(breach));
    }
    record.frames_checked += answer.delivered.len() as u64;
    if record.keep_frames {
        record.delivered.extend_from_slice(&answer.delivered);
    }
    record.told_sent.extend_from_slice(&answer.sent);
    // A new batch: a TxCounter the client did not write before and
    // the device has not acknowledged (a restarted program taking
    // Inputs.TxCounter over asks for nothing).
    let header = |image: &[u8]| OutputImage::new_checked(image, layout).map(|o| o.header());
    let acknowledged =
        InputImage::new_checked(exchange.task_input_image(), layout).map(|i| i.tx_counter());
    let written = (
        header(exchange.device_outputs()),
        header(&buffer[..layout.output_size()]),
    );
    if let ((Ok(was), Ok(now)), Ok(acknowledged)) = (written, acknowledged) {
        if now.tx_counter != was.tx_counter && now.tx_counter != acknowledged {
            record.advisories.batches += 1;
            record.advisories.empty_batches += u64::from(now.no_of_tx_messages == 0);
        }
    }
    exchange.client_wrote(&buffer[..layout.output_size()]);
    Ok(())
}

/// Ends the running program before the next starts, as a restart does (and
/// a process that runs one program after another is free for the next).
fn end_program(client: &mut Box<dyn Client>) {
    drop(std::mem::replace(client, Box::new(BetweenPrograms)));
}

/// What stands between a program that ended and the next: never asked.
struct BetweenPrograms;

impl Client for BetweenPrograms {
    fn task(
        &mut self,
        _: crate::door::client::TaskIo<'_>,
    ) -> Result<crate::door::client::TaskAnswer, IutError> {
        Err(IutError::new(
            crate::error::IutCause::HarnessBug,
            "a task between two programs",
        ))
    }
}

/// What the run holds the client to: what was declared before and what this
/// program declares, together. A program that declares otherwise than the
/// one before it (or than the run was planned on) broke the exchange.
fn declared(before: &ClientDeclaration, client: &dyn Client) -> Result<ClientDeclaration, Stop> {
    before.merged(&client.declaration()).map_err(|error| {
        Stop::Error(RunError::Iut(IutError::new(
            IutCause::Protocol,
            format!("declares otherwise than before: {error}"),
        )))
    })
}

/// Sets NoOfRxMessages = 0xFFFF if the device just entered a new batch.
fn overstated(inputs: &mut [u8], layout: ImageLayout, last_counter: u16) -> bool {
    let Ok(mut image) = InputImage::new_checked(inputs, layout) else {
        return false;
    };
    if image.rx_counter() == last_counter {
        return false;
    }
    image.set_no_of_rx_messages(0xFFFF);
    true
}

fn panic_message(panic: &Box<dyn std::any::Any + Send>) -> String {
    let text = panic
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| panic.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "a panic".into());
    format!("the client panicked: {text}")
}
