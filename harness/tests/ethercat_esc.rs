//! canif's EL6751 as masters canif did not write see it (issue 35): in the
//! real terminal's layout, and against a hostile or simply different
//! master, which is bad input. The emulated EL6751 is driven with random frames — register writes, moved and
//! resized SyncManagers and FMMUs, AL state requests, Distributed Clocks
//! settings, mailbox bytes, clock jumps — and must answer every EtherCAT
//! frame with a frame of the same length, never panic, and keep answering.
//! (Moving SM1 or SM3 past the ESC's memory and then sending a request once
//! panicked `canif device --ethercat`; a system time 2^62 ns off hung it.)

use canif_ethercat::mailbox::{SdoRequest, SdoResponse};
use canif_ethercat::subdevice::{Application, SubDevice};
use canif_harness::door::ethercat::{emulated_terminal, Emulated};
use canif_softdevice::ethercat::Terminal;
use canif_spec::Catalogue;
use proptest::prelude::*;

fn terminal() -> SubDevice<Terminal> {
    let catalogue = Catalogue::embedded().unwrap();
    let profile = catalogue.profile("el6751-mdp").unwrap();
    emulated_terminal(
        &profile.model_capabilities(),
        profile.ethercat.as_ref().unwrap(),
        &Emulated::default(),
    )
}

/// One datagram through the terminal; its data and working counter back.
fn one(
    terminal: &mut SubDevice<Terminal>,
    command: u8,
    offset: u16,
    data: Vec<u8>,
) -> (Vec<u8>, u16) {
    let length = data.len();
    let answer = terminal
        .process(&frame(&[(command, 0, offset, data)]), 0)
        .expect("an answer");
    let at = 14 + 2 + 10;
    let wkc = u16::from_le_bytes([answer[at + length], answer[at + length + 1]]);
    (answer[at..at + length].to_vec(), wkc)
}

/// A SyncManager's eight register bytes.
fn sync_manager(start: u16, length: u16, control: u8) -> Vec<u8> {
    let mut bytes = start.to_le_bytes().to_vec();
    bytes.extend(length.to_le_bytes());
    bytes.extend([control, 0, 1, 0]);
    bytes
}

const BWR: u8 = 8;
const BRD: u8 = 7;

/// The real EL6751's layout (mailboxes at 0x1000 and 0x1400 of 1024 bytes,
/// process data at 0x1800 and 0x2400 in 1-buffer mode, 000 §5.1.2) takes
/// the terminal through PREOP, an SDO upload, to SAFEOP; a master that
/// wrote it got AL status 0x0016 before.
#[test]
fn the_real_el6751_layout_is_taken() {
    let mut terminal = terminal();
    one(&mut terminal, BWR, 0x0800, sync_manager(0x1000, 1024, 0x26));
    one(&mut terminal, BWR, 0x0808, sync_manager(0x1400, 1024, 0x22));
    one(&mut terminal, BWR, 0x0120, vec![0x02, 0x00]);
    assert_eq!(format!("{:?}", terminal.state()), "PreOp");
    let upload = SdoRequest::Upload {
        index: 0x1018,
        sub: 1,
        complete_access: false,
    };
    let (_, wkc) = one(&mut terminal, BWR, 0x1000, upload.emit(1, 1024));
    assert_eq!(wkc, 1);
    let (answer, _) = one(&mut terminal, BRD, 0x1400, vec![0; 1024]);
    let vendor = match SdoResponse::parse(&answer) {
        Ok(SdoResponse::Upload { data, .. }) => u32::from_le_bytes(data[..4].try_into().unwrap()),
        other => panic!("{other:?}"),
    };
    assert_eq!(vendor, 2, "Beckhoff's vendor id");
    let (outputs, inputs) = terminal.application.process_data();
    one(
        &mut terminal,
        BWR,
        0x0810,
        sync_manager(0x1800, outputs as u16, 0x26),
    );
    one(
        &mut terminal,
        BWR,
        0x0818,
        sync_manager(0x2400, inputs as u16, 0x22),
    );
    one(&mut terminal, BWR, 0x0120, vec![0x04, 0x00]);
    let (status, _) = one(&mut terminal, BRD, 0x0134, vec![0; 2]);
    assert_eq!(
        format!("{:?}", terminal.state()),
        "SafeOp",
        "AL status code {status:02X?}"
    );
}

