//! CANopen telegrams of the quick start (002) and the SDO page (004), R6-R8.

use canif_model::canopen::cob_id::{classify, default_cob_id, Channel};
use canif_model::canopen::guarding::{self, GuardChecker, GuardResponder};
use canif_model::canopen::heartbeat;
use canif_model::canopen::nmt::{self, NmtCommand, NmtState};
use canif_model::canopen::pdo;
use canif_model::canopen::sdo::{abort_code, SdoRequest, SdoResponse};
use canif_model::canopen::NodeId;
use canif_model::frame::{CanId, Frame};

fn node(id: u8) -> NodeId {
    NodeId::new(id).unwrap()
}

/// Covers: NMT-001, NMT-006
#[test]
fn start_all_modules() {
    let frame = nmt::command_frame(NmtCommand::StartRemoteNode, None);
    assert_eq!(
        frame,
        Frame::classic(CanId::Standard(0x000), &[0x01, 0x00]).unwrap()
    );
    assert_eq!(
        nmt::parse_command(&frame),
        Some((NmtCommand::StartRemoteNode, None))
    );
    assert!(nmt::addresses(None, node(63)));
    assert!(nmt::addresses(Some(5), node(5)));
    assert!(!nmt::addresses(Some(5), node(6)));
    assert_eq!(NodeId::new(0), None, "0 is broadcast, no node's address");
    assert_eq!(NodeId::new(64), None);
}

/// Covers: NMT-002, NMT-003, NMT-004, NMT-005, ERR-R6
#[test]
fn nmt_commands_and_states() {
    let stop_as_printed = Frame::classic(CanId::Standard(0), &[0x80, 0x00]).unwrap();
    let (command, target) = nmt::parse_command(&stop_as_printed).unwrap();
    assert_eq!(
        (command, target),
        (NmtCommand::EnterPreOperational, None),
        "0x80 is enter pre-operational"
    );
    let operational = NmtState::PreOperational.apply(NmtCommand::StartRemoteNode);
    assert_eq!(operational, NmtState::Operational);
    assert!(operational.pdo_allowed());
    assert_eq!(operational.apply(command), NmtState::PreOperational);
    assert!(
        !operational.apply(command).pdo_allowed(),
        "0x80 ends PDO traffic"
    );
    assert_eq!(
        operational.apply(NmtCommand::StopRemoteNode),
        NmtState::Stopped
    );
    assert!(!NmtState::Stopped.pdo_allowed());
    for reset in [NmtCommand::ResetNode, NmtCommand::ResetCommunication] {
        assert_eq!(NmtState::Stopped.apply(reset), NmtState::PreOperational);
    }
    let bytes: Vec<u8> = [
        NmtCommand::StartRemoteNode,
        NmtCommand::StopRemoteNode,
        NmtCommand::EnterPreOperational,
        NmtCommand::ResetNode,
        NmtCommand::ResetCommunication,
    ]
    .iter()
    .map(|c| *c as u8)
    .collect();
    assert_eq!(bytes, [0x01, 0x02, 0x80, 0x81, 0x82]);
    assert_eq!(NmtCommand::from_byte(0x03), None);
    let frame = nmt::command_frame(NmtCommand::StopRemoteNode, Some(node(0x12)));
    assert_eq!(frame.data(), &[0x02, 0x12]);
}

/// Covers: COB-001, SDO-001, GRD-001, ERR-R7
#[test]
fn default_identifiers() {
    let n = node(5);
    let expected = [
        (Channel::DigitalInputs, 0x185),
        (Channel::DigitalOutputs, 0x205),
        (Channel::AnalogInputs1To4, 0x285),
        (Channel::AnalogOutputs1To4, 0x305),
        (Channel::AnalogInputs5To8, 0x385),
        (Channel::AnalogOutputs5To8, 0x405),
        (Channel::AnalogInputs9To12, 0x485),
        (Channel::AnalogOutputs9To12, 0x505),
        (Channel::SdoResponse, 0x585),
        (Channel::SdoRequest, 0x605),
        (Channel::ErrorControl, 0x705),
    ];
    for (channel, id) in expected {
        assert_eq!(default_cob_id(channel, n), id, "{channel:?}");
        assert_eq!(classify(id), Some((channel, n)));
    }
    assert_eq!(Channel::SdoRequest.base(), 1536, "0x600 = 1536, not 768");
    assert_eq!(Channel::SdoResponse.base(), 1408);
    assert_eq!(classify(0x180), None, "node 0 does not exist");
}

