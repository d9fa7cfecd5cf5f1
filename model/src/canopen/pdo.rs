//! Process data payloads of a coupler's PDOs.
//!
//! Source: 002 "Digital inputs/outputs" (1-8 bytes, I0 = first input byte from the
//! left), "Analog inputs/outputs" (4-8 bytes, Ix.0 low byte, Ix.1 high byte of
//! channel x, objects 0x6401/0x6411 are INTEGER16, CANopen little-endian).

/// Analog channel values as the PDO carries them: two bytes each, low byte first.
///
/// Requirements: PDO-002.
pub fn analog_payload(channels: &[i16]) -> Vec<u8> {
    channels
        .iter()
        .take(4)
        .flat_map(|value| value.to_le_bytes())
        .collect()
}

/// The channel values of an analog PDO payload (4-8 bytes, even length).
///
/// Requirements: PDO-002.
pub fn parse_analog(payload: &[u8]) -> Option<Vec<i16>> {
    if payload.len() < 4 || payload.len() > 8 || !payload.len().is_multiple_of(2) {
        return None;
    }
    Some(
        payload
            .chunks_exact(2)
            .map(|pair| i16::from_le_bytes([pair[0], pair[1]]))
            .collect(),
    )
}

/// Digital I/O bytes: 1-8 bytes, terminal bytes from left to right.
///
/// Requirements: PDO-001.
pub fn digital_payload(bytes: &[u8]) -> Option<&[u8]> {
    (1..=8).contains(&bytes.len()).then_some(bytes)
}

/// Index of the analog inputs' "interrupt enable" (event-driven transmission).
///
/// Requirements: PDO-003.
pub const ANALOG_INPUT_INTERRUPT_ENABLE: u16 = 0x6423;
/// Delta (0x6426), upper (0x6424) and lower (0x6425) limits, inhibit time (0x1801:03).
pub const ANALOG_INPUT_DELTA: u16 = 0x6426;
pub const ANALOG_INPUT_UPPER_LIMIT: u16 = 0x6424;
pub const ANALOG_INPUT_LOWER_LIMIT: u16 = 0x6425;
pub const TPDO2_PARAMETER: u16 = 0x1801;
