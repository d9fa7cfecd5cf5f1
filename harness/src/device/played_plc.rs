//! The PLC side of a cycle, as the harness plays it when the device is under
//! test: the reference client of 001 §6 (ruling R5), the process-data exchange
//! that delays what it sees (003: LRW two cycles, separate input update one),
//! and the tracker of how long a TxCounter increment takes to be confirmed.
//! The lockstep, the Gherkin world and the CANopen quick start all drive the
//! PLC through this one type.

use canif_model::client::PlcClient;
use canif_model::cob_id::CobId32;
use canif_model::exchange::{ExchangeMode, ProcessDataExchange};
use canif_model::image::{
    ImageLayout, InputImage, LengthField, MessageError, MessageRepr, MessageView, OutputImage,
    SizeError,
};

/// What the stimulus asks of the PLC in one task, beyond the sample code.
#[derive(Debug, Clone, Copy, Default)]
pub struct TaskStimulus<'a> {
    /// FD Tx messages whose dataLength the PLC declares other than the frame
    /// has (by transaction number): the bytes past it become junk.
    pub declared_lengths: &'a [(u16, u8)],
    /// The PLC writes this TxCounter instead of the sample code's (G1).
    pub set_tx_counter: Option<u16>,
    /// What the PLC's program writes into the image beyond the sample code:
    /// unusual or invalid input the device must cope with.
    pub edits: &'a [OutputEdit],
    /// The PLC writes this whole output image instead of the sample code's
    /// (random images: the device's robustness, G3).
    pub raw_outputs: Option<&'a [u8]>,
}

/// A field of the output image the PLC's program writes itself, after the
/// sample code, through the model's views.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OutputEdit {
    /// NoOfTxMessages (0 is a batch of nothing, HS-TX-009; more than the
    /// slots is out of range, G3).
    NoOfTxMessages(u16),
    /// The length field of a Tx slot, whatever it holds (classic above 8: G3).
    Length { slot: usize, raw: u16 },
    /// The 32-bit COB ID of a Tx slot, reserved bits and all (LAY-29-006).
    CobId { slot: usize, raw: u32 },
    /// The FD flag byte of a Tx slot (BRS or ESI without EDL: FD-BIT-001).
    Flags { slot: usize, raw: u8 },
}

impl OutputEdit {
    fn apply(self, outputs: &mut OutputImage<&mut [u8]>) {
        match self {
            OutputEdit::NoOfTxMessages(count) => outputs.set_no_of_tx_messages(count),
            OutputEdit::Length { slot, raw } => edit_slot(outputs, slot, |v| v.set_raw_length(raw)),
            OutputEdit::CobId { slot, raw } => {
                edit_slot(outputs, slot, |v| v.set_cob_id32(CobId32(raw)))
            }
            OutputEdit::Flags { slot, raw } => edit_slot(outputs, slot, |v| v.set_flags(raw)),
        }
    }
}

fn edit_slot(
    outputs: &mut OutputImage<&mut [u8]>,
    slot: usize,
    edit: impl FnOnce(&mut MessageView<&mut [u8]>),
) {
    if let Some(mut view) = outputs.tx_message_mut(slot) {
        edit(&mut view);
    }
}

/// What one PLC task saw.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct TaskReport {
    /// An increment written earlier is confirmed now: after this many cycles.
    pub confirmed_after: Option<u64>,
}

/// The PLC: client, exchange and confirmation tracking for one interface.
#[derive(Debug, Clone)]
pub struct PlcSide {
    layout: ImageLayout,
    client: PlcClient,
    exchange: ProcessDataExchange,
    /// The cycle an unconfirmed TxCounter was written in, and its value.
    increment: Option<(u64, u16)>,
}

impl PlcSide {
    pub fn new(layout: ImageLayout, mode: ExchangeMode) -> Self {
        PlcSide {
            layout,
            client: PlcClient::new(layout),
            exchange: ProcessDataExchange::new(mode, &vec![0; layout.input_size()]),
            increment: None,
        }
    }

    pub fn layout(&self) -> ImageLayout {
        self.layout
    }

    /// Queues a message in the PLC program.
    pub fn send(&mut self, message: MessageRepr) -> Result<(), MessageError> {
        self.client.send(message)
    }

    /// The output image as the PLC last wrote it.
    pub fn outputs(&self) -> &[u8] {
        self.client.outputs()
    }

    /// The input image the PLC sees in this cycle.
    pub fn inputs(&self) -> &[u8] {
        self.exchange.plc_inputs()
    }

    /// Messages the PLC has read since the last call.
    pub fn take_received(&mut self) -> Vec<MessageRepr> {
        self.client.take_received()
    }

    /// The PLC task of cycle `cycle`: reads the inputs the exchange delivers,
    /// writes the outputs.
    pub fn task(
        &mut self,
        cycle: u64,
        stimulus: TaskStimulus<'_>,
    ) -> Result<TaskReport, SizeError> {
        let seen = InputImage::new_checked(self.exchange.plc_inputs(), self.layout)?.tx_counter();
        let mut report = TaskReport::default();
        if let Some((since, counter)) = self.increment {
            if seen == counter {
                report.confirmed_after = Some(cycle - since);
                self.increment = None;
            }
        }
        self.client.task(self.exchange.plc_inputs())?;
        let layout = self.layout;
        if let Some(raw) = stimulus.raw_outputs {
            let outputs = self.client.outputs_mut();
            let n = outputs.len().min(raw.len());
            outputs[..n].copy_from_slice(&raw[..n]);
        }
        let mut outputs = OutputImage::new_checked(self.client.outputs_mut(), layout)?;
        for edit in stimulus.edits {
            edit.apply(&mut outputs);
        }
        if !stimulus.declared_lengths.is_empty() {
            declare_lengths(&mut outputs, stimulus.declared_lengths);
        }
        if let Some(counter) = stimulus.set_tx_counter {
            outputs.set_tx_counter(counter);
        }
        let written = outputs.tx_counter();
        if self.increment.is_none() && written != seen {
            self.increment = Some((cycle, written));
        }
        Ok(report)
    }

    /// The device's cycle ran on the outputs and gave these inputs.
    pub fn device_cycle_done(&mut self, inputs: &[u8]) {
        self.exchange.device_cycle_done(inputs);
    }
}

/// Rewrites the dataLength of FD Tx messages to the length the PLC means (not a
/// valid size) and fills the bytes past it with junk the device must not send.
fn declare_lengths(outputs: &mut OutputImage<&mut [u8]>, lengths: &[(u16, u8)]) {
    let message = outputs.layout().tx_message;
    if message.transaction_number.is_none() || !matches!(message.length, LengthField::Byte(_)) {
        return;
    }
    for slot in 0..outputs.layout().tx_slots {
        let Some(mut view) = outputs.tx_message_mut(slot) else {
            continue;
        };
        let number = view.transaction_number();
        let Some(&(_, declared)) = lengths.iter().find(|(n, _)| *n == number) else {
            continue;
        };
        let current = view.raw_length() as u8;
        if current == declared {
            continue;
        }
        view.set_raw_length(u16::from(declared));
        let junk = usize::from(declared)..usize::from(current.max(declared));
        view.data_field_mut()[junk].fill(0xEE);
    }
}
