//! The process image as data types: the structures a PLC program declares,
//! each member placed where the model's layout puts it.
//!
//! Nothing here knows an offset of its own: every member is one of
//! `canif_model::image`'s named ranges ([`MessageLayout`]'s fields, the
//! header's `field` ranges, [`ImageLayout`]'s slots), given the type the
//! manual names for it (000/001 §6, §8.3).

use canif_model::image::field::role;
use canif_model::image::{field, flag, ImageLayout, LengthField, MessageLayout};

/// IEC 61131-3 elementary types (the ones an image or a user's declaration of
/// it can hold).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Elementary {
    /// One bit; consecutive `BIT` members share a byte (000 §8.3's FD flags).
    Bit,
    Bool,
    Byte,
    Usint,
    Sint,
    Word,
    Uint,
    Int,
    Dword,
    Udint,
    Dint,
    Real,
    Time,
    Lword,
    Ulint,
    Lint,
    Lreal,
    Ltime,
}

impl Elementary {
    const ALL: [(Elementary, &'static str, usize); 18] = [
        (Elementary::Bit, "BIT", 0),
        (Elementary::Bool, "BOOL", 1),
        (Elementary::Byte, "BYTE", 1),
        (Elementary::Usint, "USINT", 1),
        (Elementary::Sint, "SINT", 1),
        (Elementary::Word, "WORD", 2),
        (Elementary::Uint, "UINT", 2),
        (Elementary::Int, "INT", 2),
        (Elementary::Dword, "DWORD", 4),
        (Elementary::Udint, "UDINT", 4),
        (Elementary::Dint, "DINT", 4),
        (Elementary::Real, "REAL", 4),
        (Elementary::Time, "TIME", 4),
        (Elementary::Lword, "LWORD", 8),
        (Elementary::Ulint, "ULINT", 8),
        (Elementary::Lint, "LINT", 8),
        (Elementary::Lreal, "LREAL", 8),
        (Elementary::Ltime, "LTIME", 8),
    ];

    /// Its ST keyword, case-insensitively.
    pub fn parse(word: &str) -> Option<Elementary> {
        Self::ALL
            .iter()
            .find(|(_, name, _)| name.eq_ignore_ascii_case(word))
            .map(|(e, _, _)| *e)
    }

    pub fn st_name(self) -> &'static str {
        Self::ALL
            .iter()
            .find(|(e, _, _)| *e == self)
            .map_or("", |e| e.1)
    }

    /// Bytes it takes (0 for `BIT`, which takes a bit).
    pub fn size(self) -> usize {
        Self::ALL
            .iter()
            .find(|(e, _, _)| *e == self)
            .map_or(0, |e| e.2)
    }

    /// The unsigned type of a field `bytes` wide (the image holds no signed ones).
    fn unsigned(bytes: usize, word_named: bool) -> Elementary {
        match (bytes, word_named) {
            (1, _) => Elementary::Byte,
            (2, true) => Elementary::Word,
            (2, false) => Elementary::Uint,
            (4, _) => Elementary::Udint,
            _ => Elementary::Ulint,
        }
    }
}

/// A member's or an alias's type.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum DataType {
    Elementary(Elementary),
    /// `ARRAY [low..high] OF element`.
    Array {
        low: i64,
        high: i64,
        element: Box<DataType>,
    },
    /// A structure or an alias declared beside it.
    Named(String),
}

impl DataType {
    fn array(count: usize, element: DataType) -> DataType {
        DataType::Array {
            low: 0,
            high: count as i64 - 1,
            element: Box::new(element),
        }
    }
}

/// One member of a structure, at its byte (and, for a `BIT`, bit) in it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Member {
    pub name: String,
    pub data_type: DataType,
    pub offset: usize,
    /// The bit in the byte at `offset`, for a `BIT`.
    pub bit: Option<u8>,
    /// What it holds, with the manual's section.
    pub comment: &'static str,
}

/// A structure, its members in offset order, and its size in bytes.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct StructType {
    pub name: String,
    pub members: Vec<Member>,
    pub size: usize,
    pub comment: String,
}

/// `TYPE name : data_type; END_TYPE` (000 §8.3's `CANFDMESSAGE`).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Alias {
    pub name: String,
    pub data_type: DataType,
    pub comment: &'static str,
}

/// Which way a message goes: it names the FD data field (`txData`, `rxData`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Role {
    Tx,
    Rx,
}

/// 000 §8.3: the 64 data bytes of an FD message.
pub const FD_DATA: &str = "CANFDMESSAGE";
/// The output image's structure.
pub const OUTPUTS: &str = "CANINTERFACE_OUTPUTS";
/// The input image's structure.
pub const INPUTS: &str = "CANINTERFACE_INPUTS";

