//! A client under test in another process, over the adapter protocol's
//! client role (docs/adapter-protocol.md). The process is one PLC program:
//! a PLC restart starts a new one. Whatever it does wrong — exit, hang,
//! garbage, an image of the wrong size — is an error, never a failure.

use crate::declare::Declaration;
use canif_model::config::InterfaceConfig;
use canif_model::image::{ImageLayout, MessageRepr};

use crate::declare::client::ClientDeclaration;
use crate::door::adapter::process::{AdapterProcess, Channel};
use crate::door::adapter::protocol::{Answer, Config, Hex, Request, Tasked, WireMessage};
use crate::door::client::{Client, TaskAnswer, TaskIo};
use crate::door::Timeouts;
use crate::error::IutCause;
use crate::error::IutError;

/// The client role's protocol versions: 1 on the lines, 3 in shared memory
/// (the client role has no version 2).
pub(super) const CLIENT_PROTOCOL: u64 = 3;

/// Processes of clients that said each `start` begins a new program
/// (`"restarts":true`), idle between programs: the next program of the same
/// command starts in one of them instead of a new process (an interpreter's
/// start took most of a PLC-side run). One per command; [`release_idle`]
/// ends them.
static IDLE: std::sync::Mutex<Vec<(String, Channel, AdapterProcess)>> =
    std::sync::Mutex::new(Vec::new());

fn take_idle(command: &str, channel: Channel) -> Option<AdapterProcess> {
    let mut idle = IDLE.lock().ok()?;
    let at = idle
        .iter()
        .position(|(c, ch, _)| c == command && *ch == channel)?;
    Some(idle.swap_remove(at).2)
}

/// Ends every idle client process (a run's end: `bye`, then their trees).
pub(crate) fn release_idle() {
    let idle = IDLE.lock().map(|mut idle| std::mem::take(&mut *idle));
    drop(idle);
}

pub(crate) struct ExecClient {
    /// `None` once given back to [`IDLE`].
    process: Option<AdapterProcess>,
    command: String,
    channel: Channel,
    /// It said each `start` begins a new program.
    restarts: bool,
    layout: ImageLayout,
    /// What its `started` answer declared.
    declaration: ClientDeclaration,
}

impl ExecClient {
    /// Starts `command` as the program of an interface configured as `config`.
    pub(crate) fn start(
        command: &str,
        timeouts: Timeouts,
        channel: Channel,
        config: &InterfaceConfig,
        layout: ImageLayout,
    ) -> Result<Self, IutError> {
        let mut process = match take_idle(command, channel) {
            Some(process) => process,
            None => AdapterProcess::spawn(command, timeouts, false, channel)?,
        };
        let request = Request::Start {
            protocol: CLIENT_PROTOCOL,
            config: Config::new(config, &layout),
            shared: process.shared_offer(),
        };
        let started = process.exchange(&request, Answer::STARTED)?;
        let protocol = started.protocol;
        if protocol != 1 && protocol != 3 {
            return Err(process.fail(
                IutCause::Protocol,
                format!("speaks client protocol version {protocol} (this harness speaks 1 and 3)"),
            ));
        }
        process.agree_shared(protocol == 3);
        let lines: Vec<String> = started
            .tells_sent
            .map(|tells| format!("tells-sent={}", if tells { "yes" } else { "no" }))
            .into_iter()
            .chain(started.declares.iter().map(|(k, v)| format!("{k}={v}")))
            .collect();
        let declaration = match ClientDeclaration::parse(&lines) {
            Ok(declaration) => declaration,
            Err(error) => {
                return Err(process.fail(
                    IutCause::Protocol,
                    format!("declares what cannot be taken in `started`: {error}"),
                ))
            }
        };
        Ok(ExecClient {
            restarts: started.restarts == Some(true),
            process: Some(process),
            command: command.to_string(),
            channel,
            layout,
            declaration,
        })
    }
}

impl ExecClient {
    fn process(&mut self) -> &mut AdapterProcess {
        self.process.as_mut().expect("the process, until dropped")
    }
}

/// What the library `command` hosts declares, asked of a `lib-host` before
/// any start (`declare`); the process then ends.
pub(crate) fn declares_before_start(
    command: &str,
    timeouts: Timeouts,
) -> Result<ClientDeclaration, IutError> {
    let mut process = AdapterProcess::spawn(command, timeouts, false, Channel::Control)?;
    let declares = process.exchange(&Request::Declare {}, Answer::DECLARED)?;
    let lines: Vec<String> = declares.iter().map(|(k, v)| format!("{k}={v}")).collect();
    ClientDeclaration::parse(&lines).map_err(|error| {
        process.fail(
            IutCause::Protocol,
            format!("declares what cannot be taken in `declared`: {error}"),
        )
    })
}

impl Drop for ExecClient {
    /// A program that ends in a sound process that restarts waits idle for
    /// the next one; any other process ends with its program.
    fn drop(&mut self) {
        let Some(process) = self.process.take() else {
            return;
        };
        if !(self.restarts && process.is_sound()) {
            return;
        }
        if let Ok(mut idle) = IDLE.lock() {
            if !idle
                .iter()
                .any(|(c, ch, _)| *c == self.command && *ch == self.channel)
            {
                idle.push((self.command.clone(), self.channel, process));
            }
        }
    }
}

impl Client for ExecClient {
    fn declaration(&self) -> ClientDeclaration {
        self.declaration.clone()
    }

    fn task(&mut self, io: TaskIo<'_>) -> Result<TaskAnswer, IutError> {
        let size = self.layout.output_size();
        let request = Request::Task {
            inputs: Hex(io.inputs[..self.layout.input_size()].to_vec()),
            outputs: Hex(io.outputs[..size].to_vec()),
            requests: io.requests.iter().map(WireMessage::from).collect(),
        };
        let Tasked {
            outputs,
            delivered,
            refused,
            sent,
        } = self
            .process()
            .exchange_record(&[], &request, Answer::TASKED)?;
        if outputs.0.len() != size {
            return Err(self.process().fail(
                IutCause::Impossible,
                format!(
                    "answered an output image of {} bytes; the interface's is {size}",
                    outputs.0.len()
                ),
            ));
        }
        if let Some(index) = refused.iter().find(|i| **i >= io.requests.len()) {
            return Err(self.process().fail(
                IutCause::Impossible,
                format!(
                    "refused request {index} of the {} it was given",
                    io.requests.len()
                ),
            ));
        }
        io.outputs[..size].copy_from_slice(&outputs.0);
        let mut answer = TaskAnswer {
            refused,
            sent,
            ..TaskAnswer::default()
        };
        for message in &delivered {
            match MessageRepr::try_from(message) {
                Ok(m) if answer.not_frames.is_empty() => answer.delivered.push(m),
                Ok(m) => answer
                    .not_frames
                    .push(format!("(after one that is no frame) {}", m.frame)),
                Err(e) => answer.not_frames.push(e),
            }
        }
        Ok(answer)
    }
}
