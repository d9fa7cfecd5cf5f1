//! Where everything lies in protocol 3's shared mapping
//! (docs/adapter-protocol.md, "Protocol 3"), written once: the header's
//! words, the two images, the request and answer records, and the fields of
//! a record and of its entries. All numbers are little-endian.

use std::ops::Range;

/// `"CNF3"`, at offset 0, written by the harness when it makes the mapping.
pub const MAGIC: u32 = canif_model::image::le::read(b"CNF3", 0..4) as u32;

/// The header's words (each a 32-bit atomic both processes touch).
pub mod header {
    pub const MAGIC: usize = 0;
    /// The harness adds one after writing a request.
    pub const REQUEST_SEQ: usize = 64;
    /// The implementation is (about to be) asleep on its eventfd: wake it.
    pub const IUT_ASLEEP: usize = 68;
    /// The implementation sets it to the request's sequence number after
    /// writing the answer.
    pub const ANSWER_SEQ: usize = 128;
    /// The harness is (about to be) asleep on its eventfd: wake it.
    pub const HARNESS_ASLEEP: usize = 132;
}

/// The output image (a device's outputs; the buffer a client's task is
/// handed and leaves).
pub const OUTPUTS_AT: usize = 4096;
/// The input image.
pub const INPUTS_AT: usize = OUTPUTS_AT + IMAGE_ROOM;
/// Room for either image: more than any layout needs (32 FD slots).
pub const IMAGE_ROOM: usize = 65536;
/// The request record.
pub const REQUEST_AT: usize = INPUTS_AT + IMAGE_ROOM;
/// The answer record.
pub const ANSWER_AT: usize = REQUEST_AT + RECORD_ROOM;
/// Room for a record: its head and [`MAX_ENTRIES`] entries, to whole pages.
pub const RECORD_ROOM: usize = (record::ENTRIES + MAX_ENTRIES * entry::SIZE).div_ceil(4096) * 4096;
/// The most entries one record holds.
pub const MAX_ENTRIES: usize = 4096;
/// The whole mapping.
pub const SIZE: usize = ANSWER_AT + RECORD_ROOM;

/// A record's head.
pub mod record {
    use super::Range;
    /// What the record is (`Kind`).
    pub const KIND: Range<usize> = 0..4;
    /// How many entries follow (an error: the bytes of its text).
    pub const COUNT: Range<usize> = 4..8;
    /// The request's time (`now_ns`, `end_ns`), or an answer's `next_ns`
    /// (`u64::MAX`: none).
    pub const TIME: Range<usize> = 8..16;
    /// The length of the output image the record carries (0: none).
    pub const OUTPUTS_LEN: Range<usize> = 16..20;
    /// The length of the input image the record carries (0: none).
    pub const INPUTS_LEN: Range<usize> = 20..24;
    pub const ENTRIES: usize = 24;
}

/// One entry: a bus event, a planned frame, a message, or a number.
pub mod entry {
    use super::Range;
    pub const SIZE: usize = 96;
    pub const TAG: Range<usize> = 0..4;
    /// The status flags, an index, or a text's length.
    pub const AUX: Range<usize> = 4..8;
    /// `end_ns`, `at_ns` or `not_before_ns`.
    pub const TIME: Range<usize> = 8..16;
    pub const ID: Range<usize> = 16..20;
    /// Bit 0 extended, 1 rtr, 2 fd, 3 brs, 4 esi.
    pub const FLAGS: usize = 20;
    pub const LEN: usize = 21;
    pub const TRANSACTION_NUMBER: Range<usize> = 22..24;
    /// The frame's data, a text (at most 64 bytes), or a status's counters.
    pub const DATA: Range<usize> = 24..88;
    pub const TIME_STAMP: Range<usize> = 88..96;
}

#[cfg(test)]
mod tests {
    use super::*;

    /// docs/adapter-protocol.md's table and the Python example use these numbers.
    #[test]
    fn the_offsets_are_the_documents() {
        assert_eq!(
            (OUTPUTS_AT, INPUTS_AT, REQUEST_AT, ANSWER_AT, SIZE),
            (4096, 69_632, 135_168, 532_480, 929_792)
        );
        assert_eq!((record::ENTRIES, entry::SIZE), (24, 96));
    }
}
