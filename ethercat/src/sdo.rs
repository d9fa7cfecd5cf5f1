//! The SDO server (ETG.1000.6 §5.6.2): expedited, normal and segmented
//! download and upload, complete access, abort codes, over an object
//! dictionary the application keeps.

use crate::mailbox::{abort, capacity, SdoRequest, SdoResponse};

/// One entry of an object as the dictionary holds it now.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Entry {
    pub sub: u8,
    pub value: Vec<u8>,
    pub writable: bool,
    /// What SDO Information calls it ("SubIndex nnn" when empty).
    pub name: &'static str,
    /// A VISIBLE STRING rather than a number or octets.
    pub text: bool,
}

impl Entry {
    pub fn new(sub: u8, value: Vec<u8>, writable: bool) -> Entry {
        Entry {
            sub,
            value,
            writable,
            name: "",
            text: false,
        }
    }

    pub fn named(self, name: &'static str) -> Entry {
        Entry { name, ..self }
    }

    pub fn text(self) -> Entry {
        Entry { text: true, ..self }
    }

    /// A number (UNSIGNED8/16/32/64), by its width; else a string of octets.
    pub fn unsigned(&self) -> bool {
        !self.text && matches!(self.value.len(), 1 | 2 | 4 | 8)
    }

    /// The ETG.1000.6 data type (Table 63) SDO Information gives it.
    pub fn data_type(&self) -> u16 {
        match (self.text, self.value.len()) {
            (true, _) => 0x0009,
            (false, 1) => 0x0005,
            (false, 2) => 0x0006,
            (false, 4) => 0x0007,
            (false, 8) => 0x001B,
            _ => 0x000A,
        }
    }
}

/// The objects behind the server.
pub trait ObjectDictionary {
    /// Every entry of `index`, sub-index 0 first, with the size each has when
    /// written: an array lists all the entries it can hold.
    fn object(&self, index: u16) -> Option<Vec<Entry>>;

    /// Sub-index `sub` of `index`, as [`ObjectDictionary::object`] lists it
    /// (or the abort for no such object or entry). A dictionary that builds
    /// its objects may find one entry without building the rest: a master
    /// uploads a PDO mapping entry by entry.
    fn entry(&self, index: u16, sub: u8) -> Result<Entry, u32> {
        entry_of(self.object(index), sub)
    }

    /// Writes these entries of `index` together (one download), or refuses
    /// with an abort code; nothing is written when it refuses.
    fn write(&mut self, index: u16, values: &[(u8, Vec<u8>)]) -> Result<(), u32>;

    /// Every object, in order, for SDO Information's OD list.
    fn indices(&self) -> Vec<u16> {
        Vec::new()
    }

    /// An object's name, for SDO Information.
    fn name(&self, index: u16) -> String {
        format!("Object {index:04X}")
    }
}

/// Sub-index `sub` of an object as [`ObjectDictionary::object`] gave it, or
/// the abort for no such object or entry.
pub fn entry_of(object: Option<Vec<Entry>>, sub: u8) -> Result<Entry, u32> {
    let entries = object.ok_or(abort::NO_OBJECT)?;
    entries
        .into_iter()
        .find(|e| e.sub == sub)
        .ok_or(abort::NO_SUBINDEX)
}

/// A transfer split over several mailbox messages.
#[derive(Debug, Clone)]
enum Segmented {
    Download {
        index: u16,
        sub: u8,
        complete_access: bool,
        size: usize,
        received: Vec<u8>,
        toggle: bool,
    },
    Upload {
        rest: Vec<u8>,
        toggle: bool,
    },
}

/// The server's state between messages.
#[derive(Debug, Clone, Default)]
pub struct SdoServer {
    segmented: Option<Segmented>,
}

/// With complete access, sub-index 0 travels in two bytes (ETG.1000.6 §5.6.2.1.1).
const SUB0_COMPLETE: usize = 2;

fn abort(index: u16, sub: u8, code: u32) -> SdoResponse {
    SdoResponse::Abort { index, sub, code }
}

impl SdoServer {
    /// Answers one request through a mailbox of `mailbox_size` bytes; an
    /// abort from the client ends its transfer and is not answered.
    pub fn handle(
        &mut self,
        dictionary: &mut dyn ObjectDictionary,
        request: SdoRequest,
        mailbox_size: usize,
    ) -> Option<SdoResponse> {
        if let SdoRequest::Abort { .. } = request {
            self.segmented = None;
            return None;
        }
        Some(self.answer(dictionary, request, mailbox_size))
    }

