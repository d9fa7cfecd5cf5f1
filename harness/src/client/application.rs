//! What happens around a client under test, cycle by cycle: the application
//! above it asks it to send frames, the other nodes send frames it must
//! deliver, the PLC or the device restarts, the device overstates
//! NoOfRxMessages. Each scenario is one of the life cycles the issue of the
//! PLC side names, on one interface.

use canif_model::config::{Capabilities, FrameFormat, InterfaceConfig, QueueMode};
use canif_model::dlc::FD_DATA_SIZES;
use canif_model::frame::{CanId, Frame};
use canif_model::image::MessageRepr;
use canif_model::timing::BitRates;
use canif_spec::{req_ids, ReqId};

use super::master::Master;
use crate::declare::client::{Application, ClientDeclaration};
use crate::run::Rng;

/// Something that happens at the start of a CAN interface cycle.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Event {
    /// The application asks the client to send this message.
    Send(MessageRepr),
    /// Another node sends this frame on the bus.
    Arrive(Frame),
    /// The PLC restarts: the client's program starts again from zero, and
    /// so do the master's output buffers.
    PlcRestart,
    /// The client's program restarts inside a running master (a module
    /// reloaded): it starts from zero, the master's buffers keep their images.
    ModuleRestart,
    /// The device goes INIT → OP: its counters and queues back to 0.
    DeviceRestart,
    /// The next time the device enters a batch, the image says NoOfRxMessages
    /// = 0xFFFF (a device that lies, P5).
    OverstateRxCount,
}

/// One life cycle on one interface.
#[derive(Debug, Clone)]
pub struct ClientScenario {
    pub name: String,
    pub covers: Vec<ReqId>,
    pub config: InterfaceConfig,
    pub bit_rates: BitRates,
    /// CAN interface cycles, the quiet ones at the end included.
    pub cycles: u64,
    /// By cycle, in order.
    pub events: Vec<(u64, Event)>,
    /// What the client it is run on declares (judged by it).
    pub declared: ClientDeclaration,
}

/// Cycles at the end with no new traffic, for everything to arrive.
const QUIET: u64 = 40;

/// What every run of a client checks, whatever its life cycle.
const ALWAYS: &[ReqId] = req_ids![
    "CL-TX-001",
    "CL-TX-002",
    "CL-TX-003",
    "CL-TX-004",
    "CL-TX-005",
    "CL-RX-002",
    "CL-RX-003",
    "CL-IMG-001",
];

/// The application's traffic: frames the interface can carry, with running
/// transaction numbers (never 0, CL-TN-001).
struct Traffic {
    rng: Rng,
    format: FrameFormat,
    number: u16,
}

impl Traffic {
    fn new(seed: u64, format: FrameFormat) -> Self {
        Traffic {
            rng: Rng::new(seed),
            format,
            number: 0,
        }
    }

    fn frame(&mut self) -> Frame {
        let rng = &mut self.rng;
        let extended = self.format != FrameFormat::Base11 && rng.chance(50);
        let id = if extended {
            CanId::Extended(rng.below(0x2000_0000) as u32)
        } else {
            CanId::Standard(rng.below(0x800) as u16)
        };
        if self.format == FrameFormat::Fd && rng.chance(60) {
            let size = usize::from(FD_DATA_SIZES[rng.below(16) as usize]);
            let mut data = [0u8; 64];
            data[..size].fill_with(|| rng.next_u64() as u8);
            return Frame::fd(id, rng.chance(50), false, &data[..size]).expect("a valid FD size");
        }
        if rng.chance(10) {
            return Frame::remote(id, rng.below(9) as u8).expect("at most 8");
        }
        let len = rng.below(9) as usize;
        let mut data = [0u8; 8];
        data[..len].fill_with(|| rng.next_u64() as u8);
        Frame::classic(id, &data[..len]).expect("at most 8 bytes")
    }

    fn send(&mut self) -> Event {
        self.number = self.number.checked_add(1).unwrap_or(1);
        Event::Send(MessageRepr {
            transaction_number: self.number,
            frame: self.frame(),
            time_stamp: 0,
        })
    }

    /// `cycles` of traffic from `first`: up to 2 requests and 1 arrival per
    /// cycle, about half the bus; with fewer than 4 slots, only every 4th
    /// cycle, which is what a handshake per few messages can carry.
    fn steady(&mut self, first: u64, cycles: u64, slots: u8, events: &mut Vec<(u64, Event)>) {
        let every = if slots < 4 { 4 } else { 1 };
        for cycle in (first..first + cycles).step_by(every) {
            for _ in 0..self.rng.below(3) {
                events.push((cycle, self.send()));
            }
            for _ in 0..self.rng.below(2) {
                events.push((cycle, Event::Arrive(self.frame())));
            }
        }
    }
}

fn bit_rates(config: &InterfaceConfig) -> BitRates {
    BitRates {
        nominal: 500_000,
        data: if config.format == FrameFormat::Fd {
            2_000_000
        } else {
            500_000
        },
    }
}

