//! The implementation under test, as the harness sees it: a process-image side
//! (one exchange per cycle) and a CAN-controller side (received frames in,
//! transmissions out, one at a time, completions back), and the two IUTs the
//! harness has in process: the reference model and the soft device.

use canif_model::config::{Capabilities, FrameFormat, InterfaceConfig, QueueMode, Synchronization};
use canif_model::device::Device;
use canif_model::exchange::ExchangeMode;
use canif_model::filter::{FilterAction, FilterMatch};
use canif_model::frame::{CanId, Frame};
use canif_model::info_data::ControllerStatus;
use canif_model::Nanos;
use canif_softdevice::{CanFrame, FilterRule, Format, Offer, Queue, Settings, SoftDevice};
use std::borrow::BorrowMut;

use crate::error::IutCause;
pub use crate::error::IutError;

pub use crate::error::InvalidFrame;

/// What the next frame of a controller is: a frame, none, or something that
/// is no valid frame (judged as the device's non-conformance).
pub type Transmit = Option<Result<Frame, InvalidFrame>>;

/// What the harness needs from an implementation under test. Every call can
/// fail with an [`IutError`]: the IUT itself broke (exited, hung, broke the
/// protocol), which is an `error` verdict, never a non-conformance.
pub trait Iut {
    /// One CAN interface cycle with this output image at `now`; the new input image.
    fn cycle(&mut self, outputs: &[u8], now: Nanos) -> Result<Vec<u8>, IutError>;
    /// The controller received `frame`, whose last bit ended at `end_of_reception`.
    fn receive(&mut self, frame: &Frame, end_of_reception: Nanos) -> Result<(), IutError>;
    /// The cycle the harness asks for next (`cycle` with these outputs at
    /// `now`), told ahead so that an IUT in another process starts on it
    /// while the harness works out what the model does.
    fn announce_cycle(&mut self, outputs: &[u8], now: Nanos) -> Result<(), IutError> {
        let _ = (outputs, now);
        Ok(())
    }
    /// The next frame the controller starts sending at `now`, if any.
    fn poll_transmit(&mut self, now: Nanos) -> Result<Transmit, IutError>;
    /// When a held frame (Distributed Clocks) becomes due.
    fn poll_timeout(&self) -> Option<Nanos>;
    /// The frame it started is on the bus.
    fn transmit_complete(&mut self) -> Result<(), IutError>;
    /// The controller's status and counters changed.
    fn controller_status(&mut self, status: &ControllerStatus) -> Result<(), IutError>;
    /// The frames the controller would start from `now` on, in order, if the
    /// bus let it and nothing else happened, each with the earliest time it may
    /// start; the frame on the wire, if any, is not among them; at most
    /// `most` of them. Adapter protocols 2 and 3 ask for this once per cycle.
    /// `None`: the IUT cannot tell.
    fn transmit_plan(&self, now: Nanos, most: usize) -> Option<Vec<Planned>> {
        let _ = (now, most);
        None
    }
    /// A device reached through real telegrams (an EtherCAT terminal): what
    /// it offers besides its image. `None` for every other device.
    fn telegrams(&mut self) -> Option<&mut dyn Telegrams> {
        None
    }
    /// What the device itself declares where the documents leave a choice
    /// (the adapter protocol's `configured` answer).
    fn declared(&self) -> crate::declare::choices::Declared {
        crate::declare::choices::Declared::default()
    }
}

/// What a device reached through real telegrams offers besides its image:
/// a capability of the EtherCAT door, asked for with [`Iut::telegrams`].
pub trait Telegrams {
    /// How the played master exchanges the process data (003): LRW, or
    /// LWR then LRD.
    fn exchange_with(&mut self, mode: ExchangeMode);
    /// What the last cycle showed the device doing wrong below the image the
    /// lockstep compares (the inputs an EtherCAT telegram carried): a
    /// well-formed answer that breaks a requirement, judged as a failure.
    fn take_deviation(&mut self) -> Option<Deviation>;
}

/// One frame of a [`Iut::transmit_plan`]: the frame (or what is no frame) and
/// the earliest time it may start.
pub type Planned = (Result<Frame, InvalidFrame>, Nanos);

/// How many frames a plan lists at most: more than a controller's queue holds.
pub(crate) const MOST_PLANNED: usize = 4_096;

