//! The emulated terminal's ESI file: an ETG.2000 EtherCATInfo document, so
//! that a configurator (TwinCAT, or any tool that reads ESI files) can add
//! canif's terminal offline. Everything in it is read from the terminal
//! itself — its identity, its SII's SyncManagers and content, the PDOs its
//! object dictionary assigns and maps — never written a second time.

use std::io::Cursor;

use canif_ethercat::sdo::ObjectDictionary;
use canif_ethercat::subdevice::SubDevice;
use canif_softdevice::ethercat::Terminal;
use canif_spec::EthercatIdentity;
use quick_xml::events::{BytesDecl, BytesText, Event};
use quick_xml::Writer;

/// One entry of a PDO mapping: `0xIIIISSLL` (index, sub-index, bits).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Mapped {
    pub index: u16,
    pub sub: u8,
    pub bits: u8,
}

impl Mapped {
    fn of(value: &[u8]) -> Option<Mapped> {
        let word = u32::from_le_bytes(value.get(..4)?.try_into().ok()?);
        Some(Mapped {
            index: (word >> 16) as u16,
            sub: (word >> 8) as u8,
            bits: word as u8,
        })
    }

    /// The ETG.1020 base type of this many bits (a bit string otherwise).
    pub fn data_type(&self) -> String {
        match self.bits {
            1 => "BOOL".into(),
            8 => "USINT".into(),
            16 => "UINT".into(),
            32 => "UDINT".into(),
            64 => "ULINT".into(),
            n if n % 8 == 0 => format!("OCTET_STRING[{}]", n / 8),
            n => format!("BIT{n}"),
        }
    }
}

/// A PDO as the terminal's dictionary assigns and maps it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Pdo {
    pub index: u16,
    pub entries: Vec<Mapped>,
}

/// The PDOs `assign` (0x1C12 or 0x1C13) lists, with their mapping.
pub fn assigned(dictionary: &dyn ObjectDictionary, assign: u16) -> Vec<Pdo> {
    let entries = |index| dictionary.object(index).unwrap_or_default();
    let count = |entries: &[canif_ethercat::sdo::Entry]| {
        entries
            .first()
            .and_then(|e| e.value.first())
            .copied()
            .unwrap_or(0)
    };
    let assignment = entries(assign);
    assignment
        .iter()
        .skip(1)
        .take(usize::from(count(&assignment)))
        .filter_map(|entry| Some(u16::from_le_bytes(entry.value.get(..2)?.try_into().ok()?)))
        .map(|index| {
            let mapping = entries(index);
            Pdo {
                index,
                entries: mapping
                    .iter()
                    .skip(1)
                    .take(usize::from(count(&mapping)))
                    .filter_map(|entry| Mapped::of(&entry.value))
                    .collect(),
            }
        })
        .collect()
}

/// The ESI document of `terminal`, an EL6751 of `identity` as canif emulates it.
pub fn esi(identity: &EthercatIdentity, terminal: &SubDevice<Terminal>) -> String {
    let mut xml = Writer::new_with_indent(Cursor::new(Vec::new()), b' ', 2);
    let hex32 = |n: u32| format!("#x{n:08X}");
    let text = |xml: &mut Writer<Cursor<Vec<u8>>>, name: &str, value: &str| {
        xml.create_element(name)
            .write_text_content(BytesText::new(value))
            .map(|_| ())
    };
    let written: std::io::Result<()> = (|| {
        xml.write_event(Event::Decl(BytesDecl::new("1.0", Some("UTF-8"), None)))?;
        xml.create_element("EtherCATInfo")
            .with_attribute(("Version", "1.6"))
            .write_inner_content(|xml| {
                xml.create_element("Vendor").write_inner_content(|xml| {
                    text(xml, "Id", &hex32(identity.vendor_id))?;
                    text(
                        xml,
                        "Name",
                        "Beckhoff Automation GmbH & Co. KG (emulated by canif)",
                    )
                })?;
                xml.create_element("Descriptions")
                    .write_inner_content(|xml| {
                        xml.create_element("Groups").write_inner_content(|xml| {
                            xml.create_element("Group").write_inner_content(|xml| {
                                text(xml, "Type", "CANopen")?;
                                text(xml, "Name", "CANopen master terminals")
                            })?;
                            Ok(())
                        })?;
                        xml.create_element("Devices")
                            .write_inner_content(|xml| device(xml, identity, terminal))?;
                        Ok(())
                    })?;
                Ok(())
            })?;
        Ok(())
    })();
    written.expect("writing to memory does not fail");
    String::from_utf8(xml.into_inner().into_inner()).expect("the writer writes UTF-8")
}

