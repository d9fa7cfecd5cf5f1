//! An implementation under test in another process, in any language, speaking
//! the adapter protocol of docs/adapter-protocol.md: one JSON object per line
//! on its stdin and stdout; its stderr is its log.
//!
//! Whatever the process does — exit, hang, print garbage, speak another
//! protocol version, return an image of the wrong size — becomes an `error`
//! naming what happened and the last lines of its stderr; the harness never
//! waits longer than the per-exchange timeout.

use std::collections::VecDeque;
use std::io::{BufRead, BufReader, Write};
use std::process::{Child, ChildStdin, Command, Stdio};
use std::sync::mpsc::{self, Receiver, RecvTimeoutError};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use canif_model::config::{Capabilities, FrameFormat, InterfaceConfig, QueueMode, Synchronization};
use canif_model::filter::{FilterAction, FilterMatch};
use canif_model::frame::{CanId, Frame, FrameKind};
use canif_model::image::ImageLayout;
use canif_model::info_data::ControllerStatus;
use canif_model::Nanos;
use serde_json::{json, Value};

use crate::iut::{InvalidFrame, Iut, IutError};

/// The protocol version this harness speaks.
pub const PROTOCOL_VERSION: u64 = 1;

/// How many lines of the IUT's stderr an error shows.
const STDERR_LINES: usize = 20;

/// A running IUT process.
pub struct ExecIut {
    command: String,
    child: Child,
    stdin: Option<ChildStdin>,
    lines: Receiver<String>,
    stderr: Arc<Mutex<VecDeque<String>>>,
    timeout: Duration,
    input_size: usize,
    /// When a held frame (Distributed Clocks) becomes due, as the IUT said.
    next_release: Option<Nanos>,
    /// The first failure; every later call reports it.
    failed: Option<String>,
}

impl ExecIut {
    /// Starts `command` (through `sh -c`).
    pub fn spawn(command: &str, timeout: Duration) -> Result<Self, String> {
        let mut child = Command::new("sh")
            .arg("-c")
            .arg(command)
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .map_err(|e| format!("cannot start `{command}`: {e}"))?;
        let stdout = child.stdout.take().ok_or("no stdout")?;
        let stderr = child.stderr.take().ok_or("no stderr")?;
        let (sender, lines) = mpsc::channel();
        std::thread::spawn(move || {
            for line in BufReader::new(stdout).lines() {
                let Ok(line) = line else { break };
                if sender.send(line).is_err() {
                    break;
                }
            }
        });
        let log = Arc::new(Mutex::new(VecDeque::new()));
        let log_writer = log.clone();
        std::thread::spawn(move || {
            for line in BufReader::new(stderr).lines() {
                let Ok(line) = line else { break };
                if let Ok(mut log) = log_writer.lock() {
                    log.push_back(line);
                    if log.len() > STDERR_LINES {
                        log.pop_front();
                    }
                }
            }
        });
        let stdin = child.stdin.take();
        Ok(ExecIut {
            command: command.to_string(),
            child,
            stdin,
            lines,
            stderr: log,
            timeout,
            input_size: 0,
            next_release: None,
            failed: None,
        })
    }

    fn stderr_tail(&self) -> String {
        // Give the stderr reader a moment to catch the last words of a dying process.
        std::thread::sleep(Duration::from_millis(20));
        let log = self
            .stderr
            .lock()
            .map(|l| l.iter().cloned().collect::<Vec<_>>())
            .unwrap_or_default();
        if log.is_empty() {
            "(its stderr is empty)".into()
        } else {
            format!("last lines of its stderr:\n  {}", log.join("\n  "))
        }
    }

    fn fail(&mut self, what: String) -> String {
        let message = format!("IUT `{}`: {what}; {}", self.command, self.stderr_tail());
        self.failed.get_or_insert(message).clone()
    }

