//! `canif`: the conformance suite's command line.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use canif_harness::report::{RunReport, ScenarioResult};
use canif_harness::suite::{run_profile, Options};
use canif_harness::{IutKind, Outcome};
use canif_model::frame::{CanId, Frame};
use canif_model::sizing::{self, FrameTimeBasis};
use canif_model::timing::{frame_bits, frame_duration, BitRates, Stuffing};
use canif_softdevice::Fault;
use canif_spec::{coverage, Catalogue, Status, Verification};
use clap::{Parser, Subcommand};
use std::io::{IsTerminal, Write as _};

#[derive(Parser)]
#[command(
    name = "canif",
    version,
    about = "Conformance suite for the Beckhoff CAN interface"
)]
struct Cli {
    /// A catalogue folder of the shape of spec/ instead of the embedded one.
    #[arg(long, global = true, value_name = "DIR")]
    spec: Option<PathBuf>,
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Certify an implementation against the model, per profile, on the
    /// simulated bus or a SocketCAN interface.
    Run {
        /// softdevice (the built-in soft EL6751), model (the reference itself), or
        /// exec:'COMMAND' (a process speaking the adapter protocol).
        #[arg(long, default_value = "softdevice")]
        iut: String,
        /// How long an external IUT may take to answer one request.
        #[arg(long, default_value_t = 5000)]
        timeout_ms: u64,
        /// Switch on a soft-device fault (repeatable; see `canif faults`).
        #[arg(long)]
        fault: Vec<String>,
        /// A profile name (see `canif profiles`) or `all`.
        #[arg(long, default_value = "all")]
        profile: String,
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Generated scenarios per interface.
        #[arg(long, default_value_t = 4)]
        cases: u64,
        /// Virtual seconds of generated traffic per scenario (a soak run).
        #[arg(long)]
        duration: Option<f64>,
        /// Leave out the 65,540-cycle RxCounter wrap.
        #[arg(long)]
        no_counter_wrap: bool,
        /// Where to write junit.xml, report.json and summary.md.
        #[arg(long, default_value = "reports/latest")]
        report: PathBuf,
        /// Also write every scenario's bus as a candump log and a pcapng file here.
        #[arg(long, value_name = "DIR")]
        trace: Option<PathBuf>,
        /// `interface` (the CAN interface, default) or `canopen` (check a CANopen node).
        #[arg(long, default_value = "interface")]
        suite: String,
        /// `sim` (the simulated bus, virtual time) or `socketcan:IFACE` (a Linux
        /// SocketCAN interface, real time; `socketcan:IUT_IFACE,OTHER_IFACE` for
        /// two controllers on one bus).
        #[arg(long, default_value = "sim")]
        bus: String,
        /// On a SocketCAN bus: the real cycle time in microseconds.
        #[arg(long, default_value_t = 2000)]
        cycle_us: u64,
        /// On a SocketCAN bus: how far the IUT's receive time stamps may be from the harness's, in µs.
        #[arg(long, default_value_t = 1000)]
        time_stamp_tolerance_us: u64,
        /// On a SocketCAN bus: how long a frame may take to cross the kernel, in ms.
        #[arg(long, default_value_t = 2000)]
        frame_timeout_ms: u64,
        /// On a SocketCAN bus: send the scenarios' remote frames as data frames
        /// (for controllers that cannot carry them, such as QEMU's SJA1000).
        #[arg(long)]
        no_remote_frames: bool,
        /// On a SocketCAN bus: the controllers send ESI from their own error
        /// state (real CAN FD controllers), so the scenarios' ESI bits are left out.
        #[arg(long)]
        esi_from_controller: bool,
        /// Only scenarios whose name contains this text (repeatable: any of them).
        #[arg(long, value_name = "TEXT")]
        scenario: Vec<String>,
        /// With --suite canopen: the node id to check.
        #[arg(long, default_value_t = 5)]
        node: u8,
        /// With --suite canopen on the simulated bus: a coupler fault (toggle-stuck, sdo-size-always-4, no-abort).
        #[arg(long)]
        coupler_fault: Option<String>,
    },
    /// Certify one profile: a sealed certificate (JSON + HTML) of every requirement's verdict.
    Certify {
        /// The profile to certify.
        #[arg(long, required_unless_present = "verify")]
        profile: Option<String>,
        /// softdevice, model or exec:'COMMAND'.
        #[arg(long, default_value = "softdevice")]
        iut: String,
        #[arg(long)]
        fault: Vec<String>,
        #[arg(long, default_value_t = 1)]
        seed: u64,
        #[arg(long, default_value_t = 5000)]
        timeout_ms: u64,
        /// Where to write certificate.json and certificate.html.
        #[arg(long, default_value = "reports/certificate")]
        out: PathBuf,
        /// Check the seal of an existing certificate.json instead.
        #[arg(long, value_name = "CERTIFICATE")]
        verify: Option<PathBuf>,
    },
    /// What changed between two report.json files; exit 1 on a regression.
    Compare { base: PathBuf, new: PathBuf },
    /// The soft device's deliberate faults.
    Faults,
    /// A simulated Beckhoff CANopen coupler for tools by others: behind
    /// socketcand's protocol on 127.0.0.1 (python-can's `socketcand` interface),
    /// or as a node on a SocketCAN interface.
    Coupler {
        /// TCP port on 127.0.0.1 (0: any free port, printed on stdout).
        #[arg(long, required_unless_present = "bus", conflicts_with = "bus")]
        socketcand: Option<u16>,
        /// `socketcan:IFACE`: be a node on that interface (real time) until stopped.
        #[arg(long)]
        bus: Option<String>,
        /// The coupler's node id (1..63).
        #[arg(long, default_value_t = 5)]
        node: u8,
        /// A deliberate defect: toggle-stuck, sdo-size-always-4 or no-abort.
        #[arg(long)]
        fault: Option<String>,
    },
    /// Run the soft device on its own, behind the adapter protocol on stdin/stdout.
    Device {
        /// Speak the adapter protocol (docs/adapter-protocol.md) on stdin/stdout.
        #[arg(long)]
        stdio: bool,
        /// Switch on a fault (repeatable).
        #[arg(long)]
        fault: Vec<String>,
        /// Put the device's CAN side on a SocketCAN interface (`socketcan:IFACE`):
        /// it sends and receives real frames there, and the adapter protocol
        /// carries only configure, cycle and controller_status.
        #[arg(long)]
        bus: Option<String>,
    },
    /// The suite's power: run every fault on every profile; exit 1 if one goes uncaught.
    SelfCheck {
        #[arg(long, default_value_t = 1)]
        seed: u64,
    },
    /// The requirement catalogue.
    Spec {
        #[command(subcommand)]
        command: SpecCommand,
    },
    /// The device profiles and what each offers.
    Profiles,
    /// Message slots a cycle time needs (the manual's §4, ruling R4).
    Size {
        /// Bit rate in bit/s, e.g. 500000.
        #[arg(long)]
        bitrate: u32,
        /// PLC task / CAN interface cycle time in µs.
        #[arg(long = "cycle-us")]
        cycle_us: u64,
        /// Data bytes per frame (0..=8).
        #[arg(long, default_value_t = 8)]
        payload: u8,
    },
    /// How long one frame occupies the bus (nominal and worst-case stuffing).
    FrameTime {
        #[arg(long)]
        bitrate: u32,
        /// Data-phase bit rate for CAN FD with bit rate switch.
        #[arg(long = "data-bitrate")]
        data_bitrate: Option<u32>,
        #[arg(long, default_value_t = 8)]
        payload: u8,
        /// 29-bit identifier.
        #[arg(long)]
        extended: bool,
        /// CAN FD frame (payload rounds up to a valid size).
        #[arg(long)]
        fd: bool,
    },
}

