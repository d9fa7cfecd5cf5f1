//! No IUT can hang, kill or fool the harness: every way an external IUT can
//! misbehave ends `canif run` with exit 2 within a bounded time, a report that
//! names what the IUT did, and no process of the IUT left running.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::time::{Duration, Instant};

const CANIF: &str = env!("CARGO_BIN_EXE_canif");

/// Not a speed (that is `cargo bench`'s): a run past this never ends by
/// itself. Generous, so that a busy machine (CI's load run: four busy
/// processes on two cores) is never taken for a hang.
const NEVER_ENDS: Duration = Duration::from_secs(300);

/// A scratch folder of its own for each case.
fn scratch(case: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("canif-boundary-{case}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn script(name: &str) -> String {
    format!("{}/tests/iuts/{name}", env!("CARGO_MANIFEST_DIR"))
}

/// A process that still runs (a zombie has ended).
fn alive(pid: u32) -> bool {
    std::fs::read_to_string(format!("/proc/{pid}/stat"))
        .map(|stat| {
            let state = stat.rsplit(')').next().unwrap_or("").trim_start();
            !state.starts_with('Z')
        })
        .unwrap_or(false)
}

struct Run {
    output: Output,
    elapsed: Duration,
    report: String,
    dir: PathBuf,
}

/// `canif run` against `iut` on one profile, with a short timeout; the IUT
/// records its pids in `pids` (CANIF_TEST_PIDS).
fn run(case: &str, iut: &str, extra: &[&str]) -> Run {
    let dir = scratch(case);
    let started = Instant::now();
    let output = Command::new(CANIF)
        .args([
            "run",
            "--profile",
            "fc510x",
            "--timeout-ms",
            "1000",
            "--report",
        ])
        .arg(dir.join("report"))
        .arg("--iut")
        .arg(iut)
        .args(extra)
        .env("CANIF_TEST_PIDS", dir.join("pids"))
        .output()
        .expect("canif starts");
    let elapsed = started.elapsed();
    let report = std::fs::read_to_string(dir.join("report/report.json")).unwrap_or_default();
    Run {
        output,
        elapsed,
        report,
        dir,
    }
}

impl Run {
    fn stderr(&self) -> String {
        String::from_utf8_lossy(&self.output.stderr).into_owned()
    }

    /// Exit 2 (1 where the run also found a failure: these IUTs accept every
    /// configuration, which the refusal grid fails), within `seconds`, a
    /// report naming every one of `words`, and none of the IUT's recorded
    /// processes left.
    fn is_an_error(&self, words: &[&str]) {
        let failed = self.report.contains("\"verdict\": \"fail\"");
        assert_eq!(
            self.output.status.code(),
            Some(if failed { 1 } else { 2 }),
            "exit status {:?}; stderr:\n{}",
            self.output.status,
            self.stderr()
        );
        assert!(self.elapsed < NEVER_ENDS, "took {:?}", self.elapsed);
        assert!(
            !self.report.is_empty(),
            "no report.json; stderr:\n{}",
            self.stderr()
        );
        for words in words {
            assert!(
                self.report.contains(words),
                "the report does not say {words:?}; stderr:\n{}",
                self.stderr()
            );
        }
        self.leaves_nothing_running();
    }

    fn leaves_nothing_running(&self) {
        let pids = std::fs::read_to_string(self.dir.join("pids")).unwrap_or_default();
        let survivors: Vec<u32> = pids
            .lines()
            .filter_map(|l| l.trim().parse().ok())
            .filter(|pid| alive(*pid))
            .collect();
        assert!(
            survivors.is_empty(),
            "IUT processes still running: {survivors:?}"
        );
    }
}

fn recorded(command: &str) -> String {
    format!("exec:echo $$ >> \"$CANIF_TEST_PIDS\"; {command}")
}

#[test]
fn an_iut_that_exits_after_answering_is_an_error() {
    let iut =
        recorded(r#"read l; echo '{"type":"configured","protocol":1,"accepted":true}'; exit 0"#);
    run("exits", &iut, &[]).is_an_error(&["exited (exit status: 0)"]);
}

/// A command that cannot start is one line naming it with the shell's own
/// words, and exit 2 (issue 34: it was an ERROR line per requirement, and
/// once 662 lines of `sh: not found`).
#[test]
fn a_mistyped_iut_path_is_one_line() {
    let run = run("typo", "exec:./no-such-iut-anywhere", &[]);
    assert_eq!(run.output.status.code(), Some(2), "{}", run.stderr());
    let stderr = run.stderr();
    let lines: Vec<&str> = stderr.lines().collect();
    assert_eq!(lines.len(), 1, "{stderr}");
    assert!(
        lines[0].contains("cannot start `./no-such-iut-anywhere`")
            && lines[0].contains("not found"),
        "{stderr}"
    );
    assert!(
        run.report.is_empty(),
        "a run that never started wrote a report"
    );
    // The same for the PLC side, and for a library that is no file.
    for (side, iut) in [
        ("plc", "exec:./no-such-client-anywhere"),
        ("device", "lib:./no-such-library.so"),
    ] {
        let output = Command::new(CANIF)
            .args(["run", side, "--iut", iut, "--report"])
            .arg(scratch("typo-other").join("report"))
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert_eq!(output.status.code(), Some(2), "{side}: {stderr}");
        assert_eq!(stderr.lines().count(), 1, "{side}: {stderr}");
        assert!(stderr.contains("no-such-"), "{side}: {stderr}");
    }
}

#[test]
fn a_line_that_is_not_utf8_is_an_error_not_a_hang() {
    let iut = recorded(r"printf '\377\n'; cat >/dev/null");
    run("utf8", &iut, &[]).is_an_error(&["not UTF-8"]);
}

#[test]
fn an_iut_that_closes_stdout_and_keeps_running_is_killed() {
    let iut = recorded("exec >&-; exec sleep 3599");
    run("closed", &iut, &[]).is_an_error(&["closed its stdout"]);
}

#[test]
fn an_endless_line_is_cut_off() {
    let iut = recorded("head -c 3000000 /dev/zero | tr '\\0' a; sleep 3600");
    let run = run("endless", &iut, &[]);
    run.is_an_error(&["longer than 1048576 bytes"]);
}

#[test]
fn an_iut_that_forks_and_hangs_leaves_no_process() {
    let iut = format!("exec:python3 {} fork-hang", script("misbehave.py"));
    let run = run("fork", &iut, &[]);
    run.is_an_error(&["no answer to `cycle` within 1000 ms"]);
    // Each IUT process (the refusal grid's, then the first scenario's) and its child.
    let pids = std::fs::read_to_string(run.dir.join("pids")).unwrap();
    assert!(
        pids.lines().count() >= 2,
        "the IUT and its child recorded themselves: {pids}"
    );
}

/// A child that leaves the IUT's process group and session (`setsid`) ends
/// with the IUT all the same (issue 26: it survived the run).
#[test]
fn an_iut_whose_child_leaves_its_session_leaves_no_process() {
    let iut = format!("exec:python3 {} setsid-hang", script("misbehave.py"));
    let run = run("setsid", &iut, &[]);
    run.is_an_error(&["no answer to `cycle` within 1000 ms"]);
    let pids = std::fs::read_to_string(run.dir.join("pids")).unwrap();
    assert!(pids.lines().count() >= 2, "recorded: {pids}");
}

/// A daemon the IUT starts — double fork, `setsid`, stdio closed, an empty
/// environment — ends with the IUT all the same (issue 34: it survived every
/// run, as nothing marked it as the IUT's).
#[test]
fn an_iut_whose_daemon_forgets_everything_leaves_no_process() {
    let iut = format!("exec:python3 {} daemon-hang", script("misbehave.py"));
    let run = run("daemon", &iut, &[]);
    run.is_an_error(&["no answer to `cycle` within 1000 ms"]);
    let pids = std::fs::read_to_string(run.dir.join("pids")).unwrap();
    assert!(pids.lines().count() >= 2, "recorded: {pids}");
}

/// An IUT whose first process exits while a child it started lives on: the
/// orphan comes to canif (a subreaper), which ends it with the run (issue
/// 52: such a child outlived `canif run`).
#[test]
fn an_iut_that_exits_leaving_a_child_leaves_no_process() {
    let iut = format!("exec:python3 {} exit-leaving-child", script("misbehave.py"));
    let run = run("orphan", &iut, &[]);
    run.is_an_error(&["exited"]);
    let pids = std::fs::read_to_string(run.dir.join("pids")).unwrap();
    assert!(pids.lines().count() >= 2, "recorded: {pids}");
}

#[test]
fn time_that_does_not_advance_is_an_error() {
    let iut = format!("exec:python3 {} stuck-time", script("misbehave.py"));
    run("stuck", &iut, &[]).is_an_error(&["does not advance"]);
}

#[test]
fn a_frame_whose_len_lies_is_an_error() {
    let iut = format!("exec:python3 {} lie-len", script("misbehave.py"));
    run("lie", &iut, &[]).is_an_error(&["\\\"len\\\" is 15 but \\\"data\\\" has 8 bytes"]);
}

/// A babbling controller is a non-conformance: the lockstep names it, and the
/// bus does not spin on it (features/tests/catalogue.rs holds the Gherkin
/// stage to the same bound).
#[test]
fn a_babbling_controller_is_caught_in_bounded_time() {
    let iut = format!("exec:python3 {} babble", script("misbehave.py"));
    let run = run("babble", &iut, &["--scenario", "tx-batches"]);
    assert_eq!(run.output.status.code(), Some(1), "{}", run.stderr());
    assert!(run.elapsed < NEVER_ENDS, "took {:?}", run.elapsed);
    assert!(run.report.contains("\"HS-TX-006\""), "{}", run.stderr());
    run.leaves_nothing_running();
}

/// The IUT exits exactly when its controller has a frame to send: the report
/// says it exited; it does not charge HS-TX-* with a missing frame.
#[test]
fn an_iut_that_dies_with_a_frame_due_is_an_error_not_a_failure() {
    let iut = format!(
        "exec:python3 {} {CANIF} device --stdio",
        script("dies_when_a_frame_is_due.py")
    );
    let run = run("dies", &iut, &[]);
    run.is_an_error(&["exited (exit status: 3)", "dying with a frame due"]);
    assert!(
        !run.report.contains("\"verdict\": \"fail\""),
        "a broken IUT failed a requirement"
    );
}

/// A well-formed answer describing a frame no controller can send (BRS on a
/// classic frame, an identifier wider than its format) is what the device
/// did wrong: a failure naming the frame, not a broken exchange (issue 26).
#[test]
fn a_frame_no_controller_can_send_is_a_failure_not_an_error() {
    for (mode, words) in [
        ("brs-classic", "BRS on a classic frame"),
        (
            "wide-id",
            "identifier 0x1234 does not fit an 11-bit identifier",
        ),
    ] {
        let iut = format!("python3 {} {mode}", script("misbehave.py"));
        let run = run(mode, &recorded(&iut), &[]);
        assert_eq!(run.output.status.code(), Some(1), "{}", run.stderr());
        assert!(run.report.contains(words), "{mode}: {}", run.stderr());
        assert!(
            !run.report.contains("broken frame"),
            "{mode}: judged a broken exchange: {}",
            run.stderr()
        );
        run.leaves_nothing_running();
    }
}

/// After the first error the rest of the profile is skipped, not retried.
#[test]
fn after_the_iut_breaks_the_rest_of_the_profile_is_skipped() {
    let iut =
        recorded(r#"read l; echo '{"type":"configured","protocol":1,"accepted":true}'; exit 0"#);
    let run = run("skipped", &iut, &[]);
    // The refusal grid meets it first: one answer, then it is gone.
    assert!(run
        .report
        .contains("skipped after the IUT broke in `configuration refusals`"));
    assert!(run
        .stderr()
        .contains("Gherkin scenarios not run: the IUT broke"));
}

/// SIGINT: the IUT is stopped, the reports hold what ran, marked interrupted, exit 130.
#[test]
fn an_interrupted_run_still_writes_its_reports() {
    let dir = scratch("sigint");
    let iut = format!(
        "exec:echo $$ >> \"$CANIF_TEST_PIDS\"; exec python3 {}",
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("examples/python/minimal_iut.py")
            .display()
    );
    let child = Command::new(CANIF)
        .args(["run", "--profile", "fc510x-before-fw2.14", "--report"])
        .arg(dir.join("report"))
        .arg("--iut")
        .arg(&iut)
        .env("CANIF_TEST_PIDS", dir.join("pids"))
        .stderr(std::process::Stdio::piped())
        .stdout(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    // Once the IUT has started at least twice, the run is well under way.
    let started = Instant::now();
    while std::fs::read_to_string(dir.join("pids")).map_or(0, |p| p.lines().count()) < 2 {
        assert!(
            started.elapsed() < NEVER_ENDS,
            "the run never started its IUT"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
    Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    let output = child.wait_with_output().unwrap();
    assert_eq!(
        output.status.code(),
        Some(130),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    let report = std::fs::read_to_string(dir.join("report/report.json")).unwrap();
    assert!(report.contains("\"interrupted\": true"));
    assert!(String::from_utf8_lossy(&output.stderr).contains("interrupted"));
    let pids = std::fs::read_to_string(dir.join("pids")).unwrap();
    let survivors: Vec<&str> = pids
        .lines()
        .filter(|p| p.parse().is_ok_and(alive))
        .collect();
    assert!(survivors.is_empty(), "still running: {survivors:?}");
}
