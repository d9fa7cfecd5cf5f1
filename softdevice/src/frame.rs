/// Valid CAN FD data field sizes (ISO 11898-1: DLC 9..15 → 12, 16, 20, 24, 32, 48, 64).
pub(crate) const FD_SIZES: [usize; 16] = [0, 1, 2, 3, 4, 5, 6, 7, 8, 12, 16, 20, 24, 32, 48, 64];

/// A frame as the soft device's CAN controller sees it.
///
/// `len` is the data length on the wire (for a remote frame: the requested
/// length); `data[len..]` is zero. A faulty device may produce a length that
/// is no valid FD size.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CanFrame {
    pub id: u32,
    pub extended: bool,
    pub remote: bool,
    pub fd: bool,
    pub brs: bool,
    pub esi: bool,
    pub len: usize,
    pub data: [u8; 64],
}

impl Default for CanFrame {
    fn default() -> Self {
        CanFrame {
            id: 0,
            extended: false,
            remote: false,
            fd: false,
            brs: false,
            esi: false,
            len: 0,
            data: [0; 64],
        }
    }
}