/// Covers: PDO-001, PDO-002
#[test]
fn pdo_payloads() {
    assert_eq!(pdo::digital_payload(&[0xA5]), Some(&[0xA5][..]));
    assert_eq!(pdo::digital_payload(&[]), None);
    assert_eq!(pdo::digital_payload(&[0; 9]), None);
    assert_eq!(pdo::analog_payload(&[0x1234, -2]), [0x34, 0x12, 0xFE, 0xFF]);
    assert_eq!(
        pdo::parse_analog(&[0x34, 0x12, 0xFE, 0xFF]),
        Some(vec![0x1234, -2])
    );
    assert_eq!(pdo::parse_analog(&[1, 2]), None, "at least 4 bytes");
    assert_eq!(pdo::parse_analog(&[1, 2, 3]), None);
}

/// Covers: PDO-003, SDO-003, SDO-004, SDO-002
#[test]
fn enabling_analog_events_by_sdo() {
    let request = SdoRequest::Download {
        index: pdo::ANALOG_INPUT_INTERRUPT_ENABLE,
        sub_index: 0,
        data: [1, 0, 0, 0],
        size: None,
    };
    assert_eq!(
        request.to_bytes(),
        [0x22, 0x23, 0x64, 0x00, 0x01, 0x00, 0x00, 0x00]
    );
    assert_eq!(SdoRequest::parse(&request.to_bytes()), Ok(request));
    // An analog input is read by an RTR on its identifier.
    let rtr = Frame::remote(
        CanId::Standard(default_cob_id(Channel::AnalogInputs1To4, node(1))),
        8,
    )
    .unwrap();
    assert!(rtr.is_remote());
    assert_eq!(rtr.id, CanId::Standard(0x281));
}

/// Covers: SDO-003, SDO-005, SDO-006, SDO-008, SDO-009, SDO-002
#[test]
fn expedited_sdo_command_bytes() {
    let sized: Vec<u8> = (1..=4)
        .map(|n| {
            SdoRequest::Download {
                index: 0x2000,
                sub_index: 1,
                data: [0; 4],
                size: Some(n),
            }
            .to_bytes()[0]
        })
        .collect();
    assert_eq!(sized, [0x2F, 0x2B, 0x27, 0x23]);
    let uploads: Vec<u8> = (1..=4)
        .map(|n| {
            SdoResponse::Upload {
                index: 0x1000,
                sub_index: 0,
                data: [0; 4],
                size: n,
            }
            .to_bytes()[0]
        })
        .collect();
    assert_eq!(uploads, [0x4F, 0x4B, 0x47, 0x43]);
    let u16_value = SdoResponse::Upload {
        index: 0x100C,
        sub_index: 0,
        data: [0xE8, 0x03, 0, 0],
        size: 2,
    };
    assert_eq!(
        u16_value.to_bytes(),
        [0x4B, 0x0C, 0x10, 0x00, 0xE8, 0x03, 0x00, 0x00],
        "Unsigned16 in D0, D1"
    );
    assert_eq!(SdoResponse::parse(&u16_value.to_bytes()), Ok(u16_value));
    let ack = SdoResponse::DownloadAck {
        index: 0x6423,
        sub_index: 0,
    };
    assert_eq!(ack.to_bytes(), [0x60, 0x23, 0x64, 0x00, 0, 0, 0, 0]);
    assert_eq!(
        SdoRequest::Upload {
            index: 0x1018,
            sub_index: 1
        }
        .to_bytes(),
        [0x40, 0x18, 0x10, 0x01, 0, 0, 0, 0]
    );
    for command in [0x2Fu8, 0x2B, 0x27, 0x23] {
        let SdoRequest::Download { size, .. } =
            SdoRequest::parse(&[command, 0, 0, 0, 0, 0, 0, 0]).unwrap()
        else {
            panic!()
        };
        assert_eq!(size, Some(4 - ((command >> 2) & 3)));
    }
    assert!(SdoRequest::parse(&[0x22; 7]).is_err(), "8 bytes or nothing");
}

/// Covers: SDO-007, ERR-R8
#[test]
fn abort_telegram() {
    let abort = SdoResponse::Abort {
        index: 0x6000,
        sub_index: 0x11,
        code: abort_code::SUB_INDEX_DOES_NOT_EXIST,
    };
    assert_eq!(
        abort.to_bytes(),
        [0x80, 0x00, 0x60, 0x11, 0x11, 0x00, 0x09, 0x06]
    );
    assert_eq!(SdoResponse::parse(&abort.to_bytes()), Ok(abort));
    assert_eq!(abort_code::OBJECT_DOES_NOT_EXIST, 0x0602_0000);
    assert_eq!(abort_code::COMMAND_SPECIFIER_INVALID, 0x0504_0001);
    assert_eq!(abort_code::LENGTH_MISMATCH, 0x0607_0010);
}