#[derive(Subcommand)]
enum SpecCommand {
    /// Every requirement, one line each.
    List {
        /// Only ids starting with this prefix (e.g. HS-TX).
        #[arg(long)]
        area: Option<String>,
    },
    /// One requirement in full.
    Show { id: String },
    /// Counts by area and status, and the assumptions.
    Summary,
    /// Validates the catalogue (the embedded one, or --spec DIR).
    Check,
    /// Which tests name which requirement; exit 1 if a normative or derived one has none.
    Coverage {
        /// The workspace whose tests to read.
        #[arg(long, default_value = ".")]
        root: PathBuf,
        /// List every requirement with the tests, properties and scenarios that cover it.
        #[arg(long)]
        each: bool,
    },
}

fn main() -> ExitCode {
    // `canif spec list | head` should end quietly when head stops reading, as
    // command-line tools do, rather than panic on the broken pipe.
    #[cfg(unix)]
    // SAFETY: restoring the default disposition of SIGPIPE before any other
    // thread exists; no handler is involved.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
    let cli = Cli::parse();
    let catalogue = match &cli.spec {
        Some(dir) => Catalogue::load_dir(dir),
        None => Catalogue::embedded(),
    };
    let catalogue = match catalogue {
        Ok(catalogue) => catalogue,
        Err(errors) => {
            eprint!("{errors}");
            return ExitCode::from(2);
        }
    };
    match cli.command {
        Command::Run {
            iut,
            timeout_ms,
            fault,
            profile,
            seed,
            cases,
            duration,
            no_counter_wrap,
            report,
            trace,
            suite,
            bus,
            cycle_us,
            time_stamp_tolerance_us,
            frame_timeout_ms,
            no_remote_frames,
            esi_from_controller,
            scenario,
            node,
            coupler_fault,
        } => {
            let kernel = match bus.as_str() {
                "sim" => None,
                other => match canif_kernel::BusSpec::parse(other) {
                    Ok(spec) => Some(canif_harness::kernel_bus::KernelBusOptions {
                        spec,
                        cycle_time: cycle_us.max(100) * 1_000,
                        time_stamp_tolerance: time_stamp_tolerance_us * 1_000,
                        timeout: std::time::Duration::from_millis(frame_timeout_ms),
                        remote_frames: !no_remote_frames,
                        esi_settable: !esi_from_controller,
                    }),
                    Err(error) => {
                        eprintln!("--bus {error}");
                        return ExitCode::from(2);
                    }
                },
            };
            if suite == "canopen" {
                return canopen_suite(kernel.as_ref(), node, coupler_fault.as_deref());
            }
            if suite != "interface" {
                eprintln!("unknown suite `{suite}`: interface or canopen");
                return ExitCode::from(2);
            }
            let options = Options {
                seed,
                cases: if duration.is_some() { 1 } else { cases },
                generated_cycles: duration.map_or(200, |s| (s * 1000.0).max(1.0) as u64),
                counter_wrap: !no_counter_wrap && kernel.is_none(),
                trace_dir: trace,
                kernel,
                only: scenario,
            };
            run(
                &catalogue, &iut, &fault, &profile, &options, &report, timeout_ms,
            )
        }
        Command::SelfCheck { seed } => self_check(&catalogue, seed),
        Command::Compare { base, new } => compare(&base, &new),
        Command::Coupler {
            socketcand,
            bus,
            node,
            fault,
        } => match (coupler_fault(fault.as_deref()), socketcand, bus) {
            (Err(code), ..) => code,
            (Ok(fault), Some(port), _) => serve_coupler(port, node, fault),
            (Ok(fault), None, Some(bus)) => coupler_on_bus(&bus, node, fault),
            (Ok(_), None, None) => ExitCode::from(2),
        },
        Command::Certify {
            profile,
            iut,
            fault,
            seed,
            timeout_ms,
            out,
            verify,
        } => match verify {
            Some(path) => verify_certificate(&path),
            None => certify(
                &catalogue,
                profile.as_deref().unwrap_or_default(),
                &iut,
                &fault,
                seed,
                timeout_ms,
                &out,
            ),
        },
        Command::Device { stdio, fault, bus } => device(stdio, &fault, bus.as_deref()),
        Command::Faults => {
            for fault in Fault::ALL {
                println!("{:<36} {}", fault.name(), fault.description());
            }
            ExitCode::SUCCESS
        }
        Command::Spec { command } => spec(&catalogue, command),
        Command::Profiles => profiles(&catalogue),
        Command::Size {
            bitrate,
            cycle_us,
            payload,
        } => size(bitrate, cycle_us, payload),
        Command::FrameTime {
            bitrate,
            data_bitrate,
            payload,
            extended,
            fd,
        } => frame_time(bitrate, data_bitrate, payload, extended, fd),
    }
}

