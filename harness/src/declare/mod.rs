//! What an implementation declares it is, for either role: a device's
//! choices where the documents leave one ([`choices`], docs/choices.md), a
//! client's interfaces, geometry and ways of working ([`client`],
//! docs/plc-side.md).
//!
//! Both are `NAME=VALUE` lines, and both sides read them here, one way:
//! from the command line (`--declare NAME=VALUE`), from a file
//! (`--declare @FILE`: such lines, or a JSON object of names and values as
//! `canif probe` writes it), and from the implementation itself. A name
//! declared twice with two values is refused, naming both places.

pub mod choices;
pub mod client;
mod error;
mod judged;

use std::fmt;
use std::io::Read as _;
use std::path::{Path, PathBuf};

pub use error::{DeclarationError, ReadError};
pub use judged::{ChoiceEntry, ChoiceSource};

/// What an implementation declares of itself, one `NAME=VALUE` line at a
/// time: a device's choices ([`choices::Declared`]) or what a client is
/// ([`client::ClientDeclaration`]). Both are read the one way this module
/// reads them, and refused with the one [`DeclarationError`].
pub trait Declaration: Default + Clone + fmt::Debug {
    /// Takes one `NAME=VALUE` line.
    fn declare(&mut self, line: &str) -> Result<(), DeclarationError>;

    /// Each declared name as `NAME=VALUE`, in a fixed order.
    fn lines(&self) -> Vec<String>;

    /// What `--declare` arguments declare (`NAME=VALUE` or `@FILE` each):
    /// a line that cannot be taken is refused, naming where it was made.
    fn read(arguments: &[String]) -> Result<Self, DeclarationError> {
        let mut declared = Self::default();
        for line in read_arguments(arguments)? {
            declared
                .declare(&line.text())
                .map_err(|error| DeclarationError::At {
                    origin: line.origin.clone(),
                    error: Box::new(error),
                })?;
        }
        Ok(declared)
    }

    /// What these lines declare (as an implementation gives them, or as
    /// [`Declaration::lines`] wrote them); the first that cannot be taken refuses all.
    fn parse<S: AsRef<str>>(lines: &[S]) -> Result<Self, DeclarationError> {
        let mut declared = Self::default();
        for line in lines {
            declared.declare(line.as_ref())?;
        }
        Ok(declared)
    }
}

/// What the implementation under test declared of itself in one scenario
/// run, as the side that ran it reads declarations.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub enum Declares {
    /// Nothing, or nothing it can declare (a built-in implementation).
    #[default]
    Nothing,
    /// A device's choices (the protocol's `configured` answer).
    Device(choices::Declared),
    /// What a client is (its `started` answer, a library's function).
    Client(client::ClientDeclaration),
}

impl Declares {
    /// Each declared name as `NAME=VALUE`.
    pub fn lines(&self) -> Vec<String> {
        match self {
            Declares::Nothing => Vec::new(),
            Declares::Device(declared) => declared.lines(),
            Declares::Client(declared) => declared.lines(),
        }
    }

    /// The device's choices it declared (none from a client or nothing).
    pub fn device(&self) -> choices::Declared {
        match self {
            Declares::Device(declared) => *declared,
            _ => choices::Declared::default(),
        }
    }
}

/// The largest declaration file read: far above any declaration (a few
/// hundred bytes), far below what could fill memory (`@/dev/zero`).
pub const MAX_FILE: u64 = 64 * 1024;

/// Where a declaration was made.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Origin {
    /// `--declare NAME=VALUE`.
    Argument,
    /// A line of `--declare @FILE` (1-based; a JSON file's entries count from 1 too).
    File { path: PathBuf, line: usize },
    /// The implementation's own (the protocol's answer, the C ABI's function).
    Implementation,
}

impl fmt::Display for Origin {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Origin::Argument => f.write_str("--declare"),
            Origin::File { path, line } => write!(f, "--declare @{}, line {line}", path.display()),
            Origin::Implementation => f.write_str("the implementation's own declaration"),
        }
    }
}

/// One `NAME=VALUE`, and where it was made.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Line {
    pub name: String,
    pub value: String,
    pub origin: Origin,
}

impl Line {
    /// `NAME=VALUE`, as each side's declaration takes it.
    pub fn text(&self) -> String {
        format!("{}={}", self.name, self.value)
    }
}

/// The declarations of `--declare` arguments, in order, each `NAME=VALUE`
/// or `@FILE`; a name declared again with another value is refused.
pub fn read_arguments(arguments: &[String]) -> Result<Vec<Line>, ReadError> {
    let mut lines = Vec::new();
    for argument in arguments {
        match argument.strip_prefix('@') {
            Some(path) => lines.extend(read_file(Path::new(path))?),
            None => lines.push(split(argument, Origin::Argument)?),
        }
    }
    refuse_contradictions(&lines)?;
    Ok(lines)
}

/// `lines` and `more` together; a name both declare with different values
/// is refused, naming both places.
pub fn merge(lines: &[Line], more: &[Line]) -> Result<Vec<Line>, ReadError> {
    let all: Vec<Line> = lines.iter().chain(more).cloned().collect();
    refuse_contradictions(&all)?;
    Ok(all)
}

fn refuse_contradictions(lines: &[Line]) -> Result<(), ReadError> {
    for (at, line) in lines.iter().enumerate() {
        if let Some(first) = lines[..at]
            .iter()
            .find(|l| l.name == line.name && l.value != line.value)
        {
            return Err(ReadError::Contradiction {
                name: line.name.clone(),
                first: Box::new(first.clone()),
                second: Box::new(line.clone()),
            });
        }
    }
    Ok(())
}

