//! # canif-model — the CAN interface as an executable specification
//!
//! The Beckhoff *CAN interface* lets a PLC send and receive raw CAN frames
//! through two process images: an output image it writes and an input image it
//! reads, exchanged once per task cycle. This crate says, in code, what a
//! correct device does with them. It does no I/O: no sockets, threads, files or
//! clocks. Time is an argument ([`Nanos`]), so the same model runs in virtual
//! time and beside a real bus.
//!
//! Read it beside the manual (000/001 = "CAN-Interface" 1.5/1.7, 002 = CANopen
//! quick start, 003 = EL6751 synchronisation, 004 = FC510x SDO page). Every item
//! names the requirement ids (`spec/requirements/*.yaml`) it implements.
//!
//! | concept | module | manual |
//! |---|---|---|
//! | frames, identifiers | [`frame`] | 000 §2 |
//! | COB ID word / UDINT | [`cob_id`] | 000 §6 |
//! | process images, byte for byte | [`image`] | 000 §6, §8.3, 003 |
//! | Tx/Rx counter handshake | [`handshake`] | 000 §6, 003 |
//! | the device cycle, queues | [`device`] | 003, 000 §4, §5 |
//! | what a device offers / refuses | [`config`] | 000 §2, §3 |
//! | what the documents leave free | [`freedoms`] | G3, 000 §5.1.1 |
//! | filters | [`filter`] | 000 §7 |
//! | CAN FD DLC and rounding | [`dlc`] | 000 §8.3.1 (R1) |
//! | InfoData | [`info_data`] | 001 §8.3.3 |
//! | frame timing | [`timing`], [`cia_table`] | 000 §4 (R3) |
//! | buffer sizing | [`sizing`] | 000 §4 (R4) |
//! | process-data exchange | [`exchange`] | 003 |
//! | the PLC's sample code | [`client`] | 001 §6 (R5) |
//! | CANopen NMT, SDO, guarding | [`canopen`] | 002, 004 (R6-R8) |
//!
//! ```
//! use canif_model::{config::*, device::Device, client::PlcClient, image::MessageRepr};
//! use canif_model::frame::{CanId, Frame};
//!
//! let device_caps = Capabilities::everything();
//! let mut device = Device::new(&device_caps, InterfaceConfig::new(FrameFormat::Base11, 4)).unwrap();
//! let mut plc = PlcClient::new(device.layout());
//! let frame = Frame::classic(CanId::Standard(0x318), &[1, 2]).unwrap();
//! plc.send(MessageRepr { transaction_number: 0, frame, time_stamp: 0 }).unwrap();
//!
//! let outputs = plc.task(device.inputs()).unwrap().to_vec();  // Outputs.TxCounter := 1
//! device.cycle(&outputs, 0).unwrap();                          // accepted, Inputs.TxCounter = 1
//! assert_eq!(device.poll_transmit(0), Some(frame));            // on its way to the bus
//! ```

#![forbid(unsafe_code)]

/// Nanoseconds on the device's clock (or the virtual clock of a simulation).
pub type Nanos = u64;

pub mod canopen;
pub mod cia_table;
pub mod client;
pub mod cob_id;
pub mod config;
pub mod device;
pub mod dlc;
pub mod exchange;
pub mod filter;
pub mod frame;
pub mod freedoms;
pub mod handshake;
pub mod image;
pub mod info_data;
#[cfg(feature = "serde")]
mod persist;
pub mod sizing;
pub mod timing;