    fn answer(
        &mut self,
        dictionary: &mut dyn ObjectDictionary,
        request: SdoRequest,
        mailbox_size: usize,
    ) -> SdoResponse {
        let (first, segment) = capacity(mailbox_size);
        match request {
            SdoRequest::Download {
                index,
                sub,
                complete_access,
                size,
                data,
            } => {
                self.segmented = None;
                let size = size.map_or(data.len(), |s| s as usize);
                if data.len() >= size {
                    let data = &data[..size];
                    return match store(dictionary, index, sub, complete_access, data) {
                        Ok(()) => SdoResponse::Download { index, sub },
                        Err(code) => abort(index, sub, code),
                    };
                }
                self.segmented = Some(Segmented::Download {
                    index,
                    sub,
                    complete_access,
                    size,
                    received: data,
                    toggle: false,
                });
                SdoResponse::Download { index, sub }
            }
            SdoRequest::DownloadSegment { toggle, last, data } => {
                let Some(Segmented::Download {
                    index,
                    sub,
                    complete_access,
                    size,
                    mut received,
                    toggle: expected,
                }) = self.segmented.take()
                else {
                    return abort(0, 0, abort::COMMAND_SPECIFIER);
                };
                if toggle != expected {
                    return abort(index, sub, abort::TOGGLE_BIT);
                }
                received.extend_from_slice(&data);
                if received.len() > size || (last && received.len() != size) {
                    return abort(index, sub, abort::LENGTH);
                }
                if last {
                    return match store(dictionary, index, sub, complete_access, &received) {
                        Ok(()) => SdoResponse::DownloadSegment { toggle },
                        Err(code) => abort(index, sub, code),
                    };
                }
                self.segmented = Some(Segmented::Download {
                    index,
                    sub,
                    complete_access,
                    size,
                    received,
                    toggle: !toggle,
                });
                SdoResponse::DownloadSegment { toggle }
            }
            SdoRequest::Upload {
                index,
                sub,
                complete_access,
            } => {
                self.segmented = None;
                let value = match fetch(dictionary, index, sub, complete_access) {
                    Ok(value) => value,
                    Err(code) => return abort(index, sub, code),
                };
                if value.len() <= 4 && !complete_access {
                    return SdoResponse::Upload {
                        index,
                        sub,
                        size: None,
                        data: value,
                    };
                }
                let size = Some(value.len() as u32);
                if value.len() <= first {
                    return SdoResponse::Upload {
                        index,
                        sub,
                        size,
                        data: value,
                    };
                }
                self.segmented = Some(Segmented::Upload {
                    rest: value[first..].to_vec(),
                    toggle: false,
                });
                SdoResponse::Upload {
                    index,
                    sub,
                    size,
                    data: value[..first].to_vec(),
                }
            }
            SdoRequest::UploadSegment { toggle } => {
                let Some(Segmented::Upload {
                    mut rest,
                    toggle: expected,
                }) = self.segmented.take()
                else {
                    return abort(0, 0, abort::COMMAND_SPECIFIER);
                };
                if toggle != expected {
                    return abort(0, 0, abort::TOGGLE_BIT);
                }
                let tail = rest.split_off(rest.len().min(segment));
                let last = tail.is_empty();
                if !last {
                    self.segmented = Some(Segmented::Upload {
                        rest: tail,
                        toggle: !toggle,
                    });
                }
                SdoResponse::UploadSegment {
                    toggle,
                    last,
                    data: rest,
                }
            }
            SdoRequest::Abort { index, sub, .. } => abort(index, sub, abort::COMMAND_SPECIFIER),
        }
    }
}

/// The bytes an upload returns: one entry, or with complete access sub-index 0
/// (in two bytes) and the entries after it.
fn fetch(
    dictionary: &dyn ObjectDictionary,
    index: u16,
    sub: u8,
    complete_access: bool,
) -> Result<Vec<u8>, u32> {
    if !complete_access {
        return dictionary.entry(index, sub).map(|e| e.value);
    }
    let entries = dictionary.object(index).ok_or(abort::NO_OBJECT)?;
    if sub > 1 {
        return Err(abort::UNSUPPORTED_ACCESS);
    }
    let count = entries
        .first()
        .and_then(|e| e.value.first().copied())
        .unwrap_or(0);
    let mut out = Vec::new();
    if sub == 0 {
        out.extend_from_slice(&[count, 0]);
    }
    for entry in entries
        .iter()
        .filter(|e| e.sub >= 1 && e.sub <= count.max(sub))
    {
        out.extend_from_slice(&entry.value);
    }
    Ok(out)
}

