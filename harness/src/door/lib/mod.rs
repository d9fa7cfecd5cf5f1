//! A device in a shared library, through canif's C ABI (include/canif.h,
//! crate `canif-cabi`): the vendor's own CAN interface code, in process.

use std::path::Path;

use canif_cabi::{CCapabilities, CFilter, CFrame, CStatus, Config, Device, Library};
use canif_model::config::{Capabilities, FrameFormat, InterfaceConfig, QueueMode, Synchronization};
use canif_model::filter::{FilterAction, FilterMatch};
use canif_model::frame::{CanId, Frame};
use canif_model::image::ImageLayout;
use canif_model::info_data::ControllerStatus;
use canif_model::Nanos;

use crate::declare::choices::Declared;
use crate::declare::Declaration;
use canif_cabi::guard::GuardedImage;

use crate::door::iut::{BuildError, InvalidFrame, Iut, Planned, Transmit};
use crate::error::{IutCause, IutError};

pub(crate) mod client;
mod transport;

pub use transport::{LibDoor, LibHost};

/// A library's device behind the [`Iut`] trait.
pub(crate) struct LibIut {
    device: Device,
    next: Option<Nanos>,
    /// What it declared through the optional `canif_declares`.
    declared: Declared,
    /// In a host process of its own: the output and input images behind
    /// guard pages (see [`canif_cabi::guard`]).
    guarded: Option<(GuardedImage, GuardedImage)>,
}

impl LibIut {
    /// The same, its images behind guard pages.
    pub(crate) fn guarded(mut self, output_size: usize) -> Result<Self, BuildError> {
        let image = |len| {
            GuardedImage::new(len).ok_or_else(|| {
                BuildError::Failed(IutError::new(
                    IutCause::NotStarted,
                    "cannot map a guarded image",
                ))
            })
        };
        let (outputs, inputs) = (image(output_size)?, image(self.device.input_size())?);
        canif_cabi::guard::watch(&inputs, &outputs);
        self.guarded = Some((outputs, inputs));
        Ok(self)
    }
}

/// Loads the library and makes its device for a configuration.
pub(crate) fn build(
    path: &Path,
    caps: &Capabilities,
    config: &InterfaceConfig,
) -> Result<LibIut, BuildError> {
    create(&open(path)?, caps, config)
}

/// Loads the library, checking its ABI version and functions.
pub(crate) fn open(path: &Path) -> Result<Library, BuildError> {
    Library::open(path).map_err(|e| BuildError::Failed(IutError::new(IutCause::NotStarted, e)))
}

/// The loaded library's device for a configuration.
pub(crate) fn create(
    library: &Library,
    caps: &Capabilities,
    config: &InterfaceConfig,
) -> Result<LibIut, BuildError> {
    let c_config = c_config(caps, config);
    let c_caps = CCapabilities {
        base11: u8::from(caps.base11),
        ext29: u8::from(caps.ext29),
        fd: u8::from(caps.fd),
        fast_queue: u8::from(caps.fast_queue),
        optimized_queue: u8::from(caps.optimized_queue),
        transaction_number: u8::from(caps.transaction_number),
        transaction_number_only_ext29: u8::from(caps.transaction_number_only_ext29),
        time_stamp: u8::from(caps.time_stamp),
        filters: u8::from(caps.filters),
        info_data: u8::from(caps.info_data),
        distributed_clocks: u8::from(caps.distributed_clocks),
        max_slots: caps.max_slots,
        rx_queue_depth: caps.rx_queue_depth as u32,
        tx_queue_depth: caps.tx_queue_depth as u32,
    };
    let device = library
        .create(&c_config, &c_caps)
        .map_err(BuildError::Refused)?;
    let mut declared = Declared::default();
    for line in device.declares() {
        declared.declare(&line).map_err(|error| {
            BuildError::Failed(IutError::new(
                IutCause::Protocol,
                format!("canif_declares said `{line}`: {error}"),
            ))
        })?;
    }
    Ok(LibIut {
        device,
        next: None,
        declared,
        guarded: None,
    })
}

/// The configuration as the C ABI carries it (`canif_config`).
pub(crate) fn c_config(caps: &Capabilities, config: &InterfaceConfig) -> Config {
    let layout = ImageLayout::new(config, caps.info_data);
    Config {
        format: match config.format {
            FrameFormat::Base11 => 0,
            FrameFormat::Extended29 => 1,
            FrameFormat::Fd => 2,
        },
        queue: match config.queue {
            QueueMode::Standard => 0,
            QueueMode::Optimized => 1,
            QueueMode::Fast => 2,
        },
        transaction_number: u8::from(config.transaction_number),
        time_stamp: u8::from(config.time_stamp),
        tx_slots: config.tx_slots,
        rx_slots: config.rx_slots,
        distributed_clocks: u8::from(matches!(
            config.synchronization,
            Synchronization::DistributedClocks { .. }
        )),
        sync1_shift_ns: match config.synchronization {
            Synchronization::DistributedClocks { sync1_shift } => sync1_shift,
            Synchronization::Sm2 => 0,
        },
        nominal_timing: config.nominal_timing.to_word(),
        data_timing: config.data_timing.to_word(),
        output_size: layout.output_size() as u32,
        input_size: layout.input_size() as u32,
        filters: config
            .filters
            .iter()
            .map(|row| {
                let accept = u8::from(row.action == FilterAction::Accept);
                match row.matches {
                    FilterMatch::Range { from, to } => CFilter {
                        accept,
                        is_range: 1,
                        from_or_code: from,
                        to_or_mask: to,
                    },
                    FilterMatch::CodeMask { code, mask } => CFilter {
                        accept,
                        is_range: 0,
                        from_or_code: code,
                        to_or_mask: mask,
                    },
                }
            })
            .collect(),
    }
}

