//! # canif-plctypes — the process image in the PLC programmer's languages
//!
//! The model knows every byte of the images (`canif_model::image`); this
//! crate hands them to the people who declare them by hand:
//!
//! * [`ImageTypes`] — an interface's images as data types with the manual's
//!   names (000/001 §6, §8.3), each member at the model's offset;
//! * [`export`] — those types as TwinCAT Structured Text, a C header with a
//!   static assertion on every offset and size, or Rust `repr(C, packed)`
//!   types (`canif export`);
//! * [`check_files`] — a user's own ST declarations (`.st`, `.TcDUT`) laid
//!   out as TwinCAT would and held against the image, member by member,
//!   with file and line (`canif check-layout`).

#![forbid(unsafe_code)]

mod check;
mod error;
pub mod export;
mod packing;
mod parse;
mod source;
mod types;

pub use check::{check, Checked, Defect, Difference, Roots};
pub use error::{Cause, DeclarationError, Place};
pub use packing::{Declarations, Laid, Placed};
pub use parse::{parse, Body, MemberDecl, TypeDecl, TypeExpr};
pub use source::{Source, MAX_FILE_BYTES};
pub use types::{
    Alias, DataType, Elementary, ImageTypes, Member, Role, StructType, FD_DATA, INPUTS, OUTPUTS,
};

/// TwinCAT 3's alignment on x86/x64 for a structure without `pack_mode`.
pub const TWINCAT3_DEFAULT_PACK_MODE: u8 = 8;

/// Reads every file, lays its types out and holds them against `image`.
pub fn check_files(
    paths: &[std::path::PathBuf],
    image: &ImageTypes,
    roots: &Roots,
    default_pack_mode: u8,
) -> Result<Checked, DeclarationError> {
    let mut types = Vec::new();
    for path in paths {
        for source in Source::read(path)? {
            types.extend(parse(&source)?);
        }
    }
    let declarations = Declarations::new(types, default_pack_mode)?;
    check(&declarations, image, roots)
}
