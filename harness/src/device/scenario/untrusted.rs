//! The PLC's output image as untrusted input to the device: what the sample
//! code of 001 §6 never writes, but a PLC program may. Where a document says
//! what the device does with it, the model is the judge (a batch of nothing,
//! HS-TX-009; the reserved COB ID bits, LAY-29-006; BRS or ESI without EDL,
//! FD-BIT-001); where it leaves it to the implementer (G3), only the bounds
//! are ([`Judgement::Bounds`]).

use canif_model::config::{FrameFormat, InterfaceConfig};
use canif_model::frame::{CanId, Frame};
use canif_model::image::{flag, ImageLayout, MessageRepr};
use canif_spec::ReqId;

use crate::declare::choices::Choice;

use super::generated::random_frame;
use super::scripted::{idle, message, std};
use super::{exercisable, scenario, Judgement, OutputEdit, Rng, Scenario, Step, Steps};

/// A batch the sample code writes, `count` random frames.
fn batch(rng: &mut Rng, config: &InterfaceConfig, count: usize, tn: &mut u16) -> Vec<MessageRepr> {
    (0..count)
        .map(|_| {
            *tn = tn.wrapping_add(1);
            message(random_frame(rng, config.format), *tn)
        })
        .collect()
}

/// Cycles for the device to send out everything it took (a full queue of
/// 8-byte frames at 125 kbit/s is about 150 ms, and every bounds scenario ends
/// with a valid batch that must be acknowledged).
const DRAIN: usize = 400;

fn drain(steps: &mut Vec<Step>, rng: &mut Rng, config: &InterfaceConfig, tn: &mut u16) {
    steps.push(edited(batch(rng, config, 1, tn), Vec::new()));
    steps.extend(idle(DRAIN));
}

/// A cycle in which the PLC's program sends `send` and then changes the
/// image with `edits`.
fn edited(send: Vec<MessageRepr>, edits: Vec<OutputEdit>) -> Step {
    Step {
        send,
        edits,
        ..Step::default()
    }
}

