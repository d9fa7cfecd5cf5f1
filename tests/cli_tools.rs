//! The command-line tools say what the model says: `canif frame-time` prints
//! the bit counts of `fd_bits` (held to a bit-level stuffing count in
//! model/tests/timing.rs) for every FD size and both identifier lengths, and
//! `canif size` gives both sizing figures with the safe one recommended.

use std::process::Command;

use canif_model::timing::fd_bits;

fn canif(args: &[&str]) -> String {
    let output = Command::new(env!("CARGO_BIN_EXE_canif"))
        .args(args)
        .output()
        .expect("canif runs");
    assert!(
        output.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&output.stderr)
    );
    String::from_utf8_lossy(&output.stdout).into_owned()
}

/// Covers: TIM-003
#[test]
fn frame_time_prints_the_models_split_for_every_fd_size() {
    for extended in [false, true] {
        for &len in canif_model::dlc::FD_DATA_SIZES.iter() {
            let payload = len.to_string();
            let mut args = vec![
                "frame-time",
                "--bitrate",
                "500000",
                "--data-bitrate",
                "2000000",
                "--fd",
                "--payload",
                &payload,
            ];
            if extended {
                args.push("--extended");
            }
            let text = canif(&args);
            let bits = fd_bits(extended, len, true);
            let expected = format!(
                "(arbitration {}/{}, data phase {}/{})",
                bits.arbitration.nominal,
                bits.arbitration.worst_case,
                bits.data.nominal,
                bits.data.worst_case
            );
            assert!(text.contains(&expected), "{args:?}: {text}");
        }
    }
    // The case the issue measured: 11-bit, 0 bytes.
    assert!(canif(&[
        "frame-time",
        "--bitrate",
        "125000",
        "--data-bitrate",
        "8000000",
        "--fd",
        "--payload",
        "0"
    ])
    .contains("(arbitration 30/33, data phase 32/34)"));
}

/// Covers: TIM-008
#[test]
fn size_gives_both_figures_and_recommends_the_safe_one() {
    let text = canif(&[
        "size",
        "--bitrate",
        "500000",
        "--cycle-us",
        "1000",
        "--payload",
        "8",
    ]);
    let line = |label: &str| {
        text.lines()
            .find(|l| l.contains(label))
            .unwrap_or_default()
            .to_string()
    };
    assert!(
        line("the manual's figure").contains("->    4 slots"),
        "{text}"
    );
    assert!(
        line("safe").contains("->    5 slots  <- recommended"),
        "{text}"
    );
    assert!(text.contains("4 slots can overflow"), "{text}");
}

/// Issue 36: `spec show` names a document by its title and edition, not its
/// hashed file name alone, and shows a ruling with its text.
#[test]
fn spec_show_names_the_document_and_the_ruling() {
    let shown = canif(&["spec", "show", "FD-LEN-002"]);
    assert!(
        shown.contains("source: CAN-Interface manual, version 1.7 (Chinese; the later document), §8.3.1 DLC table (001_c68c573893220081.txt)"),
        "{shown}"
    );
    assert!(
        shown.contains("ruling R1: CAN FD length/DLC: DLC 13 is 32 bytes, not 36"),
        "{shown}"
    );
}
