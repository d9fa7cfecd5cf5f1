//! The EtherCAT master between a client and the device, as a parameter of the
//! run: the worst client faults come from how client code meets the master.
//!
//! Source: 003 "EtherCAT Update" (LRW: the TxCounter increment is confirmed
//! two task cycles later; separate input update: one; a task at half the CAN
//! interface cycle), "Synchronization" (SM2 or Distributed Clocks). How a
//! master hands a task its output buffer, and that a task can overrun, the
//! documents do not say: masters differ (CL-PDX-001, an assumption).

use std::collections::VecDeque;
use std::fmt;

use canif_model::exchange::ExchangeMode;
use canif_model::image::{ImageLayout, MessageLayout};

/// What the output buffer holds when the master hands it to a task.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OutputBuffer {
    /// The image the client wrote in its last task.
    Persistent,
    /// Zeros: the client must write its whole image every task.
    Zeroed,
    /// One of `n` buffers in turn: the image the client wrote `n` tasks ago.
    Rotating(usize),
}

/// One master model.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Master {
    pub name: &'static str,
    /// The telegrams that carry the images (the model's one word for it):
    /// one LRW (the inputs it reads are the device's of the cycle before,
    /// confirmation after two tasks), or LWR after the task and LRD just
    /// before the next (confirmation after one).
    pub telegrams: ExchangeMode,
    /// LRW with the task at half the CAN interface cycle: the device's cycle
    /// runs on every second telegram.
    pub half_cycle: bool,
    pub buffer: OutputBuffer,
    /// Every `n`-th task overruns: the client does not run, the telegram
    /// carries its last outputs.
    pub overrun_every: Option<u64>,
    /// The device's cycle starts at SYNC0 and sends at SYNC1 (needs the profile's
    /// `distributed_clocks`).
    pub distributed_clocks: bool,
}

impl fmt::Display for Master {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name)
    }
}

impl Master {
    const fn new(name: &'static str, telegrams: ExchangeMode) -> Self {
        Master {
            name,
            telegrams,
            half_cycle: false,
            buffer: OutputBuffer::Persistent,
            overrun_every: None,
            distributed_clocks: false,
        }
    }

    /// Every master model a run uses, the plain LRW first.
    pub const ALL: [Master; 8] = [
        Master::new("lrw", ExchangeMode::Lrw),
        Master::new("separate-input-update", ExchangeMode::SeparateInputUpdate),
        Master {
            half_cycle: true,
            ..Master::new("half-cycle", ExchangeMode::Lrw)
        },
        Master {
            buffer: OutputBuffer::Zeroed,
            ..Master::new("lrw-zeroed-outputs", ExchangeMode::Lrw)
        },
        Master {
            buffer: OutputBuffer::Rotating(3),
            ..Master::new("lrw-triple-buffered", ExchangeMode::Lrw)
        },
        Master {
            overrun_every: Some(5),
            ..Master::new("lrw-overruns", ExchangeMode::Lrw)
        },
        Master {
            buffer: OutputBuffer::Rotating(3),
            ..Master::new(
                "separate-input-update-triple-buffered",
                ExchangeMode::SeparateInputUpdate,
            )
        },
        Master {
            distributed_clocks: true,
            ..Master::new(
                "separate-input-update-dc",
                ExchangeMode::SeparateInputUpdate,
            )
        },
    ];

    /// What the model does, in one line.
    pub fn description(&self) -> String {
        let exchange = match (self.telegrams, self.half_cycle) {
            (_, true) => "LRW with the task at half the CAN cycle",
            (ExchangeMode::Lrw, false) => "LRW (confirmation two tasks later)",
            (ExchangeMode::SeparateInputUpdate, false) => "separate input update (one task later)",
        };
        let buffer = match self.buffer {
            OutputBuffer::Persistent => String::new(),
            OutputBuffer::Zeroed => ", output buffer zeroed every task".into(),
            OutputBuffer::Rotating(n) => format!(", {n} output buffers in turn"),
        };
        let overrun = self
            .overrun_every
            .map_or(String::new(), |n| format!(", every {n}th task overruns"));
        let dc = if self.distributed_clocks {
            ", Distributed Clocks (Fast CAN Queue only)"
        } else {
            ""
        };
        format!("{exchange}{buffer}{overrun}{dc}")
    }