/// A set of declarations: aliases and structures, each after what it uses.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ImageTypes {
    /// What they declare, for the generated file's head.
    pub title: String,
    pub aliases: Vec<Alias>,
    pub structs: Vec<StructType>,
}

impl ImageTypes {
    /// The images of one interface: its message types, then
    /// [`OUTPUTS`] and [`INPUTS`].
    pub fn of(layout: &ImageLayout, title: String) -> ImageTypes {
        let mut types = ImageTypes {
            title,
            aliases: Vec::new(),
            structs: Vec::new(),
        };
        types.add_message(layout.tx_message, Role::Tx);
        types.add_message(layout.rx_message, Role::Rx);
        // Each counter described by its own image's role (000 §6): the
        // same name is a request in one and its answer in the other.
        let header = |(tx, rx): (&'static str, &'static str), third: &str, comment| {
            vec![
                member("TxCounter", field::TX_COUNTER.start, Elementary::Uint, tx),
                member("RxCounter", field::RX_COUNTER.start, Elementary::Uint, rx),
                member(
                    third,
                    field::NO_OF_MESSAGES.start,
                    Elementary::Uint,
                    comment,
                ),
            ]
        };
        let mut outputs = header(
            (role::OUTPUTS_TX_COUNTER, role::OUTPUTS_RX_COUNTER),
            "NoOfTxMessages",
            role::NO_OF_TX_MESSAGES,
        );
        outputs.push(slots(
            "TxMessage",
            (layout.tx_slots, layout.tx_message),
            layout.tx_slot(0).start,
            "003: 0x700z:04.., the Tx slots, counted from 0 (000 §6)",
        ));
        types.structs.push(StructType {
            name: OUTPUTS.into(),
            members: outputs,
            size: layout.output_size(),
            comment: "Outputs: the PLC writes them (000 §6)".into(),
        });
        let mut inputs = header(
            (role::INPUTS_TX_COUNTER, role::INPUTS_RX_COUNTER),
            "NoOfRxMessages",
            role::NO_OF_RX_MESSAGES,
        );
        if layout.transaction_number {
            inputs.push(member(
                "TransactionNumber",
                field::TRANSACTION_NUMBER.start,
                Elementary::Uint,
                "003: 0x600z:04, that of the last Tx message sent (000 §5.2)",
            ));
        }
        inputs.push(slots(
            "RxMessage",
            (layout.rx_slots, layout.rx_message),
            layout.rx_slot(0).start,
            "003: 0x600z:05.., the Rx slots, counted from 0 (000 §6)",
        ));
        if layout.info_data {
            inputs.push(Member {
                name: "InfoData".into(),
                data_type: DataType::array(
                    field::INFO_DATA_WORDS,
                    DataType::Elementary(Elementary::Udint),
                ),
                offset: layout.info_data_start(),
                bit: None,
                comment: "000/001 §9: status and bit timing",
            });
        }
        types.structs.push(StructType {
            name: INPUTS.into(),
            members: inputs,
            size: layout.input_size(),
            comment: "Inputs: the PLC only reads them (000 §6)".into(),
        });
        types
    }

    /// Every message structure, none of the images (their slot counts are
    /// the configuration's): what `include/canif.h` declares.
    pub fn messages() -> ImageTypes {
        let mut types = ImageTypes {
            title: "the message structures of every interface".into(),
            aliases: Vec::new(),
            structs: Vec::new(),
        };
        for layout in MessageLayout::ALL {
            let role = match layout.transaction_number.is_some() || layout.time_stamp.is_none() {
                true => Role::Tx,
                false => Role::Rx,
            };
            types.add_message(layout, role);
        }
        types
    }

    /// The structure named `name`.
    pub fn structure(&self, name: &str) -> Option<&StructType> {
        self.structs.iter().find(|s| s.name == name)
    }

    /// `data_type` with every alias replaced by what it names.
    pub fn resolve(&self, data_type: &DataType) -> DataType {
        match data_type {
            DataType::Named(name) => match self.aliases.iter().find(|a| &a.name == name) {
                Some(alias) => self.resolve(&alias.data_type),
                None => data_type.clone(),
            },
            DataType::Array { low, high, element } => DataType::Array {
                low: *low,
                high: *high,
                element: Box::new(self.resolve(element)),
            },
            other => other.clone(),
        }
    }

    /// Bytes a type takes (aliases and structures looked up here).
    pub fn size_of(&self, data_type: &DataType) -> usize {
        match data_type {
            DataType::Elementary(e) => e.size(),
            DataType::Array { low, high, element } => {
                element_count(*low, *high).saturating_mul(self.size_of(element))
            }
            DataType::Named(name) => match self.aliases.iter().find(|a| &a.name == name) {
                Some(alias) => self.size_of(&alias.data_type),
                None => self.structure(name).map_or(0, |s| s.size),
            },
        }
    }