fn spec(catalogue: &Catalogue, command: SpecCommand) -> ExitCode {
    match command {
        SpecCommand::List { area } => {
            for r in catalogue
                .requirements()
                .filter(|r| area.as_ref().is_none_or(|a| r.id.starts_with(a.as_str())))
            {
                println!(
                    "{:<12} {:<10} {}",
                    r.id,
                    format!("{:?}", r.status).to_lowercase(),
                    r.statement
                );
            }
        }
        SpecCommand::Show { id } => {
            let Some(r) = catalogue.requirement(&id) else {
                eprintln!("no requirement `{id}` (try `canif spec list`)");
                return ExitCode::from(2);
            };
            println!("{}  [{:?}]  {}:{}", r.id, r.status, r.file, r.line);
            println!("  {}", r.statement);
            println!("  source: {} {}", r.source.file, r.source.section);
            if !r.capabilities.is_empty() {
                println!("  needs: {}", r.capabilities.join(", "));
            }
            if !r.rulings.is_empty() {
                println!("  rulings: {}", r.rulings.join(", "));
            }
            // Coverage is read from the tests where they are (the workspace), never kept by hand.
            if let Ok(sources) = coverage::test_sources(Path::new(".")) {
                let found = coverage::coverage(catalogue, &sources);
                for (file, line) in found.covered_by.get(&r.id).into_iter().flatten() {
                    println!("  covered by: {file}:{line}");
                }
            }
            for (label, text) in [
                ("document says", &r.document_says),
                ("corrected", &r.corrected),
                ("notes", &r.notes),
                ("not tested because", &r.reason),
            ] {
                if let Some(text) = text {
                    println!("  {label}: {}", text.trim());
                }
            }
        }
        SpecCommand::Summary => summary(catalogue),
        SpecCommand::Check => {
            println!(
                "catalogue ok: {} requirements in {} areas, {} profiles, {} capabilities",
                catalogue.requirements().count(),
                catalogue.areas.len(),
                catalogue.profiles.len(),
                catalogue.capabilities.len()
            );
        }
        SpecCommand::Coverage { root, each } => return spec_coverage(catalogue, &root, each),
    }
    ExitCode::SUCCESS
}

fn summary(catalogue: &Catalogue) {
    println!(
        "{:<8} {:>9} {:>8} {:>10} {:>6}  title",
        "area", "normative", "derived", "assumption", "total"
    );
    let mut totals = [0usize; 3];
    for area in &catalogue.areas {
        let count = |status| {
            area.requirements
                .iter()
                .filter(|r| r.status == status)
                .count()
        };
        let counts = [
            count(Status::Normative),
            count(Status::Derived),
            count(Status::Assumption),
        ];
        for (total, n) in totals.iter_mut().zip(counts) {
            *total += n;
        }
        println!(
            "{:<8} {:>9} {:>8} {:>10} {:>6}  {}",
            area.area,
            counts[0],
            counts[1],
            counts[2],
            area.requirements.len(),
            area.title
        );
    }
    println!(
        "{:<8} {:>9} {:>8} {:>10} {:>6}",
        "all",
        totals[0],
        totals[1],
        totals[2],
        totals.iter().sum::<usize>()
    );
    let inspection: Vec<_> = catalogue
        .requirements()
        .filter(|r| r.verification == Verification::Inspection)
        .map(|r| r.id.as_str())
        .collect();
    println!(
        "\nchecked by inspection, not by tests: {}",
        inspection.join(", ")
    );
}

fn spec_coverage(catalogue: &Catalogue, root: &Path, each: bool) -> ExitCode {
    let sources = match coverage::test_sources(root) {
        Ok(sources) if !sources.is_empty() => sources,
        Ok(_) => {
            eprintln!(
                "no test sources under {} (run from the workspace root or pass --root)",
                root.display()
            );
            return ExitCode::from(2);
        }
        Err(error) => {
            eprintln!("cannot read tests under {}: {error}", root.display());
            return ExitCode::from(2);
        }
    };
    let result = coverage::coverage(catalogue, &sources);
    if each {
        for r in catalogue.requirements() {
            let places: Vec<String> = result
                .covered_by
                .get(&r.id)
                .into_iter()
                .flatten()
                .map(|(file, line)| format!("{file}:{line}"))
                .collect();
            let status = format!("{:?}", r.status).to_lowercase();
            let how = if r.verification == Verification::Inspection {
                "inspection".to_string()
            } else {
                places.join(" ")
            };
            println!(
                "{:<11} {:<10} {}",
                r.id,
                status,
                if how.is_empty() { "-" } else { &how }
            );
        }
        println!();
    }
    let in_runs = canif_harness::suite::checked_ids(
        &canif_model::config::Capabilities::everything(),
        &Options::default(),
    );
    println!(
        "{:<8} {:>9} {:>13}  title",
        "area", "by tests", "in IUT runs"
    );
    for area in &catalogue.areas {
        let needing: Vec<_> = area
            .requirements
            .iter()
            .filter(|r| r.needs_coverage())
            .collect();
        let covered = needing
            .iter()
            .filter(|r| result.covered_by.contains_key(&r.id))
            .count();
        let run = area
            .requirements
            .iter()
            .filter(|r| in_runs.contains(&r.id))
            .count();
        println!(
            "{:<8} {:>4}/{:<4} {:>7}/{:<5}  {}",
            area.area,
            covered,
            needing.len(),
            run,
            area.requirements.len(),
            area.title
        );
    }
    println!("(by tests: normative and derived requirements named by a test's Covers: line; in IUT runs: any requirement a `canif run` scenario checks)");
    for problem in &result.problems {
        println!("{}:{}: {}", problem.file, problem.line, problem.message);
    }
    if result.uncovered.is_empty() && result.problems.is_empty() {
        println!("every normative and derived requirement is named by a test");
        ExitCode::SUCCESS
    } else {
        println!("not covered: {}", result.uncovered.join(", "));
        ExitCode::from(1)
    }
}

