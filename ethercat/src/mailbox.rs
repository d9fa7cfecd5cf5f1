//! The mailbox header (ETG.1000.4 §5.6) and CoE SDO messages (ETG.1000.6
//! §5.6.2), both directions: a server parses requests and emits responses, a
//! client the other way round.

use std::fmt;

/// Mailbox header (6 bytes) + CoE header (2 bytes).
pub const HEADERS: usize = 8;
/// Mailbox type of CoE.
pub(crate) const TYPE_COE: u8 = 3;
/// CoE services.
pub(crate) const SERVICE_SDO_REQUEST: u16 = 2;
const SERVICE_SDO_RESPONSE: u16 = 3;
/// A segment carries at least 7 bytes; fewer are padding, counted in `n`.
const SEGMENT_MIN: usize = 7;

/// SDO abort codes (ETG.1000.6 Table 41) the server gives.
pub mod abort {
    pub const TOGGLE_BIT: u32 = 0x0503_0000;
    pub const COMMAND_SPECIFIER: u32 = 0x0504_0001;
    pub const UNSUPPORTED_ACCESS: u32 = 0x0601_0000;
    pub const WRITE_ONLY: u32 = 0x0601_0001;
    pub const READ_ONLY: u32 = 0x0601_0002;
    pub const NO_OBJECT: u32 = 0x0602_0000;
    pub const LENGTH: u32 = 0x0607_0010;
    pub const NO_SUBINDEX: u32 = 0x0609_0011;
    pub const VALUE_RANGE: u32 = 0x0609_0030;
    pub const GENERAL: u32 = 0x0800_0000;
    pub const DEVICE_STATE: u32 = 0x0800_0022;
}

/// What the client asks.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum SdoRequest {
    /// Initiate download; `size` is `None` for an expedited transfer (all of
    /// `data` in the request), else the whole length, of which `data` is the first part.
    Download {
        index: u16,
        sub: u8,
        complete_access: bool,
        size: Option<u32>,
        data: Vec<u8>,
    },
    DownloadSegment {
        toggle: bool,
        last: bool,
        data: Vec<u8>,
    },
    Upload {
        index: u16,
        sub: u8,
        complete_access: bool,
    },
    UploadSegment {
        toggle: bool,
    },
    Abort {
        index: u16,
        sub: u8,
        code: u32,
    },
}

/// What the server answers.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum SdoResponse {
    Download {
        index: u16,
        sub: u8,
    },
    DownloadSegment {
        toggle: bool,
    },
    /// `size` is `None` for an expedited answer, else the whole length.
    Upload {
        index: u16,
        sub: u8,
        size: Option<u32>,
        data: Vec<u8>,
    },
    UploadSegment {
        toggle: bool,
        last: bool,
        data: Vec<u8>,
    },
    Abort {
        index: u16,
        sub: u8,
        code: u32,
    },
}

/// Why bytes are no SDO message.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum MailboxError {
    Truncated { needed: usize, have: usize },
    NotCoe(u8),
    NotSdo(u16),
    CommandSpecifier(u8),
}

impl fmt::Display for MailboxError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            MailboxError::Truncated { needed, have } => {
                write!(f, "mailbox message of {have} bytes, {needed} needed")
            }
            MailboxError::NotCoe(t) => write!(f, "mailbox type {t}, not CoE (3)"),
            MailboxError::NotSdo(s) => write!(f, "CoE service {s}, not an SDO"),
            MailboxError::CommandSpecifier(c) => write!(f, "SDO command byte {c:#04x}"),
        }
    }
}

impl std::error::Error for MailboxError {}

fn u16_at(b: &[u8], at: usize) -> u16 {
    u16::from_le_bytes([b[at], b[at + 1]])
}

/// The SDO body of a mailbox message (from the command byte), after its
/// headers are checked, and the CoE service it came as (one of `services`).
fn body<'a>(bytes: &'a [u8], services: &[u16]) -> Result<(u16, &'a [u8]), MailboxError> {
    let truncated = |needed| MailboxError::Truncated {
        needed,
        have: bytes.len(),
    };
    if bytes.len() < HEADERS + 1 {
        return Err(truncated(HEADERS + 1));
    }
    let length = usize::from(u16_at(bytes, 0));
    if bytes.len() < 6 + length || length < 3 {
        return Err(truncated(6 + length.max(3)));
    }
    if bytes[5] & 0x0F != TYPE_COE {
        return Err(MailboxError::NotCoe(bytes[5] & 0x0F));
    }
    let coe = u16_at(bytes, 6) >> 12;
    if !services.contains(&coe) {
        return Err(MailboxError::NotSdo(coe));
    }
    Ok((coe, &bytes[HEADERS..6 + length]))
}

