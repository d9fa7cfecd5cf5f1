//! Errors of reading a user's declarations: each names the file and line,
//! and says what canif could not read or could not size. canif never guesses
//! a layout it cannot compute.

use std::fmt;

/// Where in a user's files.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Place {
    pub file: String,
    pub line: usize,
}

impl fmt::Display for Place {
    /// `file:line`, or the file alone for what concerns all of it (line 0).
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.line {
            0 => write!(f, "{}", self.file),
            line => write!(f, "{}:{line}", self.file),
        }
    }
}

#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DeclarationError {
    pub place: Place,
    pub cause: Cause,
}

#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Cause {
    Unreadable(String),
    TooLarge {
        limit: usize,
    },
    /// Not UTF-8, or control characters no ST source has.
    NotText,
    /// A `.TcDUT` that is not well-formed XML.
    Xml(String),
    /// A `.TcDUT` without a `<Declaration>`.
    NoDeclaration,
    Unterminated(&'static str),
    Expected {
        expected: &'static str,
        found: String,
    },
    /// No `TYPE … END_TYPE` in the file.
    NoTypes,
    /// An array bound that is not a number (a constant canif cannot evaluate).
    Bound(String),
    EmptyArray {
        low: i64,
        high: i64,
    },
    UnknownType(String),
    /// A construct whose size depends on what canif cannot see.
    Unsized(&'static str),
    /// A type that contains itself, or nests deeper than any image does.
    TooDeep(String),
    Duplicate {
        name: String,
        first: Place,
    },
    PackMode(String),
    ArrayOfBits,
}

impl fmt::Display for Cause {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Cause::Unreadable(e) => write!(f, "cannot read the file: {e}"),
            Cause::TooLarge { limit } => {
                write!(f, "larger than {limit} bytes: not a type declaration")
            }
            Cause::NotText => write!(f, "not Structured Text (not UTF-8 text)"),
            Cause::Xml(e) => write!(f, "not a TwinCAT .TcDUT file: {e}"),
            Cause::NoDeclaration => write!(
                f,
                "a .TcDUT file without <Declaration>: no type to read"
            ),
            Cause::Unterminated(what) => write!(f, "{what} is not closed"),
            Cause::Expected { expected, found } => {
                write!(f, "expected {expected}, found `{found}`")
            }
            Cause::NoTypes => write!(
                f,
                "no TYPE … END_TYPE declaration: not Structured Text type declarations"
            ),
            Cause::Bound(text) => write!(
                f,
                "array bound `{text}` is not a number: canif cannot size the array (write the number)"
            ),
            Cause::EmptyArray { low, high } => {
                write!(f, "ARRAY [{low}..{high}] has no elements")
            }
            Cause::UnknownType(name) => write!(
                f,
                "type `{name}` is declared in none of the files given: canif cannot size it"
            ),
            Cause::Unsized(what) => write!(
                f,
                "{what} has a size that depends on the target: canif cannot size it"
            ),
            Cause::TooDeep(name) => write!(
                f,
                "type `{name}` contains itself or nests deeper than any process image"
            ),
            Cause::Duplicate { name, first } => {
                write!(f, "type `{name}` is declared twice (first at {first})")
            }
            Cause::PackMode(value) => write!(
                f,
                "pack_mode `{value}`: TwinCAT takes 0, 1, 2, 4 or 8"
            ),
            Cause::ArrayOfBits => write!(f, "ARRAY OF BIT: TwinCAT allows BIT only as a structure member"),
        }
    }
}

impl fmt::Display for DeclarationError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: {}", self.place, self.cause)
    }
}

impl std::error::Error for DeclarationError {}
