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
mod judge;
pub mod kill_table;
pub mod master;
pub mod played_device;
pub mod rig;
pub mod soft_client;
pub mod suite;

use canif_model::client::PlcClient;
use canif_model::image::ImageLayout;

pub use crate::declare::client::ClientDeclaration;
pub use crate::door::client::{Client, TaskAnswer, TaskIo};
pub use crate::error::IutError;

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