    pub fn by_name(name: &str) -> Option<Master> {
        Master::ALL.into_iter().find(|m| m.name == name)
    }

    /// Tasks per CAN interface cycle.
    pub fn tasks_per_cycle(&self) -> u64 {
        match self.half_cycle {
            true => 2,
            false => 1,
        }
    }

    /// The most tasks from writing a TxCounter to seeing it confirmed, when
    /// the device accepts the batch in its next cycle.
    pub fn confirmation_tasks(&self) -> u64 {
        match self.half_cycle {
            true => 3,
            false => u64::from(self.telegrams.confirmation_cycles()),
        }
    }
}

/// Bytes the master maps behind each image in these runs (another device's
/// data): room for two of the largest messages, so that a client reading or
/// writing a slot past the end lands in them.
pub fn neighbour_bytes() -> usize {
    2 * MessageLayout::ALL.iter().map(|m| m.size).max().unwrap_or(0)
}

/// What the master maps behind the images: a pattern a client must leave alone.
pub const NEIGHBOUR_PATTERN: u8 = 0x5A;

/// One master at work: the process image in the device's memory, what the
/// next task sees, and the client's earlier output images.
#[derive(Debug, Clone)]
pub struct MasterRun {
    master: Master,
    layout: ImageLayout,
    /// The inputs the next task sees, neighbour bytes behind.
    task_inputs: Vec<u8>,
    /// The device's input image as its last cycle left it.
    device_inputs: Vec<u8>,
    /// The output image in the device's memory.
    device_outputs: Vec<u8>,
    /// The client's output images, newest last (as many as the buffers).
    written: VecDeque<Vec<u8>>,
    task: u64,
}

impl MasterRun {
    pub fn new(master: Master, layout: ImageLayout) -> Self {
        let mut task_inputs = vec![0; layout.input_size()];
        task_inputs.resize(layout.input_size() + neighbour_bytes(), NEIGHBOUR_PATTERN);
        MasterRun {
            master,
            layout,
            task_inputs,
            device_inputs: vec![0; layout.input_size()],
            device_outputs: vec![0; layout.output_size()],
            written: VecDeque::new(),
            task: 0,
        }
    }

    pub fn master(&self) -> Master {
        self.master
    }

    /// The task this run is at (0 first).
    pub fn task(&self) -> u64 {
        self.task
    }

    /// Does the client run in this task, or does it overrun?
    pub fn client_runs(&self) -> bool {
        self.master
            .overrun_every
            .is_none_or(|every| self.task % every != every - 1)
    }

    /// The inputs this task sees, neighbour bytes behind.
    /// The image layout the master exchanges.
    pub fn layout(&self) -> ImageLayout {
        self.layout
    }

    pub fn task_inputs(&self) -> &[u8] {
        &self.task_inputs
    }

    /// The input image alone as this task sees it.
    pub fn task_input_image(&self) -> &[u8] {
        &self.task_inputs[..self.layout.input_size()]
    }

    /// The output buffer this task is handed, neighbour bytes behind.
    pub fn output_buffer(&self) -> Vec<u8> {
        let size = self.layout.output_size();
        let mut buffer = match self.master.buffer {
            OutputBuffer::Persistent => self.written.back().cloned(),
            OutputBuffer::Zeroed => None,
            OutputBuffer::Rotating(n) => {
                (self.written.len() >= n).then(|| self.written[self.written.len() - n].clone())
            }
        }
        .unwrap_or_else(|| vec![0; size]);
        buffer.resize(size + neighbour_bytes(), NEIGHBOUR_PATTERN);
        buffer
    }

    /// The client wrote this output image (its buffer without the neighbour bytes).
    pub fn client_wrote(&mut self, image: &[u8]) {
        self.device_outputs.clear();
        self.device_outputs.extend_from_slice(image);
        self.written.push_back(image.to_vec());
        let keep = match self.master.buffer {
            OutputBuffer::Rotating(n) => n,
            _ => 1,
        };
        while self.written.len() > keep {
            self.written.pop_front();
        }
    }

