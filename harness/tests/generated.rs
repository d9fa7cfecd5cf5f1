//! Generated stimulus with shrinking, and determinism.

use canif_harness::device::run_scenario;
use canif_harness::device::scenario::{Scenario, Step, Steps};

use canif_harness::device::IutKind;
use canif_harness::Outcome;
use canif_model::config::{Capabilities, FrameFormat, InterfaceConfig};
use canif_model::exchange::ExchangeMode;
use canif_model::frame::{CanId, Frame};
use canif_model::image::MessageRepr;
use canif_model::timing::BitRates;
use canif_softdevice::Fault;
use proptest::prelude::*;
use proptest::test_runner::{Config, RngAlgorithm, TestError, TestRng, TestRunner};

/// One cycle of PLC and bus behaviour that follows the protocol.
#[derive(Debug, Clone)]
struct Cycle {
    send: Vec<(u16, u8)>,
    busy: bool,
    bus: Vec<(u64, u16, u8)>,
}

fn cycle() -> impl Strategy<Value = Cycle> {
    (
        proptest::collection::vec((0u16..0x800, 0u8..=8), 0..12),
        proptest::bool::weighted(0.2),
        proptest::collection::vec((0u64..1_000_000, 0u16..0x800, 0u8..=8), 0..12),
    )
        .prop_map(|(send, busy, bus)| Cycle { send, busy, bus })
}

fn frame(id: u16, len: u8) -> Frame {
    Frame::classic(CanId::Standard(id), &vec![len; usize::from(len)]).unwrap()
}

fn scenario_of(cycles: &[Cycle]) -> Scenario {
    let mut steps: Vec<Step> = cycles
        .iter()
        .map(|c| Step {
            send: c
                .send
                .iter()
                .map(|&(id, len)| MessageRepr {
                    transaction_number: 0,
                    frame: frame(id, len),
                    time_stamp: 0,
                })
                .collect(),
            plc_busy: c.busy,
            bus: c
                .bus
                .iter()
                .map(|&(at, id, len)| (at, frame(id, len)))
                .collect(),
            ..Step::default()
        })
        .collect();
    steps.extend(vec![Step::default(); 200]);
    Scenario {
        name: "proptest".into(),
        covers: vec![
            canif_spec::ReqId::new("HS-TX-004"),
            canif_spec::ReqId::new("HS-TX-006"),
            canif_spec::ReqId::new("HS-RX-007"),
            canif_spec::ReqId::new("RXQ-004"),
        ],
        interface: InterfaceConfig::new(FrameFormat::Base11, 4),
        exchange: ExchangeMode::SeparateInputUpdate,
        bit_rates: BitRates::classic(500_000),
        cycle_time: 1_000_000,
        check_confirmation_delay: false,
        declared_lengths: Vec::new(),
        time_stamp_tolerance: 0,
        trace: None,
        bus: canif_harness::device::medium::BusChoice::Sim,
        judgement: canif_harness::device::scenario::Judgement::Exact,
        declared: Default::default(),
        steps: Steps::Scripted(steps),
    }
}

fn caps() -> Capabilities {
    let mut caps = Capabilities::everything();
    caps.rx_queue_depth = 16;
    caps
}

fn outcome(kind: &IutKind, cycles: &[Cycle]) -> Outcome {
    let scenario = scenario_of(cycles);
    run_scenario(kind, &caps(), &scenario, scenario.steps()).outcome
}

proptest! {
    #![proptest_config(Config { cases: 64, ..Config::default() })]

    /// Covers: HS-TX-006, HS-RX-007, RXQ-004
    #[test]
    fn the_soft_device_agrees_with_the_model_under_any_traffic(cycles in proptest::collection::vec(cycle(), 1..30)) {
        let outcome = outcome(&IutKind::SoftDevice { faults: vec![], choices: vec![] }, &cycles);
        prop_assert_eq!(outcome, Outcome::Pass);
    }
}

/// A failing run shrinks to the least that shows the fault: for a device that
/// sends batches in reverse, one batch of two messages. The generator is
/// seeded: with a random one, shrinking sometimes stops at two cycles (a busy
/// one first), seen once in CI, so the exact minimum is held for a fixed seed.
#[test]
fn a_failure_shrinks_to_a_minimal_run() {
    let config = Config {
        cases: 256,
        failure_persistence: None,
        ..Config::default()
    };
    let mut runner =
        TestRunner::new_with_rng(config, TestRng::deterministic_rng(RngAlgorithm::ChaCha));
    let faulty = IutKind::SoftDevice {
        faults: vec![Fault::SendsBatchReversed],
        choices: vec![],
    };
    let result = runner.run(&proptest::collection::vec(cycle(), 1..30), |cycles| {
        prop_assert_eq!(outcome(&faulty, &cycles), Outcome::Pass);
        Ok(())
    });
    let Err(TestError::Fail(_, minimal)) = result else {
        panic!("the fault was not found: {result:?}")
    };
    let sent: usize = minimal.iter().map(|c| c.send.len()).sum();
    let received: usize = minimal.iter().map(|c| c.bus.len()).sum();
    assert_eq!(
        (minimal.len(), sent, received),
        (1, 2, 0),
        "minimal: {minimal:?}"
    );
    let Outcome::Fail(failure) = outcome(&faulty, &minimal) else {
        panic!()
    };
    assert!(
        failure
            .requirements
            .contains(&canif_spec::ReqId::new("HS-TX-004")),
        "{failure:?}"
    );
}

