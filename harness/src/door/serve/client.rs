//! The client's side of the adapter protocol for a library: what `canif
//! lib-host --role client` runs, so that what the library does wrong ends in
//! that process and not in canif. Its delivered messages pass on as the C
//! ABI gave them (canif decodes and judges them, as for a library in process).

use std::io::{BufRead, Write};
use std::path::Path;

use canif_model::image::{ImageLayout, MessageRepr};

use super::session::{self, Serves, Switch};
use crate::declare::client::ClientDeclaration;
use crate::declare::Declaration;
use crate::door::adapter::protocol::{
    Answer, Config, FrameData, Hex, Request, SharedOffer, WireFrame, WireMessage,
};
use crate::door::client::{Client, TaskIo};
use crate::door::lib::client::LibClient;

/// The layout the sizes of `config` name (with InfoData or without).
fn layout_of(config: &Config) -> Option<ImageLayout> {
    let interface = config.interface();
    [false, true]
        .into_iter()
        .map(|info_data| ImageLayout::new(&interface, info_data))
        .find(|l| l.input_size() == config.input_size && l.output_size() == config.output_size)
}

/// A library's client served: each `start` starts a program of it, its
/// images behind guard pages.
struct ClientServer<'a> {
    path: &'a Path,
    client: Option<(LibClient, ImageLayout)>,
    switch: Option<Switch>,
}

impl ClientServer<'_> {
    fn start(&mut self, protocol: u64, config: &Config, shared: Option<&SharedOffer>) -> Answer {
        let Some(layout) = layout_of(config) else {
            return Answer::error("the image sizes fit no layout of this configuration");
        };
        let started =
            LibClient::start(self.path, &config.interface(), layout).and_then(LibClient::guarded);
        let started = match started {
            Ok(started) => started,
            Err(error) => return Answer::error(error.to_string()),
        };
        let declared = started.declaration();
        self.client = Some((started, layout));
        // Version 3 where offered and the mapping opens; else 1.
        let switch = session::agree(protocol, shared);
        let protocol = match switch {
            Switch::ToShared(_) => 3,
            _ => 1,
        };
        self.switch = Some(switch);
        Answer::Started {
            protocol,
            tells_sent: None,
            restarts: None,
            declares: by_name(&declared),
        }
    }
}

/// A declaration as the protocol carries it: name to value.
fn by_name(declaration: &ClientDeclaration) -> std::collections::BTreeMap<String, String> {
    declaration
        .lines()
        .iter()
        .filter_map(|l| l.split_once('='))
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect()
}

impl Serves for ClientServer<'_> {
    fn answer(&mut self, request: &Request) -> Option<Answer> {
        Some(match request {
            Request::Bye {} => return None,
            Request::Declare {} => match LibClient::declares(self.path) {
                Ok(declaration) => Answer::Declared {
                    declares: by_name(&declaration),
                },
                Err(error) => Answer::error(error.to_string()),
            },
            Request::Start {
                protocol,
                config,
                shared,
            } => self.start(*protocol, config, shared.as_ref()),
            Request::Task {
                inputs,
                outputs,
                requests,
            } => match self.client.as_mut() {
                None => Answer::error("start first"),
                Some((client, layout)) => {
                    task(client, *layout, inputs.clone(), outputs.clone(), requests)
                }
            },
            other => Answer::error(format!(
                "`{}` is the device role's; this is a client",
                other.name()
            )),
        })
    }

    fn switch(&mut self) -> Switch {
        self.switch.take().unwrap_or(Switch::Stay)
    }
}

/// Serves the library at `path` over the protocol until `bye` or the end of
/// the input (descriptor `line_fd`).
pub fn serve_library(
    path: &Path,
    input: impl BufRead,
    line_fd: i32,
    output: impl Write,
) -> std::io::Result<()> {
    let mut server = ClientServer {
        path,
        client: None,
        switch: None,
    };
    session::run(&mut server, input, line_fd, output)
}

fn task(
    client: &mut LibClient,
    layout: ImageLayout,
    inputs: Hex,
    mut outputs: Hex,
    requests: &[WireMessage],
) -> Answer {
    if inputs.0.len() != layout.input_size() || outputs.0.len() != layout.output_size() {
        return Answer::error("images of the wrong size for the started interface");
    }
    let requests: Result<Vec<MessageRepr>, String> =
        requests.iter().map(MessageRepr::try_from).collect();
    let requests = match requests {
        Ok(requests) => requests,
        Err(error) => return Answer::error(format!("a request that is no message: {error}")),
    };
    let io = TaskIo {
        inputs: &inputs.0,
        outputs: &mut outputs.0,
        requests: &requests,
    };
    match client.task_raw(io) {
        Ok(done) => Answer::Tasked {
            outputs,
            delivered: done
                .delivered
                .iter()
                .map(|m| WireMessage {
                    frame: WireFrame {
                        id: m.frame.id,
                        extended: m.frame.extended != 0,
                        rtr: m.frame.rtr != 0,
                        fd: m.frame.fd != 0,
                        brs: m.frame.brs != 0,
                        esi: m.frame.esi != 0,
                        len: m.frame.len,
                        // A remote frame's length is what it asks for: it carries no data.
                        data: FrameData::from(match m.frame.rtr {
                            0 => &m.frame.data[..usize::from(m.frame.len).min(64)],
                            _ => &[][..],
                        }),
                    },
                    transaction_number: m.transaction_number,
                    time_stamp_ns: m.time_stamp_ns,
                })
                .collect(),
            refused: done.refused,
            sent: done.sent,
        },
        Err(error) => Answer::error(error.to_string()),
    }
}
