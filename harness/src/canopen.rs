//! CANopen as a conformance target: the telegrams of the quick start (002) and
//! the SDO page (004) sent to a node, and its answers checked. Any node that
//! takes frames and time works: the simulated coupler of the model, or a node
//! on a SocketCAN interface ([`SocketCanNode`], real time).

use canif_model::canopen::cob_id::{default_cob_id, Channel};
use canif_model::canopen::coupler::Coupler;
use canif_model::canopen::guarding::{self, GuardChecker};
use canif_model::canopen::heartbeat;
use canif_model::canopen::nmt::{command_frame, NmtCommand, NmtState};
use canif_model::canopen::sdo::{abort_code, SdoRequest, SdoResponse};
use canif_model::canopen::NodeId;
use canif_model::frame::{CanId, Frame};
use canif_model::Nanos;

/// A CANopen node under test.
pub trait CanNode {
    /// A frame reaches the node at `now`; what it answers.
    fn handle(&mut self, frame: &Frame, now: Nanos) -> Vec<Frame>;
    /// Time passes; what it sends by itself.
    fn poll(&mut self, now: Nanos) -> Vec<Frame>;
}

impl CanNode for Coupler {
    fn handle(&mut self, frame: &Frame, now: Nanos) -> Vec<Frame> {
        Coupler::handle(self, frame, now)
    }
    fn poll(&mut self, now: Nanos) -> Vec<Frame> {
        Coupler::poll(self, now)
    }
}

/// A CANopen node on a SocketCAN interface, checked in real time: `now` is
/// time since the node was opened; requests go out when their time has come.
pub struct SocketCanNode {
    socket: canif_kernel::KernelSocket,
    epoch: Nanos,
    /// How long to wait for the first answer to a request.
    pub answer_timeout: std::time::Duration,
    /// Frames that came but answered nothing (heartbeats, emergencies), for `poll`.
    backlog: Vec<Frame>,
    node: NodeId,
}

impl SocketCanNode {
    pub fn open(interface: &str, node: NodeId) -> Result<Self, String> {
        canif_kernel::probe()?;
        Ok(SocketCanNode {
            socket: canif_kernel::KernelSocket::open(interface, false)?,
            epoch: canif_kernel::realtime_ns(),
            answer_timeout: std::time::Duration::from_millis(200),
            backlog: Vec::new(),
            node,
        })
    }

    /// Real time catches up with `now`; when real time is already past it
    /// (answers take real time the checks do not count), the time base slips,
    /// so that intervals from here on are real.
    fn wait_until(&mut self, now: Nanos) {
        let real = canif_kernel::realtime_ns();
        let at = self.epoch + now;
        if at > real {
            std::thread::sleep(std::time::Duration::from_nanos(at - real));
        } else {
            self.epoch = real - now;
        }
    }

    fn drain(&mut self) -> Vec<Frame> {
        let mut frames = Vec::new();
        while let Ok(Some(received)) = self.socket.recv() {
            if let canif_kernel::Received::Frame { frame, .. } = received {
                frames.push(frame);
            }
        }
        frames
    }

    /// The identifier a request's answer comes on, if it has one.
    fn answer_id(&self, request: &Frame) -> Option<CanId> {
        let sdo_request = CanId::Standard(default_cob_id(Channel::SdoRequest, self.node));
        match request.id {
            CanId::Standard(0) => None, // NMT commands are not answered
            id if id == sdo_request => Some(CanId::Standard(default_cob_id(
                Channel::SdoResponse,
                self.node,
            ))),
            id if request.is_remote() => Some(id),
            _ => None,
        }
    }
}

