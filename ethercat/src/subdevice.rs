//! An ESC with an application behind it (ETG.1000.6 §6.4): the AL state
//! machine with the checks of each transition, the SII EEPROM, the CoE
//! mailbox, and the SyncManager 2 event that runs the application's cycle.

use crate::esc::{Esc, Touched};
use crate::mailbox::SdoRequest;
use crate::register::{self, sii};
use crate::sdo::{ObjectDictionary, SdoServer};
use crate::sdo_info::{mailbox_error, InfoRequest, Kind};
use crate::sii::{Identity, Layout};
use crate::sync0::Sync0Schedule;
use crate::wire::Frame;

/// The AL states (AL control / AL status bits 0–3).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AlState {
    Init = 1,
    PreOp = 2,
    Bootstrap = 3,
    SafeOp = 4,
    Op = 8,
}

impl AlState {
    fn from_bits(bits: u16) -> Option<AlState> {
        Some(match bits & 0x0F {
            1 => AlState::Init,
            2 => AlState::PreOp,
            3 => AlState::Bootstrap,
            4 => AlState::SafeOp,
            8 => AlState::Op,
            _ => return None,
        })
    }
}

/// AL status codes (ETG.1000.6 Table 11) this SubDevice reports.
pub mod al_status {
    pub const INVALID_STATE_CHANGE: u16 = 0x0011;
    pub const UNKNOWN_STATE: u16 = 0x0012;
    pub const BOOTSTRAP_NOT_SUPPORTED: u16 = 0x0013;
    pub const INVALID_MAILBOX_CONFIGURATION: u16 = 0x0016;
    pub const INVALID_OUTPUT_CONFIGURATION: u16 = 0x001D;
    pub const INVALID_INPUT_CONFIGURATION: u16 = 0x001E;
    pub const SYNC_MANAGER_WATCHDOG: u16 = 0x001B;
    /// Settings that contradict each other (here: a record left open by
    /// consistency nesting at PREOP → SAFEOP; the code is canif's reading).
    pub const INCONSISTENT_SETTINGS: u16 = 0x0026;
    pub const INVALID_SYNC_CONFIGURATION: u16 = 0x0030;
    pub const INVALID_SYNC_CYCLE_TIME: u16 = 0x0035;
}

/// The shortest SYNC0 cycle the terminal takes (an assumption: no source
/// gives the EL6751's; a master asking for 1 ns would have it spend a host
/// core on SYNC0 events).
pub const MIN_SYNC0_CYCLE_NS: u32 = 100_000;

/// How the application's cycle is started (003: SyncManager 2 event, or SYNC0/SYNC1).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Synchronization {
    SyncManager2,
    /// SYNC0 starts the cycle, SYNC1 follows `sync1_shift` ns later.
    DistributedClocks {
        sync0_cycle: u32,
        sync1_shift: u32,
    },
}

/// What the application learns when the master asks for SAFEOP.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Start {
    pub outputs: usize,
    pub inputs: usize,
    pub synchronization: Synchronization,
}

/// The terminal behind the ESC.
pub trait Application: ObjectDictionary {
    /// The process-data lengths its configuration needs (outputs, inputs).
    fn process_data(&self) -> (usize, usize);
    /// PREOP → SAFEOP with these SyncManager lengths; an AL status code refuses.
    fn start(&mut self, start: Start) -> Result<(), u16>;
    /// Back to PREOP or INIT.
    fn stop(&mut self);
    /// The cycle the SyncManager 2 event starts: outputs in, the new inputs.
    fn cycle(&mut self, outputs: &[u8], now: u64) -> Vec<u8>;
}

/// One emulated SubDevice.
pub struct SubDevice<A> {
    pub esc: Esc,
    pub application: A,
    eeprom: Vec<u8>,
    layout: Layout,
    state: AlState,
    /// Local time of the last complete outputs buffer (or of entering OP),
    /// for the process-data watchdog.
    outputs_seen: u64,
    sdo: SdoServer,
    /// How many SyncManager 2 events ran (for a report).
    pub cycles: u64,
    /// The logical telegrams that reached it: how a master exchanged the
    /// process data (003: LRW, or LWR then LRD for separate input update).
    pub telegrams: Telegrams,
    /// With Distributed Clocks, the SYNC0 events that start the cycle.
    sync0: Option<Sync0Schedule>,
    /// The outputs' SyncManager in 3-buffer mode: the last buffer the master
    /// wrote to its end, which is all the application ever reads (a write
    /// that stops short of the end is not handed over, ETG.1000.4 §8.2.3).
    outputs_buffer: Vec<u8>,
    /// The outputs the application last acted on in OP (zeros before):
    /// what its cycle is handed outside OP. In SAFEOP a SubDevice delivers
    /// inputs but keeps its outputs in their safe state (ETG.1000.6's state
    /// machine): nothing the master writes then is acted on until OP.
    acted_on: Vec<u8>,
    /// A firmware fault for canif's own tests: the cycle runs on the
    /// SyncManager 2 event also with Distributed Clocks (PDX-005 broken).
    pub cycles_on_frames: bool,
    /// The frame being answered and the answer's bytes: kept from frame to
    /// frame, so that answering allocates nothing once they have grown.
    frame: Frame,
    answer: Vec<u8>,
}

