//! A client under test in another process, over the adapter protocol's
//! client role (docs/adapter-protocol.md). The process is one PLC program:
//! a PLC restart starts a new one. Whatever it does wrong — exit, hang,
//! garbage, an image of the wrong size — is an error, never a failure.

use canif_model::config::InterfaceConfig;
use canif_model::image::{ImageLayout, MessageRepr};

use crate::door::adapter::process::{AdapterProcess, Channel};
use crate::door::adapter::protocol::{Answer, Config, Hex, Request, Tasked, WireMessage};
use crate::door::client::{Client, TaskAnswer, TaskIo};
use crate::door::declaration::client::ClientDeclaration;
use crate::door::Timeouts;
use crate::error::IutCause;
use crate::error::IutError;

/// The client role's protocol version.
pub(super) const CLIENT_PROTOCOL: u64 = 1;

pub(crate) struct ExecClient {
    process: AdapterProcess,
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
        let mut process = AdapterProcess::spawn(command, timeouts, true, channel)?;
        let request = Request::Start {
            protocol: CLIENT_PROTOCOL,
            config: Config::new(config, &layout),
        };
        let started = process.exchange(&request, Answer::STARTED)?;
        let protocol = started.protocol;
        if protocol != CLIENT_PROTOCOL {
            return Err(process.fail(
                IutCause::Protocol,
                format!(
                "speaks client protocol version {protocol} (this harness speaks {CLIENT_PROTOCOL})"
            ),
            ));
        }
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
            process,
            layout,
            declaration,
        })
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
        } = self.process.exchange(&request, Answer::TASKED)?;
        if outputs.0.len() != size {
            return Err(self.process.fail(
                IutCause::Impossible,
                format!(
                    "answered an output image of {} bytes; the interface's is {size}",
                    outputs.0.len()
                ),
            ));
        }
        if let Some(index) = refused.iter().find(|i| **i >= io.requests.len()) {
            return Err(self.process.fail(
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