fn profiles(catalogue: &Catalogue) -> ExitCode {
    for profile in &catalogue.profiles {
        println!("{:<22} {}", profile.name, profile.device);
        println!(
            "{:<22} offers: {}; slots ≤ {}; Rx queue {} messages{}",
            "",
            profile.capabilities.join(", "),
            profile.max_slots,
            profile.rx_queue_depth,
            if profile.transaction_number_only_ext29 {
                "; transaction number only in 29-bit mode"
            } else {
                ""
            }
        );
    }
    ExitCode::SUCCESS
}

fn size(bitrate: u32, cycle_us: u64, payload: u8) -> ExitCode {
    let cycle = cycle_us * 1_000;
    let Some(recommended) = sizing::recommend(bitrate, cycle, payload) else {
        eprintln!("cannot size: payload must be 0..=8 and the bit rate above 0");
        return ExitCode::from(2);
    };
    println!(
        "{bitrate} bit/s, {cycle_us} µs cycle, {payload}-byte 11-bit frames at 100 % bus load:"
    );
    for basis in [
        FrameTimeBasis::CiaTable,
        FrameTimeBasis::Nominal,
        FrameTimeBasis::WorstCase,
    ] {
        if let Some(s) = sizing::size(bitrate, cycle, payload, basis) {
            let mark = if s.basis == recommended.basis {
                "  <- recommended"
            } else {
                ""
            };
            println!(
                "  {:<10} frame time {:>8.1} µs -> {:>4} slots{mark}",
                format!("{basis:?}"),
                s.frame_time as f64 / 1000.0,
                s.slots
            );
        }
    }
    if recommended.slots > 32 {
        println!("  more than 32 slots cannot be configured: shorten the cycle time (000 §4)");
    }
    ExitCode::SUCCESS
}

fn frame_time(
    bitrate: u32,
    data_bitrate: Option<u32>,
    payload: u8,
    extended: bool,
    fd: bool,
) -> ExitCode {
    let id = if extended {
        CanId::Extended(0)
    } else {
        CanId::Standard(0)
    };
    let frame = if fd {
        let Some(size) = canif_model::dlc::fd_round_up(payload) else {
            eprintln!("a CAN FD frame carries at most 64 bytes");
            return ExitCode::from(2);
        };
        Frame::fd(
            id,
            data_bitrate.is_some(),
            false,
            &vec![0; usize::from(size)],
        )
    } else {
        Frame::classic(id, &vec![0; usize::from(payload)])
    };
    let frame = match frame {
        Ok(frame) => frame,
        Err(error) => {
            eprintln!("{error}");
            return ExitCode::from(2);
        }
    };
    let rates = BitRates {
        nominal: bitrate,
        data: data_bitrate.unwrap_or(bitrate),
    };
    let bits = frame_bits(&frame);
    println!(
        "{} frame, {} data bytes: {} bits nominal, {} worst case (arbitration {}/{}, data phase {}/{})",
        if fd { "CAN FD" } else { "classic" },
        frame.len(),
        bits.arbitration.nominal + bits.data.nominal,
        bits.arbitration.worst_case + bits.data.worst_case,
        bits.arbitration.nominal,
        bits.arbitration.worst_case,
        bits.data.nominal,
        bits.data.worst_case
    );
    for stuffing in [Stuffing::Nominal, Stuffing::WorstCase] {
        println!(
            "  {:<10} {:>9.2} µs",
            format!("{stuffing:?}"),
            frame_duration(&frame, rates, stuffing) as f64 / 1000.0
        );
    }
    if let Some(cell) =
        canif_model::cia_table::frame_time(bitrate, payload).filter(|_| !fd && !extended)
    {
        println!("  CiA table  {:>9.2} µs (000 §4)", cell as f64 / 1000.0);
    }
    ExitCode::SUCCESS
}

