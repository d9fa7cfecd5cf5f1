//! A client under test in a shared library, through the client role of the C
//! ABI (include/canif.h): a soft PLC's CAN-interface code, in process. The
//! library is handed pointers into the master's process image, so a client
//! that reads or writes past its image touches the neighbour bytes the judge
//! watches (CL-IMG-001). A PLC restart stops the program and starts another.

use crate::declare::Declaration;
use std::path::Path;

use canif_cabi::guard::GuardedImage;
use canif_cabi::{CMessage, ClientLibrary, ClientProgram};
use canif_model::config::{Capabilities, InterfaceConfig};
use canif_model::image::{ImageLayout, MessageRepr};

use crate::declare::client::ClientDeclaration;
use crate::door::client::{Client, TaskAnswer, TaskIo};
use crate::door::lib::{c_config, from_c, to_c};
use crate::error::IutCause;
use crate::error::IutError;

pub(crate) struct LibClient {
    program: ClientProgram,
    layout: ImageLayout,
    path: String,
    /// In a host process of its own (`canif lib-host`): the images with a
    /// guard page behind each, so an access past one stops there and is
    /// reported (CL-IMG-001) instead of reading the host's memory.
    guarded: Option<(GuardedImage, GuardedImage)>,
    /// What `canif_client_declares` said, read before the start.
    declares: Vec<String>,
}

impl LibClient {
    /// What the library at `path` declares, asked before any start
    /// (include/canif.h).
    pub(crate) fn declares(path: &Path) -> Result<ClientDeclaration, IutError> {
        let library =
            ClientLibrary::open(path).map_err(|e| IutError::new(IutCause::NotStarted, e))?;
        ClientDeclaration::parse(&library.declares()).map_err(|error| {
            IutError::new(
                IutCause::Protocol,
                format!("{}: canif_client_declares: {error}", path.display()),
            )
        })
    }

    pub(crate) fn start(
        path: &Path,
        config: &InterfaceConfig,
        layout: ImageLayout,
    ) -> Result<Self, IutError> {
        let library =
            ClientLibrary::open(path).map_err(|e| IutError::new(IutCause::NotStarted, e))?;
        let declares = library.declares();
        if let Err(error) = ClientDeclaration::parse(&declares) {
            return Err(IutError::new(
                IutCause::Protocol,
                format!("{}: canif_client_declares: {error}", path.display()),
            ));
        }
        let mut c_config = c_config(&Capabilities::everything(), config);
        // The sizes of this interface's images, InfoData or not.
        c_config.input_size = layout.input_size() as u32;
        c_config.output_size = layout.output_size() as u32;
        let program = library
            .start(&c_config)
            .map_err(|e| IutError::new(IutCause::NotStarted, format!("{}: {e}", path.display())))?;
        Ok(LibClient {
            program,
            layout,
            path: path.display().to_string(),
            guarded: None,
            declares,
        })
    }

    /// The same, its images behind guard pages (see [`canif_cabi::guard`]).
    pub(crate) fn guarded(mut self) -> Result<Self, IutError> {
        let image = |len| {
            GuardedImage::new(len)
                .ok_or_else(|| IutError::new(IutCause::NotStarted, "cannot map a guarded image"))
        };
        let inputs = image(self.layout.input_size())?;
        let outputs = image(self.layout.output_size())?;
        canif_cabi::guard::watch(&inputs, &outputs);
        self.guarded = Some((inputs, outputs));
        Ok(self)
    }
}

/// What one task of a library answered, its messages as the C ABI gave them.
pub(crate) struct RawTask {
    pub(crate) delivered: Vec<CMessage>,
    pub(crate) refused: Vec<usize>,
    pub(crate) sent: Vec<u16>,
}

impl LibClient {
    /// One task, the delivered messages undecoded (the host passes them on
    /// as they are, for canif to judge).
    pub(crate) fn task_raw(&mut self, io: TaskIo<'_>) -> Result<RawTask, IutError> {
        let requests: Vec<CMessage> = io
            .requests
            .iter()
            .map(|m| CMessage {
                frame: to_c(&m.frame),
                transaction_number: m.transaction_number,
                time_stamp_ns: m.time_stamp,
            })
            .collect();
        // Room for more than the slots: a client that reads past them is
        // judged (CL-IMG-001) rather than overflowing the harness's array.
        let capacity = 2 * self.layout.rx_slots + 16;
        let (input_size, output_size) = (self.layout.input_size(), self.layout.output_size());
        let result = match self.guarded.as_mut() {
            None => self.program.task(
                (io.inputs, input_size),
                (io.outputs, output_size),
                &requests,
                capacity,
            ),
            Some((inputs, outputs)) => {
                inputs
                    .as_mut_slice()
                    .copy_from_slice(&io.inputs[..input_size]);
                outputs
                    .as_mut_slice()
                    .copy_from_slice(&io.outputs[..output_size]);
                let result = self.program.task(
                    (inputs.as_slice(), input_size),
                    (outputs.as_mut_slice(), output_size),
                    &requests,
                    capacity,
                );
                io.outputs[..output_size].copy_from_slice(outputs.as_slice());
                result
            }
        }
        .map_err(|e| IutError::new(IutCause::Reported, format!("{}: {e}", self.path)))?;
        Ok(RawTask {
            delivered: result.delivered,
            refused: result.refused,
            sent: result.sent,
        })
    }
}

impl Client for LibClient {
    fn declaration(&self) -> ClientDeclaration {
        // A library that exports canif_client_sent tells what was sent; its
        // lines were checked when it started.
        let mut declaration = ClientDeclaration::parse(&self.declares).unwrap_or_default();
        declaration.tells_sent = declaration.tells_sent.or(Some(self.program.tells_sent()));
        declaration
    }

    fn task(&mut self, io: TaskIo<'_>) -> Result<TaskAnswer, IutError> {
        let raw = self.task_raw(io)?;
        let mut answer = TaskAnswer {
            refused: raw.refused,
            sent: raw.sent,
            ..TaskAnswer::default()
        };
        for m in &raw.delivered {
            match from_c(&m.frame) {
                Ok(frame) if answer.not_frames.is_empty() => answer.delivered.push(MessageRepr {
                    transaction_number: m.transaction_number,
                    frame,
                    time_stamp: m.time_stamp_ns,
                }),
                Ok(frame) => answer
                    .not_frames
                    .push(format!("(after one that is no frame) {frame}")),
                Err(e) => answer.not_frames.push(e.to_string()),
            }
        }
        Ok(answer)
    }
}
