//! The images' number encoding, in one place: every multi-byte field is
//! little-endian (LAY-GEN-003). Every reader and writer of a field of up to
//! eight bytes goes through these two; the adapter protocol's shared records
//! (docs/adapter-protocol.md, "Protocol 3") use the same encoding.

use super::Field;

/// The little-endian number in `buf[field]` (at most 8 bytes).
#[inline]
pub const fn read(buf: &[u8], field: Field) -> u64 {
    assert!(field.end - field.start <= 8, "a field of at most 8 bytes");
    let (mut value, mut at) = (0u64, field.end);
    while at > field.start {
        at -= 1;
        value = (value << 8) | buf[at] as u64;
    }
    value
}

/// Writes the low `field.len()` bytes of `value` into `buf[field]`, least
/// significant first.
#[inline]
pub fn write(buf: &mut [u8], field: Field, mut value: u64) {
    assert!(field.len() <= 8, "a field of at most 8 bytes");
    for byte in &mut buf[field] {
        *byte = value as u8;
        value >>= 8;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fields_are_little_endian_of_their_width() {
        let mut buf = [0xEEu8; 10];
        write(&mut buf, 1..4, 0x0012_3456);
        assert_eq!(
            buf,
            [0xEE, 0x56, 0x34, 0x12, 0xEE, 0xEE, 0xEE, 0xEE, 0xEE, 0xEE]
        );
        assert_eq!(read(&buf, 1..4), 0x12_3456);
        assert_eq!(read(&buf, 1..3), 0x3456);
        write(&mut buf, 2..10, u64::MAX - 1);
        assert_eq!(read(&buf, 2..10), u64::MAX - 1);
        assert_eq!(read(b"CNF3", 0..4), 0x3346_4E43);
    }
}
