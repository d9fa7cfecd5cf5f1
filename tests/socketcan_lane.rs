//! The suite on a real Linux CAN stack, end to end as a user runs it: `canif
//! run --bus socketcan:…` with the soft device attached and as its own process
//! (`canif device --bus …`), over vcan and over two emulated SJA1000
//! controllers; the CANopen checks and the quick start against `canif coupler
//! --bus …`; Python's canopen package over SocketCAN; and what must end in an
//! `error` verdict: an interface going down, a send buffer that stays full.
//!
//! Interfaces come from the kernel lane (`scripts/kernel-can-lane`):
//! CANIF_LANE_FD (vcan0, mtu 72), CANIF_LANE_CLASSIC (vcan1) and
//! CANIF_LANE_CONTROLLERS (can0,can1). Without AF_CAN or without the
//! interface, a trial is listed as ignored with the reason (the errno).

use std::io::{BufRead, BufReader};
use std::path::PathBuf;
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};

use canif_harness::device::quick_start::quick_start;
use canif_harness::door::adapter::protocol::OwnedBus;
use canif_harness::door::exec::ExecIut;
use canif_model::canopen::NodeId;
use canif_model::config::InterfaceConfig;
use canif_model::image::ImageLayout;
use libtest_mimic::{Arguments, Failed, Trial};

/// The `canif` under test: this build's, or CANIF_BIN (the kernel lane points
/// it at the release build: under emulation a debug build is several times slower).
/// A missing binary is named, with where the path came from.
fn canif_bin() -> String {
    let (path, from) = match std::env::var("CANIF_BIN") {
        Ok(path) => (path, "CANIF_BIN"),
        Err(_) => (env!("CARGO_BIN_EXE_canif").to_string(), "cargo"),
    };
    assert!(
        std::path::Path::new(&path).is_file(),
        "the canif binary {path} (from {from}) does not exist"
    );
    path
}

fn canif(args: &[&str]) -> Output {
    let bin = canif_bin();
    Command::new(&bin)
        .args(args)
        .output()
        .unwrap_or_else(|e| panic!("{bin} does not start: {e}"))
}

fn text(output: &Output) -> String {
    format!(
        "exit {:?}\nstdout:\n{}\nstderr:\n{}",
        output.status.code(),
        String::from_utf8_lossy(&output.stdout),
        String::from_utf8_lossy(&output.stderr)
    )
}

fn report_path(name: &str) -> PathBuf {
    std::env::temp_dir().join(format!("canif-lane-{name}-{}", std::process::id()))
}