impl CanNode for SocketCanNode {
    fn handle(&mut self, frame: &Frame, now: Nanos) -> Vec<Frame> {
        self.wait_until(now);
        let stale = self.drain();
        self.backlog.extend(stale);
        if self.socket.send(frame).is_err() {
            return Vec::new();
        }
        let Some(answer_id) = self.answer_id(frame) else {
            // Give the node a moment to act on an unanswered command.
            std::thread::sleep(std::time::Duration::from_millis(20));
            return Vec::new();
        };
        let started = std::time::Instant::now();
        let mut answers = Vec::new();
        let mut quiet_since: Option<std::time::Instant> = None;
        loop {
            for received in self.drain() {
                if received.id == answer_id {
                    answers.push(received);
                    quiet_since = Some(std::time::Instant::now());
                } else {
                    self.backlog.push(received);
                }
            }
            // After the first answer, a short quiet time shows whether a second one follows.
            let done = match quiet_since {
                Some(t) => t.elapsed() > std::time::Duration::from_millis(10),
                None => started.elapsed() > self.answer_timeout,
            };
            if done {
                return answers;
            }
            let _ = canif_kernel::KernelSocket::wait(
                &[&self.socket],
                std::time::Duration::from_millis(2),
            );
        }
    }

    fn poll(&mut self, now: Nanos) -> Vec<Frame> {
        self.wait_until(now);
        let mut frames = std::mem::take(&mut self.backlog);
        frames.extend(self.drain());
        frames
    }
}

/// One check's verdict.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CheckResult {
    pub name: &'static str,
    pub requirements: &'static [&'static str],
    pub outcome: Result<(), String>,
}

fn sdo_request(node: NodeId, request: SdoRequest) -> Frame {
    Frame::classic(
        CanId::Standard(default_cob_id(Channel::SdoRequest, node)),
        &request.to_bytes(),
    )
    .expect("8 bytes")
}

/// The one SDO answer to `request`, parsed.
fn sdo(
    target: &mut dyn CanNode,
    node: NodeId,
    request: SdoRequest,
    now: Nanos,
) -> Result<SdoResponse, String> {
    let answers = target.handle(&sdo_request(node, request), now);
    let response_id = CanId::Standard(default_cob_id(Channel::SdoResponse, node));
    let [answer] = answers.as_slice() else {
        return Err(format!(
            "expected one answer on 0x{:03X}, got {answers:?}",
            response_id.raw()
        ));
    };
    if answer.id != response_id {
        return Err(format!(
            "the answer came on 0x{:03X}, not 0x{:03X}",
            answer.id.raw(),
            response_id.raw()
        ));
    }
    SdoResponse::parse(answer.data()).map_err(|e| format!("{answer} is no SDO response: {e:?}"))
}

fn guard_state(
    target: &mut dyn CanNode,
    node: NodeId,
    checker: &mut GuardChecker,
    now: Nanos,
) -> Result<NmtState, String> {
    let answers = target.handle(&guarding::request(node), now);
    let [answer] = answers.as_slice() else {
        return Err(format!("expected one guarding answer, got {answers:?}"));
    };
    checker.check(answer)
}

