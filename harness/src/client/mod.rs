//! The PLC side under test: a client of the CAN interface (a soft-PLC
//! function block, an EtherCAT master's driver) that fills the output image
//! and reads the input image once per task. The harness plays the device (the
//! reference model on the simulated bus), the master between them
//! ([`master`]) and the application above the client, and judges every task
//! against the client requirements (`spec/requirements/client.yaml`, rulings
//! P1–P5).
//!
//! The arrows run one way: `suite` → `rig` → `master`, `judge`, `application`,
//! [`crate::client::played_device`]; `rig` → [`Client`] (the reference of `canif_model::client`,
//! the faulty clients of `faulty`).

pub mod application;
pub mod declaration;
mod exec;
pub mod faulty;
mod judge;
mod lib_client;
pub mod master;
pub mod played_device;
pub mod rig;
pub mod server;
pub mod suite;

use canif_model::client::PlcClient;
use canif_model::image::{ImageLayout, MessageRepr};

pub use crate::error::IutError;
pub use declaration::ClientDeclaration;

/// What a client sees in one PLC task.
///
/// Both images sit inside the master's process image: `inputs` and `outputs`
/// start at the interface's first byte and run on into whatever the master
/// maps behind it (other devices' data). A client that reads or writes past
/// the interface's size (`ImageLayout::input_size`, `output_size`) touches
/// those bytes, as a C driver would; the harness fills them with a pattern
/// and judges what a client does with them (P5).
#[derive(Debug)]
pub struct TaskIo<'a> {
    /// The input image as the master delivers it to this task.
    pub inputs: &'a [u8],
    /// The output buffer the master hands this task (its content depends on
    /// the master: the client's last image, zeros, or an older image); what
    /// the client leaves in it is sent to the device.
    pub outputs: &'a mut [u8],
    /// The application's send requests since the last task, in order.
    pub requests: &'a [MessageRepr],
}

/// What a client answers after one task.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct TaskAnswer {
    /// Messages the client read from the interface and handed to its
    /// application in this task, in order.
    pub delivered: Vec<MessageRepr>,
    /// The requests of this task (by index) the client reports it cannot send.
    pub refused: Vec<usize>,
    /// What it delivered that is no frame (say a 29-bit identifier without
    /// the 29-bit flag), after the `delivered` ones: judged, not an error.
    pub not_frames: Vec<String>,
    /// The transaction numbers of the Tx messages the client tells its
    /// application were sent, learned in this task, in the order sent
    /// (CL-TN-002). A client that does not tell leaves it empty.
    pub sent: Vec<u16>,
}

/// A PLC-side client under test. Every call can fail with an [`IutError`]:
/// the client itself broke, which is an `error` verdict, never a failure.
pub trait Client {
    /// One PLC task.
    fn task(&mut self, io: TaskIo<'_>) -> Result<TaskAnswer, IutError>;

    /// What the client declares it is: the interfaces it serves, its
    /// geometry, direction, application model, restart choice, and whether
    /// it tells its application which Tx messages were sent (only then do
    /// its transaction numbers have to tell the messages apart: CL-TN-001,
    /// 000 §5.2). Declaring nothing holds it to everything.
    fn declaration(&self) -> ClientDeclaration {
        ClientDeclaration::default()
    }
}

/// The reference client of 001 §6 (ruling R5) as a client under test: it
/// keeps its own output image and writes the whole of it every task, so it
/// conforms whatever buffer the master hands it.
pub struct ReferenceClient {
    layout: ImageLayout,
    client: PlcClient,
}

impl ReferenceClient {
    pub fn new(layout: ImageLayout) -> Self {
        ReferenceClient {
            layout,
            client: PlcClient::new(layout),
        }
    }
}

impl Client for ReferenceClient {
    fn task(&mut self, io: TaskIo<'_>) -> Result<TaskAnswer, IutError> {
        let mut refused = Vec::new();
        for (index, request) in io.requests.iter().enumerate() {
            if self.client.send(*request).is_err() {
                refused.push(index);
            }
        }
        let (inputs, outputs) = (
            io.inputs.get(..self.layout.input_size()),
            io.outputs.get_mut(..self.layout.output_size()),
        );
        let (Some(inputs), Some(outputs)) = (inputs, outputs) else {
            return Err(IutError::new(
                crate::error::IutCause::Impossible,
                "the images handed to the client are too short",
            ));
        };
        let written = self.client.task(inputs).map_err(|e| {
            IutError::new(
                crate::error::IutCause::Reported,
                format!("the reference client: {e}"),
            )
        })?;
        outputs.copy_from_slice(written);
        Ok(TaskAnswer {
            delivered: self.client.take_received(),
            refused,
            not_frames: Vec::new(),
            sent: self.client.take_sent(),
        })
    }

    fn declaration(&self) -> ClientDeclaration {
        ClientDeclaration {
            tells_sent: Some(true),
            ..ClientDeclaration::default()
        }
    }
}
