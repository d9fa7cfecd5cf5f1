//! The client role's door: what a PLC-side client under test is to the
//! harness, wherever it runs (in canif's process, a process over the adapter
//! protocol, a shared library). One call per PLC task.

use canif_model::image::MessageRepr;

use crate::declare::client::ClientDeclaration;
use crate::error::IutError;

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