fn scenario(
    name: &str,
    config: &InterfaceConfig,
    covers: &[ReqId],
    cycles: u64,
    mut events: Vec<(u64, Event)>,
) -> ClientScenario {
    events.sort_by_key(|(cycle, _)| *cycle);
    let mut covers: Vec<ReqId> = ALWAYS.iter().chain(covers).copied().collect();
    if config.queue == QueueMode::Fast {
        covers.push(ReqId::new("CL-FQ-001"));
    } else {
        covers.push(ReqId::new("CL-RX-001"));
        covers.push(ReqId::new("CL-RX-004"));
    }
    if config.transaction_number {
        covers.push(ReqId::new("CL-TN-001"));
        // Judged only when the client tells what was sent (rig.rs).
        covers.push(ReqId::new("CL-TN-002"));
    }
    covers.sort();
    covers.dedup();
    ClientScenario {
        name: format!("{name} ({})", describe(config)),
        covers,
        bit_rates: bit_rates(config),
        config: config.clone(),
        cycles: cycles + QUIET,
        events,
        declared: ClientDeclaration::default(),
    }
}

/// What only a client that sends is judged on.
const SENDING: &[ReqId] = req_ids![
    "CL-TX-001",
    "CL-TX-002",
    "CL-TX-003",
    "CL-TX-004",
    "CL-TX-005",
    "CL-TN-001",
    "CL-TN-002",
];

/// What only a client that receives is judged on.
const RECEIVING: &[ReqId] = req_ids![
    "CL-RX-001",
    "CL-RX-002",
    "CL-RX-003",
    "CL-RX-004",
    "CL-FQ-001"
];

/// The identifiers a several-stream application sends on: few, so that
/// each stream has frames to keep in order.
const STREAMS: u32 = 4;

impl ClientScenario {
    /// This life cycle as a client declaring `declared` meets it: traffic
    /// only the way the client moves frames, few identifiers where its
    /// application has a stream per identifier, and only the requirements
    /// it can be judged on. `None` where no traffic is left.
    pub fn for_client(mut self, declared: &ClientDeclaration) -> Option<Self> {
        let direction = declared.direction();
        self.events.retain(|(_, event)| match event {
            Event::Send(_) => direction.sends(),
            Event::Arrive(_) | Event::OverstateRxCount => direction.receives(),
            _ => true,
        });
        let traffic = |e: &Event| matches!(e, Event::Send(_) | Event::Arrive(_));
        if !self.events.iter().any(|(_, e)| traffic(e)) {
            return None;
        }
        self.covers.retain(|id| {
            (direction.sends() || !SENDING.contains(id))
                && (direction.receives() || !RECEIVING.contains(id))
        });
        let stream = |id: CanId| match id {
            CanId::Standard(raw) => CanId::Standard(0x100 + raw % STREAMS as u16),
            CanId::Extended(raw) => CanId::Extended(0x1000_0000 + raw % STREAMS),
        };
        match declared.application() {
            Application::OneStream => {}
            Application::Streams => {
                for (_, event) in &mut self.events {
                    if let Event::Send(message) = event {
                        message.frame.id = stream(message.frame.id);
                    }
                }
            }
            // Bytes on few identifiers, both ways: data frames that carry some.
            Application::ByteStream => {
                for (_, event) in &mut self.events {
                    let frame = match event {
                        Event::Send(message) => &mut message.frame,
                        Event::Arrive(frame) => frame,
                        _ => continue,
                    };
                    let id = stream(frame.id);
                    let data = match frame.data() {
                        [] => vec![id.raw() as u8],
                        data => data.to_vec(),
                    };
                    *frame =
                        Frame::classic(id, &data[..data.len().min(8)]).expect("at most 8 bytes");
                }
            }
        }
        self.declared = declared.clone();
        Some(self)
    }
}

/// The interface and its slots, as a scenario's name carries it: the
/// interface's one name ([`InterfaceConfig::describe`]) and the geometry a
/// client runs it with.
pub fn describe(config: &InterfaceConfig) -> String {
    let slots = match (config.tx_slots, config.rx_slots) {
        (tx, rx) if tx == rx => format!("{tx} slots"),
        (tx, rx) => format!("{tx} Tx and {rx} Rx slots"),
    };
    format!("{}, {slots}", config.describe())
}

/// Frames both ways, about half the bus, for a while.
pub fn steady_traffic(config: &InterfaceConfig, seed: u64) -> ClientScenario {
    let mut traffic = Traffic::new(seed, config.format);
    let mut events = Vec::new();
    traffic.steady(0, 160, config.tx_slots, &mut events);
    scenario("steady traffic", config, &[], 160, events)
}

/// More than the slots hold at once, both ways: every Rx slot filled.
pub fn bursts(config: &InterfaceConfig, seed: u64) -> ClientScenario {
    let mut traffic = Traffic::new(seed ^ 0xB0B5, config.format);
    let mut events = Vec::new();
    for (cycle, count) in [(3, 2 * config.rx_slots), (40, 3 * config.rx_slots)] {
        for _ in 0..count {
            events.push((cycle, Event::Arrive(traffic.frame())));
        }
    }
    for (cycle, count) in [(10, 2 * config.tx_slots + 1), (41, config.tx_slots)] {
        for _ in 0..count {
            events.push((cycle, traffic.send()));
        }
    }
    scenario("bursts fill every slot", config, &[], 80, events)
}