fn device(
    xml: &mut Writer<Cursor<Vec<u8>>>,
    identity: &EthercatIdentity,
    terminal: &SubDevice<Terminal>,
) -> std::io::Result<()> {
    let hex = |n: u32, width: usize| format!("#x{n:0width$X}");
    let text = |xml: &mut Writer<Cursor<Vec<u8>>>, name: &str, value: &str| {
        xml.create_element(name)
            .write_text_content(BytesText::new(value))
            .map(|_| ())
    };
    let layout = terminal.layout();
    xml.create_element("Device")
        .with_attribute(("Physics", "YY"))
        .write_inner_content(|xml| {
            xml.create_element("Type")
                .with_attribute(("ProductCode", hex(identity.product_code, 8).as_str()))
                .with_attribute(("RevisionNo", hex(identity.revision, 8).as_str()))
                .write_text_content(BytesText::new("EL6751"))?;
            text(xml, "Name", "EL6751 CANopen master/slave terminal (canif)")?;
            text(xml, "GroupType", "CANopen")?;
            for fmmu in ["Outputs", "Inputs", "MBoxState"] {
                text(xml, "Fmmu", fmmu)?;
            }
            let names = ["MBoxOut", "MBoxIn", "Outputs", "Inputs"];
            for (name, (start, size, control, _)) in names.iter().zip(layout.sync_managers()) {
                let (start, size) = (hex(u32::from(start), 4), hex(u32::from(size), 4));
                let control = hex(u32::from(control), 2);
                xml.create_element("Sm")
                    .with_attribute(("StartAddress", start.as_str()))
                    .with_attribute(("ControlByte", control.as_str()))
                    .with_attribute(("DefaultSize", size.as_str()))
                    .with_attribute(("Enable", "1"))
                    .write_text_content(BytesText::new(name))?;
            }
            let pdos = [
                ("RxPdo", 2, terminal_pdos(terminal, 0x1C12)),
                ("TxPdo", 3, terminal_pdos(terminal, 0x1C13)),
            ];
            for (kind, sm, pdos) in pdos {
                for pdo in pdos {
                    xml.create_element(kind)
                        .with_attribute(("Fixed", "1"))
                        .with_attribute(("Mandatory", "1"))
                        .with_attribute(("Sm", sm.to_string().as_str()))
                        .write_inner_content(|xml| {
                            text(xml, "Index", &hex(u32::from(pdo.index), 4))?;
                            text(xml, "Name", &format!("{kind} {:04X}", pdo.index))?;
                            for entry in &pdo.entries {
                                xml.create_element("Entry").write_inner_content(|xml| {
                                    text(xml, "Index", &hex(u32::from(entry.index), 4))?;
                                    text(xml, "SubIndex", &entry.sub.to_string())?;
                                    text(xml, "BitLen", &entry.bits.to_string())?;
                                    if entry.index != 0 {
                                        let name = format!("{:04X}:{:02X}", entry.index, entry.sub);
                                        text(xml, "Name", &name)?;
                                        text(xml, "DataType", &entry.data_type())?;
                                    }
                                    Ok(())
                                })?;
                            }
                            Ok(())
                        })?;
                }
            }
            xml.create_element("Mailbox")
                .with_attribute(("DataLinkLayer", "true"))
                .write_inner_content(|xml| {
                    xml.create_element("CoE")
                        .with_attribute(("SdoInfo", "true"))
                        .with_attribute(("CompleteAccess", "true"))
                        .with_attribute(("PdoAssign", "true"))
                        .write_empty()?;
                    Ok(())
                })?;
            xml.create_element("Dc").write_inner_content(|xml| {
                for (name, desc, sync0) in [
                    ("SM-Synchron", "SM-Synchron", false),
                    ("DC", "DC-Synchron", true),
                ] {
                    xml.create_element("OpMode").write_inner_content(|xml| {
                        text(xml, "Name", name)?;
                        text(xml, "Desc", desc)?;
                        text(
                            xml,
                            "AssignActivate",
                            if sync0 { "#x0700" } else { "#x0000" },
                        )?;
                        if sync0 {
                            xml.create_element("CycleTimeSync0")
                                .with_attribute(("Factor", "1"))
                                .write_text_content(BytesText::new("0"))?;
                        }
                        Ok(())
                    })?;
                }
                Ok(())
            })?;
            xml.create_element("Eeprom").write_inner_content(|xml| {
                let data: String = terminal.sii().iter().map(|b| format!("{b:02X}")).collect();
                text(xml, "ByteSize", &terminal.sii().len().to_string())?;
                text(xml, "Data", &data)
            })?;
            Ok(())
        })?;
    Ok(())
}

fn terminal_pdos(terminal: &SubDevice<Terminal>, assign: u16) -> Vec<Pdo> {
    assigned(&terminal.application, assign)
}
