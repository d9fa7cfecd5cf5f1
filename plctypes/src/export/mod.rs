//! The declarations in a PLC programmer's language: Structured Text as
//! TwinCAT keeps it, a C header, Rust types. Each writes [`ImageTypes`] and
//! nothing else: the offsets are the model's.

mod c;
mod rust;
mod st;

pub use c::{c_fragment, c_header};
pub use rust::rust_module;
pub use st::structured_text;

use crate::types::{DataType, Elementary, ImageTypes, Member};

/// The languages `canif export` writes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Language {
    /// IEC 61131-3 Structured Text, with TwinCAT's `pack_mode` attribute.
    StructuredText,
    C,
    Rust,
}

/// `types` in `language`; `origin` says how it was made, for the file's head.
pub fn export(types: &ImageTypes, language: Language, origin: &str) -> String {
    match language {
        Language::StructuredText => structured_text(types, origin),
        Language::C => c_header(types, origin),
        Language::Rust => rust_module(types, origin),
    }
}

/// A structure's members as C and Rust hold them: a run of `BIT`s at one
/// byte becomes that byte, whose bits are named beside it (C's and Rust's
/// bit fields are not laid out as TwinCAT lays out `BIT`s).
enum Slot<'a> {
    Field(&'a Member),
    Bits {
        offset: usize,
        bits: Vec<&'a Member>,
    },
}

fn slots(members: &[Member]) -> Vec<Slot<'_>> {
    let mut slots: Vec<Slot<'_>> = Vec::new();
    for member in members {
        if member.data_type != DataType::Elementary(Elementary::Bit) {
            slots.push(Slot::Field(member));
            continue;
        }
        match slots.last_mut() {
            Some(Slot::Bits { offset, bits }) if *offset == member.offset => bits.push(member),
            _ => slots.push(Slot::Bits {
                offset: member.offset,
                bits: vec![member],
            }),
        }
    }
    slots
}

/// An array's element count (bounds as declared).
fn count(low: i64, high: i64) -> usize {
    crate::types::element_count(low, high)
}
