//! `canif export` and `canif check-layout`: the interface whose image they
//! declare, as the command line names it.

use std::path::PathBuf;

use clap::{Args, ValueEnum};

/// The frame format of `--frame`.
#[derive(ValueEnum, Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum FrameArg {
    /// 11-bit identifiers (000 §6).
    #[value(name = "11")]
    Base11,
    /// 29-bit identifiers (000 §6).
    #[value(name = "29")]
    Extended29,
    /// CAN FD (000 §8): transaction numbers and time stamps always.
    Fd,
}

/// One interface of a profile (000 §5, §6): what its images hold.
#[derive(Args, Debug, Clone)]
pub(crate) struct InterfaceArgs {
    /// A device profile (see `canif profiles`).
    /// (`canif export --messages` needs none.)
    #[arg(long)]
    pub profile: Option<String>,
    /// Frame format [default: the profile's first].
    #[arg(long, value_enum)]
    pub frame: Option<FrameArg>,
    /// With transaction numbers (000 §5.2).
    #[arg(long)]
    pub transaction_number: bool,
    /// With receive time stamps (000 §5.3).
    #[arg(long)]
    pub time_stamp: bool,
    /// Tx message slots in the outputs.
    #[arg(long, default_value_t = 10, value_parser = clap::value_parser!(u8).range(1..=255))]
    pub tx_slots: u8,
    /// Rx message slots in the inputs.
    #[arg(long, default_value_t = 10, value_parser = clap::value_parser!(u8).range(1..=255))]
    pub rx_slots: u8,
}

/// The languages of `canif export --format`.
#[derive(ValueEnum, Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum LanguageArg {
    /// IEC 61131-3 Structured Text (TwinCAT DUTs, `pack_mode` 0).
    St,
    /// A C header with `_Static_assert` on every offset and size.
    C,
    /// Rust `#[repr(C, packed)]` types with `offset_of!` assertions.
    Rust,
}

#[derive(Args, Debug, Clone)]
pub(crate) struct ExportArgs {
    #[command(flatten)]
    pub interface: InterfaceArgs,
    #[arg(long = "format", value_enum, default_value = "st")]
    pub language: LanguageArg,
    /// Only the message structures of every interface, no image (what
    /// include/canif.h declares).
    #[arg(long, conflicts_with_all = ["profile", "frame", "transaction_number", "time_stamp"])]
    pub messages: bool,
}

#[derive(Args, Debug, Clone)]
pub(crate) struct CheckLayoutArgs {
    /// ST files declaring the image: `.st`, or TwinCAT's `.TcDUT`.
    #[arg(required = true, value_name = "FILE")]
    pub files: Vec<PathBuf>,
    #[command(flatten)]
    pub interface: InterfaceArgs,
    /// The structure that declares the outputs [default: the one with a
    /// `NoOfTxMessages` member].
    #[arg(long, value_name = "TYPE")]
    pub outputs: Option<String>,
    /// The structure that declares the inputs [default: the one with a
    /// `NoOfRxMessages` member].
    #[arg(long, value_name = "TYPE")]
    pub inputs: Option<String>,
    /// The alignment of a structure without `{attribute 'pack_mode'}`: 8 on
    /// TwinCAT 3 for x86/x64, 4 on an Arm CX7000.
    #[arg(long, default_value_t = 8, value_parser = pack_mode)]
    pub pack_mode: u8,
}

fn pack_mode(text: &str) -> Result<u8, String> {
    match text.parse::<u8>() {
        Ok(mode @ (0 | 1 | 2 | 4 | 8)) => Ok(mode),
        _ => Err(format!(
            "`{text}`: TwinCAT's pack modes are 0, 1, 2, 4 and 8"
        )),
    }
}
