//! The soft client (`--iut softclient`): a PLC-side client written against
//! the image views independently of the reference client, in the ways of
//! working a client may declare (`ClientShape`), and with its deliberate
//! faults (`ClientFault`), each breaking the client requirements the
//! way code in the field does (000 §6's samples as printed, ruling R5; the
//! variants the PLC side's issue names), so the suite proves it notices. A
//! client here is written against the image views independently of the
//! reference client; with no fault it must conform too.

use crate::declare::Declaration;
use std::collections::VecDeque;
use std::fmt;

use canif_model::config::QueueMode;
use canif_model::frame::{CanId, Frame};
use canif_model::handshake;
use canif_model::image::{ImageLayout, InputImage, MessageRepr, MessageView, OutputImage};

use super::{Client, IutError, TaskAnswer, TaskIo};

/// One deliberate defect of a client.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ClientFault {
    SendSample000,
    DecodeOverNoOfTxMessages,
    OwnRxCounter,
    TxCounterPlusOne,
    WritesBeforeAcknowledge,
    ReadsAllSlots,
    IgnoresWrap,
    OneBasedSlots,
    NoBoundOnNoOfRxMessages,
    AcknowledgesAfterFirstMessage,
    TransactionNumberZero,
    DropsRtr,
    FastQueueRereads,
    IgnoresExtendedFlag,
    NoOfTxMessagesIsTheSlotCount,
    RestartReadsAllSlots,
    IgnoresRxCounterZero,
    SentOnAcknowledge,
    AcknowledgesWithTxCounter,
    TxBatchBoundedByRxSlots,
}

impl ClientFault {
    pub const ALL: [ClientFault; 20] = [
        ClientFault::SendSample000,
        ClientFault::DecodeOverNoOfTxMessages,
        ClientFault::OwnRxCounter,
        ClientFault::TxCounterPlusOne,
        ClientFault::WritesBeforeAcknowledge,
        ClientFault::ReadsAllSlots,
        ClientFault::IgnoresWrap,
        ClientFault::OneBasedSlots,
        ClientFault::NoBoundOnNoOfRxMessages,
        ClientFault::AcknowledgesAfterFirstMessage,
        ClientFault::TransactionNumberZero,
        ClientFault::DropsRtr,
        ClientFault::FastQueueRereads,
        ClientFault::IgnoresExtendedFlag,
        ClientFault::NoOfTxMessagesIsTheSlotCount,
        ClientFault::RestartReadsAllSlots,
        ClientFault::IgnoresRxCounterZero,
        ClientFault::SentOnAcknowledge,
        ClientFault::AcknowledgesWithTxCounter,
        ClientFault::TxBatchBoundedByRxSlots,
    ];