/// Counts of the logical commands a SubDevice processed.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Telegrams {
    pub lrw: u64,
    pub lwr: u64,
    pub lrd: u64,
}

const MAILBOX_OUT: u16 = 0;
const MAILBOX_IN: u16 = 1;
const OUTPUTS: u16 = 2;
const INPUTS: u16 = 3;
const AL_ERROR: u16 = 0x10;

/// The smallest mailbox that holds an SDO message: the mailbox and CoE
/// headers and an expedited SDO (6 + 2 + 8 bytes).
const MIN_MAILBOX: usize = 16;

/// A SyncManager inside the ESC's process memory (0x1000 up to its end).
fn in_process_memory(sm: &register::SyncManager) -> bool {
    let range = sm.range();
    range.start >= 0x1000 && range.end <= crate::esc::MEMORY
}

/// Whether two enabled SyncManagers share a byte.
fn overlap(a: &register::SyncManager, b: &register::SyncManager) -> bool {
    let (a, b) = (a.range(), b.range());
    a.start < b.end && b.start < a.end
}

impl<A: Application> SubDevice<A> {
    /// A SubDevice whose SII gives the real EL6751's layout.
    pub fn new(identity: &Identity, application: A) -> SubDevice<A> {
        SubDevice::with_layout(identity, Layout::EL6751, application)
    }

    /// A SubDevice whose SII gives `layout` (any layout within the ESC's
    /// memory works: this is only what the SII advertises).
    pub fn with_layout(identity: &Identity, layout: Layout, application: A) -> SubDevice<A> {
        let mut device = SubDevice {
            esc: Esc::new(),
            application,
            eeprom: crate::sii::image(identity, &layout),
            layout,
            outputs_seen: 0,
            state: AlState::Init,
            sdo: SdoServer::default(),
            cycles: 0,
            telegrams: Telegrams::default(),
            sync0: None,
            outputs_buffer: Vec::new(),
            acted_on: Vec::new(),
            cycles_on_frames: false,
            frame: Frame::EMPTY,
            answer: Vec::new(),
        };
        device.set_status(AlState::Init, None);
        device
    }

    /// The layout its SII advertises.
    pub fn layout(&self) -> Layout {
        self.layout
    }

    /// The SII's content, as the ESC serves it.
    pub fn sii(&self) -> &[u8] {
        &self.eeprom
    }

    pub fn state(&self) -> AlState {
        self.state
    }

    /// Answers one Ethernet frame at local time `now` (ns); `None` for what is
    /// no EtherCAT frame (an ESC drops it).
    pub fn process(&mut self, bytes: &[u8], now: u64) -> Option<&[u8]> {
        let mut frame = std::mem::replace(&mut self.frame, Frame::EMPTY);
        let ethercat = frame.parse_from(bytes).is_ok();
        if ethercat {
            self.answer_frame(&mut frame, now);
        }
        self.frame = frame;
        ethercat.then_some(self.answer.as_slice())
    }

    fn answer_frame(&mut self, frame: &mut Frame, now: u64) {
        // A SYNC0 event before the frame runs first; one at its very time
        // comes just after it (the master sends its frame ahead of SYNC0).
        self.run_sync0(now, false);
        self.esc.local_time = now;
        self.watch(now);
        let mut touched = Touched::default();
        for datagram in &mut frame.datagrams {
            match datagram.command {
                crate::wire::Command::Lrw => self.telegrams.lrw += 1,
                crate::wire::Command::Lwr => self.telegrams.lwr += 1,
                crate::wire::Command::Lrd => self.telegrams.lrd += 1,
                _ => {}
            }
            self.esc.process(datagram, &mut touched);
        }
        self.after(&touched, now);
        // The frame returns through port 0 with the locally administered bit set.
        frame.source[0] |= 0x02;
        frame.emit_into(&mut self.answer);
    }

