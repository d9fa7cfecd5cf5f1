//! Why a declaration cannot be taken: one error for both sides' declarations
//! and the files they are read from, each naming the line and its place.

use std::fmt;
use std::path::PathBuf;

use super::{Line, Origin, MAX_FILE};

/// A declaration's line that cannot be taken, or its file that cannot be read.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum DeclarationError {
    /// Not `NAME=VALUE`.
    Malformed { line: String },
    /// No name this side declares: `what` it is ("choice", "client
    /// declaration"), and the names it knows.
    UnknownName {
        name: String,
        what: &'static str,
        known: Vec<&'static str>,
    },
    /// A value the name cannot take, and what it takes.
    BadValue {
        name: &'static str,
        value: String,
        expected: String,
    },
    /// Declared twice, two ways (say, on the command line and by the client).
    Conflict {
        name: &'static str,
        first: String,
        second: String,
    },
    /// The arguments or a file of them cannot be read.
    Read(ReadError),
    /// A line of `--declare` (or of its file) that cannot be taken, and where it was made.
    At {
        origin: Origin,
        error: Box<DeclarationError>,
    },
}

impl fmt::Display for DeclarationError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            DeclarationError::Malformed { line } => write!(f, "`{line}` is not NAME=VALUE"),
            DeclarationError::UnknownName { name, what, known } => {
                write!(f, "`{name}` is no {what}; known: {}", known.join(", "))
            }
            DeclarationError::BadValue {
                name,
                value,
                expected,
            } => write!(f, "{name}={value}: expected {expected}"),
            DeclarationError::Conflict {
                name,
                first,
                second,
            } => write!(f, "{name} is declared twice: {first} and {second}"),
            DeclarationError::Read(error) => write!(f, "{error}"),
            DeclarationError::At { origin, error } => write!(f, "{origin}: {error}"),
        }
    }
}

impl std::error::Error for DeclarationError {}

impl From<ReadError> for DeclarationError {
    fn from(error: ReadError) -> Self {
        DeclarationError::Read(error)
    }
}

/// Why declarations cannot be read.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum ReadError {
    /// Not `NAME=VALUE`.
    Malformed {
        origin: Origin,
        text: String,
    },
    /// `@FILE` is no regular file (a FIFO would block, a device never end).
    NotAFile {
        path: PathBuf,
        kind: &'static str,
    },
    TooLarge {
        path: PathBuf,
    },
    Unreadable {
        path: PathBuf,
        error: String,
    },
    /// A JSON file that is no object of names and values.
    NotAnObject {
        path: PathBuf,
        error: String,
    },
    /// One name, two values.
    Contradiction {
        name: String,
        first: Box<Line>,
        second: Box<Line>,
    },
}

impl fmt::Display for ReadError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ReadError::Malformed { origin, text } => {
                write!(f, "{origin}: `{text}` is not NAME=VALUE")?;
                // `--declare choices.json`: the `@` forgotten.
                let names_a_file = !text.contains('=')
                    && (text.ends_with(".json") || std::path::Path::new(text).is_file());
                if *origin == Origin::Argument && names_a_file {
                    write!(f, " (a file of declarations is `--declare @{text}`)")?;
                }
                Ok(())
            }
            ReadError::NotAFile { path, kind } => write!(
                f,
                "--declare @{}: is {kind}, not a file (declarations are read from regular files only)",
                path.display()
            ),
            ReadError::TooLarge { path } => write!(
                f,
                "--declare @{}: larger than {MAX_FILE} bytes; a declaration is a few lines",
                path.display()
            ),
            ReadError::Unreadable { path, error } => {
                write!(f, "--declare @{}: {error}", path.display())
            }
            ReadError::NotAnObject { path, error } => write!(
                f,
                "--declare @{}: not NAME=VALUE lines, nor a JSON object of names and values: {error}",
                path.display()
            ),
            ReadError::Contradiction {
                name,
                first,
                second,
            } => write!(
                f,
                "`{name}` is declared twice, two ways: `{}` ({}) and `{}` ({})",
                first.text(),
                first.origin,
                second.text(),
                second.origin
            ),
        }
    }
}

impl std::error::Error for ReadError {}
