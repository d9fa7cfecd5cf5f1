//! CAN FD data length code (DLC) and the rounding of lengths to valid sizes.
//!
//! Source: 000/001 §8.3.1 "Datenlänge", corrected by ruling R1: ISO 11898-1:2015
//! maps DLC 9..=15 to 12, 16, 20, 24, **32**, 48, 64 bytes (the manual prints 36).

/// Data field size in bytes for each DLC value 0..=15 of a CAN FD frame.
///
/// Requirements: FD-LEN-002, ERR-R1.
pub const FD_DATA_SIZES: [u8; 16] = [0, 1, 2, 3, 4, 5, 6, 7, 8, 12, 16, 20, 24, 32, 48, 64];

/// The largest data field of a CAN FD frame.
pub const FD_MAX_LEN: u8 = 64;

/// The largest data field of a classic CAN frame.
pub const CLASSIC_MAX_LEN: u8 = 8;

/// Data field size of an FD frame with this DLC; `None` for DLC > 15.
///
/// Requirements: FD-LEN-002.
pub fn fd_data_size(dlc: u8) -> Option<u8> {
    FD_DATA_SIZES.get(usize::from(dlc)).copied()
}

/// DLC of an FD frame whose data field has exactly `len` bytes; `None` when
/// `len` is not one of the 16 valid sizes.
///
/// Requirements: FD-LEN-002.
pub fn fd_dlc(len: u8) -> Option<u8> {
    FD_DATA_SIZES
        .iter()
        .position(|&size| size == len)
        .map(|dlc| dlc as u8)
}

/// The least valid FD data size that is at least `len`: what the device sends
/// for a Tx message of `len` bytes. `None` for `len > 64` (invalid input, G3).
///
/// Requirements: FD-LEN-003, FD-LEN-004, ERR-R1.
pub fn fd_round_up(len: u8) -> Option<u8> {
    FD_DATA_SIZES.iter().copied().find(|&size| size >= len)
}

/// The DLC the device puts on the bus for a Tx message of `len` bytes.
///
/// Requirements: FD-LEN-003, ERR-R1.
pub fn fd_dlc_for_length(len: u8) -> Option<u8> {
    fd_round_up(len).and_then(fd_dlc)
}
