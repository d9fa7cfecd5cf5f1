//! SDO Information (ETG.1000.6 §5.6.3): the OD list, object descriptions
//! and entry descriptions a configurator reads to learn a dictionary, and
//! the mailbox error (ETG.1000.4 §5.6) for what the terminal does not speak
//! (FoE, EoE, SoE, another CoE service).

use crate::mailbox::{abort, message, TYPE_COE};
use crate::sdo::{Entry, ObjectDictionary};

/// CoE service of SDO Information.
pub const SERVICE: u16 = 8;
/// Mailbox type of a mailbox error.
const TYPE_ERROR: u8 = 0;

/// SDO Information op codes.
mod opcode {
    pub(super) const OD_LIST_REQUEST: u8 = 1;
    pub(super) const OD_LIST_RESPONSE: u8 = 2;
    pub(super) const OBJECT_REQUEST: u8 = 3;
    pub(super) const OBJECT_RESPONSE: u8 = 4;
    pub(super) const ENTRY_REQUEST: u8 = 5;
    pub(super) const ENTRY_RESPONSE: u8 = 6;
    pub(super) const ERROR: u8 = 7;
}

/// Mailbox error details (ETG.1000.4 Table 30).
pub mod mailbox_error {
    pub const UNSUPPORTED_PROTOCOL: u16 = 0x0002;
    pub const SERVICE_NOT_SUPPORTED: u16 = 0x0004;
    pub const INVALID_HEADER: u16 = 0x0005;
}

/// What a master asks of SDO Information.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum InfoRequest {
    /// 0: how many objects each list holds; 1: all objects; 2–5 the others.
    OdList {
        list: u16,
    },
    Object {
        index: u16,
    },
    Entry {
        index: u16,
        sub: u8,
    },
}

/// The kind of a mailbox message, by its headers.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    Sdo,
    Info,
    /// Answered with this mailbox error.
    Unsupported(u16),
}

/// What a request in the master's mailbox is.
pub fn kind(bytes: &[u8]) -> Kind {
    if bytes.len() < 8 {
        return Kind::Unsupported(mailbox_error::INVALID_HEADER);
    }
    if bytes[5] & 0x0F != TYPE_COE {
        return Kind::Unsupported(mailbox_error::UNSUPPORTED_PROTOCOL);
    }
    match u16::from_le_bytes([bytes[6], bytes[7]]) >> 12 {
        crate::mailbox::SERVICE_SDO_REQUEST => Kind::Sdo,
        SERVICE => Kind::Info,
        _ => Kind::Unsupported(mailbox_error::SERVICE_NOT_SUPPORTED),
    }
}

/// A mailbox error message: type 0, then command 1 and the detail.
pub fn error(counter: u8, detail: u16, mailbox_size: usize) -> Vec<u8> {
    let mut out = vec![4, 0, 0, 0, 0, TYPE_ERROR | (counter & 7) << 4];
    out.extend_from_slice(&1u16.to_le_bytes());
    out.extend_from_slice(&detail.to_le_bytes());
    out.resize(out.len().max(mailbox_size), 0);
    out
}

impl InfoRequest {
    /// The request in a CoE message of service 8; `None` for another op code
    /// or one cut short.
    pub fn parse(bytes: &[u8]) -> Option<InfoRequest> {
        let length = usize::from(u16::from_le_bytes([*bytes.first()?, *bytes.get(1)?]));
        let body = bytes.get(8..6 + length)?;
        let u16_at = |at: usize| Some(u16::from_le_bytes([*body.get(at)?, *body.get(at + 1)?]));
        Some(match body.first()? & 0x7F {
            opcode::OD_LIST_REQUEST => InfoRequest::OdList { list: u16_at(4)? },
            opcode::OBJECT_REQUEST => InfoRequest::Object { index: u16_at(4)? },
            opcode::ENTRY_REQUEST => InfoRequest::Entry {
                index: u16_at(4)?,
                sub: *body.get(6)?,
            },
            _ => return None,
        })
    }
}

/// ETG.1000.6 Table 44: read in PREOP, SAFEOP, OP; written in PREOP.
fn access(entry: &Entry) -> u16 {
    0x07 | if entry.writable { 0x08 } else { 0 }
}

/// The answer's SDO Information body (op code, reserved, fragments left, data).
fn body(opcode: u8, data: &[u8]) -> Vec<u8> {
    let mut out = vec![opcode, 0, 0, 0];
    out.extend_from_slice(data);
    out
}