    /// The member of structure `root` that holds byte `offset`, as a path
    /// (`RxMessage[2].cobId`, `EDL/BSR/ESI` for a byte of bits), and the
    /// bytes it spans within `root`.
    pub fn path_at(&self, root: &str, offset: usize) -> Option<(String, core::ops::Range<usize>)> {
        let structure = self.structure(root)?;
        let bits: Vec<&str> = structure
            .members
            .iter()
            .filter(|m| m.bit.is_some() && m.offset == offset)
            .map(|m| m.name.as_str())
            .collect();
        if !bits.is_empty() {
            return Some((bits.join("/"), offset..offset + 1));
        }
        let member = structure.members.iter().find(|m| {
            m.bit.is_none() && (m.offset..m.offset + self.size_of(&m.data_type)).contains(&offset)
        })?;
        self.path_in(&member.name, &member.data_type, member.offset, offset)
    }

    fn path_in(
        &self,
        path: &str,
        data_type: &DataType,
        start: usize,
        offset: usize,
    ) -> Option<(String, core::ops::Range<usize>)> {
        match data_type {
            DataType::Elementary(e) => Some((path.to_string(), start..start + e.size())),
            DataType::Array { low, element, .. } => {
                let size = self.size_of(element).max(1);
                let index = (offset - start) / size;
                let path = format!("{path}[{}]", *low + index as i64);
                self.path_in(&path, element, start + index * size, offset)
            }
            DataType::Named(name) => match self.aliases.iter().find(|a| &a.name == name) {
                Some(alias) => self.path_in(path, &alias.data_type, start, offset),
                None => {
                    let (inner, range) = self.path_at(name, offset - start)?;
                    Some((
                        format!("{path}.{inner}"),
                        start + range.start..start + range.end,
                    ))
                }
            },
        }
    }

    fn add_message(&mut self, layout: &'static MessageLayout, role: Role) {
        if self.structure(layout.type_name).is_some() {
            return;
        }
        if layout.flags.is_some() && !self.aliases.iter().any(|a| a.name == FD_DATA) {
            self.aliases.push(Alias {
                name: FD_DATA.into(),
                data_type: DataType::array(
                    layout.data.len(),
                    DataType::Elementary(Elementary::Usint),
                ),
                comment: "000/001 §8.3",
            });
        }
        self.structs.push(message(layout, role));
    }
}

/// An image's message slots: `ARRAY [0..count-1] OF` the message's type.
fn slots(
    name: &str,
    (count, message): (usize, &MessageLayout),
    offset: usize,
    comment: &'static str,
) -> Member {
    Member {
        name: name.into(),
        data_type: DataType::array(count, DataType::Named(message.type_name.into())),
        offset,
        bit: None,
        comment,
    }
}

fn member(name: &str, offset: usize, ty: Elementary, comment: &'static str) -> Member {
    Member {
        name: name.into(),
        data_type: DataType::Elementary(ty),
        offset,
        bit: None,
        comment,
    }
}

/// One message structure from its named ranges. The FD structures keep
/// 001 §8.3's member names (`dataLength`, `cobId`, …; 000 spells it
/// `dataLenght`); the classic ones the names of 000 §6's sample code
/// (`CobID`, `Data`) and of its text (`Length`, `TransactionNumber`, `TimeStamp`).
fn message(layout: &'static MessageLayout, role: Role) -> StructType {
    let fd = layout.flags.is_some();
    let named = |fd_name: &'static str, classic: &'static str| match fd {
        true => fd_name,
        false => classic,
    };
    let mut members = Vec::new();
    if let Some(range) = &layout.transaction_number {
        members.push(member(
            named("transactionNumber", "TransactionNumber"),
            range.start,
            Elementary::unsigned(range.len(), false),
            "000 §5.2: any number; the last one sent comes back in the inputs",
        ));
    }
    match &layout.length {
        LengthField::InCobIdWord => {}
        LengthField::Word(range) => members.push(member(
            "Length",
            range.start,
            Elementary::unsigned(range.len(), false),
            "000 §6: data length 0..8",
        )),
        LengthField::Byte(range) => members.push(member(
            "dataLength",
            range.start,
            Elementary::unsigned(range.len(), false),
            "000 §8.3.1: data length in bytes, 0..64",
        )),
    }
    if let Some(range) = &layout.flags {
        for (name, mask, comment) in [
            ("EDL", flag::EDL, "000 §8.3: FD frame"),
            ("BSR", flag::BRS, "000 §8.3: bit rate switch (BRS)"),
            ("ESI", flag::ESI, "000 §8.3: error state indicator"),
        ] {
            members.push(Member {
                name: name.into(),
                data_type: DataType::Elementary(Elementary::Bit),
                offset: range.start,
                bit: Some(mask.trailing_zeros() as u8),
                comment,
            });
        }
    }
    let cob_id = &layout.cob_id;
    members.push(member(
        named("cobId", "CobID"),
        cob_id.start,
        Elementary::unsigned(cob_id.len(), true),
        match cob_id.len() {
            2 => "000 §6: bits 0-3 length, bit 4 RTR, bits 5-15 identifier",
            _ => "000 §6: bits 0-28 identifier, bit 30 RTR, bit 31 29-bit",
        },
    ));
    let data = &layout.data;
    members.push(Member {
        name: match (fd, role) {
            (true, Role::Tx) => "txData",
            (true, Role::Rx) => "rxData",
            (false, _) => "Data",
        }
        .into(),
        data_type: match fd {
            true => DataType::Named(FD_DATA.into()),
            false => DataType::array(data.len(), DataType::Elementary(Elementary::Byte)),
        },
        offset: data.start,
        bit: None,
        comment: "the data bytes",
    });
    if let Some(range) = &layout.time_stamp {
        members.push(member(
            named("timeStamp", "TimeStamp"),
            range.start,
            Elementary::unsigned(range.len(), false),
            "000 §5.3: reception time in ns",
        ));
    }
    members.sort_by_key(|m| (m.offset, m.bit));
    StructType {
        name: layout.type_name.into(),
        members,
        size: layout.size,
        comment: format!("{} message", layout.name),
    }
}

