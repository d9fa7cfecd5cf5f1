//! A client under test in a shared library, through the client role of the C
//! ABI (include/canif.h): a soft PLC's CAN-interface code, in process. The
//! library is handed pointers into the master's process image, so a client
//! that reads or writes past its image touches the neighbour bytes the judge
//! watches (CL-IMG-001). A PLC restart stops the program and starts another.

use std::path::Path;

use canif_cabi::{CMessage, ClientLibrary, ClientProgram};
use canif_model::config::{Capabilities, InterfaceConfig};
use canif_model::image::{ImageLayout, MessageRepr};

use super::{Client, IutError, TaskAnswer, TaskIo};
use crate::device::lib_iut::{c_config, from_c, to_c};
use crate::error::IutCause;

pub(super) struct LibClient {
    program: ClientProgram,
    layout: ImageLayout,
    path: String,
}

impl LibClient {
    pub(super) fn start(
        path: &Path,
        config: &InterfaceConfig,
        layout: ImageLayout,
    ) -> Result<Self, IutError> {
        let library =
            ClientLibrary::open(path).map_err(|e| IutError::new(IutCause::NotStarted, e))?;
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
        })
    }
}

impl Client for LibClient {
    fn task(&mut self, io: TaskIo<'_>) -> Result<TaskAnswer, IutError> {
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
        let result = self
            .program
            .task(
                (io.inputs, self.layout.input_size()),
                (io.outputs, self.layout.output_size()),
                &requests,
                capacity,
            )
            .map_err(|e| IutError::new(IutCause::Reported, format!("{}: {e}", self.path)))?;
        let mut answer = TaskAnswer {
            refused: result.refused,
            sent: result.sent,
            ..TaskAnswer::default()
        };
        for m in &result.delivered {
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