fn describe(dictionary: &dyn ObjectDictionary, request: InfoRequest) -> Result<Vec<u8>, u32> {
    match request {
        InfoRequest::OdList { list } => {
            let all = dictionary.indices();
            let mut data = list.to_le_bytes().to_vec();
            match list {
                // All, RxPDO- and TxPDO-mappable, backup, settings.
                0 => {
                    for count in [all.len(), 0, 0, 0, 0] {
                        data.extend_from_slice(&(count as u16).to_le_bytes());
                    }
                }
                1 => all
                    .iter()
                    .for_each(|i| data.extend_from_slice(&i.to_le_bytes())),
                2..=5 => {}
                _ => return Err(abort::VALUE_RANGE),
            }
            Ok(body(opcode::OD_LIST_RESPONSE, &data))
        }
        InfoRequest::Object { index } => {
            let entries = dictionary.object(index).ok_or(abort::NO_OBJECT)?;
            let highest = entries.iter().map(|e| e.sub).max().unwrap_or(0);
            let first = entries.iter().find(|e| e.sub >= 1).or(entries.first());
            // VAR for one value, ARRAY when every entry after 0 is alike, else RECORD.
            let alike = entries
                .iter()
                .filter(|e| e.sub >= 1)
                .all(|e| Some(e.data_type()) == first.map(Entry::data_type));
            let code = match (highest, alike) {
                (0, _) => 7u8,
                (_, true) => 8,
                _ => 9,
            };
            let mut data = index.to_le_bytes().to_vec();
            data.extend_from_slice(&first.map_or(0, Entry::data_type).to_le_bytes());
            data.extend_from_slice(&[highest, code]);
            data.extend_from_slice(dictionary.name(index).as_bytes());
            Ok(body(opcode::OBJECT_RESPONSE, &data))
        }
        InfoRequest::Entry { index, sub } => {
            let entries = dictionary.object(index).ok_or(abort::NO_OBJECT)?;
            let entry = entries
                .iter()
                .find(|e| e.sub == sub)
                .ok_or(abort::NO_SUBINDEX)?;
            let mut data = index.to_le_bytes().to_vec();
            // Value info 0: no unit, default, minimum or maximum follow.
            data.extend_from_slice(&[sub, 0]);
            data.extend_from_slice(&entry.data_type().to_le_bytes());
            data.extend_from_slice(&((entry.value.len() * 8) as u16).to_le_bytes());
            data.extend_from_slice(&access(entry).to_le_bytes());
            match entry.name {
                "" => data.extend_from_slice(format!("SubIndex {sub:03}").as_bytes()),
                name => data.extend_from_slice(name.as_bytes()),
            }
            Ok(body(opcode::ENTRY_RESPONSE, &data))
        }
    }
}

/// The answer to `request`: its description, or an SDO Information error
/// with the abort code (an answer longer than the mailbox too: this
/// terminal sends no fragments).
pub fn answer(
    dictionary: &dyn ObjectDictionary,
    request: InfoRequest,
    counter: u8,
    mailbox_size: usize,
) -> Vec<u8> {
    let room = mailbox_size.saturating_sub(crate::mailbox::HEADERS);
    let info = match describe(dictionary, request) {
        Ok(info) if info.len() <= room => info,
        Ok(_) => body(opcode::ERROR, &abort::GENERAL.to_le_bytes()),
        Err(code) => body(opcode::ERROR, &code.to_le_bytes()),
    };
    message(SERVICE, counter, &info, mailbox_size)
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Two;

    impl ObjectDictionary for Two {
        fn object(&self, index: u16) -> Option<Vec<Entry>> {
            match index {
                0x1008 => Some(vec![Entry::new(0, b"EL6751".to_vec(), false).text()]),
                0x8000 => Some(vec![
                    Entry::new(0, vec![0x20], false),
                    Entry::new(0x20, vec![8, 0], true).named("Flags"),
                ]),
                _ => None,
            }
        }
        fn write(&mut self, _: u16, _: &[(u8, Vec<u8>)]) -> Result<(), u32> {
            Ok(())
        }
        fn indices(&self) -> Vec<u16> {
            vec![0x1008, 0x8000]
        }
    }

    /// A CoE service-8 request with this SDO Information body.
    fn request(body: &[u8]) -> Vec<u8> {
        let mut out = ((body.len() + 2) as u16).to_le_bytes().to_vec();
        out.extend_from_slice(&[0, 0, 0, 0x13, 0x00, 0x80]);
        out.extend_from_slice(body);
        out
    }

    #[test]
    fn the_od_list_names_every_object() {
        let asked = request(&[1, 0, 0, 0, 1, 0]);
        assert_eq!(kind(&asked), Kind::Info);
        let request = InfoRequest::parse(&asked).unwrap();
        assert_eq!(request, InfoRequest::OdList { list: 1 });
        let answer = answer(&Two, request, 1, 64);
        // Length 12: CoE header, op code 2, fragments 0, list 1, 0x1008, 0x8000.
        assert_eq!(
            &answer[..18],
            &[12, 0, 0, 0, 0, 0x13, 0x00, 0x80, 2, 0, 0, 0, 1, 0, 0x08, 0x10, 0x00, 0x80]
        );
    }

    #[test]
    fn an_entry_description_gives_type_width_access_and_name() {
        let request = InfoRequest::parse(&request(&[5, 0, 0, 0, 0x00, 0x80, 0x20, 0])).unwrap();
        let answer = answer(&Two, request, 1, 64);
        // index, sub, value info, UNSIGNED16, 16 bits, read everywhere + write in PREOP, "Flags".
        assert_eq!(
            &answer[12..27],
            &[0x00, 0x80, 0x20, 0, 0x06, 0, 16, 0, 0x0F, 0, b'F', b'l', b'a', b'g', b's']
        );
    }

    #[test]
    fn a_missing_object_is_an_information_error_with_its_abort_code() {
        let request = InfoRequest::parse(&request(&[3, 0, 0, 0, 0x00, 0x90])).unwrap();
        let answer = answer(&Two, request, 1, 64);
        assert_eq!(answer[8], 7);
        assert_eq!(&answer[12..16], &abort::NO_OBJECT.to_le_bytes());
    }

    #[test]
    fn what_is_not_coe_gets_a_mailbox_error() {
        let mut foe = request(&[1, 0, 0, 0]);
        foe[5] = 0x14; // FoE
        assert_eq!(
            kind(&foe),
            Kind::Unsupported(mailbox_error::UNSUPPORTED_PROTOCOL)
        );
        let error = error(1, mailbox_error::UNSUPPORTED_PROTOCOL, 16);
        assert_eq!(&error[..10], &[4, 0, 0, 0, 0, 0x10, 1, 0, 2, 0]);
    }
}
