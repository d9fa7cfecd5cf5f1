//! The quick start (002) through an IUT's process image only.

use canif_model::canopen::cob_id::{default_cob_id, Channel};
use canif_model::canopen::guarding::{self, GuardChecker};
use canif_model::canopen::heartbeat;
use canif_model::canopen::nmt::{command_frame, NmtCommand, NmtState};
use canif_model::canopen::sdo::SdoRequest;
use canif_model::canopen::NodeId;
use canif_model::frame::{CanId, Frame};
use canif_model::Nanos;

use crate::canopen::{sdo_request, NodeCheck};

/// A PLC that has only the CAN interface's process image of `iut`: every
/// telegram goes out as a Tx message and every answer comes back as an Rx
/// message. `cycle` runs one interface cycle and gives its time.
struct ThroughImage<'a> {
    iut: &'a mut dyn crate::door::iut::Iut,
    plc: crate::device::played_plc::PlcSide,
    task_cycle: u64,
    cycle: &'a mut dyn FnMut() -> Nanos,
}

impl ThroughImage<'_> {
    /// Sends `request` (if any) and runs cycles until a message on `answer`
    /// comes back, or `cycles` pass: the last cycle's time and everything
    /// received meanwhile.
    fn exchange(
        &mut self,
        request: Option<Frame>,
        answer: Option<CanId>,
        cycles: u32,
    ) -> Result<(Nanos, Vec<(Nanos, Frame)>), String> {
        use crate::device::played_plc::TaskStimulus;
        use canif_model::image::MessageRepr;
        if let Some(frame) = request {
            self.plc
                .send(MessageRepr {
                    transaction_number: 0,
                    frame,
                    time_stamp: 0,
                })
                .map_err(|e| format!("the PLC cannot queue {frame}: {e:?}"))?;
        }
        let mut received = Vec::new();
        let mut now = 0;
        for _ in 0..cycles {
            now = (self.cycle)();
            let outputs = self.plc.outputs().to_vec();
            let inputs = self.iut.cycle(&outputs, now).map_err(|e| e.to_string())?;
            self.plc.device_cycle_done(&inputs);
            self.plc
                .task(self.task_cycle, TaskStimulus::default())
                .map_err(|e| format!("{e:?}"))?;
            self.task_cycle += 1;
            received.extend(self.plc.take_received().into_iter().map(|m| (now, m.frame)));
            if answer.is_some_and(|id| received.iter().any(|(_, f)| f.id == id)) {
                break;
            }
        }
        Ok((now, received))
    }

    /// The frame on `id` that came back, after sending `request`.
    fn ask(&mut self, request: Frame, id: CanId) -> Result<Frame, String> {
        let (_, got) = self.exchange(Some(request), Some(id), 50)?;
        got.iter()
            .map(|(_, f)| *f)
            .find(|f| f.id == id)
            .ok_or_else(|| format!("no answer on 0x{:03X} (received {got:?})", id.raw()))
    }

    /// An NMT command, then the state guarding reads.
    fn state_after(
        &mut self,
        command: Frame,
        node: NodeId,
        guard: &mut GuardChecker,
    ) -> Result<NmtState, String> {
        self.exchange(Some(command), None, 3)?;
        let guard_id = CanId::Standard(default_cob_id(Channel::ErrorControl, node));
        Ok(guard.check(&self.ask(guarding::request(node), guard_id)?)?)
    }

    /// 0x1017 = 100 ms, about 350 ms of cycles, then 0x1017 = 0: three
    /// heartbeats or more, each with the operational state.
    fn heartbeats(&mut self, node: NodeId) -> Result<(), String> {
        let sdo_id = CanId::Standard(default_cob_id(Channel::SdoResponse, node));
        let guard_id = CanId::Standard(default_cob_id(Channel::ErrorControl, node));
        let (first, _) = self.exchange(
            Some(sdo_request(node, heartbeat::set_producer_time(100))),
            Some(sdo_id),
            50,
        )?;
        let mut beats = Vec::new();
        loop {
            let (now, got) = self.exchange(None, None, 1)?;
            beats.extend(got.into_iter().filter(|(_, f)| f.id == guard_id));
            if beats.len() >= 4 || now - first > 1_000_000_000 {
                break;
            }
        }
        self.exchange(
            Some(sdo_request(node, heartbeat::set_producer_time(0))),
            Some(sdo_id),
            50,
        )?;
        if beats.len() >= 3 && beats.iter().all(|(_, f)| f.data() == [0x05]) {
            Ok(())
        } else {
            Err(format!("heartbeats {beats:?}"))
        }
    }
}

/// The quick start (002) from start to stop, driven by a PLC that has only
/// the CAN interface's process image: every telegram goes out as a Tx message
/// and every answer comes back as an Rx message of `iut`. `cycle` runs one
/// interface cycle (it waits for real time on a real bus) and gives its time.
pub fn quick_start(
    iut: &mut dyn crate::door::iut::Iut,
    layout: canif_model::image::ImageLayout,
    node: NodeId,
    cycle: &mut dyn FnMut() -> Nanos,
) -> Vec<NodeCheck> {
    use canif_model::exchange::ExchangeMode;
    let mut plc = ThroughImage {
        iut,
        plc: crate::device::played_plc::PlcSide::new(layout, ExchangeMode::SeparateInputUpdate),
        task_cycle: 0,
        cycle,
    };
    let mut results = Vec::new();
    let mut record =
        |name, requirements, outcome| results.push(NodeCheck::new(name, requirements, outcome));
    let sdo_id = CanId::Standard(default_cob_id(Channel::SdoResponse, node));
    let analog_id = CanId::Standard(default_cob_id(Channel::AnalogInputs1To4, node));
    let mut guard = GuardChecker::default();

    let started = plc.state_after(
        command_frame(NmtCommand::StartRemoteNode, None),
        node,
        &mut guard,
    );
    record(
        "NMT start (0x000: 01 00), then guarding says operational",
        &["NMT-001", "NMT-003", "GRD-001", "GRD-003"][..],
        match started {
            Ok(NmtState::Operational) => Ok(()),
            other => Err(format!("{other:?}")),
        },
    );
    let analog = plc.ask(Frame::remote(analog_id, 8).expect("rtr"), analog_id);
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
        let upload = SdoRequest::Upload {
            index,
            sub_index: 0,
        };
        let outcome = plc.ask(sdo_request(node, upload), sdo_id).and_then(|f| {
            match f.data().starts_with(expected) {
                true => Ok(()),
                false => Err(format!("answer {f}")),
            }
        });
        record(name, requirements, outcome);
    }
    record(
        "0x1017 = 100 ms: heartbeats 0x705 with the state (05), then 0 stops them",
        &["HB-001", "HB-002", "HB-003"],
        plc.heartbeats(node),
    );
    // Heartbeats still on their way would be read as guarding answers.
    let _ = plc.exchange(None, None, 30);
    let pre = plc.state_after(
        command_frame(NmtCommand::EnterPreOperational, None),
        node,
        &mut guard,
    );
    let stopped = plc.state_after(
        command_frame(NmtCommand::StopRemoteNode, Some(node)),
        node,
        &mut guard,
    );
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