/// The plan of a device that can be cloned: a copy of it is let send
/// everything, as the real one would if the bus took each frame at once.
fn plan_by_rehearsal<D: Clone>(
    device: &D,
    now: Nanos,
    most: usize,
    mut poll: impl FnMut(&mut D, Nanos) -> Option<Result<Frame, InvalidFrame>>,
    mut done: impl FnMut(&mut D),
    due: impl Fn(&D) -> Option<Nanos>,
) -> Vec<Planned> {
    let mut rehearsal = device.clone();
    done(&mut rehearsal); // the frame on the wire, if any, is not planned
    let (mut plan, mut t) = (Vec::new(), now);
    while plan.len() < most.min(MOST_PLANNED) {
        match poll(&mut rehearsal, t) {
            Some(frame) => {
                plan.push((frame, t));
                done(&mut rehearsal);
            }
            None => match due(&rehearsal).filter(|due| *due > t) {
                Some(due) => t = due,
                None => break,
            },
        }
    }
    plan
}

/// Why no IUT could be built for a configuration.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum BuildError {
    /// The IUT refuses the configuration: a legitimate answer, judged by the refusal grid.
    Refused(String),
    /// The IUT could not be started or broke the protocol.
    Failed(IutError),
}

impl std::fmt::Display for BuildError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            BuildError::Refused(reason) => write!(f, "refused: {reason}"),
            BuildError::Failed(error) => error.fmt(f),
        }
    }
}

/// The reference model as an IUT: it conforms by definition; useful to check the harness.
pub struct ModelIut(pub Device);

impl Iut for ModelIut {
    fn cycle(&mut self, outputs: &[u8], now: Nanos) -> Result<Vec<u8>, IutError> {
        self.0
            .cycle(outputs, now)
            .map(<[u8]>::to_vec)
            .map_err(|e| IutError::new(IutCause::Impossible, e.to_string()))
    }
    fn receive(&mut self, frame: &Frame, end_of_reception: Nanos) -> Result<(), IutError> {
        self.0.handle_received(*frame, end_of_reception);
        Ok(())
    }
    fn poll_transmit(&mut self, now: Nanos) -> Result<Transmit, IutError> {
        Ok(self.0.poll_transmit(now).map(Ok))
    }
    fn poll_timeout(&self) -> Option<Nanos> {
        self.0.poll_timeout()
    }
    fn transmit_complete(&mut self) -> Result<(), IutError> {
        self.0.handle_transmit_complete();
        Ok(())
    }
    fn controller_status(&mut self, status: &ControllerStatus) -> Result<(), IutError> {
        self.0.handle_controller_status(*status);
        Ok(())
    }
    fn transmit_plan(&self, now: Nanos, most: usize) -> Option<Vec<Planned>> {
        Some(plan_by_rehearsal(
            &self.0,
            now,
            most,
            |d, t| d.poll_transmit(t).map(Ok),
            Device::handle_transmit_complete,
            Device::poll_timeout,
        ))
    }
}

/// A device's answer that is well formed and breaks a requirement, seen
/// where the lockstep does not look (see [`Telegrams::take_deviation`]).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Deviation {
    /// What the device did; the device side blames it on its requirements.
    pub kind: Deviated,
    pub what: String,
    pub expected: String,
    pub actual: String,
}

/// What a door saw a device do where the lockstep does not look.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Deviated {
    /// With Distributed Clocks the cycle ran on a telegram, not on SYNC0.
    Sync0StartsTheCycle,
    /// What an LRW read was not the previous SyncManager 2 event's inputs.
    Confirmation,
}

/// The soft device behind the IUT interface; frames are translated here, so the
/// soft device itself never sees a model type. It owns the device, or borrows
/// it (the device inside an emulated EtherCAT terminal, on a SocketCAN bus).
pub struct SoftDeviceIut<D: BorrowMut<SoftDevice> = SoftDevice>(pub D);