/// An upload of one entry gets what the whole object lists for it, with
/// every profile's capabilities and at the slot counts and frame formats
/// that change the PDO mappings (built entry by entry there, not whole;
/// InfoData's 512 bits map with gaps).
#[test]
fn an_entry_is_what_its_object_lists() {
    use canif_ethercat::mailbox::abort;
    use canif_ethercat::ObjectDictionary;
    use canif_softdevice::ethercat::objects::{flags, interface, object};
    let catalogue = Catalogue::embedded().unwrap();
    let mut gaps = false;
    let el6751 = catalogue.profile("el6751-mdp").unwrap();
    let identity = el6751.ethercat.as_ref().unwrap();
    for profile in &catalogue.profiles {
        let caps = profile.model_capabilities();
        for (format, slots) in [
            (0, 1u16),
            (flags::EXT29_TRANSACTION_NUMBER, 10),
            (flags::EXT29, 32),
        ] {
            let mut terminal = emulated_terminal(&caps, identity, &Emulated::default()).application;
            let settings = [
                (interface::FLAGS, format.to_le_bytes().to_vec()),
                (interface::TX_SLOTS, slots.to_le_bytes().to_vec()),
                (interface::RX_SLOTS, slots.to_le_bytes().to_vec()),
            ];
            if terminal.write(object::INTERFACE, &settings).is_err() {
                continue; // a format this profile does not offer
            }
            for index in terminal.indices() {
                let entries = terminal.object(index).unwrap();
                for listed in &entries {
                    assert_eq!(terminal.entry(index, listed.sub).as_ref(), Ok(listed));
                    // A mapped word of index 0: the rest of an entry wider than 248 bits.
                    gaps |= matches!(index, object::RX_PDO_MAP | object::TX_PDO_MAP)
                        && listed.sub > 0
                        && listed.value[2..] == [0, 0];
                }
                let past = entries
                    .iter()
                    .map(|e| e.sub)
                    .max()
                    .unwrap_or(0)
                    .wrapping_add(1);
                if past != 0 {
                    assert_eq!(
                        terminal.entry(index, past).map(|e| e.sub),
                        Err(abort::NO_SUBINDEX),
                        "{} {index:#06x}:{past}",
                        profile.name
                    );
                }
            }
            assert_eq!(
                terminal.entry(0x5FFF, 0).map(|e| e.sub),
                Err(abort::NO_OBJECT)
            );
        }
    }
    assert!(
        gaps,
        "a mapping with gaps (InfoData's 512 bits) was checked"
    );
}

/// One datagram at local time `now`.
fn one_at(terminal: &mut SubDevice<Terminal>, now: u64, command: u8, offset: u16, data: Vec<u8>) {
    terminal
        .process(&frame(&[(command, 0, offset, data)]), now)
        .expect("an answer");
}

/// The real layout's mailboxes, then PREOP.
fn to_pre_op(terminal: &mut SubDevice<Terminal>) {
    one(terminal, BWR, 0x0800, sync_manager(0x1000, 1024, 0x26));
    one(terminal, BWR, 0x0808, sync_manager(0x1400, 1024, 0x22));
    one(terminal, BWR, 0x0120, vec![0x02, 0x00]);
}