pub(crate) fn to_c(frame: &Frame) -> CFrame {
    let mut c = CFrame {
        id: frame.id.raw(),
        extended: u8::from(frame.id.is_extended()),
        rtr: u8::from(frame.is_remote()),
        len: frame.len(),
        ..CFrame::default()
    };
    if let canif_model::frame::FrameKind::Fd { brs, esi } = frame.kind {
        (c.fd, c.brs, c.esi) = (1, u8::from(brs), u8::from(esi));
    }
    c.data[..frame.data().len()].copy_from_slice(frame.data());
    c
}

pub(crate) fn from_c(c: &CFrame) -> Result<Frame, InvalidFrame> {
    let flag = |v: u8| v != 0;
    let id = if flag(c.extended) {
        CanId::extended(c.id)
    } else {
        CanId::standard(c.id)
    }
    .ok_or(InvalidFrame::Identifier {
        id: c.id,
        extended: c.extended != 0,
    })?;
    let len = usize::from(c.len).min(64);
    let frame = if flag(c.fd) {
        Frame::fd(id, flag(c.brs), flag(c.esi), &c.data[..len])
    } else if flag(c.rtr) {
        Frame::remote(id, c.len)
    } else {
        Frame::classic(id, &c.data[..len])
    };
    frame.map_err(InvalidFrame::Parts)
}

impl Iut for LibIut {
    fn declared(&self) -> Declared {
        self.declared
    }

    fn cycle(&mut self, outputs: &[u8], now: Nanos) -> Result<Vec<u8>, IutError> {
        let reported = |e| IutError::new(IutCause::Reported, e);
        let Some((guarded_outputs, inputs)) = self.guarded.as_mut() else {
            return self.device.cycle(now, outputs).map_err(reported);
        };
        if guarded_outputs.as_slice().len() != outputs.len() {
            return Err(IutError::new(
                IutCause::HarnessBug,
                "an output image of another size than configured",
            ));
        }
        guarded_outputs.as_mut_slice().copy_from_slice(outputs);
        self.device
            .cycle_into(now, guarded_outputs.as_slice(), inputs.as_mut_slice())
            .map_err(reported)?;
        Ok(inputs.as_slice().to_vec())
    }
    fn receive(&mut self, frame: &Frame, end_of_reception: Nanos) -> Result<(), IutError> {
        self.device.receive(&to_c(frame), end_of_reception);
        Ok(())
    }
    fn poll_transmit(&mut self, now: Nanos) -> Result<Transmit, IutError> {
        let (frame, next) = self.device.poll_transmit(now);
        self.next = next;
        Ok(frame.map(|c| from_c(&c)))
    }
    fn poll_timeout(&self) -> Option<Nanos> {
        self.next
    }
    /// A library that exports `canif_transmit_plan`; `None` for one that
    /// does not, or that answered with a count no plan has.
    fn transmit_plan(&self, now: Nanos, most: usize) -> Option<Vec<Planned>> {
        let planned = self
            .device
            .transmit_plan(now, most.min(crate::door::iut::MOST_PLANNED))?
            .ok()?;
        Some(
            planned
                .iter()
                .map(|p| (from_c(&p.frame), p.not_before_ns))
                .collect(),
        )
    }
    fn transmit_complete(&mut self) -> Result<(), IutError> {
        self.device.transmit_complete();
        Ok(())
    }
    fn controller_status(&mut self, s: &ControllerStatus) -> Result<(), IutError> {
        self.device.controller_status(&CStatus {
            bus_off: u8::from(s.bus_off),
            error_passive: u8::from(s.error_passive),
            node_active: u8::from(s.node_active),
            warning_limit: u8::from(s.warning_limit),
            overload: u8::from(s.overload),
            bus_idle: u8::from(s.bus_idle),
            core_running: u8::from(s.core_running),
            transceiver_delay: s.transceiver_delay,
            ack_errors: s.ack_errors,
            bit_errors: s.bit_errors,
            crc_errors: s.crc_errors,
            form_errors: s.form_errors,
            stuff_errors: s.stuff_errors,
            receive_error_counter: s.receive_error_counter,
            transmit_error_counter: s.transmit_error_counter,
        });
        Ok(())
    }
}