/// Runs every check against `target`, a node with id `node`, from its boot
/// state. `tolerance`: how far a heartbeat may be from its due time (0 in
/// virtual time; a real bus needs the poll step plus scheduling jitter).
pub fn check_node(target: &mut dyn CanNode, node: NodeId, tolerance: Nanos) -> Vec<CheckResult> {
    let mut results = Vec::new();
    let mut now: Nanos = 0;
    let mut record = |name, requirements, outcome| {
        results.push(CheckResult {
            name,
            requirements,
            outcome,
        })
    };
    let mut guard = GuardChecker::default();

    record(
        "guarding answers with the state and a toggling bit 7",
        &["GRD-001", "GRD-002", "GRD-003", "GRD-004"],
        (0..4).try_for_each(|_| {
            now += 1_000_000;
            match guard_state(target, node, &mut guard, now)? {
                NmtState::PreOperational => Ok(()),
                other => Err(format!(
                    "state {other:?}, expected pre-operational after boot"
                )),
            }
        }),
    );

    target.handle(&command_frame(NmtCommand::StartRemoteNode, None), now);
    record(
        "NMT start (0x000: 01 00) makes the node operational",
        &["NMT-001", "NMT-003", "NMT-004", "NMT-006"],
        guard_state(target, node, &mut guard, now).and_then(|s| {
            if s == NmtState::Operational {
                Ok(())
            } else {
                Err(format!("state {s:?}"))
            }
        }),
    );

    record(
        "an RTR on the analog inputs is answered on 0x280 + node id",
        &["PDO-003", "COB-001", "PDO-002"],
        {
            let id = default_cob_id(Channel::AnalogInputs1To4, node);
            let answers = target.handle(&Frame::remote(CanId::Standard(id), 8).expect("rtr"), now);
            match answers.as_slice() {
                [answer]
                    if answer.id == CanId::Standard(id)
                        && answer.data().len() % 2 == 0
                        && !answer.data().is_empty() =>
                {
                    Ok(())
                }
                other => Err(format!("answers {other:?}")),
            }
        },
    );

    for (name, requirements, index, size, command) in [
        (
            "a 4-byte upload (0x1000) is answered with 0x43",
            &["SDO-001", "SDO-002", "SDO-005", "SDO-009"][..],
            0x1000u16,
            4u8,
            0x43u8,
        ),
        (
            "an Unsigned8 upload (0x1001) is answered with 0x4F, value in D0",
            &["SDO-005", "SDO-008"][..],
            0x1001,
            1,
            0x4F,
        ),
    ] {
        let outcome = sdo(
            target,
            node,
            SdoRequest::Upload {
                index,
                sub_index: 0,
            },
            now,
        )
        .and_then(|answer| match answer {
            SdoResponse::Upload {
                index: i,
                sub_index: 0,
                size: s,
                ..
            } if i == index && s == size => Ok(()),
            other => Err(format!(
                "answer {other:?} ({:02X?}), expected command byte 0x{command:02X}",
                other.to_bytes()
            )),
        });
        record(name, requirements, outcome);
    }

    let period_ms = 100u16;
    let download = sdo(target, node, heartbeat::set_producer_time(period_ms), now);
    record(
        "the heartbeat download (22 17 10 00 …) is confirmed with 0x60",
        &["HB-002", "SDO-003", "SDO-004", "SDO-006"],
        match download {
            Ok(SdoResponse::DownloadAck {
                index: 0x1017,
                sub_index: 0,
            }) => Ok(()),
            other => Err(format!("answer {other:?}")),
        },
    );
    let start = now;
    let mut beats = Vec::new();
    for step in 0..=35 {
        let at = start + step * 10_000_000;
        for frame in target.poll(at) {
            if frame.id == CanId::Standard(default_cob_id(Channel::ErrorControl, node)) {
                beats.push((at, frame.data().to_vec()));
            }
        }
    }
    record(
        "heartbeats carry the state every producer time",
        &["HB-001", "HB-003"],
        {
            let times: Vec<Nanos> = beats.iter().map(|(at, _)| at - start).collect();
            let states_ok = beats
                .iter()
                .all(|(_, data)| data == &[NmtState::Operational.code()]);
            let period = Nanos::from(period_ms) * 1_000_000;
            let on_time = times.len() == 4
                && times
                    .iter()
                    .zip(0..)
                    .all(|(t, k)| t.abs_diff(k * period) <= tolerance);
            if on_time && states_ok {
                Ok(())
            } else {
                Err(format!(
                    "heartbeats at {times:?} ns, data {:?}",
                    beats.iter().map(|(_, d)| d).collect::<Vec<_>>()
                ))
            }
        },
    );
    now = start + 400_000_000;
    let stop = sdo(target, node, heartbeat::set_producer_time(0), now);
    record(
        "producer time 0 stops the heartbeat",
        &["HB-002", "SDO-006"],
        match stop {
            Ok(SdoResponse::DownloadAck {
                index: 0x1017,
                sub_index: 0,
            }) => {
                now += 300_000_000;
                let late: Vec<Frame> = target
                    .poll(now)
                    .into_iter()
                    .filter(|f| {
                        f.id == CanId::Standard(default_cob_id(Channel::ErrorControl, node))
                    })
                    .collect();
                // One beat may have been on its way when the download arrived.
                if late.len() <= 1 {
                    Ok(())
                } else {
                    Err(format!("{} heartbeats after the stop", late.len()))
                }
            }
            other => Err(format!("answer {other:?}")),
        },
    );

    for (name, index, sub_index, code) in [
        (
            "an unknown object is aborted with 0x06020000",
            0x2345u16,
            0u8,
            abort_code::OBJECT_DOES_NOT_EXIST,
        ),
        (
            "an unknown sub-index is aborted with 0x06090011",
            0x1018,
            9,
            abort_code::SUB_INDEX_DOES_NOT_EXIST,
        ),
    ] {
        let outcome =
            sdo(target, node, SdoRequest::Upload { index, sub_index }, now).and_then(|answer| {
                match answer {
                    SdoResponse::Abort {
                        index: i,
                        sub_index: s,
                        code: c,
                    } if i == index && s == sub_index && c == code => Ok(()),
                    other => Err(format!("answer {other:?}")),
                }
            });
        record(name, &["SDO-007", "ERR-R8"], outcome);
    }

    target.handle(&command_frame(NmtCommand::EnterPreOperational, None), now);
    let pre_operational = guard_state(target, node, &mut guard, now);
    target.handle(&command_frame(NmtCommand::StopRemoteNode, Some(node)), now);
    let stopped = guard_state(target, node, &mut guard, now);
    record(
        "0x80 enters pre-operational (0x7F), 0x02 stops (0x04)",
        &[
            "NMT-002", "NMT-003", "NMT-004", "NMT-005", "ERR-R6", "GRD-003",
        ],
        match (pre_operational, stopped) {
            (Ok(NmtState::PreOperational), Ok(NmtState::Stopped)) => Ok(()),
            other => Err(format!("states {other:?}")),
        },
    );
    results
}