    /// The PLC restarted: its program starts from zero, its buffers too.
    pub fn client_restarted(&mut self) {
        self.written.clear();
    }

    /// The output image in the device's memory, for the device's cycle.
    pub fn device_outputs(&self) -> &[u8] {
        &self.device_outputs
    }

    /// Does the device's cycle run after this task's telegram?
    pub fn device_cycle_due(&self) -> bool {
        self.task.is_multiple_of(self.master.tasks_per_cycle())
    }

    /// Ends the task: `device_cycle` runs the device's cycle (if due) on the
    /// outputs in its memory and gives its new inputs; the telegrams decide
    /// what the next task sees.
    pub fn end_task<E>(
        &mut self,
        device_cycle: impl FnOnce(&[u8]) -> Result<Vec<u8>, E>,
    ) -> Result<(), E> {
        let size = self.layout.input_size();
        if self.master.telegrams != ExchangeMode::SeparateInputUpdate {
            // The LRW read the device's memory before its cycle.
            self.task_inputs[..size].copy_from_slice(&self.device_inputs);
        }
        if self.device_cycle_due() {
            self.device_inputs = device_cycle(&self.device_outputs)?;
        }
        if self.master.telegrams == ExchangeMode::SeparateInputUpdate {
            self.task_inputs[..size].copy_from_slice(&self.device_inputs);
        }
        self.task += 1;
        Ok(())
    }

    /// The device restarted: its memory holds zeros until its next cycle.
    pub fn device_restarted(&mut self) {
        self.device_inputs.fill(0);
    }

    /// The device's input image as its last cycle left it.
    pub fn device_inputs(&self) -> &[u8] {
        &self.device_inputs
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use canif_model::config::{FrameFormat, InterfaceConfig};
    use canif_model::image::{InputImage, OutputImage};

    fn layout() -> ImageLayout {
        ImageLayout::new(&InterfaceConfig::new(FrameFormat::Base11, 4), false)
    }

    /// Tasks until a TxCounter written in task `start` shows in the task's
    /// inputs, with a device that confirms whatever it sees.
    fn confirmation_after(master: Master, start: u64) -> u64 {
        let layout = layout();
        let mut run = MasterRun::new(master, layout);
        for task in 0..10 {
            let seen = InputImage::new_checked(run.task_input_image(), layout)
                .unwrap()
                .tx_counter();
            if seen == 1 {
                return task - start;
            }
            let mut outputs = vec![0; layout.output_size()];
            OutputImage::new_checked(&mut outputs[..], layout)
                .unwrap()
                .set_tx_counter(u16::from(task >= start));
            run.client_wrote(&outputs);
            run.end_task(|outputs: &[u8]| {
                let counter = OutputImage::new_checked(outputs, layout)
                    .unwrap()
                    .tx_counter();
                let mut inputs = vec![0; layout.input_size()];
                InputImage::new_checked(&mut inputs[..], layout)
                    .unwrap()
                    .set_tx_counter(counter);
                Ok::<_, ()>(inputs)
            })
            .unwrap();
        }
        panic!("{master} never confirmed")
    }

    /// Covers: PDX-001, PDX-002
    #[test]
    fn each_master_confirms_after_the_tasks_003_names() {
        for master in Master::ALL {
            assert_eq!(
                confirmation_after(master, 0).max(confirmation_after(master, 1)),
                master.confirmation_tasks(),
                "{master}"
            );
        }
    }

    #[test]
    fn a_rotating_buffer_hands_back_the_image_of_n_tasks_ago() {
        let layout = layout();
        let master = Master::by_name("lrw-triple-buffered").unwrap();
        let mut run = MasterRun::new(master, layout);
        for n in 1..=5u8 {
            run.client_wrote(&vec![n; layout.output_size()]);
        }
        assert_eq!(run.output_buffer()[0], 3);
        assert_eq!(run.output_buffer()[layout.output_size()], NEIGHBOUR_PATTERN);
        let zeroed = MasterRun::new(Master::by_name("lrw-zeroed-outputs").unwrap(), layout);
        assert!(zeroed.output_buffer()[..layout.output_size()]
            .iter()
            .all(|b| *b == 0));
    }
}