    /// With Distributed Clocks, when the next SYNC0 event comes (local time),
    /// for a host that waits between frames.
    pub fn poll_timeout(&self) -> Option<u64> {
        let schedule = self.sync0.as_ref()?;
        Some(self.esc.local_time_at(schedule.next()))
    }

    /// Runs the cycles of the SYNC0 events due by local time `now`.
    pub fn handle_timeout(&mut self, now: u64) {
        self.run_sync0(now, true);
        self.watch(now);
    }

    /// The SyncManager watchdog: in OP, outputs not written for longer than
    /// the process-data watchdog time take the terminal to SAFEOP with AL
    /// status code 0x001B, as a real terminal (ETG.1000.6 Table 11), where
    /// the outputs' SyncManager has its watchdog enabled (control bit 6).
    fn watch(&mut self, now: u64) {
        const WATCHDOG_ENABLED: u8 = 1 << 6;
        if self.state != AlState::Op
            || self.esc.sync_manager(OUTPUTS).control & WATCHDOG_ENABLED == 0
        {
            return;
        }
        let Some(time) = self.esc.process_data_watchdog() else {
            return;
        };
        if now.saturating_sub(self.outputs_seen) > time {
            self.esc.set16(register::WATCHDOG_STATUS_PROCESS_DATA, 0);
            self.set_status(AlState::SafeOp, Some(al_status::SYNC_MANAGER_WATCHDOG));
        }
    }

    /// SYNC0 events that came while nobody asked (a stalled host).
    pub fn missed_sync0(&self) -> u64 {
        self.sync0.map_or(0, |s| s.missed)
    }

    fn run_sync0(&mut self, now: u64, inclusive: bool) {
        if !matches!(self.state, AlState::SafeOp | AlState::Op) {
            return;
        }
        let system = self.esc.system_time_at(now);
        let Some(schedule) = self.sync0.as_mut() else {
            return;
        };
        if let Some(event) = schedule.take_due(system, inclusive) {
            let at = self.esc.local_time_at(event);
            self.sync_manager_event(at);
        }
    }

    /// What the ESC and its firmware do once a frame has passed.
    fn after(&mut self, touched: &Touched, now: u64) {
        if touched.wrote(register::SII_CONTROL) {
            self.sii_command();
        }
        if touched.wrote(register::AL_CONTROL) {
            let control = self.esc.get16(register::AL_CONTROL);
            self.al_control(control);
        }
        let mailbox_out = self.esc.sync_manager(MAILBOX_OUT);
        if self.state != AlState::Init
            && mailbox_out.enabled()
            && touched.completed(&mailbox_out.range())
        {
            self.mailbox(&mailbox_out);
        }
        let mailbox_in = self.esc.sync_manager(MAILBOX_IN);
        if touched.read_end_of(&mailbox_in.range()) {
            self.esc.set_sync_manager_status(MAILBOX_IN, 0);
        }
        let outputs = self.esc.sync_manager(OUTPUTS);
        if matches!(self.state, AlState::SafeOp | AlState::Op)
            && outputs.enabled()
            && touched.completed(&outputs.range())
        {
            self.outputs_seen = now;
            self.esc.set16(register::WATCHDOG_STATUS_PROCESS_DATA, 1);
            self.outputs_buffer.clear();
            // A SyncManager a master moved past the ESC's memory maps nothing.
            let written = self.esc.memory.get(outputs.range()).unwrap_or_default();
            self.outputs_buffer.extend_from_slice(written);
            // With Distributed Clocks the buffer waits for SYNC0 (003).
            if self.sync0.is_none() || self.cycles_on_frames {
                self.sync_manager_event(now);
            }
        }
    }

    fn sii_command(&mut self) {
        let control = self.esc.get16(register::SII_CONTROL);
        let word = self.esc.get32(register::SII_ADDRESS) as usize;
        let mut status = control & !(sii::COMMAND_MASK | sii::COMMAND_ERROR) | sii::READ_8_BYTES;
        match control & sii::COMMAND_MASK {
            sii::COMMAND_READ => {
                let at = usize::from(register::SII_DATA);
                for i in 0..8 {
                    self.esc.memory[at + i] =
                        self.eeprom.get(word * 2 + i).copied().unwrap_or(0xFF);
                }
            }
            sii::COMMAND_RELOAD | 0 => {}
            // The image is the ESC's configuration: it is not written over.
            _ => status |= sii::COMMAND_ERROR,
        }
        self.esc.set16(register::SII_CONTROL, status);
    }