/// A fresh (empty) folder for a run's reports.
fn report_dir(name: &str) -> PathBuf {
    let dir = report_path(name);
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

fn report(dir: &std::path::Path) -> Result<serde_json::Value, String> {
    let path = dir.join("report.json");
    let text = std::fs::read_to_string(&path).map_err(|e| format!("{}: {e}", path.display()))?;
    serde_json::from_str(&text).map_err(|e| format!("{}: {e}", path.display()))
}

/// A run's totals from its report, and frames checked per second of wall time.
fn totals(report: &serde_json::Value) -> (String, f64) {
    let frames: u64 = report["profiles"]
        .as_array()
        .into_iter()
        .flatten()
        .map(|p| p["frames_checked"].as_u64().unwrap_or(0))
        .sum();
    let seconds = report["wall_time_ms"].as_f64().unwrap_or(1.0) / 1000.0;
    (report["totals"].to_string(), frames as f64 / seconds)
}

/// `canif run` on a SocketCAN bus must conform, and say which bus and kernel it used.
fn conforms_on(bus: &str, iut: &str, profile: &str, extra: &[&str]) -> Result<(), Failed> {
    let dir = report_dir(&format!("{profile}-{}", bus.replace([':', ','], "-")));
    let dir_text = dir.display().to_string();
    let mut args = vec![
        "run",
        "--iut",
        iut,
        "--bus",
        bus,
        "--profile",
        profile,
        "--cases",
        "1",
        "--duration",
        "0.1",
        "--cycle-us",
        "5000",
        "--report",
        &dir_text,
    ];
    args.extend_from_slice(extra);
    let started = Instant::now();
    let output = canif(&args);
    let report = report(&dir).map_err(|e| format!("{e}\n{}", text(&output)))?;
    let (totals, rate) = totals(&report);
    eprintln!(
        "{iut} on {bus} ({profile}): {totals}, {rate:.0} checked frames/s, {:?}",
        started.elapsed()
    );
    if output.status.code() != Some(0) {
        let summary = std::fs::read_to_string(dir.join("summary.md")).unwrap_or_default();
        let summary: Vec<&str> = summary.lines().take(80).collect();
        return Err(format!(
            "expected conformance\n{}\nsummary:\n{}",
            text(&output),
            summary.join("\n")
        )
        .into());
    }
    let bus_text = report["meta"]["bus"].as_str().unwrap_or_default();
    let interface = bus
        .trim_start_matches("socketcan:")
        .split(',')
        .next()
        .unwrap_or_default();
    if !bus_text.contains(interface) || !bus_text.contains("Linux") {
        return Err(format!("the report does not name the bus and kernel: {bus_text:?}").into());
    }
    if report["totals"]["pass"].as_u64().unwrap_or(0) < 20 {
        return Err(format!("too little checked: {totals}").into());
    }
    Ok(())
}

/// A run that must fail on `requirement`: exit 1, and the requirement in its summary.
fn failed_on(output: &Output, dir: &std::path::Path, requirement: &str) -> Result<(), Failed> {
    let summary = std::fs::read_to_string(dir.join("summary.md")).unwrap_or_default();
    if output.status.code() != Some(1) || !summary.contains(requirement) {
        return Err(format!(
            "expected a failure of {requirement}\n{}\nsummary:\n{summary}",
            text(output)
        )
        .into());
    }
    Ok(())
}

fn device_command(interface: &str, fault: Option<&str>) -> String {
    format!(
        "exec:{} device --stdio --bus socketcan:{interface}{}",
        canif_bin(),
        fault.map_or(String::new(), |f| format!(" --fault {f}"))
    )
}

/// A faulty device on its own socket is rejected by the requirement it breaks.
fn fault_caught_over(interface: &str) -> Result<(), Failed> {
    let dir = report_dir("fault");
    let output = canif(&[
        "run",
        "--iut",
        &device_command(interface, Some("sends-batch-reversed")),
        "--bus",
        &format!("socketcan:{interface}"),
        "--profile",
        "fc510x",
        "--scenario",
        "tx-batches",
        "--cycle-us",
        "5000",
        "--report",
        &dir.display().to_string(),
    ]);
    failed_on(&output, &dir, "HS-TX-006")
}

/// The PLC side over a kernel: the model device's controller and the other
/// nodes on one interface, so the client's frames cross a real CAN stack;
/// the reference client conforms and a faulty one is caught on its requirement.
fn client_side_over(interface: &str) -> Result<(), Failed> {
    let bus = format!("socketcan:{interface}");
    let run = |name: &str, extra: &[&str]| {
        let dir = report_dir(name);
        let mut args = vec![
            "run",
            "plc",
            "--bus",
            &bus,
            "--profile",
            "fc532x",
            "--master",
            "lrw",
            "--no-counter-wrap",
        ];
        args.extend_from_slice(extra);
        let dir_text = dir.display().to_string();
        args.extend_from_slice(&["--report", &dir_text]);
        let started = Instant::now();
        let output = canif(&args);
        eprintln!("client side over {bus} ({name}): {:?}", started.elapsed());
        (output, dir)
    };
    let (output, dir) = run("client-reference", &[]);
    let report = report(&dir).map_err(|e| format!("{e}\n{}", text(&output)))?;
    let (totals, _) = totals(&report);
    if output.status.code() != Some(0) {
        return Err(format!(
            "expected the reference client to conform\n{}",
            text(&output)
        )
        .into());
    }
    let bus_text = report["meta"]["bus"].as_str().unwrap_or_default();
    if report["meta"]["side"] != "plc"
        || !bus_text.contains(interface)
        || !bus_text.contains("Linux")
    {
        return Err(
            format!("the report does not name the side, bus and kernel: {bus_text:?}").into(),
        );
    }
    if report["totals"]["pass"].as_u64().unwrap_or(0) < 10 {
        return Err(format!("too little checked: {totals}").into());
    }
    // The @plc Gherkin scenarios need the simulated bus: the report says they
    // did not run rather than passing without them.
    let left_out = report["meta"]["left_out"].as_str().unwrap_or_default();
    if report["meta"]["complete"] != false || !left_out.contains("Gherkin scenarios not run") {
        return Err(format!("the report hides that no Gherkin scenario ran: {left_out:?}").into());
    }
    let (output, dir) = run("client-fault", &["--fault", "one-based-slots"]);
    let summary = std::fs::read_to_string(dir.join("summary.md")).unwrap_or_default();
    if output.status.code() != Some(1) || !summary.contains("CL-TX-004") {
        return Err(format!(
            "expected one-based-slots to fail CL-TX-004\n{}\nsummary:\n{summary}",
            text(&output)
        )
        .into());
    }
    Ok(())
}

/// `ip link set IFACE up|down`, through the socketcan crate's netlink.
fn link(interface: &str, up: bool) -> Result<(), Failed> {
    canif_kernel::set_link(interface, up).map_err(Failed::from)
}

/// An interface going down mid-run ends the run with an error naming it; the
/// report is still written.
fn interface_down_is_an_error(interface: &str) -> Result<(), Failed> {
    let dir = report_dir("down");
    let child = Command::new(canif_bin())
        .args([
            "run",
            "--bus",
            &format!("socketcan:{interface}"),
            "--profile",
            "fc510x",
            "--scenario",
            "generated",
            "--duration",
            "20",
            "--cycle-us",
            "2000",
            "--report",
            &dir.display().to_string(),
        ])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()?;
    std::thread::sleep(Duration::from_millis(1500));
    let downed = link(interface, false);
    let output = wait_with_timeout(child, Duration::from_secs(60));
    link(interface, true)?;
    downed?;
    let output = output?;
    let report = report(&dir).map_err(|e| format!("{e}\n{}", text(&output)))?;
    let summary = std::fs::read_to_string(dir.join("summary.md")).unwrap_or_default();
    if output.status.code() != Some(2) || !summary.contains(interface) {
        return Err(format!(
            "expected exit 2 and an error naming {interface}\n{}\ntotals {}\nsummary:\n{summary}",
            text(&output),
            report["totals"]
        )
        .into());
    }
    eprintln!(
        "{interface} down mid-run: exit 2, {}",
        summary
            .lines()
            .find(|l| l.contains(interface))
            .unwrap_or_default()
    );
    Ok(())
}

/// A bus the kernel cannot send on (a token-bucket qdisc of 8 bit/s on the
/// interface, about one frame in 16 s): writes fail with ENOBUFS. Short
/// backpressure is waited out (seen at 1 kbit/s: the run conforms, slowly);
/// when it lasts past the frame timeout the run ends with an error naming it.
fn send_buffer_full_is_an_error(interface: &str) -> Result<(), Failed> {
    let tc = |args: &[&str]| -> Result<(), Failed> {
        let output = Command::new("tc").args(args).output()?;
        if output.status.success() {
            Ok(())
        } else {
            Err(format!("tc {}: {}", args.join(" "), text(&output)).into())
        }
    };
    tc(&[
        "qdisc", "add", "dev", interface, "root", "tbf", "rate", "8bit", "burst", "32", "limit",
        "32",
    ])?;
    let dir = report_dir("enobufs");
    let started = Instant::now();
    let output = canif(&[
        "run",
        "--bus",
        &format!("socketcan:{interface}"),
        "--profile",
        "fc510x",
        "--scenario",
        "rx-overflow",
        "--cycle-us",
        "5000",
        "--frame-timeout-ms",
        "1000",
        "--report",
        &dir.display().to_string(),
    ]);
    tc(&["qdisc", "del", "dev", interface, "root"])?;
    let summary = std::fs::read_to_string(dir.join("summary.md")).unwrap_or_default();
    if output.status.code() != Some(2) || !summary.contains("ENOBUFS") {
        return Err(format!(
            "expected exit 2 naming ENOBUFS\n{}\nsummary:\n{summary}",
            text(&output)
        )
        .into());
    }
    eprintln!(
        "{interface} throttled: ENOBUFS error verdict in {:?}",
        started.elapsed()
    );
    Ok(())
}

fn wait_with_timeout(mut child: Child, timeout: Duration) -> Result<Output, Failed> {
    let started = Instant::now();
    loop {
        if child.try_wait()?.is_some() {
            return Ok(child.wait_with_output()?);
        }
        if started.elapsed() > timeout {
            let _ = child.kill();
            return Err(format!("no end within {timeout:?}: the harness hangs").into());
        }
        std::thread::sleep(Duration::from_millis(50));
    }
}

/// `canif device --ethercat TERMINAL --bus socketcan:CAN`, until dropped.
/// It says so on stderr once both interfaces are open: a master may scan then.
fn terminal_process(
    terminal: &str,
    can: &str,
    profile: &str,
    fault: Option<&str>,
) -> Result<Background, Failed> {
    let mut command = Command::new(canif_bin());
    command.args([
        "device",
        "--ethercat",
        terminal,
        "--bus",
        &format!("socketcan:{can}"),
        "--profile",
        profile,
    ]);
    if let Some(fault) = fault {
        command.args(["--fault", fault]);
    }
    Background::start(command, Said::OnStderr("canif device:"), "the terminal")
}

/// Issue 25's two ends, as a lab runs them against a real terminal: `canif
/// device --ethercat` on one end of a veth pair with its CAN side on the
/// interface, `canif run --iut ethercat:… --bus socketcan:…` on the other.
/// Every EtherCAT terminal profile conforms; a fault behind the terminal
/// fails on its requirement.
fn ethercat_terminal_over(can: &str) -> Result<(), Failed> {
    let pair = canif_kernel::VethPair::create(&format!("{}", std::process::id() % 10_000))
        .map_err(|why| format!("no veth pair in the lane: {why}"))?;
    let run =
        |profile: &str, name: &str, scenarios: &[&str]| -> Result<(Output, PathBuf), Failed> {
            let dir = report_dir(name);
            let (iut, bus, dir_text) = (
                format!("ethercat:{}", pair.master),
                format!("socketcan:{can}"),
                dir.display().to_string(),
            );
            let mut args = vec![
                "run",
                "--iut",
                &iut,
                "--bus",
                &bus,
                "--profile",
                profile,
                "--cycle-us",
                "5000",
                "--report",
                &dir_text,
            ];
            for scenario in scenarios {
                args.extend(["--scenario", scenario]);
            }
            let started = Instant::now();
            let output = canif(&args);
            eprintln!(
                "ethercat {name}: exit {:?} in {:?}",
                output.status.code(),
                started.elapsed()
            );
            Ok((output, dir))
        };
    for profile in ["el6751-legacy", "el6751-mdp"] {
        let _terminal = terminal_process(&pair.terminal, can, profile, None)?;
        let (output, dir) = run(
            profile,
            &format!("ethercat-{profile}"),
            &["tx-batches", "rx-handshake", "filters-first-match"],
        )?;
        let summary = std::fs::read_to_string(dir.join("summary.md")).unwrap_or_default();
        let report = report(&dir).map_err(|e| format!("{e}\n{}", text(&output)))?;
        if output.status.code() != Some(0) {
            return Err(format!(
                "{profile}: expected conformance\n{}\nsummary:\n{summary}",
                text(&output)
            )
            .into());
        }
        let terminal = &report["meta"]["terminals"][0];
        if terminal["product_code"].as_u64().is_none()
            || report["totals"]["pass"].as_u64().unwrap_or(0) < 10
        {
            return Err(format!(
                "{profile}: the report names no terminal or checked too little: {}",
                report["meta"]
            )
            .into());
        }
    }
    let _terminal = terminal_process(
        &pair.terminal,
        can,
        "el6751-mdp",
        Some("sends-batch-reversed"),
    )?;
    let (output, dir) = run("el6751-mdp", "ethercat-fault", &["tx-batches"])?;
    failed_on(&output, &dir, "HS-TX-006")
}

/// `canif coupler --bus` on an interface, until dropped.
fn coupler_process(interface: &str, fault: Option<&str>) -> Result<Background, Failed> {
    let mut command = Command::new(canif_bin());
    command.args([
        "coupler",
        "--bus",
        &format!("socketcan:{interface}"),
        "--node",
        "5",
    ]);
    if let Some(fault) = fault {
        command.args(["--fault", fault]);
    }
    Background::start(command, Said::OnStdout("ready"), "the coupler")
}

/// Where a background process says it is ready, and how the line begins.
enum Said {
    OnStdout(&'static str),
    OnStderr(&'static str),
}

/// A canif process a trial needs beside the run (a coupler, a terminal),
/// killed when dropped.
struct Background(Child);

impl Background {
    /// Starts `command` and waits for its ready line.
    fn start(mut command: Command, said: Said, what: &str) -> Result<Self, Failed> {
        let (stdout, stderr, prefix) = match said {
            Said::OnStdout(prefix) => (Stdio::piped(), Stdio::inherit(), prefix),
            Said::OnStderr(prefix) => (Stdio::null(), Stdio::piped(), prefix),
        };
        let mut child = command.stdout(stdout).stderr(stderr).spawn()?;
        let mut line = String::new();
        match (child.stdout.take(), child.stderr.take()) {
            (Some(out), _) => BufReader::new(out).read_line(&mut line)?,
            (None, Some(err)) => BufReader::new(err).read_line(&mut line)?,
            (None, None) => 0,
        };
        if !line.starts_with(prefix) {
            let _ = child.kill();
            let _ = child.wait();
            return Err(format!("{what} did not start: {line:?}").into());
        }
        Ok(Background(child))
    }
}

impl Drop for Background {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// `canif run canopen` checks a node on the interface: the coupler
/// passes, each faulty variant fails on the requirement it breaks.
fn canopen_checks_over(interface: &str) -> Result<(), Failed> {
    let bus = format!("socketcan:{interface}");
    let dir = report_path("canopen");
    let report = dir.to_string_lossy().into_owned();
    let check = |fault: Option<&str>| -> Result<Output, Failed> {
        let _coupler = coupler_process(interface, fault)?;
        Ok(canif(&[
            "run", "canopen", "--bus", &bus, "--node", "5", "--report", &report,
        ]))
    };
    let output = check(None)?;
    if output.status.code() != Some(0) {
        return Err(format!("the coupler should pass\n{}", text(&output)).into());
    }
    for (fault, requirement) in [
        ("toggle-stuck", "GRD-004"),
        ("sdo-size-always-4", "SDO-008"),
        ("no-abort", "SDO-007"),
    ] {
        let output = check(Some(fault))?;
        // One line per failing requirement on stderr: `FAIL canopen-node-5::ID: …`.
        let stderr = String::from_utf8_lossy(&output.stderr);
        let caught = stderr
            .lines()
            .any(|l| l.starts_with("FAIL") && l.contains(&format!("::{requirement}:")));
        if output.status.code() != Some(1) || !caught {
            return Err(format!("{fault} must fail {requirement}\n{}", text(&output)).into());
        }
    }
    Ok(())
}

/// The quick start through the CAN interface of every profile: the PLC has only
/// the process image of `canif device` (its own socket), the coupler is another
/// process on the same interface.
fn quick_start_over(interface: &str) -> Result<(), Failed> {
    let catalogue = canif_spec::Catalogue::embedded().map_err(|e| e.to_string())?;
    let node = NodeId::new(5).expect("node 5");
    let mut failures = Vec::new();
    for profile in &catalogue.profiles {
        let caps = profile.model_capabilities();
        let config = InterfaceConfig::new(caps.first_format(), 8);
        // A coupler from boot for each profile (its guarding toggle starts at 0).
        let _coupler = coupler_process(interface, None)?;
        let layout = ImageLayout::new(&config, caps.info_data);
        let mut iut = ExecIut::spawn(
            &device_command(interface, None)["exec:".len()..],
            canif_harness::door::Timeouts::default(),
            false,
        )?;
        let epoch = canif_kernel::realtime_ns();
        let bus = OwnedBus {
            interface: interface.to_string(),
            epoch_ns: epoch,
        };
        if let canif_harness::door::exec::Configured::Refused(reason) =
            iut.configure(&caps, &config, Some(&bus))?
        {
            return Err(
                format!("{}: the device refuses {config:?}: {reason}", profile.name).into(),
            );
        }
        let cycle_time = 4_000_000;
        let mut next = canif_kernel::realtime_ns();
        let mut cycle = || {
            next += cycle_time;
            let now = canif_kernel::realtime_ns();
            if next > now {
                std::thread::sleep(Duration::from_nanos(next - now));
            }
            canif_kernel::realtime_ns() - epoch
        };
        let results = quick_start(&mut iut, layout, node, &mut cycle);
        for result in results {
            match result.outcome {
                Ok(()) => {}
                Err(why) => failures.push(format!(
                    "{}: {} ({}): {why}",
                    profile.name,
                    result.name,
                    result.requirements.join(", ")
                )),
            }
        }
    }
    if failures.is_empty() {
        eprintln!(
            "quick start over {interface}: every telegram answered on all {} profiles",
            catalogue.profiles.len()
        );
        Ok(())
    } else {
        Err(failures.join("\n").into())
    }
}

/// Python's canopen package (python-can's socketcan interface) against the coupler.
fn python_canopen_over(interface: &str) -> Result<(), Failed> {
    let _coupler = coupler_process(interface, None)?;
    let script = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/python/canopen_crosscheck.py"
    );
    let output = Command::new("python3")
        .args([script, &format!("socketcan:{interface}"), "5"])
        .output()?;
    let checks: serde_json::Value =
        serde_json::from_slice(&output.stdout).map_err(|e| format!("{e}\n{}", text(&output)))?;
    if output.status.code() != Some(0) {
        return Err(format!("canopen disagrees: {checks:#}").into());
    }
    eprintln!(
        "python canopen over {interface}: {} checks agree",
        checks.as_object().map_or(0, |o| o.len())
    );
    Ok(())
}

fn python_canopen_available() -> Result<(), String> {
    let ok = Command::new("python3")
        .args(["-c", "import canopen, can.interfaces.socketcan"])
        .output()
        .is_ok_and(|o| o.status.success());
    match (ok, std::env::var("CI").is_ok()) {
        (true, _) => Ok(()),
        // CI installs it (.ci/run): missing there is a failure, not a skip.
        (false, true) => Ok(()),
        (false, false) => {
            Err("python3 with canopen and python-can not installed (pip install canopen)".into())
        }
    }
}

/// Under emulation the CTU CAN FD pair sometimes holds a received frame back
/// until the next one arrives, when the receiving controller is sending too
/// (seen: `302##00007` "did not arrive" within 2 s, then delivered in the next
/// scenario; in about one run of three; the driver or QEMU's model, not
/// isolated: one frame at a time in both directions never shows it). That is an
/// `error` of the transport, never a non-conformance. So here a run passes
/// when nothing failed, every error is such a delay, and at least `min_passed`
/// scenarios passed over the bus; the delays are printed.
fn conforms_despite_transport_delays(
    bus: &str,
    iut: &str,
    profile: &str,
    extra: &[&str],
    min_passed: usize,
) -> Result<(), Failed> {
    let Err(first) = conforms_on(bus, iut, profile, extra) else {
        return Ok(());
    };
    let message = first.message().unwrap_or_default().to_string();
    let dir = report_path(&format!("{profile}-{}", bus.replace([':', ','], "-")));
    let report = report(&dir)?;
    let checks: Vec<serde_json::Value> = report["profiles"]
        .as_array()
        .into_iter()
        .flatten()
        .flat_map(|p| p["checks"].as_array().cloned().unwrap_or_default())
        .collect();
    let errors: Vec<String> = checks
        .iter()
        .filter(|c| c["outcome"] == "error")
        .map(|c| c["cause"].as_str().unwrap_or_default().to_string())
        .collect();
    let delays = |l: &String| l.contains("did not arrive") || l.contains("the kernel delivered");
    // Lockstep scenarios that passed over the bus (the refusal grid sends no frame).
    let passed = checks
        .iter()
        .filter(|c| c["outcome"] == "pass")
        .filter(|c| {
            c["check"].as_str().is_some_and(|k| {
                k.starts_with("scenario: ") && !k.contains("configuration refusals")
            })
        })
        .count();
    if report["totals"]["fail"] == 0
        && !errors.is_empty()
        && errors.iter().all(delays)
        && passed >= min_passed
    {
        eprintln!(
            "transport delays on the emulated controllers ({} scenario(s), {passed} passed over the bus):\n  {}",
            errors.len(),
            errors.join("\n  ")
        );
        Ok(())
    } else {
        Err(message.into())
    }
}

/// A trial that cannot run here: skipped with the reason, or failed inside the
/// kernel lane, which promised what it needs.
fn unavailable(name: &str, why: Skip) -> Trial {
    let (failure, reason) = match &why {
        Skip::Kernel(error) => (
            canif_kernel::skip_is_failure(error),
            canif_kernel::skip_reason(error),
        ),
        Skip::Missing(what) => (canif_kernel::lane_failure(what), what.clone()),
    };
    match failure {
        Some(failure) => Trial::test(name, move || Err(failure.into())),
        None => Trial::test(name, || Ok(()))
            .with_kind(format!("skipped: {reason}"))
            .with_ignored_flag(true),
    }
}

/// Why a trial cannot run here: the kernel's CAN stack, or a tool it needs.
#[derive(Debug, Clone)]
enum Skip {
    Kernel(canif_kernel::KernelError),
    Missing(String),
}

impl From<canif_kernel::KernelError> for Skip {
    fn from(error: canif_kernel::KernelError) -> Self {
        Skip::Kernel(error)
    }
}

impl From<String> for Skip {
    fn from(what: String) -> Self {
        Skip::Missing(what)
    }
}

type Check = Box<dyn Fn() -> Result<(), Failed> + Send + Sync>;

/// How a run over a bus is judged: `(bus, iut, profile, flags)`.
type Judge = fn(&str, &str, &str, &[&str]) -> Result<(), Failed>;

/// On a pair of interfaces (IUT side, other nodes): the attached soft device
/// with the `attached` scenarios, then `canif device` on its own socket with the
/// `device` scenarios, both with `flags`.
fn on_pair(
    pair: &Result<(String, String), canif_kernel::KernelError>,
    profile: &'static str,
    flags: &[&'static str],
    attached: &[&'static str],
    device: &[&'static str],
    judge: Judge,
) -> Result<Check, Skip> {
    let (a, b) = pair.clone()?;
    let with = |scenarios: &[&'static str]| -> Vec<&'static str> {
        let mut args = flags.to_vec();
        for scenario in scenarios {
            args.extend(["--scenario", scenario]);
        }
        args
    };
    let (attached, device) = (with(attached), with(device));
    Ok(Box::new(move || {
        let bus = format!("socketcan:{a},{b}");
        judge(&bus, "softdevice", profile, &attached)?;
        judge(&bus, &device_command(&a, None), profile, &device)
    }))
}

fn main() {
    let args = Arguments::from_args();
    let fd = canif_kernel::test_interface("CANIF_LANE_FD", "vcan0");
    let classic = canif_kernel::test_interface("CANIF_LANE_CLASSIC", "vcan1");
    let controllers = canif_kernel::test_interface_pair("CANIF_LANE_CONTROLLERS");
    let mut trials: Vec<(&str, Result<Check, Skip>)> = Vec::new();
    let on = |interface: &Result<String, canif_kernel::KernelError>,
              f: fn(&str) -> Result<(), Failed>| {
        interface
            .clone()
            .map(|i| Box::new(move || f(&i)) as Check)
            .map_err(Skip::from)
    };
    trials.push((
        "conformance_attached_over_vcan_fd",
        on(&fd, |i| {
            conforms_on(&format!("socketcan:{i}"), "softdevice", "fc532x", &[])
        }),
    ));
    trials.push((
        "conformance_of_device_process_over_vcan",
        on(&fd, |i| {
            conforms_on(
                &format!("socketcan:{i}"),
                &device_command(i, None),
                "fc532x",
                &[],
            )
        }),
    ));
    trials.push(("fault_caught_over_vcan", on(&classic, fault_caught_over)));
    // QEMU's SJA1000 garbles its receive FIFO after a remote frame with a length.
    let sja1000 = ["--no-remote-frames"];
    // ESI on the wire is the sending controller's error state.
    let ctu = ["--esi-from-controller"];
    trials.push((
        "conformance_over_sja1000_controllers",
        on_pair(
            &controllers,
            "fc510x",
            &sja1000,
            &["rx-"],
            &["tx-batches"],
            conforms_on,
        ),
    ));
    trials.push((
        "conformance_over_a_vxcan_pair",
        on_pair(
            &canif_kernel::test_interface_pair("CANIF_LANE_VXCAN"),
            "fc510x",
            &[],
            &["rx-handshake"],
            &["tx-batches"],
            conforms_on,
        ),
    ));
    trials.push((
        "conformance_over_ctu_can_fd_controllers",
        on_pair(
            &canif_kernel::test_interface_pair("CANIF_LANE_FD_CONTROLLERS"),
            "fc532x",
            &ctu,
            &["rx-handshake [FD", "fd-lengths [FD", "info-data [FD"],
            &["tx-batches [FD"],
            |bus, iut, profile, flags| {
                conforms_despite_transport_delays(bus, iut, profile, flags, 1)
            },
        ),
    ));
    trials.push((
        "canopen_checks_over_vcan",
        on(&classic, canopen_checks_over),
    ));
    trials.push((
        "quick_start_through_every_profile_over_vcan",
        on(&classic, quick_start_over),
    ));
    trials.push((
        "python_canopen_over_vcan",
        classic.clone().map_err(Skip::from).and_then(|i| {
            python_canopen_available()?;
            Ok(Box::new(move || python_canopen_over(&i)) as Check)
        }),
    ));
    trials.push(("client_side_over_vcan_fd", on(&fd, client_side_over)));
    trials.push((
        "ethercat_terminal_over_veth_with_its_can_side_on_vcan",
        on(&classic, ethercat_terminal_over),
    ));
    trials.push((
        "interface_down_is_an_error",
        on(&classic, interface_down_is_an_error),
    ));
    trials.push((
        "send_buffer_full_is_an_error",
        on(&classic, send_buffer_full_is_an_error),
    ));
    let trials = trials
        .into_iter()
        .map(|(name, check)| match check {
            Ok(check) => Trial::test(name, check),
            Err(why) => unavailable(name, why),
        })
        .collect();
    libtest_mimic::run(&args, trials).exit();
}