/// A message: mailbox header (with `counter`), CoE header, `sdo`, padded to `mailbox_size`.
pub(crate) fn message(service: u16, counter: u8, sdo: &[u8], mailbox_size: usize) -> Vec<u8> {
    let mut out = Vec::with_capacity(mailbox_size);
    out.extend_from_slice(&((sdo.len() + 2) as u16).to_le_bytes());
    out.extend_from_slice(&[0, 0, 0, TYPE_COE | (counter & 7) << 4]);
    out.extend_from_slice(&(service << 12).to_le_bytes());
    out.extend_from_slice(sdo);
    out.resize(out.len().max(mailbox_size), 0);
    out
}

/// Command byte, index, sub-index, four bytes.
fn initiate(command: u8, index: u16, sub: u8, four: [u8; 4]) -> Vec<u8> {
    let mut out = vec![command];
    out.extend_from_slice(&index.to_le_bytes());
    out.push(sub);
    out.extend_from_slice(&four);
    out
}

fn expedited(data: &[u8]) -> [u8; 4] {
    let mut four = [0; 4];
    four[..data.len()].copy_from_slice(data);
    four
}

/// A segment: command byte with `n` unused bytes, data padded to seven.
fn segment(command: u8, data: &[u8]) -> Vec<u8> {
    let unused = SEGMENT_MIN.saturating_sub(data.len()) as u8;
    let mut out = vec![command | unused << 1];
    out.extend_from_slice(data);
    out.resize(1 + data.len().max(SEGMENT_MIN), 0);
    out
}

fn segment_data(body: &[u8]) -> Vec<u8> {
    let unused = usize::from(body[0] >> 1 & 7);
    let data = &body[1..];
    if data.len() <= SEGMENT_MIN {
        data[..data.len().saturating_sub(unused)].to_vec()
    } else {
        data.to_vec()
    }
}

fn need(body: &[u8], needed: usize) -> Result<(), MailboxError> {
    if body.len() < needed {
        Err(MailboxError::Truncated {
            needed: HEADERS + needed,
            have: HEADERS + body.len(),
        })
    } else {
        Ok(())
    }
}

/// Bytes 1..8 of an initiate: index, sub-index, four bytes.
fn addressed(body: &[u8]) -> Result<(u16, u8, [u8; 4]), MailboxError> {
    need(body, 8)?;
    Ok((
        u16_at(body, 1),
        body[3],
        [body[4], body[5], body[6], body[7]],
    ))
}

impl SdoRequest {
    pub fn parse(bytes: &[u8]) -> Result<SdoRequest, MailboxError> {
        let (_, body) = body(bytes, &[SERVICE_SDO_REQUEST])?;
        let command = body[0];
        let complete_access = command & 0x10 != 0;
        Ok(match command >> 5 {
            0 => SdoRequest::DownloadSegment {
                toggle: command & 0x10 != 0,
                last: command & 1 != 0,
                data: segment_data(body),
            },
            1 => {
                let (index, sub, four) = addressed(body)?;
                if command & 0b10 != 0 {
                    let unused = usize::from(command >> 2 & 3);
                    SdoRequest::Download {
                        index,
                        sub,
                        complete_access,
                        size: None,
                        data: four[..4 - unused].to_vec(),
                    }
                } else {
                    SdoRequest::Download {
                        index,
                        sub,
                        complete_access,
                        size: Some(u32::from_le_bytes(four)),
                        data: body[8..].to_vec(),
                    }
                }
            }
            2 => {
                let (index, sub, _) = addressed(body)?;
                SdoRequest::Upload {
                    index,
                    sub,
                    complete_access,
                }
            }
            3 => SdoRequest::UploadSegment {
                toggle: command & 0x10 != 0,
            },
            4 => {
                let (index, sub, four) = addressed(body)?;
                SdoRequest::Abort {
                    index,
                    sub,
                    code: u32::from_le_bytes(four),
                }
            }
            _ => return Err(MailboxError::CommandSpecifier(command)),
        })
    }