/// Sends a request (if any) and runs cycles until an answer on the given
/// identifier arrives or the cycles are over: the last cycle's time and what came.
type Exchange<'a> = dyn FnMut(Option<Frame>, Option<CanId>, u32) -> Result<(Nanos, Vec<(Nanos, Frame)>), String>
    + 'a;

/// The quick start (002) from start to stop, driven by a PLC that has only
/// the CAN interface's process image: every telegram goes out as a Tx message
/// and every answer comes back as an Rx message of `iut`. `cycle` runs one
/// interface cycle (it waits for real time on a real bus) and gives its time.
pub fn quick_start(
    iut: &mut dyn crate::iut::Iut,
    layout: canif_model::image::ImageLayout,
    node: NodeId,
    cycle: &mut dyn FnMut() -> Nanos,
) -> Vec<CheckResult> {
    use canif_model::client::PlcClient;
    use canif_model::image::MessageRepr;
    let mut plc = PlcClient::new(layout);
    let mut results = Vec::new();
    // Sends `request` (if any) and runs cycles until a message on `answer` comes
    // back, or `cycles` pass; everything received meanwhile.
    let mut exchange = |request: Option<Frame>,
                        answer: Option<CanId>,
                        cycles: u32|
     -> Result<(Nanos, Vec<(Nanos, Frame)>), String> {
        if let Some(frame) = request {
            plc.send(MessageRepr {
                transaction_number: 0,
                frame,
                time_stamp: 0,
            })
            .map_err(|e| format!("the PLC cannot queue {frame}: {e:?}"))?;
        }
        let mut received = Vec::new();
        let mut now = 0;
        for _ in 0..cycles {
            now = cycle();
            let outputs = plc.outputs().to_vec();
            let inputs = iut.cycle(&outputs, now).map_err(|e| e.0)?;
            plc.task(&inputs).map_err(|e| format!("{e:?}"))?;
            received.extend(plc.take_received().into_iter().map(|m| (now, m.frame)));
            if answer.is_some_and(|id| received.iter().any(|(_, f)| f.id == id)) {
                break;
            }
        }
        Ok((now, received))
    };
    let guard_id = CanId::Standard(default_cob_id(Channel::ErrorControl, node));
    let sdo_id = CanId::Standard(default_cob_id(Channel::SdoResponse, node));
    let analog_id = CanId::Standard(default_cob_id(Channel::AnalogInputs1To4, node));
    let answer_on = |got: &[(Nanos, Frame)], id: CanId| -> Result<Frame, String> {
        got.iter()
            .map(|(_, f)| *f)
            .find(|f| f.id == id)
            .ok_or_else(|| format!("no answer on 0x{:03X} (received {got:?})", id.raw()))
    };
    let mut guard = GuardChecker::default();
    let mut guard_state = |exchange: &mut Exchange<'_>| -> Result<NmtState, String> {
        let (_, got) = exchange(Some(guarding::request(node)), Some(guard_id), 50)?;
        guard.check(&answer_on(&got, guard_id)?)
    };
    let mut record = |name, requirements, outcome| {
        results.push(CheckResult {
            name,
            requirements,
            outcome,
        })
    };

    let started = exchange(
        Some(command_frame(NmtCommand::StartRemoteNode, None)),
        None,
        3,
    )
    .and_then(|_| guard_state(&mut exchange));
    record(
        "NMT start (0x000: 01 00), then guarding says operational",
        &["NMT-001", "NMT-003", "GRD-001", "GRD-003"][..],
        match started {
            Ok(NmtState::Operational) => Ok(()),
            other => Err(format!("{other:?}")),
        },
    );
    let analog = exchange(
        Some(Frame::remote(analog_id, 8).expect("rtr")),
        Some(analog_id),
        50,
    )
    .and_then(|(_, got)| answer_on(&got, analog_id));
    record(
        "an RTR on 0x280 + node id is answered with the analog inputs",
        &["PDO-003", "COB-001"],
        analog.and_then(|f| {
            if f.data().len() == 8 {
                Ok(())
            } else {
                Err(format!("answer {f}"))
            }
        }),
    );
    for (name, requirements, index, expected) in [
        (
            "SDO upload 0x1001:0 is answered 4F 01 10 00 …",
            &["SDO-001", "SDO-005", "SDO-008"][..],
            0x1001u16,
            &[0x4F, 0x01, 0x10, 0x00][..],
        ),
        (
            "SDO upload 0x2345:0 is aborted 80 45 23 00 00 00 02 06",
            &["SDO-007", "ERR-R8"][..],
            0x2345,
            &[0x80, 0x45, 0x23, 0x00, 0x00, 0x00, 0x02, 0x06][..],
        ),
    ] {
        let outcome = exchange(
            Some(sdo_request(
                node,
                SdoRequest::Upload {
                    index,
                    sub_index: 0,
                },
            )),
            Some(sdo_id),
            50,
        )
        .and_then(|(_, got)| answer_on(&got, sdo_id))
        .and_then(|f| {
            if f.data().starts_with(expected) {
                Ok(())
            } else {
                Err(format!("answer {f}"))
            }
        });
        record(name, requirements, outcome);
    }
    let heartbeat = exchange(
        Some(sdo_request(node, heartbeat::set_producer_time(100))),
        Some(sdo_id),
        50,
    )
    .and_then(|(first, _)| {
        // About 350 ms of cycles: heartbeats every 100 ms.
        let mut beats = Vec::new();
        loop {
            let (now, got) = exchange(None, None, 1)?;
            beats.extend(got.into_iter().filter(|(_, f)| f.id == guard_id));
            if beats.len() >= 4 || now - first > 1_000_000_000 {
                break;
            }
        }
        exchange(
            Some(sdo_request(node, heartbeat::set_producer_time(0))),
            Some(sdo_id),
            50,
        )?;
        if beats.len() >= 3 && beats.iter().all(|(_, f)| f.data() == [0x05]) {
            Ok(())
        } else {
            Err(format!("heartbeats {beats:?}"))
        }
    });
    record(
        "0x1017 = 100 ms: heartbeats 0x705 with the state (05), then 0 stops them",
        &["HB-001", "HB-002", "HB-003"],
        heartbeat,
    );
    // Heartbeats still on their way would be read as guarding answers.
    let _ = exchange(None, None, 30);
    let pre = exchange(
        Some(command_frame(NmtCommand::EnterPreOperational, None)),
        None,
        3,
    )
    .and_then(|_| guard_state(&mut exchange));
    let stopped = exchange(
        Some(command_frame(NmtCommand::StopRemoteNode, Some(node))),
        None,
        3,
    )
    .and_then(|_| guard_state(&mut exchange));
    record(
        "0x80 enters pre-operational, 0x02 stops: guarding says 7F, then 04",
        &["NMT-002", "NMT-005", "ERR-R6", "GRD-003"],
        match (pre, stopped) {
            (Ok(NmtState::PreOperational), Ok(NmtState::Stopped)) => Ok(()),
            other => Err(format!("{other:?}")),
        },
    );
    results
}