    /// Sends one request and waits for the one-line answer of the expected type.
    fn exchange(&mut self, request: Value, answer_type: &str) -> Result<Value, String> {
        if let Some(failure) = &self.failed {
            return Err(failure.clone());
        }
        let written = match self.stdin.as_mut() {
            Some(stdin) => writeln!(stdin, "{request}").and_then(|_| stdin.flush()),
            None => Err(std::io::Error::other("stdin closed")),
        };
        if let Err(error) = written {
            let status = self.child.try_wait().ok().flatten();
            return Err(self.fail(match status {
                Some(status) => format!(
                    "exited ({status}) before the `{}` request",
                    request["type"].as_str().unwrap_or("?")
                ),
                None => format!("cannot write to its stdin: {error}"),
            }));
        }
        let line = match self.lines.recv_timeout(self.timeout) {
            Ok(line) => line,
            Err(RecvTimeoutError::Timeout) => {
                let _ = self.child.kill();
                return Err(self.fail(format!(
                    "no answer to `{}` within {} ms (hung; killed)",
                    request["type"].as_str().unwrap_or("?"),
                    self.timeout.as_millis()
                )));
            }
            Err(RecvTimeoutError::Disconnected) => {
                let status = self
                    .child
                    .wait()
                    .map(|s| s.to_string())
                    .unwrap_or_else(|e| e.to_string());
                return Err(self.fail(format!(
                    "exited ({status}) instead of answering `{}`",
                    request["type"].as_str().unwrap_or("?")
                )));
            }
        };
        let answer: Value = match serde_json::from_str(&line) {
            Ok(value) => value,
            Err(error) => {
                return Err(self.fail(format!(
                    "printed something that is not a JSON object ({error}): {}",
                    truncate(&line)
                )))
            }
        };
        match answer["type"].as_str() {
            Some(kind) if kind == answer_type => Ok(answer),
            Some("error") => Err(self.fail(format!(
                "reported an error: {}",
                answer["message"].as_str().unwrap_or("(no message)")
            ))),
            Some(kind) => Err(self.fail(format!(
                "answered `{kind}` where `{answer_type}` was due: {}",
                truncate(&line)
            ))),
            None => Err(self.fail(format!("answered without a \"type\": {}", truncate(&line)))),
        }
    }

    /// Offers a configuration. `Ok(true)`: accepted; `Ok(false)`: refused (a
    /// legitimate answer); `Err`: the IUT failed.
    pub fn configure(
        &mut self,
        caps: &Capabilities,
        config: &InterfaceConfig,
        bus: Option<&crate::iut::OwnedBus>,
    ) -> Result<Result<(), String>, String> {
        let layout = ImageLayout::new(config, caps.info_data);
        let mut request = json!({
            "type": "configure",
            "protocol": PROTOCOL_VERSION,
            "config": config_json(config, &layout),
            "capabilities": caps_json(caps),
        });
        if let Some(bus) = bus {
            request["bus"] = json!({"socketcan": bus.interface, "epoch_ns": bus.epoch_ns});
        }
        let answer = self.exchange(request, "configured")?;
        if answer["protocol"].as_u64() != Some(PROTOCOL_VERSION) {
            return Err(self.fail(format!(
                "speaks protocol version {} (this harness speaks {PROTOCOL_VERSION})",
                answer["protocol"]
            )));
        }
        self.input_size = layout.input_size();
        match answer["accepted"].as_bool() {
            Some(true) => Ok(Ok(())),
            Some(false) => Ok(Err(answer["reason"]
                .as_str()
                .unwrap_or("refused")
                .to_string())),
            None => {
                Err(self.fail("a `configured` answer needs \"accepted\": true or false".into()))
            }
        }
    }
}