    pub fn name(self) -> &'static str {
        match self {
            ClientFault::SendSample000 => "send-sample-000",
            ClientFault::DecodeOverNoOfTxMessages => "decode-over-no-of-tx-messages",
            ClientFault::OwnRxCounter => "own-rx-counter",
            ClientFault::TxCounterPlusOne => "tx-counter-plus-one",
            ClientFault::WritesBeforeAcknowledge => "writes-before-acknowledge",
            ClientFault::ReadsAllSlots => "reads-all-slots",
            ClientFault::IgnoresWrap => "ignores-wrap",
            ClientFault::OneBasedSlots => "one-based-slots",
            ClientFault::NoBoundOnNoOfRxMessages => "no-bound-on-no-of-rx-messages",
            ClientFault::AcknowledgesAfterFirstMessage => "acknowledges-after-first-message",
            ClientFault::TransactionNumberZero => "transaction-number-zero",
            ClientFault::DropsRtr => "drops-rtr",
            ClientFault::FastQueueRereads => "fast-queue-rereads",
            ClientFault::IgnoresExtendedFlag => "ignores-extended-flag",
            ClientFault::NoOfTxMessagesIsTheSlotCount => "no-of-tx-messages-is-the-slot-count",
            ClientFault::RestartReadsAllSlots => "restart-reads-all-slots",
            ClientFault::IgnoresRxCounterZero => "ignores-rx-counter-zero",
            ClientFault::SentOnAcknowledge => "sent-on-acknowledge",
            ClientFault::AcknowledgesWithTxCounter => "acknowledges-with-tx-counter",
            ClientFault::TxBatchBoundedByRxSlots => "tx-batch-bounded-by-rx-slots",
        }
    }

    pub fn description(self) -> &'static str {
        match self {
            ClientFault::SendSample000 => {
                "000 §6's send sample as printed: loops 0 to NumberOfMessagesToSend, one slot too many"
            }
            ClientFault::DecodeOverNoOfTxMessages => {
                "000 §6's 11-bit decode sample as printed: reads NoOfTxMessages messages, not NoOfRxMessages"
            }
            ClientFault::OwnRxCounter => {
                "acknowledges Rx by incrementing a counter of its own instead of copying Inputs.RxCounter"
            }
            ClientFault::TxCounterPlusOne => {
                "Outputs.TxCounter := Outputs.TxCounter + 1 (000 §6) with Outputs the buffer the master hands it, not resynchronised from Inputs.TxCounter"
            }
            ClientFault::WritesBeforeAcknowledge => {
                "writes a new batch whenever it has messages, without waiting for the acknowledge"
            }
            ClientFault::ReadsAllSlots => "reads every Rx slot instead of NoOfRxMessages",
            ClientFault::IgnoresWrap => {
                "compares the counters with > and increments without the wrap at 0xFFFF"
            }
            ClientFault::OneBasedSlots => "numbers the Tx and Rx slots from 1",
            ClientFault::NoBoundOnNoOfRxMessages => {
                "reads NoOfRxMessages messages even when there are fewer slots"
            }
            ClientFault::AcknowledgesAfterFirstMessage => {
                "acknowledges after reading only the first message of a batch"
            }
            ClientFault::TransactionNumberZero => "writes transaction number 0 into every Tx message",
            ClientFault::DropsRtr => "writes remote frames as data frames (the RTR bit lost)",
            ClientFault::FastQueueRereads => {
                "with the Fast CAN Queue never writes Outputs.RxCounter, so it reads the same batch again"
            }
            ClientFault::IgnoresExtendedFlag => {
                "decodes Rx messages without the 29-bit flag (every identifier as 11 bits)"
            }
            ClientFault::NoOfTxMessagesIsTheSlotCount => {
                "writes NoOfTxMessages = the Tx slots, however many messages it wrote"
            }
            ClientFault::RestartReadsAllSlots => {
                "after a PLC restart reads every Rx slot once, to be sure nothing is missed"
            }
            ClientFault::IgnoresRxCounterZero => {
                "takes Inputs.RxCounter = 0 for a device with nothing yet, so it never acknowledges a restarted device"
            }
            ClientFault::SentOnAcknowledge => {
                "tells its application a batch was sent once Inputs.TxCounter acknowledges it, not once Inputs.TransactionNumber names it"
            }
            ClientFault::AcknowledgesWithTxCounter => {
                "acknowledges Rx by copying Inputs.TxCounter into Outputs.RxCounter: the wrong counter copied"
            }
            ClientFault::TxBatchBoundedByRxSlots => {
                "bounds its Tx batch by the Rx slot count, as if the terminal had one count for both"
            }
        }
    }

    pub fn from_name(name: &str) -> Option<ClientFault> {
        ClientFault::ALL.into_iter().find(|f| f.name() == name)
    }
}

impl fmt::Display for ClientFault {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A way of working the documents allow a client only where it declares it
/// (issue 27): the soft client takes one and declares it, or, to prove the
/// declaration is what makes it pass, does not.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ClientShape {
    /// Sends only: never reads the Rx slots nor acknowledges.
    TxOnly,
    /// Receives only: refuses every request to send.
    RxOnly,
    /// Written for 10 slots each way, whatever the image has.
    TenSlots,
    /// Writes each batch ordered by identifier: one stream per identifier.
    Streams,
    /// Fills each frame with the next bytes of its identifier: a byte stream.
    ByteStream,
    /// After a restart, acknowledges the batch it finds without reading it (P3).
    DropsRestartBatch,
    /// Serves 11-bit interfaces only: it cannot start on another.
    Only11Bit,
}

impl ClientShape {
    pub const ALL: [ClientShape; 7] = [
        ClientShape::TxOnly,
        ClientShape::RxOnly,
        ClientShape::TenSlots,
        ClientShape::Streams,
        ClientShape::ByteStream,
        ClientShape::DropsRestartBatch,
        ClientShape::Only11Bit,
    ];

