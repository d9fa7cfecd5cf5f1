//! Where a statement of the catalogue comes from: a source document and its section.

use serde::Deserialize;

/// Where a statement comes from.
#[derive(Debug, Clone, PartialEq, Eq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Source {
    pub file: String,
    pub section: String,
}
