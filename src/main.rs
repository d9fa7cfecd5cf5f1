//! `canif`: the conformance suite's command line.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use canif_model::frame::{CanId, Frame};
use canif_model::sizing::{self, FrameTimeBasis};
use canif_model::timing::{frame_bits, frame_duration, BitRates, Stuffing};
use canif_spec::{coverage, Catalogue, Status, Verification};
use clap::{Parser, Subcommand};

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
    },
}

fn main() -> ExitCode {
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
        SpecCommand::Coverage { root } => return spec_coverage(catalogue, &root),
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

fn spec_coverage(catalogue: &Catalogue, root: &Path) -> ExitCode {
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
        println!(
            "{:<8} {:>3}/{:<3} normative+derived covered  {}",
            area.area,
            covered,
            needing.len(),
            area.title
        );
    }
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
