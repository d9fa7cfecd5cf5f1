//! Requirement ids as code names them.

/// A requirement id named in code: in a blame table, a scenario's list, a
/// fault's target. Written `ReqId::new("HS-TX-002")`; `spec/tests/ids_in_code.rs`
/// fails when code names an id the catalogue does not have.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct ReqId(&'static str);

impl ReqId {
    pub const fn new(id: &'static str) -> Self {
        ReqId(id)
    }

    pub const fn as_str(&self) -> &'static str {
        self.0
    }

    /// The ids as one text, `sep` between them.
    pub fn join(ids: &[ReqId], sep: &str) -> String {
        ids.iter().map(|id| id.0).collect::<Vec<_>>().join(sep)
    }
}

impl std::fmt::Display for ReqId {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.0)
    }
}

impl PartialEq<str> for ReqId {
    fn eq(&self, other: &str) -> bool {
        self.0 == other
    }
}

impl PartialEq<String> for ReqId {
    fn eq(&self, other: &String) -> bool {
        self.0 == other
    }
}

impl AsRef<str> for ReqId {
    fn as_ref(&self) -> &str {
        self.0
    }
}

impl serde::Serialize for ReqId {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        serializer.serialize_str(self.0)
    }
}

/// An id read back from a file (a shard's part of a run). Code names its ids
/// as literals; one read from a file is kept for the life of the process,
/// which reads each id of a part once (`canif merge`).
impl<'de> serde::Deserialize<'de> for ReqId {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        let id = String::deserialize(deserializer)?;
        Ok(ReqId(Box::leak(id.into_boxed_str())))
    }
}

/// A `&'static [ReqId]` from string literals: `req_ids!["HS-TX-002", "FQ-003"]`.
#[macro_export]
macro_rules! req_ids {
    ($($id:literal),* $(,)?) => {{
        const IDS: &[$crate::ReqId] = &[$($crate::ReqId::new($id)),*];
        IDS
    }};
}