#[allow(clippy::too_many_arguments)]
fn run(
    catalogue: &Catalogue,
    iut: &str,
    faults: &[String],
    profile: &str,
    options: &Options,
    report_dir: &Path,
    timeout_ms: u64,
) -> ExitCode {
    let kind = match resolve_iut(iut, faults, timeout_ms) {
        Ok(kind) => kind,
        Err(code) => return code,
    };
    let profiles: Vec<_> = if profile == "all" {
        catalogue.profiles.iter().collect()
    } else {
        match catalogue.profile(profile) {
            Some(p) => vec![p],
            None => {
                let names: Vec<_> = catalogue.profiles.iter().map(|p| p.name.as_str()).collect();
                eprintln!("unknown profile `{profile}`; known: {}", names.join(", "));
                return ExitCode::from(2);
            }
        }
    };
    if let Some(kernel) = &options.kernel {
        // A bus that cannot be opened at all is one error, not one per scenario.
        let opened = canif_kernel::probe().and_then(|()| {
            canif_kernel::KernelSocket::open(&kernel.spec.iut, false)?;
            canif_kernel::KernelSocket::open(&kernel.spec.tester, false).map(|_| ())
        });
        if let Err(error) = opened {
            eprintln!("error: --bus {}: {error}", kernel.spec.describe());
            return ExitCode::from(2);
        }
    }
    let started = std::time::Instant::now();
    let terminal = std::io::stderr().is_terminal();
    let mut results = Vec::new();
    for (n, p) in profiles.iter().enumerate() {
        let mut done = 0;
        let result = run_profile(catalogue, p, &kind, options, |scenario_run| {
            done += 1;
            if terminal {
                eprint!(
                    "\r\x1b[2K[{}/{}] {}: {} ({} scenarios)",
                    n + 1,
                    profiles.len(),
                    p.name,
                    scenario_run.scenario,
                    done
                );
                let _ = std::io::stderr().flush();
            }
        });
        let failed = result
            .runs
            .iter()
            .filter(|r| matches!(r.outcome, Outcome::Fail(_)))
            .count();
        let errors = result
            .runs
            .iter()
            .filter(|r| matches!(r.outcome, Outcome::Error(_)))
            .count();
        if terminal {
            eprint!("\r\x1b[2K");
        }
        eprintln!(
            "[{}/{}] {:<22} {} scenarios, {} cycles, {} frames checked: {}",
            n + 1,
            profiles.len(),
            p.name,
            result.runs.len(),
            result.cycles(),
            result.frames_checked(),
            match (failed, errors) {
                (0, 0) => "conforms".to_string(),
                (f, 0) => format!("{f} scenario(s) FAIL"),
                (f, e) => format!("{f} fail, {e} ERROR"),
            }
        );
        results.push(result);
    }
    let scenarios = if options.kernel.is_some() || !options.only.is_empty() {
        // The Gherkin scenarios run on the simulated bus; a SocketCAN or filtered run leaves them out.
        eprintln!(
            "Gherkin scenarios: not run (they use the simulated bus; run without --bus/--scenario)"
        );
        Vec::new()
    } else {
        match run_features(&kind, &profiles) {
            Ok(scenarios) => scenarios,
            Err(error) => {
                eprintln!("the feature files do not parse: {error}");
                return ExitCode::from(2);
            }
        }
    };
    let failed = scenarios
        .iter()
        .filter(|s| s.outcome.is_err() && !s.error)
        .count();
    let broken = scenarios.iter().filter(|s| s.error).count();
    if !scenarios.is_empty() {
        eprintln!(
            "Gherkin scenarios: {} run, {} failed, {} error",
            scenarios.len(),
            failed,
            broken
        );
    }
    let report = RunReport {
        iut: kind.name(),
        seed: options.seed,
        bus: match &options.kernel {
            None => "simulated bus (virtual time)".into(),
            Some(k) => format!(
                "{} on Linux {}, real time, {} µs cycle, time stamps within {} µs{}",
                k.spec.describe(),
                canif_kernel::kernel_release(),
                k.cycle_time / 1_000,
                k.time_stamp_tolerance / 1_000,
                match (k.remote_frames, k.esi_settable) {
                    (true, true) => "",
                    (false, true) => ", remote frames sent as data frames",
                    (true, false) => ", ESI left to the controllers",
                    (false, false) =>
                        ", remote frames sent as data frames, ESI left to the controllers",
                }
            ),
        },
        profiles: results,
        scenarios,
        wall_time_ms: started.elapsed().as_millis(),
    };
    if let Err(error) = report.write(catalogue, report_dir) {
        eprintln!(
            "cannot write the reports to {}: {error}",
            report_dir.display()
        );
        return ExitCode::from(2);
    }
    let totals = report.totals();
    println!(
        "{}: {} pass, {} fail, {} error, {} not applicable, {} not testable — reports in {}",
        report.iut,
        totals.pass,
        totals.fail,
        totals.error,
        totals.not_applicable,
        totals.not_testable,
        report_dir.display()
    );
    ExitCode::from(report.exit_code())
}

fn self_check(catalogue: &Catalogue, seed: u64) -> ExitCode {
    let options = Options {
        cases: 2,
        generated_cycles: 150,
        ..Options::quick(seed)
    };
    let rows = canif_harness::suite::kill_matrix(catalogue, &options, |fault| {
        eprintln!("running {fault} on every profile")
    });
    let mut uncaught = 0;
    println!("| fault | caught on | requirements that failed |\n|---|---|---|");
    for row in &rows {
        let caught: Vec<&str> = row
            .caught
            .iter()
            .filter(|(_, ids)| !ids.is_empty())
            .map(|(p, _)| p.as_str())
            .collect();
        let mut ids: Vec<&str> = row
            .caught
            .iter()
            .flat_map(|(_, ids)| ids.iter().map(String::as_str))
            .collect();
        ids.sort();
        ids.dedup();
        if caught.is_empty() {
            uncaught += 1;
        }
        println!(
            "| {} | {}/{} profiles | {} |",
            row.fault.name(),
            caught.len(),
            row.caught.len(),
            if ids.is_empty() {
                "NOT CAUGHT".to_string()
            } else {
                ids.join(", ")
            }
        );
    }
    println!(
        "\n{} of {} faults caught",
        rows.len() - uncaught,
        rows.len()
    );
    ExitCode::from(u8::from(uncaught > 0))
}