/// The pcapng of a run: section header, one interface of link type 227 with
/// nanosecond time stamps, and one enhanced packet per frame on the bus, the CAN
/// id big-endian; the candump log has one line per frame. If tshark is
/// installed (.ci/run installs it), it must read the file too.
/// An FD scenario on the soft device traced into a folder of its own:
/// the folder and the run.
fn fd_trace(tag: &str) -> (std::path::PathBuf, canif_harness::ScenarioRun) {
    let (dir, run) = fd_trace_of(tag, vec![]);
    assert_eq!(run.outcome, Outcome::Pass);
    (dir, run)
}

/// The same scenario on the soft device with `faults`.
fn fd_trace_of(tag: &str, faults: Vec<Fault>) -> (std::path::PathBuf, canif_harness::ScenarioRun) {
    use canif_harness::device::run_scenario;
    use canif_harness::device::scenario;
    let dir = std::env::temp_dir().join(format!("canif-trace-{tag}-{}", std::process::id()));
    let mut config = InterfaceConfig::new(FrameFormat::Fd, 4);
    config.transaction_number = true;
    config.time_stamp = true;
    let mut scenario = scenario::fd_lengths(&config);
    scenario.trace = Some((dir.clone(), "fd".into(), 0));
    let run = run_scenario(
        &IutKind::SoftDevice {
            faults,
            choices: vec![],
        },
        &Capabilities::everything(),
        &scenario,
        scenario.steps(),
    );
    (dir, run)
}

/// Issue 37: the frame a failure is about carries the failure as its
/// packet comment, read back with the pcapng reader canif writes with.
#[test]
fn the_failing_frame_is_marked_in_the_pcapng() {
    use pcap_file::pcapng::blocks::enhanced_packet::EnhancedPacketOption;
    use pcap_file::pcapng::{Block, PcapNgReader};
    let (dir, run) = fd_trace_of("failing", vec![Fault::FdPaddingFf]);
    let Outcome::Fail(failure) = &run.outcome else {
        panic!("fd-padding-ff fails fd-lengths: {:?}", run.outcome)
    };
    let file = std::fs::File::open(dir.join("fd.pcapng")).unwrap();
    let mut reader = PcapNgReader::new(file).unwrap();
    let mut comments = Vec::new();
    while let Some(block) = reader.next_block() {
        if let Block::EnhancedPacket(packet) = block.unwrap() {
            for option in &packet.options {
                if let EnhancedPacketOption::Comment(text) = option {
                    comments.push(text.to_string());
                }
            }
        }
    }
    assert_eq!(comments.len(), 1, "one failing frame: {comments:?}");
    assert!(
        comments[0].starts_with("canif FAIL FD-LEN-005: cycle ")
            && comments[0].contains(&failure.actual),
        "{comments:?}"
    );
    // The candump log stays candump's; the mark beside it names its line.
    let marks = std::fs::read_to_string(dir.join("fd.failing.txt")).expect("fd.failing.txt");
    let log = std::fs::read_to_string(dir.join("fd.log")).unwrap();
    assert_eq!(marks.lines().count(), 1, "{marks}");
    let (place, rest) = marks.split_once(": ").unwrap();
    let line: usize = place.strip_prefix("fd.log:").unwrap().parse().unwrap();
    let (frame, comment) = rest.split_once("  <- ").unwrap();
    assert_eq!(
        log.lines().nth(line - 1),
        Some(frame),
        "line {line} of fd.log"
    );
    assert_eq!(comment.trim_end(), comments[0]);
    assert!(
        log.lines().all(|l| l.starts_with('(')),
        "every log line a frame"
    );
    let _ = std::fs::remove_dir_all(dir);
}