    fn set_status(&mut self, state: AlState, error: Option<u16>) {
        self.state = state;
        let flag = if error.is_some() { AL_ERROR } else { 0 };
        self.esc.set16(register::AL_STATUS, state as u16 | flag);
        self.esc.set16(register::AL_STATUS_CODE, error.unwrap_or(0));
    }

    fn al_control(&mut self, control: u16) {
        let acknowledged = control & AL_ERROR != 0;
        let in_error = self.esc.get16(register::AL_STATUS) & AL_ERROR != 0;
        if in_error && !acknowledged {
            return; // an error stays until the master acknowledges it
        }
        let Some(requested) = AlState::from_bits(control) else {
            return self.set_status(self.state, Some(al_status::UNKNOWN_STATE));
        };
        let result = self.transition(requested);
        match result {
            Ok(()) => self.set_status(requested, None),
            Err(code) => self.set_status(self.state, Some(code)),
        }
    }

    fn transition(&mut self, to: AlState) -> Result<(), u16> {
        use AlState::*;
        match (self.state, to) {
            (_, Bootstrap) => Err(al_status::BOOTSTRAP_NOT_SUPPORTED),
            (from, to) if from == to => Ok(()),
            (_, Init) => {
                self.sync0 = None;
                self.application.stop();
                Ok(())
            }
            (Init, PreOp) => self.check_mailbox(),
            (SafeOp | Op, PreOp) => {
                self.sync0 = None;
                self.application.stop();
                Ok(())
            }
            (PreOp, SafeOp) => self.start(),
            (Op, SafeOp) => Ok(()),
            (SafeOp, Op) => {
                self.outputs_seen = self.esc.local_time;
                Ok(())
            }
            _ => Err(al_status::INVALID_STATE_CHANGE),
        }
    }

    /// INIT → PREOP: two mailbox SyncManagers, the master's (SM0) and the
    /// terminal's (SM1), wherever a master put them in process memory: the
    /// SII's layout or another, such as the real EL6751's (0x1000 and
    /// 0x1400, 1024 bytes each). What no ESC could hold is refused with
    /// 0x0016, as a real one refuses it.
    fn check_mailbox(&self) -> Result<(), u16> {
        let out = self.esc.sync_manager(MAILBOX_OUT);
        let inn = self.esc.sync_manager(MAILBOX_IN);
        let sane = |sm: &register::SyncManager, by_master: bool| {
            sm.enabled()
                && sm.mailbox()
                && sm.written_by_master() == by_master
                && usize::from(sm.length) >= MIN_MAILBOX
                && in_process_memory(sm)
        };
        if !sane(&out, true) || !sane(&inn, false) || overlap(&out, &inn) {
            return Err(al_status::INVALID_MAILBOX_CONFIGURATION);
        }
        Ok(())
    }

    /// PREOP → SAFEOP: process-data SyncManagers of the lengths the
    /// configuration needs, anywhere in process memory clear of the
    /// mailboxes, in 3-buffer or 1-buffer mode (the EL6751 runs its buffered
    /// queues in 1-buffer mode, 000 §5.1.2, the Fast CAN Queue in 3-buffer).
    fn start(&mut self) -> Result<(), u16> {
        let (outputs, inputs) = self.application.process_data();
        let mailboxes = [
            self.esc.sync_manager(MAILBOX_OUT),
            self.esc.sync_manager(MAILBOX_IN),
        ];
        let fits = |n: u16, needed: usize, by_master: bool| {
            let sm = self.esc.sync_manager(n);
            sm.enabled()
                && sm.control & 0b11 != 0b11
                && sm.control & 0b11 != 0b01
                && sm.written_by_master() == by_master
                && usize::from(sm.length) == needed
                && in_process_memory(&sm)
                && !mailboxes.iter().any(|mailbox| overlap(&sm, mailbox))
        };
        if !fits(OUTPUTS, outputs, true) {
            return Err(al_status::INVALID_OUTPUT_CONFIGURATION);
        }
        if !fits(INPUTS, inputs, false)
            || overlap(
                &self.esc.sync_manager(OUTPUTS),
                &self.esc.sync_manager(INPUTS),
            )
        {
            return Err(al_status::INVALID_INPUT_CONFIGURATION);
        }
        let activation = self.esc.memory[usize::from(register::DC_SYNC_ACTIVATION)];
        let synchronization = if activation & 0b001 == 0 {
            Synchronization::SyncManager2
        } else if activation & 0b110 == 0 {
            return Err(al_status::INVALID_SYNC_CONFIGURATION);
        } else {
            Synchronization::DistributedClocks {
                sync0_cycle: self.esc.get32(register::DC_SYNC0_CYCLE),
                sync1_shift: if activation & 0b100 != 0 {
                    self.esc.get32(register::DC_SYNC1_CYCLE)
                } else {
                    0
                },
            }
        };
        if let Synchronization::DistributedClocks { sync0_cycle, .. } = synchronization {
            if sync0_cycle < MIN_SYNC0_CYCLE_NS {
                return Err(al_status::INVALID_SYNC_CYCLE_TIME);
            }
        }
        self.application.start(Start {
            outputs,
            inputs,
            synchronization,
        })?;
        self.outputs_buffer.clear();
        self.acted_on.clear();
        if let Synchronization::DistributedClocks { sync0_cycle, .. } = synchronization {
            let now = self.esc.system_time_at(self.esc.local_time);
            let start = self.esc.get64(register::DC_START_TIME);
            self.sync0 = Sync0Schedule::new(start, sync0_cycle, now);
            if self.sync0.is_none() {
                self.application.stop();
                return Err(al_status::INVALID_SYNC_CONFIGURATION);
            }
        }
        Ok(())
    }