/// Every Gherkin scenario against the IUT: once per profile whose capabilities
/// it needs, the manual's tables (`@model`) and `@once` scenarios once.
fn run_features(
    kind: &IutKind,
    profiles: &[&canif_spec::Profile],
) -> Result<Vec<ScenarioResult>, String> {
    let mut results = Vec::new();
    for scenario in canif_features::scenarios()? {
        let mut targets = Vec::new();
        if scenario.model_only {
            targets.push((
                "model".to_string(),
                IutKind::Model,
                canif_model::config::Capabilities::everything(),
            ));
        } else if scenario.once {
            // A profile scenario names its device; it runs when that profile is certified.
            let named = profiles
                .iter()
                .find(|p| scenario.profile.as_deref().is_none_or(|n| n == p.name));
            if let Some(profile) = named {
                targets.push((
                    profile.name.clone(),
                    kind.clone(),
                    profile.model_capabilities(),
                ));
            }
        } else {
            for profile in profiles
                .iter()
                .filter(|p| scenario.capabilities.iter().all(|c| p.has(c)))
            {
                targets.push((
                    profile.name.clone(),
                    kind.clone(),
                    profile.model_capabilities(),
                ));
            }
        }
        for (suite, iut, caps) in targets {
            let target = canif_features::Target {
                iut,
                profile: suite.clone(),
                caps,
            };
            let (outcome, error) =
                match canif_features::run_scenario(&scenario.file, scenario.line, target) {
                    canif_features::ScenarioOutcome::Passed => (Ok(()), false),
                    canif_features::ScenarioOutcome::Failed(report) => (Err(report), false),
                    canif_features::ScenarioOutcome::Error(report) => (Err(report), true),
                };
            results.push(ScenarioResult {
                suite,
                name: scenario.name.clone(),
                file: scenario.file.clone(),
                line: scenario.line,
                requirements: scenario.requirements.clone(),
                outcome,
                error,
            });
        }
    }
    results.sort_by(|a, b| (&a.suite, &a.file, a.line).cmp(&(&b.suite, &b.file, b.line)));
    Ok(results)
}

fn device(stdio: bool, faults: &[String], bus: Option<&str>) -> ExitCode {
    if !stdio {
        eprintln!("canif device needs --stdio: its process image is served over the adapter protocol (docs/adapter-protocol.md)");
        return ExitCode::from(2);
    }
    let chosen = match soft_device_faults(faults) {
        Ok(chosen) => chosen,
        Err(code) => return code,
    };
    if let Some(bus) = bus {
        let spec = match canif_kernel::BusSpec::parse(bus) {
            Ok(spec) => spec,
            Err(error) => {
                eprintln!("--bus {error}");
                return ExitCode::from(2);
            }
        };
        if let Err(error) = canif_kernel::probe() {
            eprintln!("canif device --bus {bus}: {error}");
            return ExitCode::from(2);
        }
        return match canif_harness::exec::serve_on_bus(
            &IutKind::SoftDevice { faults: chosen },
            Some(&spec.iut),
        ) {
            Ok(()) => ExitCode::SUCCESS,
            Err(error) => {
                eprintln!("canif device: {error}");
                ExitCode::from(2)
            }
        };
    }
    let stdin = std::io::stdin();
    match canif_harness::exec::serve(
        &IutKind::SoftDevice { faults: chosen },
        stdin.lock(),
        std::io::stdout(),
    ) {
        Ok(()) => ExitCode::SUCCESS,
        Err(error) => {
            eprintln!("canif device: {error}");
            ExitCode::from(2)
        }
    }
}

fn compare(base: &Path, new: &Path) -> ExitCode {
    let load = |path: &Path| -> Result<std::collections::BTreeMap<String, String>, String> {
        let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
        let value: serde_json::Value =
            serde_json::from_str(&text).map_err(|e| format!("{}: {e}", path.display()))?;
        canif_harness::compare::verdicts(&value).map_err(|e| format!("{}: {e}", path.display()))
    };
    let (base, new) = match (load(base), load(new)) {
        (Ok(base), Ok(new)) => (base, new),
        (Err(e), _) | (_, Err(e)) => {
            eprintln!("{e}");
            return ExitCode::from(2);
        }
    };
    let comparison = canif_harness::compare::compare(&base, &new);
    print!("{}", comparison.markdown());
    ExitCode::from(u8::from(!comparison.regressions.is_empty()))
}

/// The IUT named on the command line, or the exit code of a usage error.
fn resolve_iut(iut: &str, faults: &[String], timeout_ms: u64) -> Result<IutKind, ExitCode> {
    let chosen = soft_device_faults(faults)?;
    let kind = match iut {
        _ if iut.starts_with("exec:") => {
            if !chosen.is_empty() {
                eprintln!(
                    "--fault applies to the soft device only (pass it to the IUT's own command)"
                );
                return Err(ExitCode::from(2));
            }
            IutKind::Exec {
                command: iut["exec:".len()..].to_string(),
                timeout_ms,
            }
        }
        "softdevice" => IutKind::SoftDevice { faults: chosen },
        "model" if chosen.is_empty() => IutKind::Model,
        "model" => {
            eprintln!("--fault applies to the soft device only");
            return Err(ExitCode::from(2));
        }
        other => {
            eprintln!("unknown IUT `{other}`: use softdevice, model or exec:'COMMAND'");
            return Err(ExitCode::from(2));
        }
    };
    Ok(kind)
}

#[allow(clippy::too_many_arguments)]
fn certify(
    catalogue: &Catalogue,
    profile: &str,
    iut: &str,
    faults: &[String],
    seed: u64,
    timeout_ms: u64,
    out: &Path,
) -> ExitCode {
    let kind = match resolve_iut(iut, faults, timeout_ms) {
        Ok(kind) => kind,
        Err(code) => return code,
    };
    let Some(profile) = catalogue.profile(profile) else {
        eprintln!("unknown profile `{profile}`; `canif profiles` lists them");
        return ExitCode::from(2);
    };
    let options = Options {
        seed,
        ..Options::default()
    };
    let run = run_profile(catalogue, profile, &kind, &options, |r| {
        eprintln!("  {}", r.scenario)
    });
    let scenarios = match run_features(&kind, &[profile]) {
        Ok(scenarios) => scenarios,
        Err(error) => {
            eprintln!("the feature files do not parse: {error}");
            return ExitCode::from(2);
        }
    };
    let failed = scenarios.iter().filter(|s| s.outcome.is_err()).count();
    let files: Vec<(String, String)> = canif_spec::embedded_files()
        .iter()
        .map(|(p, t)| (p.to_string(), t.to_string()))
        .collect();
    let hash = canif_harness::certificate::catalogue_hash(&files);
    let certificate = canif_harness::certificate::certificate(
        catalogue,
        &hash,
        &run,
        &kind.name(),
        seed,
        (scenarios.len(), failed),
    );
    let written = std::fs::create_dir_all(out)
        .and_then(|_| {
            std::fs::write(
                out.join("certificate.json"),
                serde_json::to_string_pretty(&certificate).unwrap_or_default(),
            )
        })
        .and_then(|_| {
            std::fs::write(
                out.join("certificate.html"),
                canif_harness::certificate::html(&certificate, catalogue),
            )
        });
    if let Err(error) = written {
        eprintln!("cannot write the certificate to {}: {error}", out.display());
        return ExitCode::from(2);
    }
    println!(
        "{} {} on {}: {} — {}/certificate.{{json,html}}, seal {}",
        kind.name(),
        if certificate["conforms"] == serde_json::json!(true) {
            "CONFORMS"
        } else {
            "DOES NOT CONFORM"
        },
        profile.name,
        certificate["totals"],
        out.display(),
        certificate["result_sha256"].as_str().unwrap_or("")
    );
    let errors = run
        .verdicts
        .values()
        .any(|v| matches!(v, canif_harness::Verdict::Error(_)));
    ExitCode::from(if errors {
        2
    } else {
        u8::from(certificate["conforms"] != serde_json::json!(true))
    })
}

