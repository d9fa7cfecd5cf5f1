//! Expedited SDO: reading and writing up to 4 bytes of an object dictionary entry.
//!
//! Source: 004 (upload response 0x4F/0x4B/0x47/0x43, download request 0x22 or
//! 0x2F/0x2B/0x27/0x23, download response 0x60; index little-endian, then
//! sub-index, then data LSB first), 002 (0x6423 and 0x1017 examples), rulings R7
//! (request id 0x600 = 1536) and R8 (abort: 0x80, index, sub-index, 4-byte code).

/// The CiA 301 abort codes the suite uses.
///
/// Requirements: SDO-007, ERR-R8.
pub mod abort_code {
    pub const COMMAND_SPECIFIER_INVALID: u32 = 0x0504_0001;
    pub const OBJECT_DOES_NOT_EXIST: u32 = 0x0602_0000;
    pub const LENGTH_MISMATCH: u32 = 0x0607_0010;
    pub const SUB_INDEX_DOES_NOT_EXIST: u32 = 0x0609_0011;
    pub const READ_ONLY: u32 = 0x0601_0002;
    pub const VALUE_RANGE_EXCEEDED: u32 = 0x0609_0030;
}

/// A client's request (on 0x600 + node id).
///
/// Requirements: SDO-002, SDO-003, SDO-004.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SdoRequest {
    /// Initiate upload: command byte 0x40.
    Upload { index: u16, sub_index: u8 },
    /// Expedited download. `size: None` is 0x22 (size not indicated); `Some(n)`,
    /// n in 1..=4, is 0x2F, 0x2B, 0x27, 0x23.
    Download {
        index: u16,
        sub_index: u8,
        data: [u8; 4],
        size: Option<u8>,
    },
    Abort {
        index: u16,
        sub_index: u8,
        code: u32,
    },
}

/// A server's response (on 0x580 + node id).
///
/// Requirements: SDO-005, SDO-006, SDO-007.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SdoResponse {
    /// Expedited upload with size: 0x4F (1 byte), 0x4B, 0x47, 0x43 (4 bytes).
    Upload {
        index: u16,
        sub_index: u8,
        data: [u8; 4],
        size: u8,
    },
    /// Download confirmed: 0x60, the data bytes 0.
    DownloadAck { index: u16, sub_index: u8 },
    Abort {
        index: u16,
        sub_index: u8,
        code: u32,
    },
}

/// Why 8 bytes are not a telegram this module knows.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SdoError {
    WrongLength(usize),
    UnknownCommand(u8),
}

const UPLOAD_REQUEST: u8 = 0x40;
const DOWNLOAD_NO_SIZE: u8 = 0x22;
const DOWNLOAD_ACK: u8 = 0x60;
const ABORT: u8 = 0x80;

/// Command byte of an expedited transfer with `n` (1..=4) bytes indicated:
/// `base | (4 - n) << 2 | 0b11` (0x43 family for upload, 0x23 for download).
///
/// Requirements: SDO-003, SDO-005.
pub fn sized_command(base: u8, n: u8) -> u8 {
    base | ((4 - n.clamp(1, 4)) << 2) | 0b11
}

fn size_of_command(command: u8) -> u8 {
    4 - ((command >> 2) & 0b11)
}

fn header(command: u8, index: u16, sub_index: u8) -> [u8; 8] {
    let [low, high] = index.to_le_bytes();
    [command, low, high, sub_index, 0, 0, 0, 0]
}

fn with_data(mut bytes: [u8; 8], data: [u8; 4]) -> [u8; 8] {
    bytes[4..].copy_from_slice(&data);
    bytes
}

fn split(bytes: &[u8]) -> Result<(u8, u16, u8, [u8; 4]), SdoError> {
    let bytes: &[u8; 8] = bytes
        .try_into()
        .map_err(|_| SdoError::WrongLength(bytes.len()))?;
    let index = u16::from_le_bytes([bytes[1], bytes[2]]);
    Ok((
        bytes[0],
        index,
        bytes[3],
        [bytes[4], bytes[5], bytes[6], bytes[7]],
    ))
}

impl SdoRequest {
    /// An expedited download (0x22) of `value`; the node takes the entry's length.
    ///
    /// Requirements: SDO-003, SDO-004.
    pub fn download(index: u16, sub_index: u8, value: u32) -> Self {
        SdoRequest::Download {
            index,
            sub_index,
            data: value.to_le_bytes(),
            size: None,
        }
    }

    pub fn to_bytes(self) -> [u8; 8] {
        match self {
            SdoRequest::Upload { index, sub_index } => header(UPLOAD_REQUEST, index, sub_index),
            SdoRequest::Download {
                index,
                sub_index,
                data,
                size,
            } => {
                let command = size.map_or(DOWNLOAD_NO_SIZE, |n| sized_command(0x20, n));
                with_data(header(command, index, sub_index), data)
            }
            SdoRequest::Abort {
                index,
                sub_index,
                code,
            } => with_data(header(ABORT, index, sub_index), code.to_le_bytes()),
        }
    }

    pub fn parse(bytes: &[u8]) -> Result<Self, SdoError> {
        let (command, index, sub_index, data) = split(bytes)?;
        match command {
            UPLOAD_REQUEST => Ok(SdoRequest::Upload { index, sub_index }),
            DOWNLOAD_NO_SIZE => Ok(SdoRequest::Download {
                index,
                sub_index,
                data,
                size: None,
            }),
            0x23 | 0x27 | 0x2B | 0x2F => Ok(SdoRequest::Download {
                index,
                sub_index,
                data,
                size: Some(size_of_command(command)),
            }),
            ABORT => Ok(SdoRequest::Abort {
                index,
                sub_index,
                code: u32::from_le_bytes(data),
            }),
            other => Err(SdoError::UnknownCommand(other)),
        }
    }
}

impl SdoResponse {
    /// An expedited upload response with `value` in its first `size` bytes.
    ///
    /// Requirements: SDO-005.
    pub fn upload(index: u16, sub_index: u8, value: u32, size: u8) -> Self {
        SdoResponse::Upload {
            index,
            sub_index,
            data: value.to_le_bytes(),
            size,
        }
    }

    /// The value an upload response carries; `None` for any other response.
    pub fn value(&self) -> Option<u32> {
        match self {
            SdoResponse::Upload { data, .. } => Some(u32::from_le_bytes(*data)),
            _ => None,
        }
    }

    pub fn to_bytes(self) -> [u8; 8] {
        match self {
            SdoResponse::Upload {
                index,
                sub_index,
                data,
                size,
            } => with_data(header(sized_command(0x40, size), index, sub_index), data),
            SdoResponse::DownloadAck { index, sub_index } => header(DOWNLOAD_ACK, index, sub_index),
            SdoResponse::Abort {
                index,
                sub_index,
                code,
            } => with_data(header(ABORT, index, sub_index), code.to_le_bytes()),
        }
    }

    pub fn parse(bytes: &[u8]) -> Result<Self, SdoError> {
        let (command, index, sub_index, data) = split(bytes)?;
        match command {
            0x43 | 0x47 | 0x4B | 0x4F => Ok(SdoResponse::Upload {
                index,
                sub_index,
                data,
                size: size_of_command(command),
            }),
            DOWNLOAD_ACK => Ok(SdoResponse::DownloadAck { index, sub_index }),
            ABORT => Ok(SdoResponse::Abort {
                index,
                sub_index,
                code: u32::from_le_bytes(data),
            }),
            other => Err(SdoError::UnknownCommand(other)),
        }
    }
}