impl<D: BorrowMut<SoftDevice>> Iut for SoftDeviceIut<D> {
    fn cycle(&mut self, outputs: &[u8], now: Nanos) -> Result<Vec<u8>, IutError> {
        self.0
            .borrow_mut()
            .sync_manager_event(outputs, now)
            .map(<[u8]>::to_vec)
            .map_err(|e| IutError::new(IutCause::Impossible, e.to_string()))
    }
    fn receive(&mut self, frame: &Frame, end_of_reception: Nanos) -> Result<(), IutError> {
        soft_controller::receive(self.0.borrow_mut(), frame, end_of_reception);
        Ok(())
    }
    fn poll_transmit(&mut self, now: Nanos) -> Result<Transmit, IutError> {
        Ok(soft_controller::poll_transmit(self.0.borrow_mut(), now))
    }
    fn poll_timeout(&self) -> Option<Nanos> {
        self.0.borrow().next_release()
    }
    fn transmit_complete(&mut self) -> Result<(), IutError> {
        self.0.borrow_mut().tx_done_interrupt();
        Ok(())
    }
    fn controller_status(&mut self, status: &ControllerStatus) -> Result<(), IutError> {
        soft_controller::status(self.0.borrow_mut(), status);
        Ok(())
    }
    fn transmit_plan(&self, now: Nanos, most: usize) -> Option<Vec<Planned>> {
        Some(soft_controller::plan(self.0.borrow(), now, most))
    }
}

/// The soft device's CAN controller, in model terms: shared by the soft device
/// in process and the soft device behind an emulated EtherCAT terminal.
pub(crate) mod soft_controller {
    use super::*;

    pub(crate) fn receive(device: &mut SoftDevice, frame: &Frame, end_of_reception: Nanos) {
        device.rx_interrupt(to_soft(frame), end_of_reception);
    }

    pub(crate) fn poll_transmit(device: &mut SoftDevice, now: Nanos) -> Transmit {
        device.controller_idle(now).map(|f| from_soft(&f))
    }

    pub(crate) fn status(device: &mut SoftDevice, status: &ControllerStatus) {
        use canif_softdevice::field::info;
        device.set_controller_word(info::STATUS, status.status_word());
        device.set_controller_word(info::TRANSCEIVER_DELAY, status.transceiver_delay);
        for (index, value) in [
            (info::ACK_ERRORS, status.ack_errors),
            (info::BIT_ERRORS, status.bit_errors),
            (info::CRC_ERRORS, status.crc_errors),
            (info::FORM_ERRORS, status.form_errors),
            (info::CORE_RUNNING, u32::from(status.core_running)),
            (info::STUFF_ERRORS, status.stuff_errors),
            (info::RECEIVE_ERROR_COUNTER, status.receive_error_counter),
            (info::TRANSMIT_ERROR_COUNTER, status.transmit_error_counter),
        ] {
            device.set_controller_word(index, value);
        }
    }

    /// What a rehearsal on a copy would find (the queue sent in order, each
    /// frame not before its release), read off the queue: copying the whole
    /// device every cycle was a fifth of a protocol 3 answer's work.
    pub(crate) fn plan(device: &SoftDevice, now: Nanos, most: usize) -> Vec<Planned> {
        let mut start = now;
        device
            .waiting()
            .take(most.min(MOST_PLANNED))
            .map(|(frame, release)| {
                start = start.max(release);
                (from_soft(frame), start)
            })
            .collect()
    }

    /// The rehearsal [`plan`] stands for, for the test that they agree.
    #[cfg(test)]
    pub(crate) fn rehearsed(device: &SoftDevice, now: Nanos, most: usize) -> Vec<Planned> {
        plan_by_rehearsal(
            device,
            now,
            most,
            |d, t| d.controller_idle(t).map(|f| from_soft(&f)),
            SoftDevice::tx_done_interrupt,
            SoftDevice::next_release,
        )
    }
}

fn to_soft(frame: &Frame) -> CanFrame {
    let mut soft = CanFrame {
        id: frame.id.raw(),
        extended: frame.id.is_extended(),
        len: usize::from(frame.len()),
        ..CanFrame::default()
    };
    match frame.kind {
        canif_model::frame::FrameKind::Classic { rtr } => soft.remote = rtr,
        canif_model::frame::FrameKind::Fd { brs, esi } => {
            soft.fd = true;
            soft.brs = brs;
            soft.esi = esi;
        }
    }
    soft.data[..frame.data().len()].copy_from_slice(frame.data());
    soft
}

pub(crate) fn from_soft(soft: &CanFrame) -> Result<Frame, InvalidFrame> {
    let id = if soft.extended {
        CanId::extended(soft.id)
    } else {
        CanId::standard(soft.id)
    };
    let id = id.ok_or(InvalidFrame::Identifier {
        id: soft.id,
        extended: soft.extended,
    })?;
    // What no controller sends is judged as such, as the adapter
    // protocol's frames are (`WireFrame::to_frame`).
    InvalidFrame::of_fd_bits(soft.fd, soft.remote, soft.brs, soft.esi)?;
    let frame = if soft.fd {
        Frame::fd(id, soft.brs, soft.esi, &soft.data[..soft.len.min(64)])
    } else if soft.remote {
        Frame::remote(id, soft.len as u8)
    } else {
        Frame::classic(id, &soft.data[..soft.len.min(64)])
    };
    frame.map_err(InvalidFrame::Parts)
}