    fn mailbox(&mut self, mailbox_out: &register::SyncManager) {
        // An answer fills the terminal's mailbox as the master set it up;
        // one shrunk below any message since PREOP is answered nothing.
        let size = usize::from(self.esc.sync_manager(MAILBOX_IN).length);
        if size < MIN_MAILBOX {
            return;
        }
        // A mailbox a master moved past the ESC's memory holds no request.
        let Some(request) = self.esc.memory.get(mailbox_out.range()) else {
            return;
        };
        let counter = request.get(5).map_or(0, |b| b >> 4 & 7);
        let answer = match crate::sdo_info::kind(request) {
            Kind::Sdo => match SdoRequest::parse(request) {
                Ok(request) => self
                    .sdo
                    .handle(&mut self.application, request, size)
                    .map(|answer| answer.emit(counter, size)),
                // A message the server cannot read is answered with an abort of no object.
                Err(_) => Some(
                    crate::mailbox::SdoResponse::Abort {
                        index: 0,
                        sub: 0,
                        code: crate::mailbox::abort::COMMAND_SPECIFIER,
                    }
                    .emit(counter, size),
                ),
            },
            Kind::Info => Some(match InfoRequest::parse(request) {
                Some(asked) => crate::sdo_info::answer(&self.application, asked, counter, size),
                None => crate::sdo_info::error(counter, mailbox_error::SERVICE_NOT_SUPPORTED, size),
            }),
            Kind::Unsupported(detail) => Some(crate::sdo_info::error(counter, detail, size)),
        };
        if let Some(bytes) = answer {
            // The answer fills the mailbox as the master set it now, as far
            // as it lies in the ESC's memory (a master may have moved or
            // shrunk it since PREOP).
            let range = self.esc.sync_manager(MAILBOX_IN).range();
            let end = range.end.min(self.esc.memory.len());
            if let Some(mailbox) = self.esc.memory.get_mut(range.start..end.max(range.start)) {
                let n = mailbox.len().min(bytes.len());
                mailbox[..n].copy_from_slice(&bytes[..n]);
            }
            self.esc
                .set_sync_manager_status(MAILBOX_IN, register::SyncManager::STATUS_MAILBOX_FULL);
        }
    }

    /// The application's cycle: in OP on the last complete outputs buffer
    /// (zeros before the master wrote one); in SAFEOP on the outputs it last
    /// acted on, so that a batch handed over before OP goes out at OP's
    /// first cycle if it is still in the outputs then, and not before.
    fn sync_manager_event(&mut self, now: u64) {
        let length = self.esc.sync_manager(OUTPUTS).range().len();
        self.outputs_buffer.resize(length, 0);
        if self.state == AlState::Op {
            self.acted_on.clone_from(&self.outputs_buffer);
        }
        self.acted_on.resize(length, 0);
        let inputs = self.application.cycle(&self.acted_on, now);
        let range = self.esc.sync_manager(INPUTS).range();
        let end = range.end.min(self.esc.memory.len()).max(range.start);
        if let Some(image) = self.esc.memory.get_mut(range.start..end) {
            let n = inputs.len().min(image.len());
            image[..n].copy_from_slice(&inputs[..n]);
        }
        self.cycles += 1;
    }
}
