//! Every record read back as written, and broken ones refused.

use super::*;
use crate::door::adapter::protocol::{Hex, InvalidWireFrame, PlannedFrame, Status};

fn frame(id: u32, data: &[u8]) -> WireFrame {
    WireFrame {
        id,
        extended: id > 0x7FF,
        rtr: false,
        fd: data.len() > 8,
        brs: data.len() > 8,
        esi: false,
        len: data.len() as u8,
        data: FrameData::from(data),
    }
}

fn round_request(request: Request) -> Request {
    let encoded = encode_request(Vec::new(), &request).unwrap();
    let outputs = encoded.outputs.unwrap_or_default().to_vec();
    let inputs = encoded.inputs.unwrap_or_default().to_vec();
    let (events, request) = Decoded::new(&encoded.record, outputs, inputs)
        .unwrap()
        .batch()
        .unwrap();
    assert!(events.is_empty());
    request
}

fn round_answer(answer: Answer) -> Answer {
    let encoded = encode_answer(Vec::new(), &answer).unwrap();
    let outputs = encoded.outputs.unwrap_or_default().to_vec();
    let inputs = encoded.inputs.unwrap_or_default().to_vec();
    Decoded::new(&encoded.record, outputs, inputs)
        .unwrap()
        .answer()
        .unwrap()
}

#[test]
fn every_hot_request_reads_back_as_written() {
    let status = ControllerStatus {
        bus_off: true,
        core_running: true,
        crc_errors: 7,
        transmit_error_counter: 255,
        ..ControllerStatus::default()
    };
    for request in [
        Request::Cycle {
            now_ns: 5,
            outputs: Hex(vec![1, 2, 3]),
        },
        Request::Receive {
            frame: frame(0x123, &[9; 8]),
            end_ns: 77,
        },
        Request::PollTransmit { now_ns: 9 },
        Request::TransmitComplete {},
        Request::ControllerStatus {
            status: Status(status),
        },
        Request::Step {
            now_ns: 1_000_000,
            outputs: Hex(vec![0xAA; 40]),
            events: vec![
                BusEvent::Received {
                    frame: frame(0x1ABCDEF, &[1; 64]),
                    end_ns: 3,
                },
                BusEvent::Started { at_ns: 4 },
                BusEvent::Completed,
                BusEvent::Status {
                    status: Status(status),
                },
            ],
        },
        Request::Plan {
            now_ns: 8,
            events: vec![BusEvent::Started { at_ns: 7 }, BusEvent::Completed],
        },
        Request::Task {
            inputs: Hex(vec![4; 12]),
            outputs: Hex(vec![5; 10]),
            requests: vec![WireMessage {
                frame: frame(0x10, &[]),
                transaction_number: 513,
                time_stamp_ns: 0,
            }],
        },
    ] {
        assert_eq!(round_request(request.clone()), request);
    }
}

#[test]
fn every_hot_answer_reads_back_as_written() {
    for answer in [
        Answer::Ok,
        Answer::error("configure first — ü"),
        Answer::Inputs {
            inputs: Hex(vec![8; 33]),
        },
        Answer::Transmit {
            frame: None,
            next_ns: None,
        },
        Answer::Transmit {
            frame: Some(Transmitted::Frame(frame(0x7FF, &[1, 2]))),
            next_ns: Some(12),
        },
        Answer::Transmit {
            frame: Some(Transmitted::Invalid(InvalidWireFrame {
                invalid: "FD length 9".into(),
            })),
            next_ns: None,
        },
        Answer::Stepped {
            inputs: Hex(vec![1; 20]),
            plan: vec![
                PlannedFrame {
                    frame: Some(frame(1, &[2])),
                    invalid: None,
                    not_before_ns: 5,
                },
                PlannedFrame {
                    frame: None,
                    invalid: Some("no frame".into()),
                    not_before_ns: 6,
                },
            ],
            more: true,
        },
        Answer::Tasked {
            outputs: Hex(vec![3; 14]),
            delivered: vec![WireMessage {
                frame: frame(0x55, &[1, 2, 3]),
                transaction_number: 0,
                time_stamp_ns: 123_456,
            }],
            refused: vec![2, 5],
            sent: vec![7, 8],
        },
    ] {
        assert_eq!(round_answer(answer.clone()), answer);
    }
}

#[test]
fn a_polled_devices_cycle_carries_the_bus_events_before_it() {
    let events = vec![
        BusEvent::Received {
            frame: frame(0x100, &[1]),
            end_ns: 10,
        },
        BusEvent::Completed,
    ];
    let request = Request::PollTransmit { now_ns: 20 };
    let encoded = encode_batch(Vec::new(), &events, &request).unwrap();
    let decoded = Decoded::new(&encoded.record, Vec::new(), Vec::new()).unwrap();
    assert_eq!(decoded.batch().unwrap(), (events, request));
    assert!(encode_batch(Vec::new(), &[], &Request::TransmitComplete {}).is_err());
}

#[test]
fn a_record_whose_count_overruns_its_area_is_an_error_not_a_panic() {
    let mut encoded = encode_answer(Vec::new(), &Answer::Ok).unwrap();
    put(&mut encoded.record, record::KIND, kind::TASKED.into());
    put(&mut encoded.record, record::COUNT, u32::MAX.into());
    assert!(Decoded::new(&encoded.record, Vec::new(), Vec::new()).is_err());
    put(&mut encoded.record, record::KIND, 9999);
    put(&mut encoded.record, record::COUNT, 0);
    let decoded = Decoded::new(&encoded.record, Vec::new(), Vec::new()).unwrap();
    assert!(decoded.answer().unwrap_err().contains("9999"));
}
