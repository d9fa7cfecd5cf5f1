//! # canif-spec — the requirement catalogue and the device profiles
//!
//! The catalogue is data (`spec/*.yaml`): every testable statement of the source
//! documents with an id, its source, a status and the capabilities it needs, and
//! one profile per device of the manual's feature matrix. This crate loads it,
//! validates it (unknown keys, duplicate ids, unknown capabilities, dangling
//! references) and reports every problem with file, line and field.
//!
//! The catalogue is embedded at build time ([`Catalogue::embedded`]); a vendor's
//! own folder of the same shape loads with [`Catalogue::load_dir`].

#![forbid(unsafe_code)]

mod catalogue;
pub mod coverage;
mod error;
mod lines;
mod profile;
mod req_id;
mod scope;
mod source;

pub use catalogue::{
    Area, Capability, Catalogue, Requirement, Ruling, Source, SourceDocument, Status, Verification,
};
pub use error::{SpecError, SpecErrors};
pub use profile::{EthercatIdentity, Profile};
pub use req_id::ReqId;
pub use scope::{Scope, Side, Suite};

/// The embedded catalogue's files (path, text), in load order: what a
/// certificate's catalogue hash covers.
pub fn embedded_files() -> &'static [(&'static str, &'static str)] {
    embedded::EMBEDDED
}

mod embedded {
    include!(concat!(env!("OUT_DIR"), "/embedded.rs"));
}