/// Covers: GRD-001, GRD-002, GRD-003, GRD-004, GRD-006
#[test]
fn node_guarding_with_toggle() {
    let request = guarding::request(node(3));
    assert_eq!(request, Frame::remote(CanId::Standard(0x703), 1).unwrap());
    let mut responder = GuardResponder::default();
    let mut checker = GuardChecker::default();
    let answers: Vec<u8> = (0..4)
        .map(|_| responder.respond(node(3), NmtState::Operational).data()[0])
        .collect();
    assert_eq!(answers, [0x05, 0x85, 0x05, 0x85]);
    for byte in answers {
        let frame = Frame::classic(CanId::Standard(0x703), &[byte]).unwrap();
        assert_eq!(checker.check(&frame), Ok(NmtState::Operational));
    }
    assert_eq!(guarding::status_byte(NmtState::PreOperational, true), 0xFF);
    assert_eq!(guarding::status_byte(NmtState::Stopped, false), 0x04);
    // A repeated toggle is caught.
    let stuck = Frame::classic(CanId::Standard(0x703), &[0x85]).unwrap();
    assert!(
        checker.check(&stuck).is_err(),
        "expected toggle 0 after four answers"
    );
}

/// Covers: GRD-005
#[test]
fn life_time_is_guard_time_times_life_time_factor() {
    assert_eq!(guarding::life_time(100, 3), Some(300_000_000));
    assert_eq!(guarding::life_time(0, 3), None);
    assert_eq!(guarding::life_time(100, 0), None);
}

/// Covers: HB-001, HB-002, HB-003
#[test]
fn heartbeat() {
    assert_eq!(
        heartbeat::heartbeat(node(9), NmtState::Operational),
        Frame::classic(CanId::Standard(0x709), &[0x05]).unwrap()
    );
    assert_eq!(
        heartbeat::set_producer_time(0xABCD).to_bytes(),
        [0x22, 0x17, 0x10, 0x00, 0xCD, 0xAB, 0x00, 0x00]
    );
    assert_eq!(heartbeat::next_due(1_000, 100), Some(100_001_000));
    assert_eq!(heartbeat::next_due(1_000, 0), None);
}

/// An SDO request to the simulated coupler, answered or not.
fn sdo(
    coupler: &mut canif_model::canopen::coupler::Coupler,
    request: SdoRequest,
) -> Option<SdoResponse> {
    let id = CanId::Standard(default_cob_id(Channel::SdoRequest, coupler.node()));
    let frame = Frame::classic(id, &request.to_bytes()).unwrap();
    coupler
        .handle(&frame, 0)
        .first()
        .map(|answer| SdoResponse::parse(answer.data()).unwrap())
}

fn upload(index: u16) -> SdoRequest {
    SdoRequest::Upload {
        index,
        sub_index: 0,
    }
}

fn download(index: u16, value: u32) -> SdoRequest {
    SdoRequest::download(index, 0, value)
}

fn value(response: Option<SdoResponse>) -> u32 {
    response.and_then(|r| r.value()).expect("an upload answer")
}

/// Covers: NMT-008
#[test]
fn a_stopped_node_answers_no_sdo_but_still_guarding() {
    let mut coupler = canif_model::canopen::coupler::Coupler::new(node(5), 2, 4);
    assert!(
        sdo(&mut coupler, upload(0x1017)).is_some(),
        "pre-operational serves SDO"
    );
    coupler.handle(
        &nmt::command_frame(NmtCommand::StopRemoteNode, Some(node(5))),
        0,
    );
    assert_eq!(coupler.state(), NmtState::Stopped);
    assert_eq!(sdo(&mut coupler, upload(0x1017)), None);
    let guard = guarding::request(node(5));
    assert_eq!(coupler.handle(&guard, 0).len(), 1, "error control goes on");
    coupler.handle(&nmt::command_frame(NmtCommand::StartRemoteNode, None), 0);
    assert!(sdo(&mut coupler, upload(0x1017)).is_some());
}

