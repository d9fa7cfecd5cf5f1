//! One session of the adapter protocol as an implementation's side runs it,
//! for either role: requests on the line channel, and once `configure` or
//! `start` agreed version 3, records in the shared mapping, each answered
//! where it came. Whatever a line holds — not JSON, not UTF-8, fields the
//! protocol does not name — it gets an `error` answer.

use std::io::{BufRead, Write};
use std::os::fd::AsFd;

use crate::door::adapter::protocol::{Answer, BusEvent, Request, SharedOffer};
use crate::door::adapter::shared::{IutEnd, Next};

/// What serves the requests: a device or a client.
pub trait Serves {
    /// Reads one request line: the request, or the error answer to give.
    fn parse(&self, line: &str) -> Result<Request, Answer> {
        serde_json::from_str(line).map_err(|e| Answer::error(format!("not a request: {e}")))
    }
    /// The answer to one request; `None` for `bye`.
    fn answer(&mut self, request: &Request) -> Option<Answer>;
    /// Where the requests after the last answer come: asked once per line
    /// answered (a `configure` or `start` may change it).
    fn switch(&mut self) -> Switch;
}

/// Where the next requests come.
pub enum Switch {
    /// Where they came so far.
    Stay,
    /// The shared mapping (version 3 agreed).
    ToShared(IutEnd),
    /// The lines (a version below 3 agreed).
    ToLines,
}

/// Version 3 where the harness offered it (`offered` at least 3, with its
/// descriptors) and the mapping opens; the lines otherwise.
pub fn agree(offered: u64, shared: Option<&SharedOffer>) -> Switch {
    match shared.filter(|_| offered >= 3).map(IutEnd::open) {
        Some(Ok(end)) => Switch::ToShared(end),
        _ => Switch::ToLines,
    }
}

/// Writes one answer as a line.
pub fn write_answer(output: &mut impl Write, answer: &Answer) -> std::io::Result<()> {
    // Writing an internally tagged enum buffers nothing (only reading does).
    let mut line = serde_json::to_vec(answer).expect("answers serialize");
    line.push(b'\n');
    output.write_all(&line)?;
    output.flush()
}

/// Serves until `bye` or the end of `input`, the line channel, whose
/// descriptor is `line_fd` (watched for a line while version 3 runs in
/// the shared mapping).
pub fn run(
    server: &mut dyn Serves,
    mut input: impl BufRead,
    line_fd: i32,
    mut output: impl Write,
) -> std::io::Result<()> {
    // Our own descriptor for the channel, to wait on beside the eventfd.
    let line = canif_cabi::shared::inherited(line_fd)?;
    let mut shared: Option<IutEnd> = None;
    let mut bytes = Vec::new();
    loop {
        if let Some(end) = shared.as_mut() {
            match end.next(line.as_fd())? {
                Next::Request(events, request) => {
                    // The events as version 1 sends them, each answered
                    // `ok`: the first that is not is the record's answer.
                    let answer = events
                        .into_iter()
                        .map(BusEvent::into_request)
                        .chain(std::iter::once(request))
                        .map(|request| {
                            server
                                .answer(&request)
                                .unwrap_or_else(|| Answer::error("`bye` comes on the line channel"))
                        })
                        .find(|answer| !matches!(answer, Answer::Ok))
                        .unwrap_or(Answer::Ok);
                    end.answer(&answer);
                    continue;
                }
                Next::Broken(why) => {
                    end.answer(&Answer::error(format!("not a record: {why}")));
                    continue;
                }
                Next::Line => {}
            }
        }
        bytes.clear();
        if input.read_until(b'\n', &mut bytes)? == 0 {
            return Ok(());
        }
        let answer = match std::str::from_utf8(&bytes) {
            Err(error) => Answer::error(format!("not UTF-8: {error}")),
            Ok(text) if text.trim().is_empty() => continue,
            Ok(text) => match server.parse(text) {
                Ok(request) => match server.answer(&request) {
                    Some(answer) => answer,
                    None => return Ok(()),
                },
                Err(answer) => answer,
            },
        };
        write_answer(&mut output, &answer)?;
        match server.switch() {
            Switch::Stay => {}
            Switch::ToShared(end) => shared = Some(end),
            Switch::ToLines => shared = None,
        }
    }
}
