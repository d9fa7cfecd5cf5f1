//! The node checks of the quick start (002) and the SDO page (004), against
//! any [`CanNode`].

use canif_model::canopen::cob_id::{default_cob_id, Channel};
use canif_model::canopen::guarding::{self, GuardChecker, GuardError, GUARD_TIME};
use canif_model::canopen::heartbeat::{self, PRODUCER_HEARTBEAT_TIME};
use canif_model::canopen::nmt::{command_frame, NmtCommand, NmtState};
use canif_model::canopen::pdo::ANALOG_INPUT_INTERRUPT_ENABLE as ANALOG_EVENTS;
use canif_model::canopen::sdo::{abort_code, SdoRequest, SdoResponse};
use canif_model::canopen::NodeId;
use canif_model::frame::{CanId, Frame};
use canif_model::Nanos;

use super::CanNode;

/// One check's verdict.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct NodeCheck {
    pub name: &'static str,
    /// What the check exercises.
    pub requirements: &'static [&'static str],
    /// What a failure of it breaks: those it exercises, unless the answer
    /// says which statement it contradicts.
    pub blamed: &'static [&'static str],
    pub outcome: Result<(), String>,
}

impl NodeCheck {
    /// A check whose failure breaks every requirement it exercises.
    pub fn new(
        name: &'static str,
        requirements: &'static [&'static str],
        outcome: Result<(), String>,
    ) -> Self {
        NodeCheck {
            name,
            requirements,
            blamed: requirements,
            outcome,
        }
    }

    /// The check for [`crate::verdict::judge`]: a failure blames every requirement it exercises.
    pub fn check(&self) -> crate::verdict::Check {
        use crate::verdict::{Check, CheckResult, Evidence, Finding};
        let covers: Vec<String> = self.requirements.iter().map(|s| s.to_string()).collect();
        let blamed: Vec<String> = self.blamed.iter().map(|s| s.to_string()).collect();
        Check {
            evidence: Evidence::NodeCheck(self.name.into()),
            result: match &self.outcome {
                Ok(()) => CheckResult::Pass,
                Err(why) => CheckResult::Fail(Finding {
                    rest: crate::verdict::Rest::Stopped,
                    requirements: blamed,
                    cause: why.lines().next().unwrap_or_default().to_string(),
                    details: why.clone(),
                    failure: None,
                }),
            },
            covers,
            elapsed: std::time::Duration::ZERO,
        }
    }
}

/// Every requirement the node checks exercise: what a run of `canif run canopen` can judge.
/// (Found by running the checks once on the simulated coupler, then kept.)
pub fn node_check_ids() -> Vec<&'static str> {
    static IDS: std::sync::OnceLock<Vec<&'static str>> = std::sync::OnceLock::new();
    IDS.get_or_init(|| {
        let node = NodeId::new(5).expect("5 is a node id");
        let mut coupler = canif_model::canopen::coupler::Coupler::new(node, 2, 4);
        let mut ids: Vec<&str> = check_node(&mut coupler, node, 0)
            .iter()
            .flat_map(|c| c.requirements.iter().copied())
            .collect();
        ids.sort_unstable();
        ids.dedup();
        ids
    })
    .clone()
}

pub fn sdo_request(node: NodeId, request: SdoRequest) -> Frame {
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

/// A guarding exchange, a failure with the statement it contradicts (002):
/// no single answer to the request (GRD-001), not one status byte or a
/// toggle bit that did not invert (GRD-002, and the master's detection of
/// it, GRD-004), bits that name no state (GRD-003).
fn guard_answer(
    target: &mut dyn CanNode,
    node: NodeId,
    checker: &mut GuardChecker,
    now: Nanos,
) -> Result<NmtState, (&'static [&'static str], String)> {
    let answers = target.handle(&guarding::request(node), now);
    let [answer] = answers.as_slice() else {
        let why = format!("expected one guarding answer, got {answers:?}");
        return Err((&["GRD-001"], why));
    };
    checker.check(answer).map_err(|error| {
        let blamed: &'static [&'static str] = match error {
            GuardError::Length(_) => &["GRD-002"],
            GuardError::Toggle { .. } => &["GRD-002", "GRD-004"],
            GuardError::NotAState(_) => &["GRD-003"],
        };
        (blamed, error.to_string())
    })
}

/// Runs every check against `target`, a node with id `node`, from its boot
/// state. `tolerance`: how far a heartbeat may be from its due time (0 in
/// virtual time; a real bus needs the poll step plus scheduling jitter).
pub fn check_node(target: &mut dyn CanNode, node: NodeId, tolerance: Nanos) -> Vec<NodeCheck> {
    let mut script = Script {
        target,
        node,
        tolerance,
        now: 0,
        guard: GuardChecker::default(),
        results: Vec::new(),
    };
    script.guarding_after_boot();
    script.nmt_start();
    script.analog_inputs_on_request();
    script.expedited_uploads();
    script.heartbeat();
    script.aborts();
    script.analog_event_objects();
    script.state_changes();
    script.stopped_node_is_silent();
    script.resets();
    script.results
}