/// Elements of `ARRAY [low..high]` (as parsed: at most 2^24): what an
/// array type holds, whoever reads its bounds.
pub(crate) fn element_count(low: i64, high: i64) -> usize {
    usize::try_from(i128::from(high) - i128::from(low) + 1).unwrap_or(0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use canif_model::config::{FrameFormat, InterfaceConfig};

    #[test]
    fn the_fd_rx_queue_is_001s_with_the_models_offsets() {
        let layout = ImageLayout::new(&InterfaceConfig::new(FrameFormat::Fd, 2), true);
        let types = ImageTypes::of(&layout, String::new());
        let rx = types.structure("CANFDTSRXQUEUE").expect("declared");
        let placed: Vec<(&str, usize, Option<u8>)> = rx
            .members
            .iter()
            .map(|m| (m.name.as_str(), m.offset, m.bit))
            .collect();
        assert_eq!(
            placed,
            [
                ("dataLength", 0, None),
                ("EDL", 1, Some(0)),
                ("BSR", 1, Some(1)),
                ("ESI", 1, Some(2)),
                ("cobId", 2, None),
                ("rxData", 6, None),
                ("timeStamp", 70, None),
            ]
        );
        assert_eq!(rx.size, 78);
    }

    #[test]
    fn a_byte_of_the_inputs_is_named_by_its_member() {
        let layout = ImageLayout::new(&InterfaceConfig::new(FrameFormat::Fd, 3), true);
        let types = ImageTypes::of(&layout, String::new());
        let cob_id = layout.rx_slot(2).start + 3;
        let (path, range) = types.path_at(INPUTS, cob_id).expect("inside the image");
        assert_eq!(path, "RxMessage[2].cobId");
        assert_eq!(
            range,
            layout.rx_slot(2).start + 2..layout.rx_slot(2).start + 6
        );
        let flags = layout.rx_slot(0).start + 1;
        assert_eq!(
            types.path_at(INPUTS, flags).unwrap().0,
            "RxMessage[0].EDL/BSR/ESI"
        );
        let data = layout.rx_slot(1).start + 6 + 63;
        assert_eq!(
            types.path_at(INPUTS, data).unwrap().0,
            "RxMessage[1].rxData[63]"
        );
        let info = layout.info_data_start() + 4 * 15;
        assert_eq!(types.path_at(INPUTS, info).unwrap().0, "InfoData[15]");
        assert_eq!(types.path_at(INPUTS, layout.input_size()), None);
    }

    #[test]
    fn inputs_have_the_transaction_number_only_where_the_interface_does() {
        let mut config = InterfaceConfig::new(FrameFormat::Extended29, 3);
        let names = |config: &InterfaceConfig| {
            let types = ImageTypes::of(&ImageLayout::new(config, false), String::new());
            let inputs = types.structure(INPUTS).expect("declared").clone();
            inputs
                .members
                .iter()
                .map(|m| m.name.clone())
                .collect::<Vec<_>>()
        };
        assert!(!names(&config).contains(&"TransactionNumber".to_string()));
        config.transaction_number = true;
        assert!(names(&config).contains(&"TransactionNumber".to_string()));
    }
}