fn verify_certificate(path: &Path) -> ExitCode {
    let certificate: serde_json::Value = match std::fs::read_to_string(path)
        .map_err(|e| e.to_string())
        .and_then(|t| serde_json::from_str(&t).map_err(|e| e.to_string()))
    {
        Ok(value) => value,
        Err(error) => {
            eprintln!("{}: {error}", path.display());
            return ExitCode::from(2);
        }
    };
    match canif_harness::certificate::verify(&certificate) {
        Ok(()) => {
            println!(
                "{}: the seal matches ({})",
                path.display(),
                certificate["result_sha256"].as_str().unwrap_or("")
            );
            ExitCode::SUCCESS
        }
        Err(error) => {
            println!("{}: {error}", path.display());
            ExitCode::from(1)
        }
    }
}

/// The simulated coupler behind socketcand's text protocol on loopback TCP, so
/// that CANopen tools written by others (python-can's `socketcand` interface,
/// the `canopen` package) can talk to it. Real time drives its heartbeat.
fn serve_coupler(
    port: u16,
    node: u8,
    fault: Option<canif_model::canopen::coupler::CouplerFault>,
) -> ExitCode {
    use canif_model::frame::{CanId, Frame};
    use std::io::{BufRead, BufReader, Write};
    let node = match node_id(node) {
        Ok(node) => node,
        Err(code) => return code,
    };
    let listener = match std::net::TcpListener::bind(("127.0.0.1", port)) {
        Ok(listener) => listener,
        Err(error) => {
            eprintln!("cannot listen on 127.0.0.1:{port}: {error}");
            return ExitCode::from(2);
        }
    };
    // The port goes to stdout first, so a caller that asked for port 0 learns it.
    println!(
        "{}",
        listener.local_addr().map(|a| a.port()).unwrap_or(port)
    );
    let _ = std::io::stdout().flush();
    let Ok((stream, _)) = listener.accept() else {
        return ExitCode::from(2);
    };
    let _ = stream.set_read_timeout(Some(std::time::Duration::from_millis(5)));
    let mut writer = match stream.try_clone() {
        Ok(writer) => writer,
        Err(_) => return ExitCode::from(2),
    };
    let started = std::time::Instant::now();
    let now = || started.elapsed().as_nanos() as u64;
    let frame_text = |frame: &Frame, at: u64| {
        let id = match frame.id {
            CanId::Standard(id) => format!("{id:03X}"),
            CanId::Extended(id) => format!("{id:08X}"),
        };
        let data: String = frame.data().iter().map(|b| format!("{b:02X}")).collect();
        format!(
            "< frame {id} {}.{:06} {data} >",
            at / 1_000_000_000,
            (at % 1_000_000_000) / 1_000
        )
    };
    let mut coupler = simulated_coupler(node, fault);
    let mut reader = BufReader::new(stream);
    let mut pending = String::new();
    if writer.write_all(b"< hi >").is_err() {
        return ExitCode::from(2);
    }
    loop {
        let mut chunk = Vec::new();
        match reader.read_until(b'>', &mut chunk) {
            Ok(0) => return ExitCode::SUCCESS, // the client left
            Ok(_) => pending.push_str(&String::from_utf8_lossy(&chunk)),
            Err(error)
                if matches!(
                    error.kind(),
                    std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                ) =>
            {
                pending.push_str(&String::from_utf8_lossy(&chunk));
            }
            Err(_) => return ExitCode::SUCCESS,
        }
        let mut out = Vec::new();
        while let (Some(start), Some(end)) = (pending.find('<'), pending.find('>')) {
            if end < start {
                pending.drain(..=end);
                continue;
            }
            let command: Vec<String> = pending[start + 1..end]
                .split_whitespace()
                .map(String::from)
                .collect();
            pending.drain(..=end);
            match command.first().map(String::as_str) {
                Some("open") | Some("rawmode") => out.push("< ok >".to_string()),
                Some("send") if command.len() >= 3 => {
                    let raw = u32::from_str_radix(&command[1], 16).unwrap_or(0);
                    let id = if command[1].len() > 3 {
                        CanId::extended(raw)
                    } else {
                        CanId::standard(raw)
                    };
                    let data: Vec<u8> = command[3..]
                        .iter()
                        .filter_map(|b| u8::from_str_radix(b, 16).ok())
                        .collect();
                    if let Some(frame) = id.and_then(|id| Frame::classic(id, &data).ok()) {
                        let at = now();
                        out.extend(coupler.handle(&frame, at).iter().map(|f| frame_text(f, at)));
                    }
                }
                _ => out.push("< error unknown command >".to_string()),
            }
        }
        let at = now();
        out.extend(coupler.poll(at).iter().map(|f| frame_text(f, at)));
        if !out.is_empty() && writer.write_all(out.concat().as_bytes()).is_err() {
            return ExitCode::SUCCESS;
        }
    }
}