fn split(text: &str, origin: Origin) -> Result<Line, ReadError> {
    match text.split_once('=') {
        Some((name, value)) if !name.trim().is_empty() => Ok(Line {
            name: name.trim().to_string(),
            value: value.trim().to_string(),
            origin,
        }),
        _ => Err(ReadError::Malformed {
            origin,
            text: text.to_string(),
        }),
    }
}

/// The declarations of a file: `NAME=VALUE` lines (blank lines and `#`
/// comments left out), or a JSON object of names and values. Only a
/// regular file is opened, and never read past [`MAX_FILE`].
pub fn read_file(path: &Path) -> Result<Vec<Line>, ReadError> {
    let unreadable = |error: std::io::Error| ReadError::Unreadable {
        path: path.to_path_buf(),
        error: error.to_string(),
    };
    // Opening a FIFO for reading waits for a writer: look before opening.
    let kind = std::fs::metadata(path).map_err(unreadable)?.file_type();
    if !kind.is_file() {
        use std::os::unix::fs::FileTypeExt;
        let kind = match () {
            _ if kind.is_dir() => "a directory",
            _ if kind.is_fifo() => "a FIFO",
            _ if kind.is_char_device() || kind.is_block_device() => "a device",
            _ if kind.is_socket() => "a socket",
            _ => "no regular file",
        };
        return Err(ReadError::NotAFile {
            path: path.to_path_buf(),
            kind,
        });
    }
    let mut bytes = Vec::new();
    std::fs::File::open(path)
        .map_err(unreadable)?
        .take(MAX_FILE + 1)
        .read_to_end(&mut bytes)
        .map_err(unreadable)?;
    if bytes.len() as u64 > MAX_FILE {
        return Err(ReadError::TooLarge {
            path: path.to_path_buf(),
        });
    }
    let text = String::from_utf8(bytes).map_err(|e| ReadError::Unreadable {
        path: path.to_path_buf(),
        error: format!("not UTF-8 text ({e})"),
    })?;
    let at = |line| Origin::File {
        path: path.to_path_buf(),
        line,
    };
    if text.trim_start().starts_with('{') {
        let object: serde_json::Map<String, serde_json::Value> = serde_json::from_str(&text)
            .map_err(|e| ReadError::NotAnObject {
                path: path.to_path_buf(),
                error: e.to_string(),
            })?;
        return Ok(object
            .into_iter()
            .enumerate()
            .map(|(n, (name, value))| Line {
                name,
                value: match value {
                    serde_json::Value::String(text) => text,
                    other => other.to_string(),
                },
                origin: at(n + 1),
            })
            .collect());
    }
    text.lines()
        .enumerate()
        .filter(|(_, line)| !line.trim().is_empty() && !line.trim_start().starts_with('#'))
        .map(|(n, line)| split(line.trim(), at(n + 1)))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("canif-declare-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    #[test]
    fn one_name_two_values_is_refused_naming_both() {
        let error = read_arguments(&["a=1".into(), "a=2".into()]).unwrap_err();
        assert!(
            matches!(&error, ReadError::Contradiction { name, .. } if name == "a"),
            "{error}"
        );
        assert!(error.to_string().contains("`a=1`") && error.to_string().contains("`a=2`"));
        // The same value twice says nothing new.
        assert_eq!(
            read_arguments(&["a=1".into(), "a=1".into()]).unwrap().len(),
            2
        );
    }

    #[test]
    fn a_file_holds_lines_or_a_json_object_alike() {
        let dir = scratch("forms");
        std::fs::write(dir.join("lines"), "# a comment\n\nx=1\ny = two\n").unwrap();
        std::fs::write(dir.join("json"), r#"{"x": "1", "y": "two"}"#).unwrap();
        for file in ["lines", "json"] {
            let lines = read_file(&dir.join(file)).unwrap();
            let texts: Vec<String> = lines.iter().map(Line::text).collect();
            assert_eq!(texts, ["x=1", "y=two"], "{file}");
        }
        let error = read_file(&dir.join("lines")).map(|_| ()).and_then(|()| {
            std::fs::write(dir.join("bad"), "x=1\nnot a line\n").unwrap();
            read_file(&dir.join("bad")).map(|_| ())
        });
        assert!(
            error.unwrap_err().to_string().contains("line 2"),
            "a bad line is named by its number"
        );
    }

    /// `@FIFO` hung and `@/dev/zero` grew to 1 GiB (issue 34).
    #[test]
    fn a_fifo_a_device_and_a_huge_file_are_refused_without_reading() {
        let dir = scratch("special");
        let fifo = dir.join("fifo");
        assert!(std::process::Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .unwrap()
            .success());
        assert!(matches!(
            read_file(&fifo),
            Err(ReadError::NotAFile { kind: "a FIFO", .. })
        ));
        assert!(matches!(
            read_file(Path::new("/dev/zero")),
            Err(ReadError::NotAFile {
                kind: "a device",
                ..
            })
        ));
        std::fs::write(dir.join("huge"), vec![b'#'; MAX_FILE as usize + 1]).unwrap();
        assert!(matches!(
            read_file(&dir.join("huge")),
            Err(ReadError::TooLarge { .. })
        ));
    }
}
