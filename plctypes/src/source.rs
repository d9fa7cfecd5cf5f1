//! A user's declaration file as text: plain ST (`.st`, an exported `.TcGVL`…)
//! or a TwinCAT `.TcDUT`, whose `<Declaration>` holds the ST. Lines are
//! always the file's own, so an error points where the user looks.

use std::io::Read;
use std::path::Path;

use quick_xml::events::Event;
use quick_xml::Reader;

use crate::error::{Cause, DeclarationError, Place};

/// No declaration of an image comes near this; a larger file is something else.
pub const MAX_FILE_BYTES: usize = 4 << 20;

/// ST text, and the file line its first line is on.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Source {
    pub file: String,
    pub text: String,
    pub first_line: usize,
}

impl Source {
    /// Reads `path` (at most [`MAX_FILE_BYTES`]; a FIFO or device is read
    /// only that far).
    pub fn read(path: &Path) -> Result<Vec<Source>, DeclarationError> {
        let file = path.display().to_string();
        let failed = |cause| DeclarationError {
            place: Place {
                file: file.clone(),
                line: 0,
            },
            cause,
        };
        let metadata =
            std::fs::metadata(path).map_err(|e| failed(Cause::Unreadable(e.to_string())))?;
        if !metadata.is_file() {
            return Err(failed(Cause::Unreadable("not a regular file".into())));
        }
        let mut bytes = Vec::new();
        std::fs::File::open(path)
            .and_then(|f| {
                f.take(MAX_FILE_BYTES as u64 + 1)
                    .read_to_end(&mut bytes)
                    .map(|_| ())
            })
            .map_err(|e| failed(Cause::Unreadable(e.to_string())))?;
        Self::of_bytes(&file, &bytes)
    }

    /// `bytes` as the file `file`: a `.TcDUT`'s declarations, or the text itself.
    pub fn of_bytes(file: &str, bytes: &[u8]) -> Result<Vec<Source>, DeclarationError> {
        let failed = |cause| DeclarationError {
            place: Place {
                file: file.to_string(),
                line: 0,
            },
            cause,
        };
        if bytes.len() > MAX_FILE_BYTES {
            return Err(failed(Cause::TooLarge {
                limit: MAX_FILE_BYTES,
            }));
        }
        let text = std::str::from_utf8(bytes).map_err(|_| failed(Cause::NotText))?;
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        if text
            .chars()
            .any(|c| c.is_control() && !matches!(c, '\n' | '\r' | '\t'))
        {
            return Err(failed(Cause::NotText));
        }
        if text.trim_start().starts_with('<') {
            return tc_dut(file, text);
        }
        Ok(vec![Source {
            file: file.to_string(),
            text: text.to_string(),
            first_line: 1,
        }])
    }
}

/// The `<Declaration>` texts of a TwinCAT XML file.
fn tc_dut(file: &str, text: &str) -> Result<Vec<Source>, DeclarationError> {
    let line_at = |at: usize| 1 + text[..at.min(text.len())].matches('\n').count();
    let mut reader = Reader::from_str(text);
    let mut inside = false;
    let mut found = Vec::new();
    loop {
        let before = usize::try_from(reader.buffer_position()).unwrap_or(0);
        let event = reader.read_event().map_err(|e| DeclarationError {
            place: Place {
                file: file.to_string(),
                line: line_at(usize::try_from(reader.error_position()).unwrap_or(0)),
            },
            cause: Cause::Xml(e.to_string()),
        })?;
        match event {
            Event::Start(tag) if tag.name().as_ref() == b"Declaration" => inside = true,
            Event::End(tag) if tag.name().as_ref() == b"Declaration" => inside = false,
            Event::CData(data) if inside => {
                let body = String::from_utf8_lossy(&data.into_inner()).into_owned();
                found.push(Source {
                    file: file.to_string(),
                    text: body,
                    // `<![CDATA[` begins the text on its own line.
                    first_line: line_at(before),
                });
            }
            Event::Eof => break,
            _ => {}
        }
    }
    if found.is_empty() {
        return Err(DeclarationError {
            place: Place {
                file: file.to_string(),
                line: 1,
            },
            cause: Cause::NoDeclaration,
        });
    }
    Ok(found)
}

#[cfg(test)]
mod tests {
    use super::*;

    const DUT: &str = r#"<?xml version="1.0" encoding="utf-8"?>
<TcPlcObject Version="1.1.0.1" ProductVersion="3.1.4024.12">
  <DUT Name="ST_CanOut" Id="{8a5b3c1e-0000-0000-0000-000000000000}">
    <Declaration><![CDATA[{attribute 'pack_mode' := '0'}
TYPE ST_CanOut :
STRUCT
    TxCounter : UINT;
END_STRUCT
END_TYPE
]]></Declaration>
  </DUT>
</TcPlcObject>"#;

    #[test]
    fn a_tcdut_gives_its_declaration_on_the_files_lines() {
        let sources = Source::of_bytes("ST_CanOut.TcDUT", DUT.as_bytes()).expect("read");
        assert_eq!(sources.len(), 1);
        assert_eq!(sources[0].first_line, 4);
        assert!(sources[0].text.starts_with("{attribute"));
    }

    #[test]
    fn binary_and_broken_xml_are_named_errors() {
        let binary = Source::of_bytes("x.st", &[0x7f, b'E', b'L', b'F', 0, 1]).unwrap_err();
        assert_eq!(binary.cause, Cause::NotText);
        let broken = Source::of_bytes("x.TcDUT", b"<TcPlcObject><DUT></TcPlcObject>").unwrap_err();
        assert!(matches!(broken.cause, Cause::Xml(_)), "{broken}");
    }
}
