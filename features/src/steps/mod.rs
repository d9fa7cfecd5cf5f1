//! The step library. Every step is documented in features/README.md; the
//! steps are grouped as the scenarios read: given, when, then, the
//! documents' tables, and CANopen.

mod canopen;
mod client;
mod given;
mod tables;
mod then;
mod when;

use canif_model::frame::CanId;

use canif_spec::ReqId;

pub(crate) type StepResult = Result<(), String>;

pub(crate) fn num(text: &str) -> u32 {
    let text = text.trim();
    match text.strip_prefix("0x").or_else(|| text.strip_prefix("0X")) {
        Some(hex) => {
            u32::from_str_radix(hex, 16).unwrap_or_else(|_| panic!("not a hex number: {text}"))
        }
        None => text
            .parse()
            .unwrap_or_else(|_| panic!("not a number: {text}")),
    }
}

pub(crate) fn bytes(text: &str) -> Vec<u8> {
    text.split_whitespace()
        .map(|b| u8::from_str_radix(b, 16).unwrap_or_else(|_| panic!("not a hex byte: {b}")))
        .collect()
}

pub(crate) fn id(text: &str, extended: bool) -> CanId {
    if extended {
        CanId::Extended(num(text))
    } else {
        CanId::Standard(num(text) as u16)
    }
}

/// The identifier a step names: 29-bit when the value needs more than 11 bits.
pub(crate) fn id_of(cob: &str) -> CanId {
    id(cob, num(cob) > 0x7FF)
}

pub(crate) fn check(condition: bool, message: impl FnOnce() -> String) -> StepResult {
    if condition {
        Ok(())
    } else {
        Err(message())
    }
}

/// The blame sets of the fields a check reads (`canif_harness::device::blame`).
pub(crate) type Witness<'a> = &'a [&'static [ReqId]];

/// [`check`], and when it fails the scenario blames only its tags among the
/// `witness` sets (`canif_harness::device::blame::narrow_tags`): a wrong RxCounter in
/// a filter scenario is a handshake finding, not a filter one.
pub(crate) fn check_as(
    witness: Witness,
    condition: bool,
    message: impl FnOnce() -> String,
) -> StepResult {
    if !condition {
        crate::world::record_witness(witness);
    }
    check(condition, message)
}

// ---------------------------------------------------------------- Given