/// The PLC restarts twice while the device's counters are not 0.
pub fn plc_restart(config: &InterfaceConfig, seed: u64) -> ClientScenario {
    let mut traffic = Traffic::new(seed ^ 0x9E57, config.format);
    let mut events = Vec::new();
    traffic.steady(0, 120, config.tx_slots, &mut events);
    events.extend([(37, Event::PlcRestart), (74, Event::PlcRestart)]);
    scenario(
        "PLC restart with the counters not 0",
        config,
        req_ids!["CL-RST-001"],
        120,
        events,
    )
}

/// The client's program restarts twice inside a running master that keeps
/// its output buffers: the new program is first handed what the old one wrote.
pub fn module_restart(config: &InterfaceConfig, seed: u64) -> ClientScenario {
    let mut traffic = Traffic::new(seed ^ 0x40D1, config.format);
    let mut events = Vec::new();
    traffic.steady(0, 120, config.tx_slots, &mut events);
    events.extend([(41, Event::ModuleRestart), (83, Event::ModuleRestart)]);
    scenario(
        "module restart, the master's buffers kept",
        config,
        req_ids!["CL-RST-001"],
        120,
        events,
    )
}

/// The device goes through INIT to OP under a running client.
pub fn device_restart(config: &InterfaceConfig, seed: u64) -> ClientScenario {
    let mut traffic = Traffic::new(seed ^ 0xDE71, config.format);
    let mut events = Vec::new();
    traffic.steady(0, 120, config.tx_slots, &mut events);
    events.push((53, Event::DeviceRestart));
    scenario(
        "device restart under a running client",
        config,
        req_ids!["CL-RST-002"],
        120,
        events,
    )
}

/// Full Rx batches, and the device says NoOfRxMessages = 0xFFFF (P5).
pub fn overstated_rx_count(config: &InterfaceConfig, seed: u64) -> ClientScenario {
    let mut traffic = Traffic::new(seed ^ 0x0FF, config.format);
    let mut events = Vec::new();
    for cycle in [3, 30] {
        for _ in 0..config.rx_slots {
            events.push((cycle, Event::Arrive(traffic.frame())));
        }
        events.push((cycle, Event::OverstateRxCount));
    }
    scenario(
        "NoOfRxMessages beyond the slots",
        config,
        req_ids!["CL-IMG-001"],
        60,
        events,
    )
}

/// Both counters wrap at 0xFFFF: a batch each way every cycle.
pub fn counter_wrap(config: &InterfaceConfig, seed: u64) -> ClientScenario {
    let mut traffic = Traffic::new(seed ^ 0xFFFF, config.format);
    let mut events = Vec::new();
    let cycles = 65_600;
    for cycle in 0..cycles {
        events.push((cycle, traffic.send()));
        events.push((cycle, Event::Arrive(traffic.frame())));
    }
    scenario("both counters wrap at 0xFFFF", config, &[], cycles, events)
}

/// The interfaces a profile offers a client: each frame format with the
/// Buffered CAN Queue, and the Fast CAN Queue where there is one.
pub fn interfaces(caps: &Capabilities) -> Vec<InterfaceConfig> {
    let interface = crate::run::interface;
    let mut list = Vec::new();
    for (offered, format) in [
        (caps.base11, FrameFormat::Base11),
        (caps.ext29, FrameFormat::Extended29),
        (caps.fd, FrameFormat::Fd),
    ] {
        if offered {
            list.push(interface(format, QueueMode::Standard, caps));
        }
    }
    // The Optimized CAN Queue: the buffered handshake (003) on an 11-bit
    // interface without transaction numbers or filters (CFG), as offered.
    if caps.optimized_queue && caps.base11 {
        list.push(interface(FrameFormat::Base11, QueueMode::Optimized, caps));
    }
    if caps.fast_queue {
        list.push(interface(caps.first_format(), QueueMode::Fast, caps));
    }
    list
}

/// The life cycles of traffic alone, for the edges of the slot range.
pub fn traffic(config: &InterfaceConfig, seed: u64) -> Vec<ClientScenario> {
    vec![steady_traffic(config, seed), bursts(config, seed)]
}

/// The life cycles a client runs on one interface under one master. The
/// counter wrap (65,600 cycles) runs once per profile, under the master with
/// a batch every cycle.
pub fn scenarios(
    config: &InterfaceConfig,
    master: Master,
    seed: u64,
    wrap: bool,
) -> Vec<ClientScenario> {
    let mut list = vec![
        steady_traffic(config, seed),
        bursts(config, seed),
        plc_restart(config, seed),
        module_restart(config, seed),
        device_restart(config, seed),
        overstated_rx_count(config, seed),
    ];
    if wrap && master.name == "separate-input-update" {
        list.push(counter_wrap(config, seed));
    }
    list
}