/// A single entry's download at the entry's width. A number may come in
/// another width than the dictionary's (1, 2 or 4 bytes) when its value
/// fits: configurators write these objects at widths the public
/// documentation does not give (docs/ethercat.md, an assumption); a value
/// that does not fit is out of range, any other length a length error.
fn fitted(entry: &Entry, data: &[u8]) -> Result<Vec<u8>, u32> {
    let width = entry.value.len();
    if data.len() == width {
        return Ok(data.to_vec());
    }
    if !entry.unsigned() || !matches!(data.len(), 1 | 2 | 4) {
        return Err(abort::LENGTH);
    }
    if data.iter().skip(width).any(|&b| b != 0) {
        return Err(abort::VALUE_RANGE);
    }
    let mut value = data[..data.len().min(width)].to_vec();
    value.resize(width, 0);
    Ok(value)
}

/// Splits a download into entries by the sizes the dictionary gives, and writes them.
fn store(
    dictionary: &mut dyn ObjectDictionary,
    index: u16,
    sub: u8,
    complete_access: bool,
    data: &[u8],
) -> Result<(), u32> {
    if !complete_access {
        let entry = dictionary.entry(index, sub)?;
        if !entry.writable {
            return Err(abort::READ_ONLY);
        }
        let value = fitted(&entry, data)?;
        return dictionary.write(index, &[(sub, value)]);
    }
    let entries = dictionary.object(index).ok_or(abort::NO_OBJECT)?;
    if sub > 1 {
        return Err(abort::UNSUPPORTED_ACCESS);
    }
    let mut values = Vec::new();
    let mut rest = data;
    if sub == 0 {
        if rest.len() < SUB0_COMPLETE {
            return Err(abort::LENGTH);
        }
        values.push((0, vec![rest[0]]));
        rest = &rest[SUB0_COMPLETE..];
    }
    for entry in entries.iter().filter(|e| e.sub >= 1) {
        if rest.is_empty() {
            break;
        }
        let size = entry.value.len();
        if rest.len() < size {
            return Err(abort::LENGTH);
        }
        // A read-only entry a complete access carries unchanged is no write
        // (a master writing a whole record sends its constants too).
        if !entry.writable {
            if rest[..size] != entry.value[..] {
                return Err(abort::READ_ONLY);
            }
        } else {
            values.push((entry.sub, rest[..size].to_vec()));
        }
        rest = &rest[size..];
    }
    if !rest.is_empty() {
        return Err(abort::LENGTH);
    }
    dictionary.write(index, &values)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A filter-table-like array: sub 0 the count, then up to four 10-byte entries.
    #[derive(Default)]
    struct Table {
        count: u8,
        rows: [[u8; 10]; 4],
        writes: usize,
    }

    impl ObjectDictionary for Table {
        fn object(&self, index: u16) -> Option<Vec<Entry>> {
            (index == 0x8001).then(|| {
                let mut entries = vec![Entry::new(0, vec![self.count], true)];
                entries
                    .extend((0..4).map(|i| Entry::new(i as u8 + 1, self.rows[i].to_vec(), true)));
                entries
            })
        }
        fn write(&mut self, _: u16, values: &[(u8, Vec<u8>)]) -> Result<(), u32> {
            for (sub, value) in values {
                match sub {
                    0 if value[0] > 4 => return Err(abort::VALUE_RANGE),
                    0 => self.count = value[0],
                    s => self.rows[usize::from(*s) - 1].copy_from_slice(value),
                }
            }
            self.writes += 1;
            Ok(())
        }
    }

    fn download(data: Vec<u8>) -> SdoRequest {
        SdoRequest::Download {
            index: 0x8001,
            sub: 0,
            complete_access: true,
            size: Some(data.len() as u32),
            data,
        }
    }

    #[test]
    fn a_complete_access_download_in_segments_writes_the_table_once() {
        let mut table = Table::default();
        let mut server = SdoServer::default();
        let mut data = vec![3, 0];
        for row in 1..=3u8 {
            data.extend_from_slice(&[row; 10]);
        }
        // A 24-byte mailbox carries 8 bytes after the initiate, 15 after a segment's command.
        let (first, segment) = capacity(24);
        assert_eq!((first, segment), (8, 15));
        let whole = data.clone();
        let mut rest = data.split_off(first);
        let mut request = SdoRequest::Download {
            index: 0x8001,
            sub: 0,
            complete_access: true,
            size: Some(whole.len() as u32),
            data,
        };
        let mut toggle = false;
        loop {
            let answer = server.handle(&mut table, request, 24).unwrap();
            assert!(!matches!(answer, SdoResponse::Abort { .. }), "{answer:?}");
            if rest.is_empty() {
                break;
            }
            let tail = rest.split_off(rest.len().min(segment));
            request = SdoRequest::DownloadSegment {
                toggle,
                last: tail.is_empty(),
                data: std::mem::replace(&mut rest, tail),
            };
            toggle = !toggle;
        }
        assert_eq!((table.count, table.writes), (3, 1));
        assert_eq!(table.rows[2], [3; 10]);
        // And it reads back the same way, in segments.
        let mut answer = server
            .handle(
                &mut table,
                SdoRequest::Upload {
                    index: 0x8001,
                    sub: 0,
                    complete_access: true,
                },
                24,
            )
            .unwrap();
        let mut read = Vec::new();
        let mut toggle = false;
        loop {
            match answer {
                SdoResponse::Upload { data, size, .. } => {
                    assert_eq!(size, Some(whole.len() as u32));
                    read.extend(data);
                }
                SdoResponse::UploadSegment { data, last, .. } => {
                    read.extend(data);
                    if last {
                        break;
                    }
                }
                other => panic!("{other:?}"),
            }
            answer = server
                .handle(&mut table, SdoRequest::UploadSegment { toggle }, 24)
                .unwrap();
            toggle = !toggle;
        }
        assert_eq!(read, whole);
    }

    #[test]
    fn refusals_carry_their_abort_codes() {
        let mut table = Table::default();
        let mut server = SdoServer::default();
        let answer = |server: &mut SdoServer, table: &mut Table, request| match server
            .handle(table, request, 128)
        {
            Some(SdoResponse::Abort { code, .. }) => code,
            other => panic!("{other:?}"),
        };
        assert_eq!(
            answer(&mut server, &mut table, download(vec![9, 0])),
            abort::VALUE_RANGE
        );
        assert_eq!(
            answer(&mut server, &mut table, download(vec![1, 0, 1, 2])),
            abort::LENGTH
        );
        let mut missing = download(vec![1, 0]);
        if let SdoRequest::Download { index, .. } = &mut missing {
            *index = 0x8002;
        }
        assert_eq!(answer(&mut server, &mut table, missing), abort::NO_OBJECT);
        let stray = SdoRequest::DownloadSegment {
            toggle: false,
            last: true,
            data: vec![1],
        };
        assert_eq!(
            answer(&mut server, &mut table, stray),
            abort::COMMAND_SPECIFIER
        );
        assert_eq!(table.writes, 0);
    }

    #[test]
    fn a_number_may_come_in_another_width_when_its_value_fits() {
        let uint16 = Entry::new(0x21, vec![0, 0], true);
        assert_eq!(fitted(&uint16, &[10]), Ok(vec![10, 0]));
        assert_eq!(fitted(&uint16, &[150, 0, 0, 0]), Ok(vec![150, 0]));
        assert_eq!(fitted(&uint16, &[0, 0, 1, 0]), Err(abort::VALUE_RANGE));
        assert_eq!(fitted(&uint16, &[1, 2, 3]), Err(abort::LENGTH));
        let row = Entry::new(1, vec![0; 10], true);
        assert_eq!(fitted(&row, &[1, 2]), Err(abort::LENGTH));
        let name = Entry::new(0, b"EL".to_vec(), true).text();
        assert_eq!(fitted(&name, &[1]), Err(abort::LENGTH));
    }

    #[test]
    fn a_wrong_toggle_aborts_the_transfer() {
        let mut table = Table::default();
        let mut server = SdoServer::default();
        let mut data = vec![2, 0];
        data.extend_from_slice(&[1; 20]);
        let first = capacity(24).0;
        let rest = data.split_off(first);
        let mut request = download(data);
        if let SdoRequest::Download { size, .. } = &mut request {
            *size = Some(22);
        }
        server.handle(&mut table, request, 24);
        let answer = server.handle(
            &mut table,
            SdoRequest::DownloadSegment {
                toggle: true,
                last: true,
                data: rest,
            },
            24,
        );
        assert!(matches!(
            answer,
            Some(SdoResponse::Abort {
                code: abort::TOGGLE_BIT,
                ..
            })
        ));
        assert_eq!(table.writes, 0);
    }
}
