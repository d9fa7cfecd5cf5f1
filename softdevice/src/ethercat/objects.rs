//! The EL6751's objects, numbered as Beckhoff's public object description
//! of the CAN interface numbers them, and the sub-indices and values that
//! description leaves open, as docs/ethercat.md assumes them.

/// Object indices.
pub mod object {
    pub const DEVICE_TYPE: u16 = 0x1000;
    pub const DEVICE_NAME: u16 = 0x1008;
    pub const HARDWARE_VERSION: u16 = 0x1009;
    pub const SOFTWARE_VERSION: u16 = 0x100A;
    pub const IDENTITY: u16 = 0x1018;
    pub const RX_PDO_MAP: u16 = 0x1600;
    pub const TX_PDO_MAP: u16 = 0x1A00;
    /// TxPDO-Map CAN Status: `0xF108` behind the interface's inputs.
    pub const STATUS_PDO_MAP: u16 = 0x1A85;
    pub const SYNC_MANAGER_TYPES: u16 = 0x1C00;
    pub const RX_PDO_ASSIGN: u16 = 0x1C12;
    pub const TX_PDO_ASSIGN: u16 = 0x1C13;
    pub const SYNC_OUTPUTS: u16 = 0x1C32;
    pub const SYNC_INPUTS: u16 = 0x1C33;
    pub const INPUTS_11: u16 = 0x6000;
    pub const INPUTS_29: u16 = 0x6001;
    pub const OUTPUTS_11: u16 = 0x7000;
    pub const OUTPUTS_29: u16 = 0x7001;
    pub const INTERFACE: u16 = 0x8000;
    pub const FILTERS: u16 = 0x8001;
    pub const MODULAR_DEVICE: u16 = 0xF000;
    pub const CAN_STATUS: u16 = 0xF108;
    /// InfoData (000 §8.3.3) where a terminal offers it: not an EL6751
    /// object (no EL6751 profile offers InfoData); canif's number.
    pub const INFO_DATA: u16 = 0xF109;
    pub const BUS_PARAMETERS: u16 = 0xF800;

    /// Every object, in order (SDO Information's OD list).
    pub const ALL: [u16; 23] = [
        DEVICE_TYPE,
        DEVICE_NAME,
        HARDWARE_VERSION,
        SOFTWARE_VERSION,
        IDENTITY,
        RX_PDO_MAP,
        TX_PDO_MAP,
        STATUS_PDO_MAP,
        SYNC_MANAGER_TYPES,
        RX_PDO_ASSIGN,
        TX_PDO_ASSIGN,
        SYNC_OUTPUTS,
        SYNC_INPUTS,
        INPUTS_11,
        INPUTS_29,
        OUTPUTS_11,
        OUTPUTS_29,
        INTERFACE,
        FILTERS,
        MODULAR_DEVICE,
        CAN_STATUS,
        INFO_DATA,
        BUS_PARAMETERS,
    ];

    /// The object's name in the EL6751's description.
    pub fn name(index: u16) -> &'static str {
        match index {
            DEVICE_TYPE => "Device type",
            DEVICE_NAME => "Device name",
            HARDWARE_VERSION => "Hardware version",
            SOFTWARE_VERSION => "Software version",
            IDENTITY => "Identity",
            RX_PDO_MAP => "RxPDO-Map CAN Interface",
            TX_PDO_MAP => "TxPDO-Map CAN Interface",
            STATUS_PDO_MAP => "TxPDO-Map CAN Status",
            SYNC_MANAGER_TYPES => "Sync manager type",
            RX_PDO_ASSIGN => "RxPDO assign",
            TX_PDO_ASSIGN => "TxPDO assign",
            SYNC_OUTPUTS => "SM output parameter",
            SYNC_INPUTS => "SM input parameter",
            INPUTS_11 => "CAN Rx message queue",
            INPUTS_29 => "CAN Rx extended message queue",
            OUTPUTS_11 => "CAN Tx message queue",
            OUTPUTS_29 => "CAN Tx extended message queue",
            INTERFACE => "CAN Interface configuration",
            FILTERS => "CAN filter table",
            MODULAR_DEVICE => "Modular device profile",
            CAN_STATUS => "CAN Status",
            INFO_DATA => "InfoData",
            BUS_PARAMETERS => "CAN bus parameter",
            _ => "",
        }
    }
}