    pub fn name(self) -> &'static str {
        match self {
            ClientShape::TxOnly => "tx-only",
            ClientShape::RxOnly => "rx-only",
            ClientShape::TenSlots => "ten-slots",
            ClientShape::Streams => "streams",
            ClientShape::ByteStream => "byte-stream",
            ClientShape::DropsRestartBatch => "drops-restart-batch",
            ClientShape::Only11Bit => "only-11-bit",
        }
    }

    /// The declaration that makes this shape conform.
    pub fn declares(self) -> &'static str {
        match self {
            ClientShape::TxOnly => "direction=tx",
            ClientShape::RxOnly => "direction=rx",
            ClientShape::TenSlots => "slots=10",
            ClientShape::Streams => "application=streams",
            ClientShape::ByteStream => "application=byte-stream",
            ClientShape::DropsRestartBatch => "restart=drops-once",
            ClientShape::Only11Bit => "formats=11-bit",
        }
    }

    pub fn from_name(name: &str) -> Option<ClientShape> {
        ClientShape::ALL.into_iter().find(|s| s.name() == name)
    }
}

/// A client with at most one fault.
pub struct FaultyClient {
    layout: ImageLayout,
    queue: QueueMode,
    fault: Option<ClientFault>,
    /// The way of working it takes, and whether it declares it.
    shape: Option<(ClientShape, bool)>,
    /// The whole output image as this program keeps it.
    image: Vec<u8>,
    to_send: VecDeque<MessageRepr>,
    own_rx_counter: u16,
    /// No task has run since the program started.
    started: bool,
    /// Transaction numbers written and not yet known to be on the bus.
    unconfirmed: VecDeque<u16>,
}

impl FaultyClient {
    pub fn new(layout: ImageLayout, queue: QueueMode, fault: Option<ClientFault>) -> Self {
        FaultyClient {
            layout,
            queue,
            fault,
            shape: None,
            image: vec![0; layout.output_size()],
            to_send: VecDeque::new(),
            own_rx_counter: 0,
            started: true,
            unconfirmed: VecDeque::new(),
        }
    }

    /// The same client taking `shape`, declaring it or not.
    pub fn shaped(self, shape: ClientShape, declared: bool) -> Self {
        FaultyClient {
            shape: Some((shape, declared)),
            ..self
        }
    }

    fn has(&self, fault: ClientFault) -> bool {
        self.fault == Some(fault)
    }

    fn takes(&self, shape: ClientShape) -> bool {
        self.shape.is_some_and(|(s, _)| s == shape)
    }

    /// Up to `slots` frames, each filled with the next bytes of its
    /// identifier from the requests in a row that share it (a byte stream
    /// cut its own way); a request partly taken keeps the rest.
    fn packed(&mut self, slots: usize) -> Vec<MessageRepr> {
        let mut batch = Vec::new();
        while batch.len() < slots {
            let Some(first) = self.to_send.pop_front() else {
                break;
            };
            let id = first.frame.id;
            let mut bytes = first.frame.data().to_vec();
            while let Some(next) = self.to_send.front_mut().filter(|n| n.frame.id == id) {
                let data = next.frame.data();
                let take = (8 - bytes.len()).min(data.len());
                if take == 0 {
                    break;
                }
                bytes.extend_from_slice(&data[..take]);
                match Frame::classic(id, &data[take..]) {
                    Ok(rest) if take < data.len() => next.frame = rest,
                    _ => {
                        self.to_send.pop_front();
                    }
                }
            }
            let frame = Frame::classic(id, &bytes).expect("at most 8 bytes");
            batch.push(MessageRepr { frame, ..first });
        }
        batch
    }

    /// The slots its code thinks the image has, each way.
    fn slots(&self, actual: usize) -> usize {
        match self.takes(ClientShape::TenSlots) {
            true => 10,
            false => actual,
        }
    }

    /// The slot a program means by index `n`.
    fn slot(&self, n: usize) -> usize {
        n + usize::from(self.has(ClientFault::OneBasedSlots))
    }

