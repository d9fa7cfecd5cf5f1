//! Every broken door is one clear error (issue 34): a command that cannot
//! start, a reader that goes away, a probe of an IUT that breaks. Each case
//! runs `canif` as a user would and holds it to its exit code and words.

use std::io::Read as _;
use std::path::PathBuf;
use std::process::{Command, Stdio};

const CANIF: &str = env!("CARGO_BIN_EXE_canif");

fn scratch(case: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("canif-doors-{case}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// `canif run 2>&1 | head -c 64`: the reader leaves after a few bytes, and
/// canif neither panics nor loses its reports.
#[test]
fn a_reader_that_goes_away_ends_nothing_badly() {
    let dir = scratch("pipe");
    let (mut reader, writer) = std::io::pipe().unwrap();
    let mut child = Command::new(CANIF)
        .args(["run", "--profile", "fc510x", "--report"])
        .arg(dir.join("report"))
        .stdin(Stdio::null())
        .stdout(writer.try_clone().unwrap())
        .stderr(writer)
        .spawn()
        .unwrap();
    let mut head = [0u8; 64];
    reader.read_exact(&mut head).unwrap();
    drop(reader);
    let status = child.wait().unwrap();
    assert_eq!(
        status.code(),
        Some(0),
        "{status} (101 is a panic on the closed pipe)"
    );
    assert!(
        dir.join("report/report.json").is_file(),
        "the report was not written"
    );
}
