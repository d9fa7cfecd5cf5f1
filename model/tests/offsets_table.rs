//! The image offsets table of `docs/adapter-protocol.md`, rendered from the
//! model's layouts (LAY-GEN-002..007, LAY-11-001, LAY-29-001, LAY-FD-001/002):
//! an adapter written from the document alone must find every offset there,
//! and the table can never drift from the layouts the harness judges by.
//!
//! `CANIF_BLESS=1 cargo test -p canif-model --test offsets_table` rewrites it.

use std::fmt::Write;
use std::path::PathBuf;

use canif_model::config::{FrameFormat, InterfaceConfig};
use canif_model::image::{field, Field, ImageLayout, LengthField, MessageLayout};

const BEGIN: &str =
    "<!-- image offsets: generated from the model by model/tests/offsets_table.rs -->";
const END: &str = "<!-- end of image offsets -->";

/// The interface kinds: (name, format, transaction number, time stamp).
const INTERFACES: [(&str, FrameFormat, bool, bool); 6] = [
    ("11-bit", FrameFormat::Base11, false, false),
    (
        "11-bit, transaction number",
        FrameFormat::Base11,
        true,
        false,
    ),
    ("29-bit", FrameFormat::Extended29, false, false),
    (
        "29-bit, transaction number",
        FrameFormat::Extended29,
        true,
        false,
    ),
    (
        "29-bit, transaction number and time stamp",
        FrameFormat::Extended29,
        true,
        true,
    ),
    ("CAN FD", FrameFormat::Fd, true, true),
];

fn range(field: &Field) -> String {
    if field.len() == 1 {
        format!("{}", field.start)
    } else {
        format!("{}..{}", field.start, field.end)
    }
}

fn header_rows(out: &mut String) {
    out.push_str("| Field | Outputs (0x700z) | Inputs (0x600z) |\n|---|---|---|\n");
    let rows = [
        (
            "TxCounter: UINT",
            range(&field::TX_COUNTER),
            range(&field::TX_COUNTER),
        ),
        (
            "RxCounter: UINT",
            range(&field::RX_COUNTER),
            range(&field::RX_COUNTER),
        ),
        (
            "NoOfTxMessages / NoOfRxMessages: UINT",
            range(&field::NO_OF_MESSAGES),
            range(&field::NO_OF_MESSAGES),
        ),
        (
            "TransactionNumber: UINT",
            "—".to_string(),
            format!(
                "{} (with transaction numbers; always with CAN FD)",
                range(&field::TRANSACTION_NUMBER)
            ),
        ),
    ];
    for (name, outputs, inputs) in rows {
        writeln!(out, "| {name} | {outputs} | {inputs} |").unwrap();
    }
}

fn interface_rows(out: &mut String) {
    out.push_str(
        "| Interface | TxMessage[n] | RxMessage[n] | InfoData[0] (r Rx slots) | \
         Outputs size (t Tx slots) |\n|---|---|---|---|---|\n",
    );
    for (name, format, transaction_number, time_stamp) in INTERFACES {
        let mut config = InterfaceConfig::new(format, 1);
        config.transaction_number = transaction_number;
        config.time_stamp = time_stamp;
        let layout = ImageLayout::new(&config, true);
        let (tx, rx) = (layout.tx_message, layout.rx_message);
        let rx_start = layout.rx_slot(0).start;
        writeln!(
            out,
            "| {name} | {} + {}·n ({}) | {rx_start} + {}·n ({}) | {rx_start} + {}·r | {} + {}·t |",
            layout.tx_slot(0).start,
            tx.size,
            tx.name,
            rx.size,
            rx.name,
            rx.size,
            field::MESSAGES,
            tx.size,
        )
        .unwrap();
    }
    writeln!(
        out,
        "\nInfoData is {} UDINTs ({} bytes) when the device offers it; the inputs end there.",
        field::INFO_DATA_WORDS,
        4 * field::INFO_DATA_WORDS
    )
    .unwrap();
}

fn message_rows(out: &mut String) {
    out.push_str(
        "| Message | Size | TransactionNumber | Length | Flags (EDL bit 0, BRS bit 1, ESI bit 2) \
         | COB ID | Data | TimeStamp |\n|---|---|---|---|---|---|---|---|\n",
    );
    let optional = |field: &Option<Field>| field.as_ref().map_or("—".to_string(), range);
    for message in MessageLayout::ALL {
        let length = match &message.length {
            LengthField::InCobIdWord => "bits 0–3 of the COB ID word".to_string(),
            LengthField::Word(field) => format!("{} (UINT)", range(field)),
            LengthField::Byte(field) => format!("{} (BYTE)", range(field)),
        };
        let cob_id = if message.cob_id.len() == 2 {
            format!(
                "{} (WORD: id << 5, RTR bit 4, length bits 0–3)",
                range(&message.cob_id)
            )
        } else {
            format!(
                "{} (UDINT: bit 31 = 29-bit, bit 30 = RTR)",
                range(&message.cob_id)
            )
        };
        writeln!(
            out,
            "| {} | {} | {} | {length} | {} | {cob_id} | {} | {} |",
            message.name,
            message.size,
            optional(&message.transaction_number),
            optional(&message.flags),
            range(&message.data),
            optional(&message.time_stamp),
        )
        .unwrap();
    }
}

fn table() -> String {
    let mut out = String::new();
    out.push_str(
        "Byte offsets, little-endian, packed; `a..b` is the bytes from a up to, not \
         including, b. Message fields are offsets inside the message.\n\n",
    );
    header_rows(&mut out);
    out.push('\n');
    interface_rows(&mut out);
    out.push('\n');
    message_rows(&mut out);
    out
}

#[test]
fn the_protocol_document_has_every_offset_the_model_uses() {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../docs/adapter-protocol.md");
    let document = std::fs::read_to_string(&path).expect("docs/adapter-protocol.md");
    let (Some(begin), Some(end)) = (document.find(BEGIN), document.find(END)) else {
        panic!(
            "{}: the markers `{BEGIN}` and `{END}` are missing",
            path.display()
        );
    };
    let current = &document[begin + BEGIN.len()..end];
    let expected = format!("\n{}", table());
    if current == expected {
        return;
    }
    if std::env::var_os("CANIF_BLESS").is_some() {
        let updated = format!(
            "{}{expected}{}",
            &document[..begin + BEGIN.len()],
            &document[end..]
        );
        std::fs::write(&path, updated).expect("write docs/adapter-protocol.md");
        return;
    }
    panic!(
        "{}: the image offsets table differs from the model's layouts; \
         run `CANIF_BLESS=1 cargo test -p canif-model --test offsets_table`.\nExpected:\n{expected}",
        path.display()
    );
}