/// PREOP, the real layout's process data (outputs' watchdog on, as the SII
/// gives it), SAFEOP; the AL status code back.
fn to_safe_op(terminal: &mut SubDevice<Terminal>) -> u16 {
    to_pre_op(terminal);
    let (outputs, inputs) = terminal.application.process_data();
    one(
        terminal,
        BWR,
        0x0810,
        sync_manager(0x1800, outputs as u16, 0x66),
    );
    one(
        terminal,
        BWR,
        0x0818,
        sync_manager(0x2400, inputs as u16, 0x22),
    );
    one(terminal, BWR, 0x0120, vec![0x04, 0x00]);
    let (code, _) = one(terminal, BRD, 0x0134, vec![0; 2]);
    u16::from_le_bytes([code[0], code[1]])
}

/// A terminal whose outputs stop coming for longer than the process-data
/// watchdog (100 ms at the ESC's reset values) goes to SAFEOP with AL
/// status code 0x001B, as a real one; with the watchdog off it stays in OP.
#[test]
fn the_sync_manager_watchdog_takes_a_starved_terminal_to_safeop() {
    for watchdog_on in [true, false] {
        let mut terminal = terminal();
        assert_eq!(to_safe_op(&mut terminal), 0);
        if !watchdog_on {
            one(&mut terminal, BWR, 0x0420, vec![0, 0]);
        }
        one(&mut terminal, BWR, 0x0120, vec![0x08, 0x00]);
        let (outputs, _) = terminal.application.process_data();
        one_at(&mut terminal, 1_000_000, BWR, 0x1800, vec![0; outputs]);
        one_at(&mut terminal, 100_000_000, BRD, 0x0130, vec![0; 2]);
        assert_eq!(format!("{:?}", terminal.state()), "Op");
        one_at(&mut terminal, 101_000_001, BRD, 0x0130, vec![0; 2]);
        let (code, _) = one(&mut terminal, BRD, 0x0134, vec![0; 2]);
        let expected = if watchdog_on {
            ("SafeOp", [0x1B, 0x00])
        } else {
            ("Op", [0, 0])
        };
        assert_eq!(
            (
                format!("{:?}", terminal.state()).as_str(),
                [code[0], code[1]]
            ),
            expected,
            "watchdog on: {watchdog_on}"
        );
    }
}

/// A SYNC0 cycle of 1 ns would have the terminal spend a core on SYNC0
/// events: refused with 0x0035 (invalid sync cycle time).
#[test]
fn a_sync0_cycle_no_terminal_could_keep_is_refused() {
    let mut terminal = terminal();
    to_pre_op(&mut terminal);
    one(&mut terminal, BWR, 0x09A0, 1u32.to_le_bytes().to_vec());
    one(&mut terminal, BWR, 0x0981, vec![0b011]);
    assert_eq!(to_safe_op(&mut terminal), 0x0035);
    assert_eq!(format!("{:?}", terminal.state()), "PreOp");
}

/// SDO Information lists the dictionary a configurator reads; FoE, which
/// the terminal does not speak, gets a mailbox error, not silence.
#[test]
fn sdo_information_lists_the_dictionary_and_foe_gets_a_mailbox_error() {
    let mut terminal = terminal();
    to_pre_op(&mut terminal);
    // Get OD list (op code 1), all objects (list type 1).
    let mut request = vec![8, 0, 0, 0, 0, 0x13, 0x00, 0x80, 1, 0, 0, 0, 1, 0];
    request.resize(1024, 0);
    one(&mut terminal, BWR, 0x1000, request);
    let (answer, _) = one(&mut terminal, BRD, 0x1400, vec![0; 1024]);
    assert_eq!(
        (answer[5] & 0x0F, answer[8]),
        (3, 2),
        "{:02X?}",
        &answer[..16]
    );
    let length = usize::from(u16::from_le_bytes([answer[0], answer[1]]));
    let listed: Vec<u16> = answer[14..6 + length]
        .chunks(2)
        .map(|w| u16::from_le_bytes([w[0], w[1]]))
        .collect();
    for index in [
        0x1000, 0x1018, 0x1A85, 0x1C32, 0x1C33, 0x6001, 0x7001, 0x8000, 0xF000, 0xF108,
    ] {
        assert!(listed.contains(&index), "{index:#06x} not in {listed:04X?}");
    }
    // FoE read request (mailbox type 4).
    let mut foe = vec![6, 0, 0, 0, 0, 0x24, 0, 0, 0, 0, 0, 0];
    foe.resize(1024, 0);
    one(&mut terminal, BWR, 0x1000, foe);
    let (answer, _) = one(&mut terminal, BRD, 0x1400, vec![0; 1024]);
    assert_eq!(
        &answer[5..10],
        &[0x20, 1, 0, 2, 0],
        "mailbox error, unsupported protocol"
    );
}