/// A scenario judged by the bounds of G3 alone: its pass is evidence for
/// those requirements only, not for the layouts it happens to use.
fn bounded(
    name: &str,
    config: &InterfaceConfig,
    (covers, decided_by): (&[&'static str], &'static [Choice]),
    steps: Vec<Step>,
) -> Scenario {
    let mut scenario = scenario(name, config, &[], Steps::Scripted(steps));
    scenario.judgement = Judgement::Bounds { decided_by };
    scenario.covers = covers
        .iter()
        .filter(|id| exercisable(id, config))
        .map(|id| ReqId::new(id))
        .collect();
    scenario
}

/// NoOfTxMessages = 0 with a new TxCounter: nothing is sent, and the batch
/// is still acknowledged (HS-TX-009); the handshake goes on after it.
pub fn tx_batch_of_nothing(config: &InterfaceConfig) -> Scenario {
    let mut rng = Rng::new(0x0B);
    let mut tn = 0;
    let mut steps = Vec::new();
    for round in 0..6 {
        let nothing = round % 2 == 0;
        let edits = if nothing {
            vec![OutputEdit::NoOfTxMessages(0)]
        } else {
            Vec::new()
        };
        steps.push(edited(batch(&mut rng, config, 2, &mut tn), edits));
        steps.extend(idle(4));
    }
    steps.extend(idle(20));
    let covers = ["HS-TX-002", "HS-TX-007", "HS-TX-009"];
    scenario(
        "tx-batch-of-nothing",
        config,
        &covers,
        Steps::Scripted(steps),
    )
}

/// NoOfTxMessages beyond the slot count (one more, 32, 255, 0xFFFF): never
/// more frames than slots, and the interface goes on (HS-TX-010, G3).
pub fn tx_batch_beyond_the_slots(config: &InterfaceConfig) -> Scenario {
    let slots = usize::from(config.tx_slots);
    let mut rng = Rng::new(0x10);
    let mut tn = 0;
    let mut steps = Vec::new();
    for count in [slots as u16 + 1, 32, 33, 255, 0x8000, 0xFFFF] {
        let beyond = OutputEdit::NoOfTxMessages(count.max(slots as u16 + 1));
        steps.push(edited(
            batch(&mut rng, config, slots, &mut tn),
            vec![beyond],
        ));
        steps.extend(idle(10));
    }
    drain(&mut steps, &mut rng, config, &mut tn);
    let decided_by = &[Choice::OversizeBatch];
    bounded(
        "tx-batch-beyond-the-slots",
        config,
        (&["HS-TX-010"], decided_by),
        steps,
    )
}

/// Length fields out of range: classic above 8 (up to 15 in the COB ID word,
/// 0xFFFF in a length word), FD above 64, and RTR with EDL (G3).
pub fn tx_length_out_of_range(config: &InterfaceConfig) -> Scenario {
    let slots = usize::from(config.tx_slots);
    let mut rng = Rng::new(0x1E);
    let mut tn = 0;
    let lengths: &[u16] = match config.format {
        FrameFormat::Base11 => &[9, 12, 15],
        FrameFormat::Extended29 => &[9, 64, 255, 0xFFFF],
        FrameFormat::Fd => &[65, 100, 255],
    };
    let mut steps = Vec::new();
    for (k, &raw) in lengths.iter().enumerate() {
        let mut edits: Vec<OutputEdit> = (0..slots)
            .filter(|slot| slot % 2 == k % 2)
            .map(|slot| OutputEdit::Length { slot, raw })
            .collect();
        if config.format == FrameFormat::Fd {
            // A remote FD frame: RTR with EDL (LAY-FD-003).
            edits.push(OutputEdit::CobId {
                slot: 1 % slots,
                raw: 0x4000_0000 | 0x123,
            });
        }
        steps.push(edited(batch(&mut rng, config, slots, &mut tn), edits));
        steps.extend(idle(10));
    }
    drain(&mut steps, &mut rng, config, &mut tn);
    let covers = ["LAY-GEN-008", "FD-LEN-006", "LAY-FD-003", "HS-TX-010"];
    let decided_by = &[Choice::BadTxLength];
    bounded(
        "tx-length-out-of-range",
        config,
        (&covers, decided_by),
        steps,
    )
}

/// Random output images, every byte, for many cycles: the bounds of G3 hold
/// whatever the PLC writes.
pub fn random_output_images(config: &InterfaceConfig, seed: u64) -> Scenario {
    let layout = ImageLayout::new(config, false);
    let mut rng = Rng::new(seed ^ 0x0BAD);
    let mut tn = 0;
    let mut steps: Vec<Step> = (0..60)
        .map(|_| Step {
            raw_outputs: Some(
                (0..layout.output_size())
                    .map(|_| rng.next_u64() as u8)
                    .collect(),
            ),
            ..Step::default()
        })
        .collect();
    drain(&mut steps, &mut rng, config, &mut tn);
    let covers = ["HS-TX-010", "LAY-GEN-008", "FD-LEN-006", "LAY-FD-003"];
    let decided_by = &[Choice::OversizeBatch, Choice::BadTxLength];
    bounded("random-output-images", config, (&covers, decided_by), steps)
}

/// 29-bit COB IDs with bit 31 = 0 and bits 11-28 set: only bits 0-10 are the
/// identifier; and bit 29, reserved, set beside an extended one (LAY-29-006).
pub fn reserved_cob_id_bits(config: &InterfaceConfig) -> Scenario {
    let slots = usize::from(config.tx_slots);
    let mut rng = Rng::new(0x29);
    let mut tn = 0;
    let mut steps = Vec::new();
    for _ in 0..6 {
        let send = batch(&mut rng, config, slots, &mut tn);
        let edits = send
            .iter()
            .enumerate()
            .map(|(slot, m)| {
                let rtr = if m.frame.is_remote() { 0x4000_0000 } else { 0 };
                let raw = match m.frame.id {
                    CanId::Standard(id) => {
                        let high = (rng.next_u64() as u32 & 0x1FFF_F800) | 0x800;
                        rtr | high | u32::from(id)
                    }
                    CanId::Extended(id) => 0x8000_0000 | 0x2000_0000 | rtr | id,
                };
                OutputEdit::CobId { slot, raw }
            })
            .collect();
        steps.push(edited(send, edits));
        steps.extend(idle(5));
    }
    steps.extend(idle(20));
    scenario(
        "reserved-cob-id-bits",
        config,
        &["LAY-29-006", "HS-TX-006"],
        Steps::Scripted(steps),
    )
}

/// BRS or ESI written without EDL: EDL alone decides, and a classic frame
/// goes out (FD-BIT-001).
pub fn classic_frame_with_fd_bits(config: &InterfaceConfig) -> Scenario {
    let mut tn = 0u16;
    let mut steps = Vec::new();
    for (k, bits) in [flag::BRS, flag::ESI, flag::BRS | flag::ESI]
        .into_iter()
        .enumerate()
    {
        let send: Vec<MessageRepr> = (0..3u16)
            .map(|i| {
                tn = tn.wrapping_add(1);
                let id = 0x300 + 8 * k as u16 + i;
                message(std(id, &[k as u8, i as u8]), tn)
            })
            .collect();
        let edits = (0..send.len())
            .map(|slot| OutputEdit::Flags { slot, raw: bits })
            .collect();
        steps.push(edited(send, edits));
        steps.extend(idle(5));
    }
    steps.extend(idle(20));
    scenario(
        "classic-frame-with-fd-bits",
        config,
        &["FD-BIT-001", "FD-BIT-002", "FD-BIT-003"],
        Steps::Scripted(steps),
    )
}

/// Every slot used: batches of exactly the slot count (32 where the profile
/// allows) and bursts of more received frames than there are Rx slots.
pub fn full_slots(config: &InterfaceConfig) -> Scenario {
    let slots = usize::from(config.tx_slots);
    let mut rng = Rng::new(0x32);
    let mut tn = 0;
    let mut steps = Vec::new();
    for round in 0..6u16 {
        let bus = (0..usize::from(config.rx_slots) + 8)
            .map(|i| {
                let id = (round * 64 + i as u16) & 0x7FF;
                let frame = Frame::classic(CanId::Standard(id), &[i as u8]).unwrap();
                (10_000 + 1_000 * i as u64, frame)
            })
            .collect();
        steps.push(Step {
            send: batch(&mut rng, config, slots, &mut tn),
            ..Step::default()
        });
        steps.push(Step {
            bus,
            ..Step::default()
        });
        // The PLC reads nothing while the burst arrives: the next read finds
        // every Rx slot filled.
        steps.extend((0..12).map(|_| Step {
            plc_busy: true,
            ..Step::default()
        }));
        steps.extend(idle(30));
    }
    steps.extend(idle(60));
    let covers = [
        "HS-TX-009",
        "HS-TX-011",
        "HS-RX-002",
        "HS-RX-007",
        "LAY-GEN-007",
    ];
    scenario("full-slots", config, &covers, Steps::Scripted(steps))
}