impl Drop for ExecIut {
    fn drop(&mut self) {
        if self.failed.is_none() {
            if let Some(stdin) = self.stdin.as_mut() {
                let _ = writeln!(stdin, "{}", json!({"type": "bye"}));
            }
        }
        self.stdin = None; // EOF tells a well-behaved IUT to leave
        for _ in 0..20 {
            if matches!(self.child.try_wait(), Ok(Some(_))) {
                return;
            }
            std::thread::sleep(Duration::from_millis(5));
        }
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

fn truncate(line: &str) -> String {
    if line.len() > 200 {
        format!(
            "{}…",
            &line[..line.char_indices().nth(200).map_or(line.len(), |(i, _)| i)]
        )
    } else {
        line.to_string()
    }
}

fn hex_decode(text: &str) -> Option<Vec<u8>> {
    if !text.len().is_multiple_of(2) {
        return None;
    }
    (0..text.len())
        .step_by(2)
        .map(|i| u8::from_str_radix(text.get(i..i + 2)?, 16).ok())
        .collect()
}

fn hex_encode(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

/// A frame as the protocol writes it.
pub fn frame_json(frame: &Frame) -> Value {
    let (rtr, fd, brs, esi) = match frame.kind {
        FrameKind::Classic { rtr } => (rtr, false, false, false),
        FrameKind::Fd { brs, esi } => (false, true, brs, esi),
    };
    json!({
        "id": frame.id.raw(), "extended": frame.id.is_extended(), "rtr": rtr, "fd": fd, "brs": brs, "esi": esi,
        "len": frame.len(), "data": hex_encode(frame.data()),
    })
}

/// A frame from the protocol; `Err` says what is wrong with it.
pub fn frame_from_json(value: &Value) -> Result<Frame, String> {
    let id = value["id"]
        .as_u64()
        .ok_or("a frame needs a numeric \"id\"")? as u32;
    let flag = |name: &str| value[name].as_bool().unwrap_or(false);
    let id = if flag("extended") {
        CanId::extended(id)
    } else {
        CanId::standard(id)
    }
    .ok_or_else(|| format!("identifier 0x{id:X} out of range"))?;
    let data = hex_decode(value["data"].as_str().unwrap_or("")).ok_or("\"data\" is not hex")?;
    let frame = if flag("fd") {
        Frame::fd(id, flag("brs"), flag("esi"), &data)
    } else if flag("rtr") {
        Frame::remote(id, value["len"].as_u64().unwrap_or(0) as u8)
    } else {
        Frame::classic(id, &data)
    };
    frame.map_err(|e| e.to_string())
}

fn config_json(config: &InterfaceConfig, layout: &ImageLayout) -> Value {
    json!({
        "format": match config.format { FrameFormat::Base11 => "11-bit", FrameFormat::Extended29 => "29-bit", FrameFormat::Fd => "fd" },
        "queue": match config.queue { QueueMode::Standard => "standard", QueueMode::Optimized => "optimized", QueueMode::Fast => "fast" },
        "transaction_number": config.transaction_number,
        "time_stamp": config.time_stamp,
        "tx_slots": config.tx_slots,
        "rx_slots": config.rx_slots,
        "filters": config.filters.iter().map(|row| {
            let action = if row.action == FilterAction::Accept { "accept" } else { "reject" };
            match row.matches {
                FilterMatch::Range { from, to } => json!({"action": action, "kind": "range", "from": from, "to": to}),
                FilterMatch::CodeMask { code, mask } => json!({"action": action, "kind": "mask", "code": code, "mask": mask}),
            }
        }).collect::<Vec<_>>(),
        "sync1_shift_ns": match config.synchronization { Synchronization::Sm2 => Value::Null, Synchronization::DistributedClocks { sync1_shift } => json!(sync1_shift) },
        "nominal_timing": config.nominal_timing.to_word(),
        "data_timing": config.data_timing.to_word(),
        "output_size": layout.output_size(),
        "input_size": layout.input_size(),
    })
}

fn caps_json(caps: &Capabilities) -> Value {
    json!({
        "base11": caps.base11, "ext29": caps.ext29, "fd": caps.fd, "fast_queue": caps.fast_queue,
        "optimized_queue": caps.optimized_queue, "transaction_number": caps.transaction_number,
        "transaction_number_only_ext29": caps.transaction_number_only_ext29, "timestamp": caps.time_stamp,
        "filters": caps.filters, "info_data": caps.info_data, "distributed_clocks": caps.distributed_clocks,
        "max_slots": caps.max_slots, "rx_queue_depth": caps.rx_queue_depth, "tx_queue_depth": caps.tx_queue_depth,
    })
}

impl Iut for ExecIut {
    fn cycle(&mut self, outputs: &[u8], now: Nanos) -> Result<Vec<u8>, IutError> {
        let answer = self
            .exchange(
                json!({"type": "cycle", "now_ns": now, "outputs": hex_encode(outputs)}),
                "inputs",
            )
            .map_err(IutError)?;
        let inputs = match answer["inputs"].as_str().and_then(hex_decode) {
            Some(inputs) => inputs,
            None => return Err(IutError(self.fail("\"inputs\" is not a hex string".into()))),
        };
        if inputs.len() != self.input_size {
            return Err(IutError(self.fail(format!(
                "returned an input image of {} bytes; the layout has {}",
                inputs.len(),
                self.input_size
            ))));
        }
        Ok(inputs)
    }

    fn receive(&mut self, frame: &Frame, end_of_reception: Nanos) {
        let _ = self.exchange(
            json!({"type": "receive", "frame": frame_json(frame), "end_ns": end_of_reception}),
            "ok",
        );
    }

    fn poll_transmit(&mut self, now: Nanos) -> Option<Result<Frame, InvalidFrame>> {
        let answer = self
            .exchange(json!({"type": "poll_transmit", "now_ns": now}), "transmit")
            .ok()?;
        self.next_release = answer["next_ns"].as_u64();
        if answer["frame"].is_null() {
            return None;
        }
        Some(frame_from_json(&answer["frame"]).map_err(InvalidFrame))
    }

    fn poll_timeout(&self) -> Option<Nanos> {
        self.next_release
    }

    fn transmit_complete(&mut self) {
        let _ = self.exchange(json!({"type": "transmit_complete"}), "ok");
    }

    fn controller_status(&mut self, status: &ControllerStatus) {
        let request = json!({"type": "controller_status", "status": {
            "bus_off": status.bus_off, "error_passive": status.error_passive, "node_active": status.node_active,
            "warning_limit": status.warning_limit, "overload": status.overload, "bus_idle": status.bus_idle,
            "transceiver_delay": status.transceiver_delay, "ack_errors": status.ack_errors, "bit_errors": status.bit_errors,
            "crc_errors": status.crc_errors, "form_errors": status.form_errors, "stuff_errors": status.stuff_errors,
            "receive_error_counter": status.receive_error_counter, "transmit_error_counter": status.transmit_error_counter,
            "core_running": status.core_running,
        }});
        let _ = self.exchange(request, "ok");
    }
}

fn config_from_json(value: &Value) -> Result<(Capabilities, InterfaceConfig), String> {
    let config = &value["config"];
    let caps_value = &value["capabilities"];
    let flag = |v: &Value, name: &str| v[name].as_bool().unwrap_or(false);
    let number = |v: &Value, name: &str| {
        v[name]
            .as_u64()
            .ok_or_else(|| format!("\"{name}\" missing or not a number"))
    };
    let format = match config["format"].as_str() {
        Some("11-bit") => FrameFormat::Base11,
        Some("29-bit") => FrameFormat::Extended29,
        Some("fd") => FrameFormat::Fd,
        other => return Err(format!("unknown format {other:?}")),
    };
    let queue = match config["queue"].as_str() {
        Some("standard") => QueueMode::Standard,
        Some("optimized") => QueueMode::Optimized,
        Some("fast") => QueueMode::Fast,
        other => return Err(format!("unknown queue {other:?}")),
    };
    let mut interface = InterfaceConfig::new(format, number(config, "tx_slots")? as u8);
    interface.queue = queue;
    interface.rx_slots = number(config, "rx_slots")? as u8;
    interface.transaction_number = flag(config, "transaction_number");
    interface.time_stamp = flag(config, "time_stamp");
    interface.synchronization = match config["sync1_shift_ns"].as_u64() {
        Some(shift) => Synchronization::DistributedClocks { sync1_shift: shift },
        None => Synchronization::Sm2,
    };
    interface.nominal_timing = canif_model::info_data::BitTiming::from_word(
        config["nominal_timing"].as_u64().unwrap_or(0) as u32,
    );
    interface.data_timing = canif_model::info_data::BitTiming::from_word(
        config["data_timing"].as_u64().unwrap_or(0) as u32,
    );
    for row in config["filters"].as_array().into_iter().flatten() {
        let action = if row["action"] == "accept" {
            FilterAction::Accept
        } else {
            FilterAction::Reject
        };
        let matches = if row["kind"] == "range" {
            FilterMatch::Range {
                from: number(row, "from")? as u32,
                to: number(row, "to")? as u32,
            }
        } else {
            FilterMatch::CodeMask {
                code: number(row, "code")? as u32,
                mask: number(row, "mask")? as u32,
            }
        };
        interface
            .filters
            .push(canif_model::filter::FilterRow { action, matches });
    }
    let caps = Capabilities {
        base11: flag(caps_value, "base11"),
        ext29: flag(caps_value, "ext29"),
        fd: flag(caps_value, "fd"),
        fast_queue: flag(caps_value, "fast_queue"),
        optimized_queue: flag(caps_value, "optimized_queue"),
        transaction_number: flag(caps_value, "transaction_number"),
        transaction_number_only_ext29: flag(caps_value, "transaction_number_only_ext29"),
        time_stamp: flag(caps_value, "timestamp"),
        filters: flag(caps_value, "filters"),
        info_data: flag(caps_value, "info_data"),
        distributed_clocks: flag(caps_value, "distributed_clocks"),
        max_slots: number(caps_value, "max_slots")? as u8,
        rx_queue_depth: number(caps_value, "rx_queue_depth")? as usize,
        tx_queue_depth: number(caps_value, "tx_queue_depth")? as usize,
    };
    Ok((caps, interface))
}

fn status_from_json(value: &Value) -> ControllerStatus {
    let flag = |name: &str| value[name].as_bool().unwrap_or(false);
    let count = |name: &str| value[name].as_u64().unwrap_or(0) as u32;
    ControllerStatus {
        bus_off: flag("bus_off"),
        error_passive: flag("error_passive"),
        node_active: flag("node_active"),
        warning_limit: flag("warning_limit"),
        overload: flag("overload"),
        bus_idle: flag("bus_idle"),
        transceiver_delay: count("transceiver_delay"),
        ack_errors: count("ack_errors"),
        bit_errors: count("bit_errors"),
        crc_errors: count("crc_errors"),
        form_errors: count("form_errors"),
        stuff_errors: count("stuff_errors"),
        receive_error_counter: count("receive_error_counter"),
        transmit_error_counter: count("transmit_error_counter"),
        core_running: flag("core_running"),
    }
}

/// Serves an in-process IUT over the adapter protocol: what `canif device
/// --stdio` runs. Returns when the harness says `bye` or closes the input.
pub fn serve(
    kind: &crate::iut::IutKind,
    input: impl BufRead,
    mut output: impl Write,
) -> std::io::Result<()> {
    let mut iut: Option<Box<dyn Iut>> = None;
    for line in input.lines() {
        let line = line?;
        if line.trim().is_empty() {
            continue;
        }
        let answer = match serde_json::from_str(&line) {
            Ok(request) => match answer(kind, &mut iut, &request, true) {
                Some(answer) => answer,
                None => return Ok(()),
            },
            Err(error) => not_json(error),
        };
        writeln!(output, "{answer}")?;
        output.flush()?;
    }
    Ok(())
}

fn not_json(error: serde_json::Error) -> Value {
    json!({"type": "error", "message": format!("not JSON: {error}")})
}

/// The answer to one request; `None` for `bye`. `drives_bus`: the harness
/// drives the CAN side through the protocol (no SocketCAN bus).
fn answer(
    kind: &crate::iut::IutKind,
    iut: &mut Option<Box<dyn Iut>>,
    request: &Value,
    drives_bus: bool,
) -> Option<Value> {
    let bus_request = matches!(
        request["type"].as_str(),
        Some("receive" | "poll_transmit" | "transmit_complete")
    );
    Some(match (request["type"].as_str(), iut.as_mut()) {
        (Some("bye"), _) => return None,
        (Some("configure"), _) => match config_from_json(request) {
            Ok((caps, config)) => match kind.build(&caps, &config) {
                Ok(built) => {
                    *iut = Some(built);
                    json!({"type": "configured", "protocol": PROTOCOL_VERSION, "accepted": true})
                }
                Err(error) => {
                    *iut = None;
                    json!({"type": "configured", "protocol": PROTOCOL_VERSION, "accepted": false, "reason": error.to_string()})
                }
            },
            Err(error) => json!({"type": "error", "message": error}),
        },
        (Some(_), None) => json!({"type": "error", "message": "configure first"}),
        (Some(kind), _) if bus_request && !drives_bus => json!({
            "type": "error",
            "message": format!("`{kind}`: this device is on a SocketCAN bus and owns its CAN side")
        }),
        (Some("cycle"), Some(iut)) => {
            let outputs = hex_decode(request["outputs"].as_str().unwrap_or("")).unwrap_or_default();
            match iut.cycle(&outputs, request["now_ns"].as_u64().unwrap_or(0)) {
                Ok(inputs) => json!({"type": "inputs", "inputs": hex_encode(&inputs)}),
                Err(error) => json!({"type": "error", "message": error.0}),
            }
        }
        (Some("receive"), Some(iut)) => match frame_from_json(&request["frame"]) {
            Ok(frame) => {
                iut.receive(&frame, request["end_ns"].as_u64().unwrap_or(0));
                json!({"type": "ok"})
            }
            Err(error) => json!({"type": "error", "message": error}),
        },
        (Some("poll_transmit"), Some(iut)) => {
            let frame = match iut.poll_transmit(request["now_ns"].as_u64().unwrap_or(0)) {
                Some(Ok(frame)) => frame_json(&frame),
                Some(Err(invalid)) => json!({"invalid": invalid.0}),
                None => Value::Null,
            };
            json!({"type": "transmit", "frame": frame, "next_ns": iut.poll_timeout()})
        }
        (Some("transmit_complete"), Some(iut)) => {
            iut.transmit_complete();
            json!({"type": "ok"})
        }
        (Some("controller_status"), Some(iut)) => {
            iut.controller_status(&status_from_json(&request["status"]));
            json!({"type": "ok"})
        }
        (other, _) => json!({"type": "error", "message": format!("unknown request {other:?}")}),
    })
}

/// The device's CAN side on a SocketCAN interface, while `serve_on_bus` runs.
struct DeviceBus {
    socket: canif_kernel::KernelSocket,
    epoch: Nanos,
    /// The frame the controller is sending, and whether the kernel took it.
    sending: Option<Frame>,
    written: bool,
}

impl DeviceBus {
    fn open(interface: &str, epoch: Nanos) -> Result<Self, String> {
        canif_kernel::probe()?;
        Ok(DeviceBus {
            socket: canif_kernel::KernelSocket::open(interface, true)?,
            epoch,
            sending: None,
            written: false,
        })
    }

    fn now(&self) -> Nanos {
        canif_kernel::realtime_ns().saturating_sub(self.epoch)
    }

    /// The controller's interrupts: frames received (with the kernel's time
    /// stamp), the frame sent confirmed, the next one started.
    fn pump(&mut self, iut: &mut dyn Iut) -> Result<(), String> {
        let name = &self.socket.interface;
        while let Some(received) = self.socket.recv().map_err(|e| format!("{name}: {e}"))? {
            match received {
                canif_kernel::Received::Frame {
                    frame,
                    at,
                    own: false,
                } => iut.receive(&frame, at.saturating_sub(self.epoch)),
                canif_kernel::Received::Frame { own: true, .. } => {
                    self.sending = None;
                    self.written = false;
                    iut.transmit_complete();
                }
                canif_kernel::Received::Error { .. } => {}
            }
        }
        loop {
            let frame = match (self.sending, self.written) {
                (Some(_), true) => return Ok(()),
                (Some(frame), false) => frame,
                (None, _) => match iut.poll_transmit(self.now()) {
                    None => return Ok(()),
                    Some(Err(invalid)) => {
                        eprintln!(
                            "{name}: the device produced an invalid frame, not sent: {}",
                            invalid.0
                        );
                        continue;
                    }
                    Some(Ok(frame)) => frame,
                },
            };
            self.sending = Some(frame);
            match self.socket.send(&frame) {
                Ok(()) => self.written = true,
                // The queue is full: the frame goes out on a later pump.
                Err(error) if error.raw_os_error() == Some(canif_kernel::ENOBUFS) => {
                    self.written = false;
                    return Ok(());
                }
                Err(error) => return Err(format!("{name}: {error}")),
            }
        }
    }
}

/// Serves an in-process IUT over the adapter protocol on stdin/stdout with its
/// CAN side on a SocketCAN interface: `canif device --stdio --bus socketcan:IFACE`.
/// The interface is the one `configure.bus.socketcan` names, else `interface`.
pub fn serve_on_bus(kind: &crate::iut::IutKind, interface: Option<&str>) -> Result<(), String> {
    let (lines, requests) = std::sync::mpsc::channel::<String>();
    std::thread::spawn(move || {
        for line in std::io::stdin().lines().map_while(Result::ok) {
            if lines.send(line).is_err() {
                break;
            }
        }
    });
    let mut output = std::io::stdout();
    let mut iut: Option<Box<dyn Iut>> = None;
    let mut bus: Option<DeviceBus> = None;
    loop {
        let line = match requests.recv_timeout(Duration::from_micros(500)) {
            Ok(line) => Some(line),
            Err(std::sync::mpsc::RecvTimeoutError::Timeout) => None,
            Err(std::sync::mpsc::RecvTimeoutError::Disconnected) => return Ok(()),
        };
        if let (Some(bus), Some(device)) = (bus.as_mut(), iut.as_mut()) {
            // Frames the kernel delivered before a request count as received before it.
            bus.pump(device.as_mut())?;
        }
        let Some(line) = line.filter(|l| !l.trim().is_empty()) else {
            continue;
        };
        let request: Value = match serde_json::from_str(&line) {
            Ok(request) => request,
            Err(error) => {
                writeln!(output, "{}", not_json(error)).map_err(|e| e.to_string())?;
                output.flush().map_err(|e| e.to_string())?;
                continue;
            }
        };
        let Some(mut reply) = answer(kind, &mut iut, &request, false) else {
            return Ok(());
        };
        if request["type"] == "configure" && iut.is_some() {
            let name = request["bus"]["socketcan"].as_str().or(interface);
            let epoch = request["bus"]["epoch_ns"].as_u64().unwrap_or(0);
            bus = None;
            match name.map(|name| DeviceBus::open(name, epoch)) {
                Some(Ok(opened)) => bus = Some(opened),
                Some(Err(error)) => reply = json!({"type": "error", "message": error}),
                None => {
                    reply = json!({"type": "error", "message": "no SocketCAN interface: start with --bus socketcan:IFACE or send configure.bus"})
                }
            }
        }
        writeln!(output, "{reply}").map_err(|e| e.to_string())?;
        output.flush().map_err(|e| e.to_string())?;
        if let (Some(bus), Some(device)) = (bus.as_mut(), iut.as_mut()) {
            bus.pump(device.as_mut())?;
        }
    }
}