/// Covers: NMT-009, NMT-010
#[test]
fn resets_restore_the_power_on_values() {
    let mut coupler = canif_model::canopen::coupler::Coupler::new(node(5), 2, 4);
    for (index, written) in [(0x1017, 1000), (0x100C, 100), (0x6423, 1)] {
        assert!(matches!(
            sdo(&mut coupler, download(index, written)),
            Some(SdoResponse::DownloadAck { .. })
        ));
    }
    assert!(!coupler.poll(0).is_empty(), "heartbeats run");
    let boot = coupler.handle(&nmt::command_frame(NmtCommand::ResetCommunication, None), 0);
    assert_eq!(boot.len(), 1, "boot-up");
    assert_eq!(
        (
            value(sdo(&mut coupler, upload(0x1017))),
            value(sdo(&mut coupler, upload(0x100C)))
        ),
        (0, 0)
    );
    assert_eq!(
        value(sdo(&mut coupler, upload(0x6423))),
        1,
        "reset communication keeps application objects"
    );
    assert!(
        coupler.poll(2_000_000_000).is_empty(),
        "no heartbeat after the reset"
    );
    coupler.handle(&nmt::command_frame(NmtCommand::ResetNode, Some(node(5))), 0);
    assert_eq!(
        value(sdo(&mut coupler, upload(0x6423))),
        0,
        "reset node restores them too"
    );
}

/// Covers: HB-005
#[test]
fn heartbeats_keep_their_nominal_schedule() {
    let mut coupler = canif_model::canopen::coupler::Coupler::new(node(5), 2, 4);
    sdo(&mut coupler, download(0x1017, 100));
    // Polled every 7 ms: each beat is late by up to 7 ms, but the schedule
    // does not slip: 30 beats in 3 s, not 28.
    let beats = (0..=3_000 / 7)
        .filter(|k| !coupler.poll(k * 7_000_000).is_empty())
        .count();
    assert_eq!(beats, 30);
}

/// Covers: PDO-004, PDO-005
#[test]
fn analog_events_are_thinned_out_by_delta_limits_and_inhibit_time() {
    use canif_model::canopen::coupler::Coupler;
    let started = || {
        let mut coupler = Coupler::new(node(5), 2, 4);
        coupler.handle(&nmt::command_frame(NmtCommand::StartRemoteNode, None), 0);
        sdo(&mut coupler, download(0x6423, 1));
        coupler
    };
    let write = |coupler: &mut Coupler, index: u16, sub: u8, value: u32| {
        let request = SdoRequest::download(index, sub, value);
        assert!(
            matches!(sdo(coupler, request), Some(SdoResponse::DownloadAck { .. })),
            "0x{index:04X}:{sub}"
        );
    };
    // No thinning: every change is an event.
    let mut plain = started();
    assert_eq!(plain.set_analog_input(0, 1).len(), 1);
    // Delta 100 on channel 0: changes below it are not events.
    let mut delta = started();
    write(&mut delta, 0x6426, 1, 100);
    assert!(delta.set_analog_input(0, 50).is_empty());
    assert!(delta.set_analog_input(0, 99).is_empty());
    assert_eq!(
        delta.set_analog_input(0, 100).len(),
        1,
        "moved 100 from the last sent 0"
    );
    assert!(
        delta.set_analog_input(0, 150).is_empty(),
        "50 from the last sent 100"
    );
    assert_eq!(
        delta.set_analog_input(1, 1).len(),
        1,
        "channel 1 has no delta"
    );
    // Limits: only values outside [lower, upper] are events.
    let mut limits = started();
    write(&mut limits, 0x6424, 1, 1000);
    write(&mut limits, 0x6425, 1, 200);
    assert!(limits.set_analog_input(0, 500).is_empty());
    assert_eq!(limits.set_analog_input(0, 1500).len(), 1);
    assert_eq!(limits.set_analog_input(0, 100).len(), 1);
    // Inhibit time 10 ms (100 x 100 us): a second event waits, then the latest values go.
    let mut inhibit = started();
    write(&mut inhibit, 0x1801, 3, 100);
    inhibit.poll(1_000_000);
    assert_eq!(inhibit.set_analog_input(0, 1).len(), 1);
    assert!(inhibit.set_analog_input(0, 2).is_empty());
    assert!(inhibit.set_analog_input(0, 3).is_empty());
    assert!(inhibit.poll(5_000_000).is_empty(), "still inhibited");
    let late = inhibit.poll(11_000_000);
    assert_eq!(late.len(), 1);
    assert_eq!(&late[0].data()[..2], &[3, 0], "the latest value");
    // The objects 002 names exist (no abort 0x06020000).
    for (index, sub) in [(0x6424, 1), (0x6425, 1), (0x6426, 1), (0x1801, 3)] {
        assert!(matches!(
            sdo(
                &mut inhibit,
                SdoRequest::Upload {
                    index,
                    sub_index: sub
                }
            ),
            Some(SdoResponse::Upload { .. })
        ));
    }
}