    fn read(&mut self, inputs: &[u8], delivered: &mut Vec<MessageRepr>) -> Result<(), IutError> {
        let layout = self.layout;
        if self.takes(ClientShape::TxOnly) {
            return Ok(());
        }
        let image = InputImage::new_checked(&inputs[..layout.input_size()], layout)
            .map_err(|e| IutError::new(crate::error::IutCause::Impossible, e.to_string()))?;
        let outputs = OutputImage::new_checked(&self.image[..], layout)
            .map_err(|e| IutError::new(crate::error::IutCause::Impossible, e.to_string()))?;
        let (seen, mine, tx_count) = (
            image.rx_counter(),
            outputs.rx_counter(),
            outputs.no_of_tx_messages(),
        );
        let fresh = match self.fault {
            Some(ClientFault::IgnoresWrap) => seen > mine,
            Some(ClientFault::IgnoresRxCounterZero) => seen != 0 && seen != mine,
            _ => handshake::new_messages(mine, seen),
        };
        let first = std::mem::take(&mut self.started);
        if !fresh {
            return Ok(());
        }
        let count = match self.fault {
            Some(ClientFault::DecodeOverNoOfTxMessages) => usize::from(tx_count),
            Some(ClientFault::ReadsAllSlots) => layout.rx_slots,
            Some(ClientFault::RestartReadsAllSlots) if first => layout.rx_slots,
            Some(ClientFault::NoBoundOnNoOfRxMessages) => usize::from(image.no_of_rx_messages()),
            Some(ClientFault::AcknowledgesAfterFirstMessage) => {
                usize::from(image.no_of_rx_messages()).min(1)
            }
            _ if first && self.takes(ClientShape::DropsRestartBatch) => 0,
            _ => usize::from(image.no_of_rx_messages()).min(self.slots(layout.rx_slots)),
        };
        for n in 0..count {
            // Where slot n lies in the master's memory, whether or not it is
            // one of the image's slots: a C driver would read it all the same.
            let range = layout.rx_slot(self.slot(n));
            let Some(bytes) = inputs.get(range) else {
                break;
            };
            let view = MessageView::new_checked(bytes, layout.rx_message)
                .map_err(|e| IutError::new(crate::error::IutCause::Impossible, e.to_string()))?;
            let mut message = MessageRepr::parse_clamped(&view).0;
            if self.has(ClientFault::IgnoresExtendedFlag) {
                if let CanId::Extended(raw) = message.frame.id {
                    message.frame.id = CanId::Standard((raw & 0x7FF) as u16);
                }
            }
            delivered.push(message);
        }
        let fault = self.fault;
        let mut outputs = OutputImage::new_checked(&mut self.image[..], layout)
            .map_err(|e| IutError::new(crate::error::IutCause::Impossible, e.to_string()))?;
        match fault {
            Some(ClientFault::OwnRxCounter) => {
                let own = handshake::next(self.own_rx_counter);
                outputs.set_rx_counter(own);
                self.own_rx_counter = own;
            }
            Some(ClientFault::FastQueueRereads) if self.queue == QueueMode::Fast => {}
            Some(ClientFault::AcknowledgesWithTxCounter) => {
                outputs.set_rx_counter(image.tx_counter())
            }
            _ => outputs.set_rx_counter(seen),
        }
        Ok(())
    }

    /// The messages this task learns were sent: up to the one
    /// Inputs.TransactionNumber names, for the device sends in order.
    fn learn_sent(&mut self, inputs: &[u8]) -> Result<Vec<u16>, IutError> {
        let layout = self.layout;
        let image = InputImage::new_checked(&inputs[..layout.input_size()], layout)
            .map_err(|e| IutError::new(crate::error::IutCause::Impossible, e.to_string()))?;
        if self.has(ClientFault::SentOnAcknowledge) {
            let mine = OutputImage::new_checked(&self.image[..], layout)
                .map_err(|e| IutError::new(crate::error::IutCause::Impossible, e.to_string()))?
                .tx_counter();
            if handshake::ready_to_send(mine, image.tx_counter()) {
                return Ok(self.unconfirmed.drain(..).collect());
            }
            return Ok(Vec::new());
        }
        let last = image.transaction_number();
        Ok(
            match self.unconfirmed.iter().rposition(|n| Some(*n) == last) {
                Some(at) => self.unconfirmed.drain(..=at).collect(),
                None => Vec::new(),
            },
        )
    }