/// The pcapng's blocks, read here without a library: the block kinds, each
/// packet's CAN id and direction flags (the layout asserted on the way).
fn read_pcapng(path: &std::path::Path) -> (Vec<u32>, Vec<u32>, Vec<u32>) {
    let bytes = std::fs::read(path).unwrap();
    let word = |at: usize| u32::from_le_bytes(bytes[at..at + 4].try_into().unwrap());
    let half = |at: usize| u16::from_le_bytes([bytes[at], bytes[at + 1]]);
    // (code, value) of the options from `at` to the block's end.
    let options = |mut at: usize, end: usize| {
        let mut found = Vec::new();
        while at + 4 <= end {
            let (code, len) = (half(at), usize::from(half(at + 2)));
            if code == 0 {
                break;
            }
            found.push((code, bytes[at + 4..at + 4 + len].to_vec()));
            at += 4 + len.div_ceil(4) * 4;
        }
        found
    };
    let (mut at, mut ids) = (0, Vec::new());
    let (mut kinds, mut directions) = (Vec::new(), Vec::new());
    while at < bytes.len() {
        let (kind, length) = (word(at), word(at + 4) as usize);
        assert_eq!(
            word(at + length - 4) as usize,
            length,
            "block lengths agree"
        );
        kinds.push(kind);
        if kind == 1 {
            assert_eq!(half(at + 8), 227, "LINKTYPE_CAN_SOCKETCAN");
            let idb = options(at + 16, at + length - 4);
            assert!(
                idb.contains(&(2, b"canif-sim".to_vec())),
                "if_name: {idb:?}"
            );
            assert!(
                idb.contains(&(9, vec![9])),
                "if_tsresol = 9 (nanoseconds): {idb:?}"
            );
        }
        if kind == 6 {
            let data = at + 28;
            ids.push(u32::from_be_bytes(
                bytes[data..data + 4].try_into().unwrap(),
            ));
            let captured = word(at + 20) as usize;
            let epb = options(data + captured.div_ceil(4) * 4, at + length - 4);
            let flags = epb.iter().find(|(code, _)| *code == 2).expect("epb_flags");
            directions.push(u32::from_le_bytes(flags.1[..4].try_into().unwrap()) & 0b11);
        }
        at += length;
    }
    (kinds, ids, directions)
}

#[test]
fn traces_are_pcapng_and_candump() {
    let (dir, run) = fd_trace("files");
    let (kinds, ids, directions) = read_pcapng(&dir.join("fd.pcapng"));
    let packets = ids.len();
    assert_eq!(&kinds[..2], &[0x0A0D_0D0A, 1]);
    assert_eq!(packets as u64, run.frames_checked);
    assert!(
        ids.contains(&(0x8000_1000)),
        "an extended id with the EFF flag, big-endian"
    );
    // The scenario has frames both ways: the IUT's are outbound (2), the other nodes' inbound (1).
    assert!(
        directions.iter().all(|d| *d == 1 || *d == 2),
        "{directions:?}"
    );
    assert!(
        directions.contains(&1) && directions.contains(&2),
        "{directions:?}"
    );
    let log = std::fs::read_to_string(dir.join("fd.log")).unwrap();
    assert_eq!(log.lines().count() as u64, run.frames_checked);
    assert!(
        log.lines()
            .any(|l| l.contains(" canif-sim ") && l.contains("##")),
        "FD frames as ##"
    );

    let _ = std::fs::remove_dir_all(dir);
}

#[test]
#[cfg_attr(
    canif_no_tshark,
    ignore = "tshark is not installed (apt-get install tshark; .ci/run does)"
)]
fn tshark_reads_the_pcapng_as_canif_wrote_it() {
    let (dir, run) = fd_trace("tshark");
    let (_, _, directions) = read_pcapng(&dir.join("fd.pcapng"));
    let tshark = std::process::Command::new("tshark")
        .args(["-r"])
        .arg(dir.join("fd.pcapng"))
        .args(["-T", "fields", "-E", "separator=,"])
        .args([
            "-e",
            "can.id",
            "-e",
            "frame.interface_name",
            "-e",
            "frame.packet_flags_direction",
        ])
        .output();
    match tshark {
        Ok(out) if out.status.success() => {
            let text = String::from_utf8_lossy(&out.stdout);
            assert_eq!(
                text.lines().count() as u64,
                run.frames_checked,
                "tshark reads every frame: {text}"
            );
            // Wireshark names the interface and tells the IUT's frames from the other nodes'.
            let seen: Vec<(String, String)> = text
                .lines()
                .map(|l| {
                    let fields: Vec<&str> = l.split(',').collect();
                    (fields[1].to_string(), fields[2].to_string())
                })
                .collect();
            assert!(seen.iter().all(|(name, _)| name == "canif-sim"), "{text}");
            let expected: Vec<String> = directions.iter().map(|d| format!("0x{d:08x}")).collect();
            let got: Vec<String> = seen.iter().map(|(_, d)| d.clone()).collect();
            assert_eq!(got, expected, "tshark's packet_flags_direction");
        }
        Ok(out) => panic!(
            "tshark cannot read the pcapng: {}",
            String::from_utf8_lossy(&out.stderr)
        ),
        Err(e) => {
            panic!("tshark: {e} (.ci/run installs it; elsewhere this test is ignored without it)")
        }
    }
    let _ = std::fs::remove_dir_all(dir);
}
