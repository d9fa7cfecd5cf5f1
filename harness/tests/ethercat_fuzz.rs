//! A hostile or simply different master is bad input (issue 35): canif's
//! emulated EL6751 is driven with random frames — register writes, moved and
//! resized SyncManagers and FMMUs, AL state requests, Distributed Clocks
//! settings, mailbox bytes, clock jumps — and must answer every EtherCAT
//! frame with a frame of the same length, never panic, and keep answering.
//! (Moving SM1 or SM3 past the ESC's memory and then sending a request once
//! panicked `canif device --ethercat`; a system time 2^62 ns off hung it.)

use canif_harness::door::ethercat::{emulated_terminal, Emulated};
use canif_spec::Catalogue;
use proptest::prelude::*;

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
        let catalogue = Catalogue::embedded().unwrap();
        let profile = catalogue.profile("el6751-mdp").unwrap();
        let mut terminal = emulated_terminal(
            &profile.model_capabilities(),
            profile.ethercat.as_ref().unwrap(),
            &Emulated { faults: vec![], choices: vec![], link_fault: None },
        );
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