/// The reads of an SII word address, 8 bytes at a time, through the ESC's
/// SII registers (0x0502 control, 0x0504 address, 0x0508 data), as a
/// master reads the EEPROM.
fn read_sii(terminal: &mut SubDevice<Terminal>, bytes: usize) -> Vec<u8> {
    let mut out = Vec::new();
    for word in (0..bytes / 2).step_by(4) {
        let mut command = vec![0x00, 0x01]; // read
        command.extend((word as u32).to_le_bytes());
        one(terminal, BWR, 0x0502, command);
        let (data, _) = one(terminal, BRD, 0x0508, vec![0; 8]);
        out.extend(data);
    }
    out.truncate(bytes);
    out
}

/// An XML element: its name, attributes and text.
type Element = (String, Vec<(String, String)>, String);

/// Every element of an XML text with its attributes and text, in order.
fn elements(xml: &str) -> Vec<Element> {
    use quick_xml::events::Event;
    let mut reader = quick_xml::Reader::from_str(xml);
    let mut out: Vec<Element> = Vec::new();
    loop {
        match reader.read_event().expect("well-formed XML") {
            Event::Start(e) | Event::Empty(e) => {
                let attributes = e
                    .attributes()
                    .map(|a| {
                        let a = a.unwrap();
                        let key = String::from_utf8(a.key.as_ref().to_vec()).unwrap();
                        let value = a.normalized_value(quick_xml::XmlVersion::Implicit1_0);
                        (key, value.unwrap().into_owned())
                    })
                    .collect();
                let name = String::from_utf8(e.name().as_ref().to_vec()).unwrap();
                out.push((name, attributes, String::new()));
            }
            Event::Text(t) => {
                let text = t.decode().unwrap();
                if let (Some(last), false) = (out.last_mut(), text.trim().is_empty()) {
                    last.2 = text.trim().to_string();
                }
            }
            Event::Eof => break,
            _ => {}
        }
    }
    out
}

fn number(text: &str) -> u32 {
    match text.strip_prefix("#x") {
        Some(hex) => u32::from_str_radix(hex, 16).unwrap(),
        None => text.parse().unwrap(),
    }
}

