//! The client's side of the adapter protocol for a library: what `canif
//! lib-host --role client` runs, so that what the library does wrong ends in
//! that process and not in canif. Its delivered messages pass on as the C
//! ABI gave them (canif decodes and judges them, as for a library in process).

use std::io::{BufRead, Write};
use std::path::Path;

use canif_model::config::InterfaceConfig;
use canif_model::image::{ImageLayout, MessageRepr};

use crate::door::adapter::protocol::{Answer, Config, Hex, Request, WireFrame, WireMessage};
use crate::door::client::{Client, TaskIo};
use crate::door::lib::client::LibClient;
use crate::error::IutError;

/// The client role's protocol version this server speaks.
const PROTOCOL: u64 = 1;

/// The layout the sizes of `config` name (with InfoData or without).
fn layout_of(config: &Config) -> Option<ImageLayout> {
    let interface = config.interface();
    [false, true]
        .into_iter()
        .map(|info_data| ImageLayout::new(&interface, info_data))
        .find(|l| l.input_size() == config.input_size && l.output_size() == config.output_size)
}

/// Serves the library at `path` over the protocol until `bye` or the end of
/// the input: each `start` starts a program of it, its images behind guard pages.
pub fn serve_library(
    path: &Path,
    input: impl BufRead,
    mut output: impl Write,
) -> std::io::Result<()> {
    let start = |config: &InterfaceConfig, layout| -> Result<LibClient, IutError> {
        LibClient::start(path, config, layout)?.guarded()
    };
    let mut client: Option<(LibClient, ImageLayout)> = None;
    for line in input.lines() {
        let line = match line {
            Ok(line) if line.trim().is_empty() => continue,
            Ok(line) => line,
            Err(error) => {
                answer(&mut output, &Answer::error(format!("not a line: {error}")))?;
                continue;
            }
        };
        let reply = match serde_json::from_str::<Request>(&line) {
            Err(error) => Answer::error(format!("not a request: {error}")),
            Ok(Request::Bye {}) => return Ok(()),
            Ok(Request::Start { config, .. }) => match layout_of(&config) {
                None => Answer::error("the image sizes fit no layout of this configuration"),
                Some(layout) => match start(&config.interface(), layout) {
                    Ok(started) => {
                        let declared = started.declaration();
                        client = Some((started, layout));
                        Answer::Started {
                            protocol: PROTOCOL,
                            tells_sent: None,
                            declares: declared
                                .lines()
                                .iter()
                                .filter_map(|l| l.split_once('='))
                                .map(|(k, v)| (k.to_string(), v.to_string()))
                                .collect(),
                        }
                    }
                    Err(error) => Answer::error(error.to_string()),
                },
            },
            Ok(Request::Task {
                inputs,
                outputs,
                requests,
            }) => match client.as_mut() {
                None => Answer::error("start first"),
                Some((client, layout)) => task(client, *layout, inputs, outputs, &requests),
            },
            Ok(other) => Answer::error(format!(
                "`{}` is the device role's; this is a client",
                other.name()
            )),
        };
        answer(&mut output, &reply)?;
    }
    Ok(())
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
                        data: Hex(match m.frame.rtr {
                            0 => m.frame.data[..usize::from(m.frame.len).min(64)].to_vec(),
                            _ => Vec::new(),
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

fn answer(output: &mut impl Write, answer: &Answer) -> std::io::Result<()> {
    let mut line = serde_json::to_vec(answer).map_err(std::io::Error::other)?;
    line.push(b'\n');
    output.write_all(&line)?;
    output.flush()
}