    fn write(&mut self, inputs: &[u8], buffer: &mut [u8]) -> Result<(), IutError> {
        let layout = self.layout;
        let image = InputImage::new_checked(&inputs[..layout.input_size()], layout)
            .map_err(|e| IutError::new(crate::error::IutCause::Impossible, e.to_string()))?;
        let mine = OutputImage::new_checked(&self.image[..], layout)
            .map_err(|e| IutError::new(crate::error::IutCause::Impossible, e.to_string()))?
            .tx_counter();
        let ready = match self.fault {
            Some(ClientFault::WritesBeforeAcknowledge) => true,
            _ => handshake::ready_to_send(mine, image.tx_counter()),
        };
        if !ready || self.to_send.is_empty() {
            return Ok(());
        }
        // One count for both directions, as when the terminal's two
        // settings are taken for one: visible only where they differ.
        let slots = match self.fault {
            Some(ClientFault::TxBatchBoundedByRxSlots) => self.slots(layout.rx_slots),
            _ => self.slots(layout.tx_slots),
        };
        let mut batch: Vec<MessageRepr> = match self.takes(ClientShape::ByteStream) {
            true => self.packed(slots),
            false => self
                .to_send
                .drain(..self.to_send.len().min(slots))
                .collect(),
        };
        let count = batch.len();
        if self.takes(ClientShape::Streams) {
            batch.sort_by_key(|m| m.frame.id.raw());
        }
        // 000's loop runs to NumberOfMessagesToSend inclusive.
        let written = count + usize::from(self.has(ClientFault::SendSample000));
        for n in 0..written {
            let message = match batch.get(n) {
                Some(message) => Some(*message),
                None => self.to_send.front().copied(),
            };
            let Some(mut message) = message.or(Some(MessageRepr {
                transaction_number: 0,
                frame: Frame::classic(CanId::Standard(0), &[]).expect("an empty frame"),
                time_stamp: 0,
            })) else {
                break;
            };
            if self.has(ClientFault::TransactionNumberZero) {
                message.transaction_number = 0;
            }
            if n < count && layout.transaction_number {
                self.unconfirmed.push_back(message.transaction_number);
            }
            if self.has(ClientFault::DropsRtr) && message.frame.is_remote() {
                let zeros = [0u8; 8];
                message.frame =
                    Frame::classic(message.frame.id, &zeros[..usize::from(message.frame.len())])
                        .expect("a remote frame asks at most 8 bytes");
            }
            let range = layout.tx_slot(self.slot(n));
            let size = self.image.len();
            // A slot past the image lands in what the master maps behind it.
            let target: &mut [u8] = if range.end <= size {
                &mut self.image[range]
            } else if let Some(behind) = buffer.get_mut(range) {
                behind
            } else {
                break;
            };
            let mut view = MessageView::new_checked(target, layout.tx_message)
                .map_err(|e| IutError::new(crate::error::IutCause::Impossible, e.to_string()))?;
            message
                .emit(&mut view)
                .map_err(|e| IutError::new(crate::error::IutCause::Impossible, e.to_string()))?;
        }
        let mut outputs = OutputImage::new_checked(&mut self.image[..], layout)
            .map_err(|e| IutError::new(crate::error::IutCause::Impossible, e.to_string()))?;
        let declared = match self.fault {
            Some(ClientFault::NoOfTxMessagesIsTheSlotCount) => layout.tx_slots,
            _ => count,
        };
        outputs.set_no_of_tx_messages(declared as u16);
        let next = match self.fault {
            Some(ClientFault::IgnoresWrap) => image.tx_counter().saturating_add(1),
            Some(ClientFault::TxCounterPlusOne | ClientFault::WritesBeforeAcknowledge) => {
                handshake::next(mine)
            }
            _ => handshake::next(image.tx_counter()),
        };
        outputs.set_tx_counter(next);
        Ok(())
    }
}

impl Client for FaultyClient {
    fn task(&mut self, io: TaskIo<'_>) -> Result<TaskAnswer, IutError> {
        let layout = self.layout;
        if io.inputs.len() < layout.input_size() || io.outputs.len() < layout.output_size() {
            return Err(IutError::new(
                crate::error::IutCause::Impossible,
                "the images handed to the client are too short",
            ));
        }
        let size = layout.output_size();
        if self.has(ClientFault::TxCounterPlusOne) {
            // The program's Outputs are the buffer the master hands it.
            self.image.copy_from_slice(&io.outputs[..size]);
        }
        let mut answer = TaskAnswer::default();
        for (index, request) in io.requests.iter().enumerate() {
            if self.takes(ClientShape::RxOnly) {
                answer.refused.push(index);
                continue;
            }
            let mut scratch = vec![0u8; layout.tx_message.size];
            let fits = MessageView::new_checked(&mut scratch[..], layout.tx_message)
                .ok()
                .is_some_and(|mut view| request.emit(&mut view).is_ok());
            if fits {
                self.to_send.push_back(*request);
            } else {
                answer.refused.push(index);
            }
        }
        self.read(io.inputs, &mut answer.delivered)?;
        answer.sent = self.learn_sent(io.inputs)?;
        self.write(io.inputs, io.outputs)?;
        io.outputs[..size].copy_from_slice(&self.image);
        Ok(answer)
    }

    fn declaration(&self) -> super::ClientDeclaration {
        let mut lines = vec!["tells-sent=yes"];
        if let Some((shape, true)) = self.shape {
            lines.push(shape.declares());
        }
        super::ClientDeclaration::parse(&lines).expect("the soft client's lines are valid")
    }
}