/// `0x1000`: the modular device profile of the CAN interface (5001, as the
/// EL6751's profile-specific objects say), no module bits (an assumption).
pub const DEVICE_TYPE: u32 = 5001;

/// Sub-indices of `0x8000` (ETHERCAT.md: the public example configuration
/// writes these five).
pub mod interface {
    pub const FLAGS: u8 = 0x20;
    pub const RX_SLOTS: u8 = 0x21;
    pub const TX_SLOTS: u8 = 0x22;
    pub const RX_QUEUE: u8 = 0x23;
    pub const TX_QUEUE: u8 = 0x24;
    /// The deepest queue the EL6751 keeps (000 §4: 150 Rx messages; the
    /// public example writes 150 for both).
    pub const MAX_QUEUE_DEPTH: u16 = 150;
}

/// The flags of `0x8000:20`. The public example writes 0x0008 for an
/// interface of 29-bit messages with transaction numbers and filters (its
/// sizes, 166 and 154 bytes at 10 slots, say so; Beckhoff: the Optimized
/// and Fast CAN Queues "support only 11-bit identifiers" and no filters),
/// so the frame format is one bit per choice of TwinCAT's dialog (000 §3,
/// "Auswahl des Frame-Formats"). Which bit is which beyond 0x0008 is
/// canif's assumption.
pub mod flags {
    pub const OPTIMIZED_QUEUE: u16 = 1 << 0;
    pub const FAST_QUEUE: u16 = 1 << 1;
    pub const EXT29: u16 = 1 << 2;
    pub const EXT29_TRANSACTION_NUMBER: u16 = 1 << 3;
    pub const STD11_TRANSACTION_NUMBER: u16 = 1 << 4;
    pub const FD: u16 = 1 << 5;
    pub const TIME_STAMP: u16 = 1 << 6;
    /// The frame-format bits: at most one may be set (none: 11-bit).
    pub const FORMATS: u16 = EXT29 | EXT29_TRANSACTION_NUMBER | STD11_TRANSACTION_NUMBER | FD;
    /// Every bit with a meaning.
    pub const KNOWN: u16 = OPTIMIZED_QUEUE | FAST_QUEUE | FORMATS | TIME_STAMP;
}

/// Sub-indices of `0x1C32`/`0x1C33` (ETG.1020 "SM output/input parameter").
pub mod sync {
    pub const MODE: u8 = 0x01;
    pub const CYCLE_TIME: u8 = 0x02;
    pub const SHIFT_TIME: u8 = 0x03;
    pub const MODES_SUPPORTED: u8 = 0x04;
    /// 000 §5: with `:08` set, the longest local cycle measured.
    pub const MINIMUM_CYCLE_TIME: u8 = 0x05;
    pub const CALC_AND_COPY_TIME: u8 = 0x06;
    pub const GET_CYCLE_TIME: u8 = 0x08;
    pub const DELAY_TIME: u8 = 0x09;
    pub const SYNC0_CYCLE_TIME: u8 = 0x0A;
    pub const SM_EVENT_MISSED: u8 = 0x0B;
    pub const CYCLE_TIME_TOO_SMALL: u8 = 0x0C;
    pub const SYNC_ERROR: u8 = 0x20;
    /// Free run, SM-synchronous, DC SYNC0 (an assumption).
    pub const SUPPORTED: u16 = 0x0007;
    /// Free run, SM-synchronous, DC SYNC0, DC SYNC1, and for the inputs
    /// "synchronous with the SM2 event" (0x22).
    pub fn mode_known(inputs: bool, mode: u16) -> bool {
        matches!(mode, 0..=3) || (inputs && mode == 0x22)
    }
}

/// Sub-indices of `0xF108` CAN Status, mapped by `0x1A85` (three UINTs
/// make the 6 status bytes of the public example; their meaning is
/// canif's assumption: the controller's status bits and error counters).
pub mod status {
    pub const STATE: u8 = 1;
    pub const RX_ERROR_COUNTER: u8 = 2;
    pub const TX_ERROR_COUNTER: u8 = 3;
    /// Bytes `0x1A85` adds to the inputs.
    pub const BYTES: usize = 6;
}

/// Rows the filter table holds (an assumption: the documents give no number).
pub const FILTER_ROWS: u8 = 32;
/// A filter row: flags (bit 0 accept, bit 1 code/mask), a reserved byte, two UDINTs.
pub const FILTER_ROW: usize = 10;