/// The script's state between its checks: the node, the time, the
/// guarding toggle seen last, and the checks so far. Each method is one
/// step of the script, in the order [`check_node`] takes them.
struct Script<'t> {
    target: &'t mut dyn CanNode,
    node: NodeId,
    tolerance: Nanos,
    now: Nanos,
    guard: GuardChecker,
    results: Vec<NodeCheck>,
}

impl Script<'_> {
    fn record(
        &mut self,
        name: &'static str,
        requirements: &'static [&'static str],
        outcome: Result<(), String>,
    ) {
        self.results
            .push(NodeCheck::new(name, requirements, outcome));
    }

    fn guard_answer(&mut self) -> Result<NmtState, (&'static [&'static str], String)> {
        guard_answer(self.target, self.node, &mut self.guard, self.now)
    }

    fn sdo(&mut self, request: SdoRequest) -> Result<SdoResponse, String> {
        sdo(self.target, self.node, request, self.now)
    }

    fn guarding_after_boot(&mut self) {
        let guarding = (0..4).try_for_each(|_| {
            self.now += 1_000_000;
            match self.guard_answer()? {
                NmtState::PreOperational => Ok(()),
                other => Err((
                    &["GRD-003"][..],
                    format!("state {other:?}, expected pre-operational after boot"),
                )),
            }
        });
        self.results.push(NodeCheck {
            name: "guarding answers with the state and a toggling bit 7",
            requirements: &["GRD-001", "GRD-002", "GRD-003", "GRD-004"],
            blamed: guarding.as_ref().err().map_or(&[][..], |(ids, _)| ids),
            outcome: guarding.map_err(|(_, why)| why),
        });
    }

    fn nmt_start(&mut self) {
        self.target
            .handle(&command_frame(NmtCommand::StartRemoteNode, None), self.now);
        const NMT_START: &[&str] = &["NMT-001", "NMT-003", "NMT-004", "NMT-006"];
        // When the state cannot be read the guarding answer is what broke, and
        // NMT start is charged nothing (issue 36: the statement, not the symptom).
        let (blamed, outcome) = match self.guard_answer() {
            Err((blamed, why)) => (blamed, Err(format!("the state cannot be read: {why}"))),
            Ok(NmtState::Operational) => (NMT_START, Ok(())),
            Ok(other) => (NMT_START, Err(format!("state {other:?}"))),
        };
        self.results.push(NodeCheck {
            name: "NMT start (0x000: 01 00) makes the node operational",
            requirements: NMT_START,
            blamed,
            outcome,
        });
    }

    fn analog_inputs_on_request(&mut self) {
        let id = default_cob_id(Channel::AnalogInputs1To4, self.node);
        let answers = self.target.handle(
            &Frame::remote(CanId::Standard(id), 8).expect("rtr"),
            self.now,
        );
        let outcome = match answers.as_slice() {
            [answer]
                if answer.id == CanId::Standard(id)
                    && answer.data().len() % 2 == 0
                    && !answer.data().is_empty() =>
            {
                Ok(())
            }
            other => Err(format!("answers {other:?}")),
        };
        self.record(
            "an RTR on the analog inputs is answered on 0x280 + node id",
            &["PDO-003", "COB-001", "PDO-002"],
            outcome,
        );
    }

    fn expedited_uploads(&mut self) {
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
            let outcome = self.sdo(upload(index)).and_then(|answer| match answer {
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
            self.record(name, requirements, outcome);
        }
    }

    fn heartbeat(&mut self) {
        let period_ms = 100u16;
        let download = self.sdo(heartbeat::set_producer_time(period_ms));
        self.record(
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
        let start = self.now;
        let mut beats = Vec::new();
        for step in 0..=35 {
            let at = start + step * 10_000_000;
            for frame in self.target.poll(at) {
                if frame.id == CanId::Standard(default_cob_id(Channel::ErrorControl, self.node)) {
                    beats.push((at, frame.data().to_vec()));
                }
            }
        }
        self.record(
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
                        .all(|(t, k)| t.abs_diff(k * period) <= self.tolerance);
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
        self.now = start + 400_000_000;
        let stopped = match self.sdo(heartbeat::set_producer_time(0)) {
            Ok(SdoResponse::DownloadAck {
                index: 0x1017,
                sub_index: 0,
            }) => {
                self.now += 300_000_000;
                let late: Vec<Frame> = self
                    .target
                    .poll(self.now)
                    .into_iter()
                    .filter(|f| {
                        f.id == CanId::Standard(default_cob_id(Channel::ErrorControl, self.node))
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
        };
        self.record(
            "producer time 0 stops the heartbeat",
            &["HB-002", "SDO-006"],
            stopped,
        );
    }

    fn aborts(&mut self) {
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
            let outcome = self
                .sdo(SdoRequest::Upload { index, sub_index })
                .and_then(|answer| match answer {
                    SdoResponse::Abort {
                        index: i,
                        sub_index: s,
                        code: c,
                    } if i == index && s == sub_index && c == code => Ok(()),
                    other => Err(format!("answer {other:?}")),
                });
            self.record(name, &["SDO-007", "ERR-R8"], outcome);
        }
    }

    fn analog_event_objects(&mut self) {
        let missing: Vec<String> = [(0x6424u16, 1u8), (0x6425, 1), (0x6426, 1), (0x1801, 3)]
            .into_iter()
            .filter_map(|(index, sub_index)| {
                match self.sdo(SdoRequest::Upload { index, sub_index }) {
                    Ok(SdoResponse::Upload { .. }) => None,
                    other => Some(format!("0x{index:04X}:{sub_index} {other:?}")),
                }
            })
            .collect();
        self.record(
            "the analog event objects 002 names answer: 0x6424, 0x6425, 0x6426, 0x1801",
            &["PDO-004"],
            if missing.is_empty() {
                Ok(())
            } else {
                Err(missing.join("; "))
            },
        );
    }

    fn state_changes(&mut self) {
        self.target.handle(
            &command_frame(NmtCommand::EnterPreOperational, None),
            self.now,
        );
        let pre_operational = self.guard_answer();
        self.target.handle(
            &command_frame(NmtCommand::StopRemoteNode, Some(self.node)),
            self.now,
        );
        let stopped = self.guard_answer();
        const STATES: &[&str] = &[
            "NMT-002", "NMT-003", "NMT-004", "NMT-005", "ERR-R6", "GRD-003",
        ];
        let (blamed, outcome) = match (pre_operational, stopped) {
            (Ok(NmtState::PreOperational), Ok(NmtState::Stopped)) => (STATES, Ok(())),
            (Err((blamed, why)), _) | (_, Err((blamed, why))) => {
                (blamed, Err(format!("the state cannot be read: {why}")))
            }
            other => (STATES, Err(format!("states {other:?}"))),
        };
        self.results.push(NodeCheck {
            name: "0x80 enters pre-operational (0x7F), 0x02 stops (0x04)",
            requirements: STATES,
            blamed,
            outcome,
        });
    }

    fn stopped_node_is_silent(&mut self) {
        // CiA 301: stopped serves NMT and error control only.
        let answers = self
            .target
            .handle(&sdo_request(self.node, upload(0x1017)), self.now);
        let response_id = CanId::Standard(default_cob_id(Channel::SdoResponse, self.node));
        self.record(
            "a stopped node answers no SDO (CiA 301)",
            &["NMT-008"],
            match answers.iter().find(|f| f.id == response_id) {
                None => Ok(()),
                Some(answer) => Err(format!("answered {answer}")),
            },
        );
    }

    /// Resets restore the power-on values: communication objects for reset
    /// communication, every object for reset node; each ends with a boot-up.
    fn resets(&mut self) {
        self.target
            .handle(&command_frame(NmtCommand::StartRemoteNode, None), self.now);
        let node = self.node;
        let reset = |target: &mut dyn CanNode, command: NmtCommand, now: &mut Nanos| {
            for (index, value) in [
                (GUARD_TIME, 100),
                (PRODUCER_HEARTBEAT_TIME, 1000),
                (ANALOG_EVENTS, 1),
            ] {
                sdo(target, node, SdoRequest::download(index, 0, value), *now)?;
            }
            *now += 10_000_000;
            let mut seen = target.handle(&command_frame(command, Some(node)), *now);
            *now += 50_000_000;
            seen.extend(target.poll(*now));
            let boot = CanId::Standard(default_cob_id(Channel::ErrorControl, node));
            if !seen.iter().any(|f| f.id == boot && f.data() == [0x00]) {
                return Err(format!(
                    "no boot-up (0x{:03X}: 00) among {seen:?}",
                    boot.raw()
                ));
            }
            [GUARD_TIME, PRODUCER_HEARTBEAT_TIME, ANALOG_EVENTS]
                .into_iter()
                .map(|index| {
                    let answer = sdo(target, node, upload(index), *now)?;
                    answer
                        .value()
                        .ok_or_else(|| format!("0x{index:04X}: {answer:?}"))
                })
                .collect::<Result<Vec<u32>, String>>()
        };
        let communication = reset(self.target, NmtCommand::ResetCommunication, &mut self.now);
        self.record(
            "reset communication (0x82) restores 0x100C and 0x1017, keeps 0x6423 (CiA 301)",
            &["NMT-009"],
            communication.and_then(|values| match values[..] {
                [0, 0, 1] => Ok(()),
                _ => Err(format!(
                    "0x100C, 0x1017, 0x6423 read {values:?}, expected [0, 0, 1]"
                )),
            }),
        );
        let node = reset(self.target, NmtCommand::ResetNode, &mut self.now);
        self.record(
            "reset node (0x81) restores every object, 0x6423 too (CiA 301)",
            &["NMT-010"],
            node.and_then(|values| match values[..] {
                [0, 0, 0] => Ok(()),
                _ => Err(format!(
                    "0x100C, 0x1017, 0x6423 read {values:?}, expected [0, 0, 0]"
                )),
            }),
        );
    }
}

fn upload(index: u16) -> SdoRequest {
    SdoRequest::Upload {
        index,
        sub_index: 0,
    }
}
