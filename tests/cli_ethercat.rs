//! `canif run --iut ethercat:emulated` as a new user runs it: the soft device
//! behind an emulated EtherCAT terminal, reached through real EtherCAT frames
//! by canif's master. Exit 0 on every terminal profile; exit 1 with a fault,
//! on the fault's requirement; exit 2 for a profile that is no terminal.

use std::process::{Command, Output};

fn canif(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_canif"))
        .args(args)
        .output()
        .expect("canif runs")
}

fn report_dir(name: &str) -> String {
    let dir = std::env::temp_dir().join(format!("canif-ecat-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir.to_string_lossy().into_owned()
}

#[test]
fn every_terminal_profile_conforms_through_ethercat_without_naming_them_and_a_fault_fails_its_requirement(
) {
    let dir = report_dir("pass");
    let out = canif(&[
        "run",
        "--iut",
        "ethercat:emulated",
        "--requirement",
        "HS-TX-001",
        "--requirement",
        "FLT-001",
        "--report",
        &dir,
    ]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{stdout}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    // A selection is a partial run: it passes what ran, it does not "conform".
    assert!(
        stdout.contains("ethercat:emulated PASSES WHAT RAN"),
        "{stdout}"
    );
    assert!(stdout.contains(" 0 fail, 0 error"), "{stdout}");
    // Without --profile, `all` is every terminal profile, and only those.
    let progress = String::from_utf8_lossy(&out.stderr);
    assert!(
        progress.contains("[1/2] el6751-legacy") && progress.contains("[2/2] el6751-mdp"),
        "{progress}"
    );

    let dir = report_dir("fault");
    let out = canif(&[
        "run",
        "--iut",
        "ethercat:emulated",
        "--fault",
        "filter-last-match-wins",
        "--profile",
        "el6751-mdp",
        "--requirement",
        "FLT-005",
        "--report",
        &dir,
    ]);
    let said = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(out.status.code(), Some(1), "{said}");
    // The first-match order is canif's assumption (G7), and said to be one.
    assert!(
        said.contains("FAIL el6751-mdp::FLT-005 (assumption)"),
        "{said}"
    );
}

#[test]
fn a_profile_that_is_no_terminal_is_a_usage_error_naming_the_terminals() {
    let out = canif(&["run", "--iut", "ethercat:emulated", "--profile", "fc510x"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("fc510x is no EtherCAT terminal"),
        "{stderr}"
    );
    assert!(stderr.contains("el6751-legacy, el6751-mdp"), "{stderr}");
}

/// `canif esi` writes the terminal's ESI file for each terminal profile
/// (harness/tests/ethercat_esc.rs holds its content to the terminal), and
/// names the terminals for a profile that is none.
#[test]
fn esi_writes_an_ethercat_info_document_for_a_terminal_profile() {
    for profile in ["el6751-legacy", "el6751-mdp"] {
        let out = canif(&["esi", "--profile", profile]);
        let xml = String::from_utf8_lossy(&out.stdout);
        assert_eq!(
            out.status.code(),
            Some(0),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        assert!(
            xml.starts_with("<?xml") && xml.contains("<EtherCATInfo"),
            "{xml}"
        );
    }
    let out = canif(&["esi", "--profile", "fc510x"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("el6751-legacy, el6751-mdp"), "{stderr}");
}

/// Why a test that needs what this machine lacks does not run: said on
/// stderr, and a failure where CI requires it (CANIF_VETH=required).
fn skip(test: &str, why: &str) {
    assert!(
        std::env::var("CANIF_VETH").as_deref() != Ok("required"),
        "CANIF_VETH=required, but {why}"
    );
    eprintln!("SKIP {test}: {why}");
}

/// canif's terminal on one end of a fresh veth pair (`tag` tells the pairs
/// of concurrent tests apart), or `None` where none can be made (skipped).
fn terminal_on_veth(test: &str, tag: u32) -> Option<(canif_kernel::VethPair, std::process::Child)> {
    let pair =
        canif_kernel::VethPair::for_test(&format!("{}", std::process::id() % 10_000 + tag), test)?;
    let terminal = Command::new(env!("CARGO_BIN_EXE_canif"))
        .args(["device", "--ethercat", &pair.terminal])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("canif device starts");
    Some((pair, terminal))
}

/// The same run across the kernel's packet path: the emulated terminal on one
/// end of a veth pair, canif's master on the other. Needs root (CI runs as
/// root and must not skip it: CANIF_VETH=required).
#[test]
fn the_terminal_is_certified_across_a_veth_pair() {
    let tag = format!("{}", std::process::id() % 10_000);
    let Some(pair) =
        canif_kernel::VethPair::for_test(&tag, "the_terminal_is_certified_across_a_veth_pair")
    else {
        return;
    };
    let iut = format!("ethercat:emulated@{},{}", pair.master, pair.terminal);
    let dir = report_dir("veth");
    let selection = ["--requirement", "HS-TX-001", "--requirement", "FLT-005"];
    let mut args = vec![
        "run",
        "--iut",
        &iut,
        "--profile",
        "el6751-mdp",
        "--report",
        &dir,
    ];
    args.extend(selection);
    let out = canif(&args);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{stdout}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(stdout.contains(" 0 fail, 0 error"), "{stdout}");

    args.extend(["--fault", "filter-last-match-wins"]);
    let out = canif(&args);
    let said = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(out.status.code(), Some(1), "{said}");
    // The first-match order is canif's assumption (G7), and said to be one.
    assert!(
        said.contains("FAIL el6751-mdp::FLT-005 (assumption)"),
        "{said}"
    );
}

/// A SOEM script (pysoem) against `canif device --ethercat` across a fresh
/// veth pair: what the script printed (it exited 0) and what the terminal
/// served; `None` where this machine cannot (said as a skip).
fn soem_against_the_terminal(test: &str, tag: u32, script: &str) -> Option<(String, String)> {
    soem_script(test, tag, script, &[])
}

/// [`soem_against_the_terminal`] with arguments after the interface.
fn soem_script(test: &str, tag: u32, script: &str, args: &[&str]) -> Option<(String, String)> {
    if !has_pysoem() {
        skip(test, "no Python package pysoem (.ci/run installs it)");
        return None;
    }
    let (pair, mut terminal) = terminal_on_veth(test, tag)?;
    // It opens its socket before it says so on stderr.
    std::thread::sleep(std::time::Duration::from_millis(500));
    let script = format!("{}/tests/python/{script}", env!("CARGO_MANIFEST_DIR"));
    let master = Command::new("timeout")
        .args(["60", "python3", &script, &pair.master])
        .args(args)
        .output()
        .expect("python3 runs");
    // SIGINT: the terminal says what it served and exits.
    let _ = Command::new("kill")
        .args(["-INT", &terminal.id().to_string()])
        .status();
    let served = wait_at_most(&mut terminal, std::time::Duration::from_secs(10));
    let said = String::from_utf8_lossy(&master.stdout).to_string();
    assert_eq!(
        master.status.code(),
        Some(0),
        "{said}{}",
        String::from_utf8_lossy(&master.stderr)
    );
    Some((said, served))
}

/// A second, independent master (SOEM, through the Python package pysoem)
/// scans, configures and runs canif's terminal across a veth pair, and the
/// CAN message its process image asked for shows on the terminal's side:
/// the terminal is not tuned to ethercrab.
#[test]
fn an_independent_master_drives_the_terminal() {
    let test = "an_independent_master_drives_the_terminal";
    let Some((said, served)) = soem_against_the_terminal(test, 1, "pysoem_master.py") else {
        return;
    };
    assert!(said.contains("Inputs.TxCounter confirmed 1"), "{said}");
    assert!(
        served.contains(" 123#CA1F"),
        "the terminal's side: {served}"
    );
}

/// A real EL6751 configuration starts canif's terminal: SOEM (pysoem)
/// plays the start-up list a configurator derives from the EL6751's public
/// description, in the real layout the SII gives, and exchanges a 29-bit
/// message with its transaction number through the 166/154-byte image.
#[test]
fn a_real_start_up_list_configures_the_terminal() {
    let test = "a_real_start_up_list_configures_the_terminal";
    let Some((said, served)) = soem_against_the_terminal(test, 3, "pysoem_start_up.py") else {
        return;
    };
    assert!(
        said.contains("mapped 166 output and 154 input bytes"),
        "{said}"
    );
    assert!(said.contains("Inputs.TransactionNumber 0x42"), "{said}");
    assert!(
        said.contains("0x7001:01 and 0x6001:04 read the image"),
        "{said}"
    );
    assert!(
        served.contains("01234567#CA1F"),
        "the terminal's side: {served}"
    );
}

/// A master that never asks for OP gets nothing onto the CAN side: it
/// configures the terminal, reaches SAFEOP and cycles 100 times with a batch
/// handed over (ETG.1000.6: outputs stay safe until OP; issue 58).
#[test]
fn a_master_that_never_requests_op_sends_nothing() {
    let test = "a_master_that_never_requests_op_sends_nothing";
    let script = "pysoem_outputs_safe.py";
    let Some((said, served)) = soem_script(test, 4, script, &["never-op"]) else {
        return;
    };
    assert!(
        said.contains("SAFEOP: 100 cycles, Inputs.TxCounter stays 0"),
        "{said}"
    );
    // The terminal prints each CAN frame it sends on stdout (candump's format).
    assert!(
        !served.lines().any(|line| line.contains('#')),
        "a frame went out before OP: {served}"
    );
}

/// In OP every batch goes; after the master's fall back to SAFEOP and after
/// the SM watchdog's, nothing new goes until OP again, and then it does.
#[test]
fn outputs_are_acted_on_in_op_only_also_after_a_fall_back() {
    let test = "outputs_are_acted_on_in_op_only_also_after_a_fall_back";
    let script = "pysoem_outputs_safe.py";
    let Some((said, served)) = soem_script(test, 5, script, &["fallbacks"]) else {
        return;
    };
    for step in [
        "SAFEOP: 100 cycles, Inputs.TxCounter stays 0",
        "OP: Inputs.TxCounter confirmed 1",
        "SAFEOP again (the master's): 50 cycles, Inputs.TxCounter stays 2",
        "OP again: Inputs.TxCounter confirmed 3",
        "the SM watchdog: SAFEOP, AL status 0x001b",
        "SAFEOP after the watchdog: 50 cycles, Inputs.TxCounter stays 3",
        "OP after the watchdog: Inputs.TxCounter confirmed 4",
    ] {
        assert!(said.contains(step), "{step}: {said}");
    }
    // Each batch once, in the order handed over.
    let at = |frame: &str| {
        assert_eq!(served.matches(frame).count(), 1, "{frame}: {served}");
        served.find(frame).unwrap()
    };
    let order = [
        at(" 111#5AFE"),
        at(" 222#0B0B"),
        at(" 333#33"),
        at(" 444#44"),
    ];
    assert!(order.windows(2).all(|w| w[0] < w[1]), "{served}");
}

/// Beckhoff's manual configures the CAN interface "with Complete Access or
/// with consistency nesting": both give the same configuration, and a
/// record left open keeps the terminal from SAFEOP.
#[test]
fn consistency_nesting_configures_the_terminal_as_complete_access_does() {
    let test = "consistency_nesting_configures_the_terminal_as_complete_access_does";
    let Some((said, served)) = soem_script(test, 6, "pysoem_nesting.py", &[]) else {
        return;
    };
    for step in [
        "complete access and nesting read back alike",
        "0x8000:00 reads 0 while open",
        "an open 0x8000 refuses SAFEOP with AL status 0x0026",
        "mapped 166 output and 154 input bytes",
        "Inputs.TxCounter confirmed 1, Inputs.TransactionNumber 0x42",
    ] {
        assert!(said.contains(step), "{step}: {said}");
    }
    assert!(served.contains("01234567#CA1F"), "{served}");
}

fn has_pysoem() -> bool {
    Command::new("python3")
        .args(["-c", "import pysoem"])
        .output()
        .is_ok_and(|o| o.status.success())
}

/// A master whose source address is locally administered (a veth's, a
/// VM's, a USB NIC's) is answered: an ESC processes every EtherCAT frame
/// (issue 35: such frames were ignored). A BRD of the ESC type register
/// from 02:00:00:00:00:01 comes back with working counter 1.
#[test]
fn a_master_on_a_locally_administered_address_is_answered() {
    let test = "a_master_on_a_locally_administered_address_is_answered";
    let Some((pair, mut terminal)) = terminal_on_veth(test, 2) else {
        return;
    };
    let master = canif_kernel::PacketSocket::open(&pair.master, 0x88A4).unwrap();
    #[rustfmt::skip]
    let mut frame = vec![
        0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, // to everyone
        0x02, 0x00, 0x00, 0x00, 0x00, 0x01, // from a locally administered address
        0x88, 0xA4, // EtherCAT
        0x0E, 0x10, // 14 bytes of datagrams, type 1
        0x07, 0x00, // BRD, index 0
        0x00, 0x00, 0x00, 0x00, // position 0, register 0x0000 (type)
        0x02, 0x00, 0x00, 0x00, // 2 bytes, last datagram; no IRQ
        0x00, 0x00, // data
        0x00, 0x00, // working counter
    ];
    frame.resize(60, 0);
    let mut answer = vec![0u8; 2048];
    let mut answered = None;
    // Until the terminal has opened its socket (a readiness wait, not a
    // speed: it ends at the first answer).
    for _ in 0..200 {
        master.send(&frame).unwrap();
        if let Some(n) = master
            .recv(&mut answer, std::time::Duration::from_millis(100))
            .unwrap()
        {
            answered = Some(n);
            break;
        }
    }
    let _ = Command::new("kill")
        .args(["-INT", &terminal.id().to_string()])
        .status();
    wait_at_most(&mut terminal, std::time::Duration::from_secs(10));
    let n = answered.expect("the terminal never answered a frame from 02:00:00:00:00:01");
    assert!(n >= 30, "{:02X?}", &answer[..n]);
    assert_eq!(&answer[12..14], [0x88, 0xA4], "{:02X?}", &answer[..n]);
    let working_counter = u16::from_le_bytes([answer[28], answer[29]]);
    assert_eq!(working_counter, 1, "{:02X?}", &answer[..n]);
}

/// The child's stdout once it ended; killed if it does not end in time.
fn wait_at_most(child: &mut std::process::Child, limit: std::time::Duration) -> String {
    let began = std::time::Instant::now();
    while child.try_wait().ok().flatten().is_none() && began.elapsed() < limit {
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    let _ = child.kill();
    let mut out = String::new();
    if let Some(mut stdout) = child.stdout.take() {
        use std::io::Read;
        let _ = stdout.read_to_string(&mut out);
    }
    let _ = child.wait();
    out
}

/// SIGTERM ends `canif device --ethercat` at once, saying what it served
/// (issue 35: a terminal hung by a master once ignored the first one).
#[test]
fn sigterm_ends_the_terminal_at_once() {
    let test = "sigterm_ends_the_terminal_at_once";
    let Some((_pair, mut terminal)) = terminal_on_veth(test, 4) else {
        return;
    };
    std::thread::sleep(std::time::Duration::from_millis(300));
    let _ = Command::new("kill")
        .args(["-TERM", &terminal.id().to_string()])
        .status();
    // A readiness bound, not a speed: a terminal that ignores SIGTERM is
    // killed after it and found still running.
    let began = std::time::Instant::now();
    while terminal.try_wait().ok().flatten().is_none()
        && began.elapsed() < std::time::Duration::from_secs(10)
    {
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    let status = terminal.try_wait().ok().flatten();
    let _ = terminal.kill();
    let _ = terminal.wait();
    assert!(
        status.is_some_and(|s| s.success()),
        "canif device --ethercat did not end on SIGTERM: {status:?}"
    );
}