/// The soft device's settings for a model configuration and profile.
pub fn soft_settings(caps: &Capabilities, config: &InterfaceConfig) -> Settings {
    Settings {
        offer: Offer {
            std11: caps.base11,
            ext29: caps.ext29,
            fd: caps.fd,
            fast: caps.fast_queue,
            optimized: caps.optimized_queue,
            transaction_number: caps.transaction_number,
            transaction_number_29bit_only: caps.transaction_number_only_ext29,
            time_stamp: caps.time_stamp,
            filters: caps.filters,
            info_data: caps.info_data,
            distributed_clocks: caps.distributed_clocks,
            max_slots: caps.max_slots,
        },
        format: match config.format {
            FrameFormat::Base11 => Format::Std11,
            FrameFormat::Extended29 => Format::Ext29,
            FrameFormat::Fd => Format::Fd,
        },
        queue: match config.queue {
            QueueMode::Standard => Queue::Buffered,
            QueueMode::Optimized => Queue::Optimized,
            QueueMode::Fast => Queue::Fast,
        },
        transaction_number: config.transaction_number,
        time_stamp: config.time_stamp,
        tx_slots: config.tx_slots,
        rx_slots: config.rx_slots,
        filters: config
            .filters
            .iter()
            .map(|row| {
                let accept = row.action == FilterAction::Accept;
                match row.matches {
                    FilterMatch::Range { from, to } => FilterRule::Range {
                        accept,
                        low: from,
                        high: to,
                    },
                    FilterMatch::CodeMask { code, mask } => FilterRule::Mask { accept, code, mask },
                }
            })
            .collect(),
        dc_sync1_shift: match config.synchronization {
            Synchronization::Sm2 => None,
            Synchronization::DistributedClocks { sync1_shift } => Some(sync1_shift),
        },
        rx_fifo_depth: caps.rx_queue_depth,
        tx_fifo_depth: caps.tx_queue_depth,
        nominal_timing: config.nominal_timing.to_word(),
        data_timing: config.data_timing.to_word(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use canif_model::client::PlcClient;
    use canif_model::image::{ImageLayout, MessageRepr};

    /// The soft device's plan, read off its queue, is the plan a rehearsal on
    /// a copy finds: with Distributed Clocks holding each batch's first frame
    /// until SYNC1, and with a frame on the wire.
    #[test]
    fn the_soft_devices_plan_is_what_a_rehearsal_finds() {
        let mut config = InterfaceConfig::new(FrameFormat::Base11, 4);
        config.queue = QueueMode::Fast;
        config.synchronization = Synchronization::DistributedClocks {
            sync1_shift: 300_000,
        };
        let caps = Capabilities::everything();
        let mut device = SoftDevice::new(soft_settings(&caps, &config)).unwrap();
        let layout = ImageLayout::new(&config, caps.info_data);
        let mut client = PlcClient::new(layout);
        let (mut now, mut inputs) = (0, vec![0; layout.input_size()]);
        for batch in 0..3u8 {
            for n in 0..3u8 {
                let frame = Frame::classic(CanId::Standard(u16::from(batch * 8 + n)), &[n]);
                let message = MessageRepr {
                    transaction_number: 0,
                    frame: frame.unwrap(),
                    time_stamp: 0,
                };
                client.send(message).unwrap();
            }
            let outputs = client.task(&inputs).unwrap().to_vec();
            inputs = device.sync_manager_event(&outputs, now).unwrap().to_vec();
            now += 100_000;
        }
        let plans = |device: &SoftDevice, now| {
            (
                soft_controller::plan(device, now, 5),
                soft_controller::rehearsed(device, now, 5),
            )
        };
        let (read, rehearsed) = plans(&device, now);
        assert_eq!(read.len(), 5, "{read:?}");
        assert_eq!(read, rehearsed);
        // The first batch's first frame waits for SYNC1; the second batch's too.
        assert_eq!(read[0].1, 300_000);
        assert_eq!(read[3].1, 400_000);
        device.controller_idle(now + 300_000).unwrap();
        let (read, rehearsed) = plans(&device, now + 300_000);
        assert_eq!(read, rehearsed);
        assert_eq!(read.len(), 5);
    }
}