    pub fn emit(&self, counter: u8, mailbox_size: usize) -> Vec<u8> {
        let ca = |complete_access: bool| if complete_access { 0x10 } else { 0 };
        let sdo = match self {
            SdoRequest::Download {
                index,
                sub,
                complete_access,
                size: None,
                data,
            } => initiate(
                0x23 | ((4 - data.len() as u8) << 2) | ca(*complete_access),
                *index,
                *sub,
                expedited(data),
            ),
            SdoRequest::Download {
                index,
                sub,
                complete_access,
                size: Some(size),
                data,
            } => {
                let mut out = initiate(
                    0x21 | ca(*complete_access),
                    *index,
                    *sub,
                    size.to_le_bytes(),
                );
                out.extend_from_slice(data);
                out
            }
            SdoRequest::DownloadSegment { toggle, last, data } => {
                segment(ca(*toggle) | u8::from(*last), data)
            }
            SdoRequest::Upload {
                index,
                sub,
                complete_access,
            } => initiate(0x40 | ca(*complete_access), *index, *sub, [0; 4]),
            SdoRequest::UploadSegment { toggle } => {
                let mut out = vec![0x60 | ca(*toggle)];
                out.resize(8, 0);
                out
            }
            SdoRequest::Abort { index, sub, code } => {
                initiate(0x80, *index, *sub, code.to_le_bytes())
            }
        };
        message(SERVICE_SDO_REQUEST, counter, &sdo, mailbox_size)
    }
}

impl SdoResponse {
    pub fn parse(bytes: &[u8]) -> Result<SdoResponse, MailboxError> {
        // An abort comes as an SDO request (ETG.1000.6 §5.6.2.7: "Abort SDO
        // Transfer Request", as SOES and a real terminal send it); older
        // stacks send it as a response. Both are the terminal's refusal.
        let (service, body) = body(bytes, &[SERVICE_SDO_RESPONSE, SERVICE_SDO_REQUEST])?;
        let command = body[0];
        if service == SERVICE_SDO_REQUEST && command >> 5 != 4 {
            return Err(MailboxError::NotSdo(service));
        }
        Ok(match command >> 5 {
            0 => SdoResponse::UploadSegment {
                toggle: command & 0x10 != 0,
                last: command & 1 != 0,
                data: segment_data(body),
            },
            1 => SdoResponse::DownloadSegment {
                toggle: command & 0x10 != 0,
            },
            2 => {
                let (index, sub, four) = addressed(body)?;
                if command & 0b10 != 0 {
                    let unused = usize::from(command >> 2 & 3);
                    SdoResponse::Upload {
                        index,
                        sub,
                        size: None,
                        data: four[..4 - unused].to_vec(),
                    }
                } else {
                    SdoResponse::Upload {
                        index,
                        sub,
                        size: Some(u32::from_le_bytes(four)),
                        data: body[8..].to_vec(),
                    }
                }
            }
            3 => {
                let (index, sub, _) = addressed(body)?;
                SdoResponse::Download { index, sub }
            }
            4 => {
                let (index, sub, four) = addressed(body)?;
                SdoResponse::Abort {
                    index,
                    sub,
                    code: u32::from_le_bytes(four),
                }
            }
            _ => return Err(MailboxError::CommandSpecifier(command)),
        })
    }

    pub fn emit(&self, counter: u8, mailbox_size: usize) -> Vec<u8> {
        let toggled = |toggle: bool| if toggle { 0x10 } else { 0 };
        let sdo = match self {
            SdoResponse::Download { index, sub } => initiate(0x60, *index, *sub, [0; 4]),
            SdoResponse::DownloadSegment { toggle } => {
                let mut out = vec![0x20 | toggled(*toggle)];
                out.resize(8, 0);
                out
            }
            SdoResponse::Upload {
                index,
                sub,
                size: None,
                data,
            } => initiate(
                0x43 | ((4 - data.len() as u8) << 2),
                *index,
                *sub,
                expedited(data),
            ),
            SdoResponse::Upload {
                index,
                sub,
                size: Some(size),
                data,
            } => {
                let mut out = initiate(0x41, *index, *sub, size.to_le_bytes());
                out.extend_from_slice(data);
                out
            }
            SdoResponse::UploadSegment { toggle, last, data } => {
                segment(toggled(*toggle) | u8::from(*last), data)
            }
            SdoResponse::Abort { index, sub, code } => {
                initiate(0x80, *index, *sub, code.to_le_bytes())
            }
        };
        // "Abort SDO Transfer" is a request, whichever end sends it
        // (ETG.1000.6 §5.6.2.7): a master reading service 3 only (SOEM)
        // took a refused download for a success.
        let service = match self {
            SdoResponse::Abort { .. } => SERVICE_SDO_REQUEST,
            _ => SERVICE_SDO_RESPONSE,
        };
        message(service, counter, &sdo, mailbox_size)
    }
}

