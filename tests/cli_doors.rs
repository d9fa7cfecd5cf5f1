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

/// `canif probe` against an IUT that breaks — prints garbage, hangs,
/// exits — says so and exits 2, and writes no choices file (issue 34: it
/// exited 0 and wrote `{}`, a declaration of nothing taken for a finding).
#[test]
fn a_probe_of_a_broken_iut_is_an_error_and_writes_nothing() {
    for (case, iut) in [
        ("garbage", "exec:echo not json; cat > /dev/null"),
        ("hangs", "exec:exec sleep 3600"),
        ("exits", "exec:exit 3"),
    ] {
        let dir = scratch(&format!("probe-{case}"));
        let out = dir.join("choices.json");
        let output = Command::new(CANIF)
            .args(["probe", "--profile", "fc510x", "--timeout-ms", "500"])
            .args(["--start-timeout-ms", "500", "--iut", iut, "--out"])
            .arg(&out)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert_eq!(output.status.code(), Some(2), "{case}: {stderr}");
        // One that never answers cannot start: said before anything runs.
        let says = match case {
            "hangs" => "within 500 ms, the start limit",
            _ => "the IUT broke",
        };
        assert!(stderr.contains(says), "{case}: {stderr}");
        assert!(!out.exists(), "{case}: a choices file was written");
    }
}

/// Issue 52: an IUT that never answers its first request (a Python IUT that
/// forgets to flush stdout) is started once, not once per profile or probe
/// step: `canif run` on every profile and `canif probe` each end with one
/// error naming the limit, how to raise it and the usual cause.
#[test]
fn an_iut_that_never_answers_is_started_once_and_said_once() {
    for command in [&["run", "--report"][..], &["probe", "--out"]] {
        let dir = scratch(&format!("never-answers-{}", command[0]));
        let starts = dir.join("starts");
        let iut = format!(
            "exec:echo started >> '{}'; exec sleep 3600",
            starts.display()
        );
        let output = Command::new(CANIF)
            .args(command)
            .arg(dir.join("out"))
            .args([
                "--timeout-ms",
                "500",
                "--start-timeout-ms",
                "500",
                "--iut",
                &iut,
            ])
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert_eq!(output.status.code(), Some(2), "{command:?}: {stderr}");
        for words in [
            "within 500 ms, the start limit",
            "CANIF_START_TIMEOUT_MS",
            "flush its stdout",
        ] {
            assert!(stderr.contains(words), "{command:?}: {stderr}");
        }
        let started = std::fs::read_to_string(&starts).unwrap_or_default();
        assert_eq!(
            started.lines().count(),
            1,
            "{command:?}: started {started:?}"
        );
    }
}