/// `canif esi`'s document describes the terminal that serves it: its
/// identity, its SII byte for byte as read through the ESC, and a layout
/// and PDOs that, written as a configurator derives them from the file,
/// take the terminal to SAFEOP (issue 35).
#[test]
fn the_esi_file_is_the_terminal_it_describes() {
    let catalogue = Catalogue::embedded().unwrap();
    let profile = catalogue.profile("el6751-mdp").unwrap();
    let identity = profile.ethercat.unwrap();
    let mut terminal = terminal();
    let document = canif_harness::door::ethercat::esi::esi(&identity, &terminal);
    let elements = elements(&document);
    let first = |name: &str| {
        elements
            .iter()
            .find(|(n, _, _)| n == name)
            .unwrap_or_else(|| panic!("no <{name}>"))
    };
    let attribute = |element: &Element, name: &str| {
        element.1.iter().find(|(k, _)| k == name).unwrap().1.clone()
    };
    assert_eq!(number(&first("Id").2), identity.vendor_id);
    let device_type = elements
        .iter()
        .find(|(n, a, _)| n == "Type" && !a.is_empty())
        .unwrap();
    assert_eq!(
        number(&attribute(device_type, "ProductCode")),
        identity.product_code
    );
    assert_eq!(
        number(&attribute(device_type, "RevisionNo")),
        identity.revision
    );
    // The EEPROM as the ESC serves it.
    let size: usize = first("ByteSize").2.parse().unwrap();
    let data = &first("Data").2;
    let served: String = read_sii(&mut terminal, size)
        .iter()
        .map(|b| format!("{b:02X}"))
        .collect();
    assert_eq!(data, &served);
    // The layout and process data a configurator writes from the file.
    let sms: Vec<_> = elements.iter().filter(|(n, _, _)| n == "Sm").collect();
    assert_eq!(sms.len(), 4);
    let bits = |kind: &str| -> u32 {
        let mut inside = false;
        let mut total = 0;
        for (name, _, text) in &elements {
            match name.as_str() {
                "RxPdo" | "TxPdo" => inside = name == kind,
                "BitLen" if inside => total += number(text),
                _ => {}
            }
        }
        total
    };
    let sizes = [None, None, Some(bits("RxPdo") / 8), Some(bits("TxPdo") / 8)];
    for (n, (sm, size)) in sms.iter().zip(sizes).enumerate() {
        let start = number(&attribute(sm, "StartAddress")) as u16;
        let length = size.unwrap_or_else(|| number(&attribute(sm, "DefaultSize"))) as u16;
        let control = number(&attribute(sm, "ControlByte")) as u8;
        one(
            &mut terminal,
            BWR,
            0x0800 + 8 * n as u16,
            sync_manager(start, length, control),
        );
        if n == 1 {
            one(&mut terminal, BWR, 0x0120, vec![0x02, 0x00]);
            assert_eq!(format!("{:?}", terminal.state()), "PreOp", "{sm:?}");
        }
    }
    one(&mut terminal, BWR, 0x0120, vec![0x04, 0x00]);
    let (code, _) = one(&mut terminal, BRD, 0x0134, vec![0; 2]);
    assert_eq!(
        format!("{:?}", terminal.state()),
        "SafeOp",
        "AL status code {code:02X?}: the file's PDOs are not the terminal's"
    );
}

/// What no ESC could hold is refused with the code a real one gives: a
/// mailbox past the ESC's memory, or one over the other.
#[test]
fn a_mailbox_no_esc_could_hold_is_refused_with_0x0016() {
    for (out, inn) in [
        ((0x1000, 1024), (0x2F00, 1024)),
        ((0x1000, 1024), (0x1200, 128)),
    ] {
        let mut terminal = terminal();
        one(&mut terminal, BWR, 0x0800, sync_manager(out.0, out.1, 0x26));
        one(&mut terminal, BWR, 0x0808, sync_manager(inn.0, inn.1, 0x22));
        one(&mut terminal, BWR, 0x0120, vec![0x02, 0x00]);
        let (code, _) = one(&mut terminal, BRD, 0x0134, vec![0; 2]);
        assert_eq!(format!("{:?}", terminal.state()), "Init", "{out:?} {inn:?}");
        assert_eq!(
            u16::from_le_bytes([code[0], code[1]]),
            0x0016,
            "{out:?} {inn:?}"
        );
    }
}

/// Where a master's datagram lands: the registers that steer the ESC more
/// often than the rest of its 64 KiB address space.
fn address() -> impl Strategy<Value = u16> {
    prop_oneof![
        3 => 0x0600u16..0x0640, // FMMUs
        3 => 0x0800u16..0x0840, // SyncManagers
        2 => 0x0900u16..0x09B0, // Distributed Clocks
        2 => Just(0x0120u16),   // AL control
        1 => 0x0500u16..0x0510, // SII
        2 => 0x1000u16..0x3000, // process memory and mailboxes
        1 => any::<u16>(),
    ]
}