/// How many data bytes one message of a mailbox this size carries after an
/// initiate (10 bytes of SDO header) and after a segment's command byte.
pub fn capacity(mailbox_size: usize) -> (usize, usize) {
    (mailbox_size - 16, mailbox_size - HEADERS - 1)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An expedited download of 0x8000:21 = 10 (u16), as a master sends it in a 128-byte mailbox.
    static EXPEDITED_DOWNLOAD: [u8; 16] = [
        0x0A, 0x00, 0x00, 0x00, 0x00, 0x13, // 10 bytes, CoE, counter 1
        0x00, 0x20, // SDO request
        0x2B, 0x00, 0x80, 0x21, // expedited, 2 bytes unused; 0x8000:21
        0x0A, 0x00, 0x00, 0x00,
    ];

    #[test]
    fn parses_an_expedited_download() {
        assert_eq!(
            SdoRequest::parse(&EXPEDITED_DOWNLOAD),
            Ok(SdoRequest::Download {
                index: 0x8000,
                sub: 0x21,
                complete_access: false,
                size: None,
                data: vec![0x0A, 0x00],
            })
        );
        let emitted = SdoRequest::parse(&EXPEDITED_DOWNLOAD).unwrap().emit(1, 128);
        assert_eq!(&emitted[..16], EXPEDITED_DOWNLOAD);
        assert_eq!(emitted.len(), 128);
    }

    /// The terminal refusing 0x8000:21 with 0x06090011 (no such
    /// sub-index), as SOES and a real terminal send it: CoE service 2.
    static ABORT: [u8; 16] = [
        0x0A, 0x00, 0x00, 0x00, 0x00, 0x23, // 10 bytes, CoE, counter 2
        0x00, 0x20, // SDO request: "Abort SDO Transfer Request"
        0x80, 0x00, 0x80, 0x21, // abort; 0x8000:21
        0x11, 0x00, 0x09, 0x06, // 0x06090011
    ];

    #[test]
    fn an_abort_is_sent_as_an_sdo_request_and_read_as_either() {
        let refusal = SdoResponse::Abort {
            index: 0x8000,
            sub: 0x21,
            code: abort::NO_SUBINDEX,
        };
        assert_eq!(refusal.emit(2, 16), ABORT);
        assert_eq!(SdoResponse::parse(&ABORT), Ok(refusal.clone()));
        // An older stack's abort, as a response (service 3), is a refusal too.
        let mut as_response = ABORT;
        as_response[7] = 0x30;
        assert_eq!(SdoResponse::parse(&as_response), Ok(refusal));
        // A service-2 message that is no abort is no answer.
        let mut upload = ABORT;
        upload[8] = 0x40;
        assert!(SdoResponse::parse(&upload).is_err());
    }

    #[test]
    fn every_message_survives_its_round_trip() {
        let requests = [
            SdoRequest::Download {
                index: 0x8001,
                sub: 0,
                complete_access: true,
                size: Some(42),
                data: vec![1; 30],
            },
            SdoRequest::DownloadSegment {
                toggle: true,
                last: true,
                data: vec![7; 3],
            },
            SdoRequest::Upload {
                index: 0x1C12,
                sub: 0,
                complete_access: false,
            },
            SdoRequest::UploadSegment { toggle: false },
            SdoRequest::Abort {
                index: 0x8000,
                sub: 0,
                code: abort::GENERAL,
            },
        ];
        for request in requests {
            assert_eq!(SdoRequest::parse(&request.emit(3, 64)), Ok(request));
        }
        let responses = [
            SdoResponse::Download {
                index: 0x8000,
                sub: 0x21,
            },
            SdoResponse::DownloadSegment { toggle: true },
            SdoResponse::Upload {
                index: 0x1A00,
                sub: 1,
                size: None,
                data: vec![0x10, 0x01, 0x00, 0x60],
            },
            SdoResponse::Upload {
                index: 0x1018,
                sub: 0,
                size: Some(200),
                data: vec![9; 40],
            },
            SdoResponse::UploadSegment {
                toggle: false,
                last: false,
                data: vec![5; 20],
            },
            SdoResponse::Abort {
                index: 0x6000,
                sub: 9,
                code: abort::NO_SUBINDEX,
            },
        ];
        for response in responses {
            assert_eq!(SdoResponse::parse(&response.emit(2, 64)), Ok(response));
        }
    }

    #[test]
    fn refuses_what_is_no_sdo() {
        let mut other = EXPEDITED_DOWNLOAD;
        other[5] = 0x14; // FoE
        assert_eq!(SdoRequest::parse(&other), Err(MailboxError::NotCoe(4)));
        assert!(matches!(
            SdoRequest::parse(&EXPEDITED_DOWNLOAD[..7]),
            Err(MailboxError::Truncated { .. })
        ));
        let mut response = EXPEDITED_DOWNLOAD;
        response[7] = 0x30;
        assert_eq!(SdoRequest::parse(&response), Err(MailboxError::NotSdo(3)));
    }
}