/// The simulated coupler as a node on a SocketCAN interface, in real time,
/// until it is stopped. Prints `ready` once it listens.
fn coupler_on_bus(
    bus: &str,
    node: u8,
    fault: Option<canif_model::canopen::coupler::CouplerFault>,
) -> ExitCode {
    let node = match node_id(node) {
        Ok(node) => node,
        Err(code) => return code,
    };
    let opened = canif_kernel::BusSpec::parse(bus)
        .and_then(|spec| canif_kernel::probe().map(|()| spec))
        .and_then(|spec| canif_kernel::KernelSocket::open(&spec.iut, false));
    let socket = match opened {
        Ok(socket) => socket,
        Err(error) => {
            eprintln!("canif coupler --bus {bus}: {error}");
            return ExitCode::from(2);
        }
    };
    let mut coupler = simulated_coupler(node, fault);
    let epoch = canif_kernel::realtime_ns();
    println!("ready: node {} on {}", node.get(), socket.interface);
    let _ = std::io::stdout().flush();
    loop {
        let _ = canif_kernel::KernelSocket::wait(&[&socket], std::time::Duration::from_millis(1));
        let mut out = Vec::new();
        loop {
            match socket.recv() {
                Ok(Some(canif_kernel::Received::Frame { frame, at, .. })) => {
                    out.extend(coupler.handle(&frame, at.saturating_sub(epoch)))
                }
                Ok(Some(_)) => {}
                Ok(None) => break,
                Err(error) => {
                    eprintln!("{}: {error}", socket.interface);
                    return ExitCode::from(2);
                }
            }
        }
        out.extend(coupler.poll(canif_kernel::realtime_ns().saturating_sub(epoch)));
        for frame in out {
            if let Err(error) = socket.send(&frame) {
                eprintln!("{}: sending {frame}: {error}", socket.interface);
            }
        }
    }
}

/// `canif run --suite canopen`: the CANopen node checks (002, 004), on the
/// simulated coupler or on a node on a SocketCAN interface.
fn canopen_suite(
    kernel: Option<&canif_harness::kernel_bus::KernelBusOptions>,
    node: u8,
    fault: Option<&str>,
) -> ExitCode {
    let node = match node_id(node) {
        Ok(node) => node,
        Err(code) => return code,
    };
    let (results, target) = match kernel {
        None => {
            let mut coupler = match coupler_fault(fault) {
                Ok(chosen) => simulated_coupler(node, chosen),
                Err(code) => return code,
            };
            let results = canif_harness::canopen::check_node(&mut coupler, node, 0);
            let target = format!(
                "simulated coupler, node {}{}",
                node.get(),
                fault.map_or(String::new(), |f| format!(" with {f}"))
            );
            (results, target)
        }
        Some(options) => {
            if fault.is_some() {
                eprintln!("--coupler-fault applies to the simulated coupler; on a SocketCAN bus, start `canif coupler --bus … --fault …` instead");
                return ExitCode::from(2);
            }
            let mut remote =
                match canif_harness::canopen::SocketCanNode::open(&options.spec.tester, node) {
                    Ok(remote) => remote,
                    Err(error) => {
                        eprintln!("error: {error}");
                        return ExitCode::from(2);
                    }
                };
            remote.answer_timeout = options.timeout.min(std::time::Duration::from_millis(500));
            // Real time: heartbeats are seen at the 10 ms poll step, plus scheduling jitter.
            let results = canif_harness::canopen::check_node(&mut remote, node, 30_000_000);
            let target = format!(
                "node {} on {} (Linux {})",
                node.get(),
                options.spec.tester,
                canif_kernel::kernel_release()
            );
            (results, target)
        }
    };
    let mut failed = 0;
    for result in &results {
        match &result.outcome {
            Ok(()) => println!("pass  {} ({})", result.name, result.requirements.join(", ")),
            Err(why) => {
                failed += 1;
                println!(
                    "FAIL  {} ({}): {why}",
                    result.name,
                    result.requirements.join(", ")
                );
            }
        }
    }
    println!("{target}: {} checks, {failed} failed", results.len());
    ExitCode::from(u8::from(failed > 0))
}

/// The quick start's coupler (2 digital, 4 analog channels), with a fault if asked.
fn simulated_coupler(
    node: canif_model::canopen::NodeId,
    fault: Option<canif_model::canopen::coupler::CouplerFault>,
) -> canif_model::canopen::coupler::Coupler {
    let mut coupler = canif_model::canopen::coupler::Coupler::new(node, 2, 4);
    if let Some(fault) = fault {
        coupler.inject(fault);
    }
    coupler
}

/// A CANopen node id from the command line, or the exit code of a usage error.
fn node_id(node: u8) -> Result<canif_model::canopen::NodeId, ExitCode> {
    canif_model::canopen::NodeId::new(node).ok_or_else(|| {
        eprintln!("node ids are 1..63, not {node}");
        ExitCode::from(2)
    })
}

/// The soft-device faults named on the command line, or the exit code of a usage error.
fn soft_device_faults(names: &[String]) -> Result<Vec<Fault>, ExitCode> {
    names
        .iter()
        .map(|name| {
            Fault::from_name(name).ok_or_else(|| {
                eprintln!("unknown fault `{name}`; `canif faults` lists them");
                ExitCode::from(2)
            })
        })
        .collect()
}

/// The coupler fault named on the command line, or the exit code of a usage error.
fn coupler_fault(
    name: Option<&str>,
) -> Result<Option<canif_model::canopen::coupler::CouplerFault>, ExitCode> {
    use canif_model::canopen::coupler::CouplerFault;
    match name {
        None => Ok(None),
        Some(name) => CouplerFault::from_name(name).map(Some).ok_or_else(|| {
            let known: Vec<&str> = CouplerFault::ALL.iter().map(|f| f.name()).collect();
            eprintln!("unknown coupler fault `{name}`: {}", known.join(", "));
            ExitCode::from(2)
        }),
    }
}