/// One datagram: command (the 15 of ETG.1000.4; a frame with another is no
/// EtherCAT frame to the wire format, `canif_ethercat::wire`), address, data.
fn datagram() -> impl Strategy<Value = (u8, u16, u16, Vec<u8>)> {
    prop_oneof![
        6 => (
            0u8..15,
            prop_oneof![Just(0u16), Just(0x1000u16), any::<u16>()],
            address(),
            prop_oneof![
                2 => proptest::collection::vec(any::<u8>(), 0..16),
                1 => proptest::collection::vec(any::<u8>(), 0..300),
            ],
        ),
        // A whole mailbox message (BWR over the mailbox SyncManager, CoE
        // header and random SDO bytes), so that the mailbox is served.
        1 => proptest::collection::vec(any::<u8>(), 120).prop_map(|sdo| {
            let mut message = vec![0x0A, 0x00, 0x00, 0x00, 0x00, 0x13, 0x00, 0x20];
            message.extend(sdo);
            (8u8, 0u16, 0x1000u16, message)
        }),
    ]
}

/// SM0 and SM1 as the terminal's SII describes its mailboxes, then PREOP.
fn to_preop() -> Vec<(u8, u16, u16, Vec<u8>)> {
    vec![
        (8, 0, 0x0800, vec![0x00, 0x10, 128, 0, 0x26, 0, 1, 0]),
        (8, 0, 0x0808, vec![0x80, 0x10, 128, 0, 0x22, 0, 1, 0]),
        (8, 0, 0x0120, vec![0x02, 0x00]),
    ]
}

/// An Ethernet frame of EtherCAT datagrams, as a master sends it.
fn frame(datagrams: &[(u8, u16, u16, Vec<u8>)]) -> Vec<u8> {
    let mut body = Vec::new();
    for (at, (command, position, offset, data)) in datagrams.iter().enumerate() {
        let more = if at + 1 < datagrams.len() { 0x8000 } else { 0 };
        body.push(*command);
        body.push(at as u8);
        body.extend_from_slice(&position.to_le_bytes());
        body.extend_from_slice(&offset.to_le_bytes());
        body.extend_from_slice(&(data.len() as u16 | more).to_le_bytes());
        body.extend_from_slice(&[0, 0]);
        body.extend_from_slice(data);
        body.extend_from_slice(&[0, 0]);
    }
    let mut frame = vec![0xFF; 6];
    frame.extend_from_slice(&[0x02, 0, 0, 0, 0, 1, 0x88, 0xA4]);
    frame.extend_from_slice(&(body.len() as u16 & 0x7FF | 0x1000).to_le_bytes());
    frame.extend_from_slice(&body);
    // The Ethernet minimum, as a master's NIC pads it.
    frame.resize(frame.len().max(60), 0);
    frame
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]

    #[test]
    fn the_terminal_answers_every_frame_whatever_a_master_writes(
        frames in proptest::collection::vec(
            (proptest::collection::vec(datagram(), 1..4), prop_oneof![
                4 => 0u64..2_000_000,
                1 => any::<u64>(),
            ]),
            1..40,
        )
    ) {
        let mut terminal = terminal();
        // From PREOP, where the mailbox is served: most of what a master can
        // break is reachable only from there.
        prop_assert!(terminal.process(&frame(&to_preop()), 0).is_some());
        prop_assert_eq!(format!("{:?}", terminal.state()), "PreOp");
        let mut now = 0u64;
        for (datagrams, step) in frames {
            now = now.saturating_add(step);
            let sent = frame(&datagrams);
            if sent.len() > 1514 {
                continue;
            }
            let answer = terminal.process(&sent, now);
            prop_assert!(answer.is_some(), "an EtherCAT frame went unanswered");
            prop_assert_eq!(answer.unwrap().len(), sent.len());
            if let Some(due) = terminal.poll_timeout() {
                terminal.handle_timeout(due.max(now));
            }
        }
    }
}
