//! `canif run device|plc|canopen`'s arguments: each side its own, so that
//! clap itself refuses a flag the side does not have; `canif run` with no
//! side is the device run.

use std::path::PathBuf;

use clap::{Args, Subcommand};

use super::{bus_arg, seconds, BusArg, IutOptions, ProductOptions};

/// How a SocketCAN bus is run (ignored on the simulated bus).
#[derive(Args, Debug, Clone)]
pub(crate) struct RealTimeOptions {
    /// On a SocketCAN bus: the real cycle time in microseconds.
    #[arg(long, default_value_t = 2000, value_parser = clap::value_parser!(u64).range(100..=10_000_000))]
    pub cycle_us: u64,
    /// On a SocketCAN bus: how far the IUT's receive time stamps may be from the harness's, in µs.
    #[arg(long, default_value_t = 1000, value_parser = clap::value_parser!(u64).range(0..=10_000_000))]
    pub time_stamp_tolerance_us: u64,
    #[command(flatten)]
    pub frame_timeout: FrameTimeout,
    /// On a SocketCAN bus: send the scenarios' remote frames as data frames
    /// (for controllers that cannot carry them, such as QEMU's SJA1000).
    #[arg(long)]
    pub no_remote_frames: bool,
    /// On a SocketCAN bus: the controllers send ESI from their own error
    /// state (real CAN FD controllers), so the scenarios' ESI bits are left out.
    #[arg(long)]
    pub esi_from_controller: bool,
    /// Over EtherCAT: before the run, exchange idle cycles with each terminal
    /// every --cycle-us for this many seconds and report the cycles that missed
    /// their deadline and the worst one (0: 1,000 cycles, unpaced).
    #[arg(long, default_value_t = 0, value_parser = clap::value_parser!(u64).range(0..=86_400))]
    pub ethercat_soak_s: u64,
}

/// How long a frame may take to cross the kernel, on every side's SocketCAN bus.
#[derive(Args, Debug, Clone, Copy)]
pub(crate) struct FrameTimeout {
    /// On a SocketCAN bus: how long a frame may take to cross the kernel, in ms.
    #[arg(long, default_value_t = 2000, value_parser = clap::value_parser!(u64).range(1..=600_000))]
    pub(crate) frame_timeout_ms: u64,
}

impl FrameTimeout {
    pub(crate) fn duration(self) -> std::time::Duration {
        std::time::Duration::from_millis(self.frame_timeout_ms)
    }
}

/// Which side of the interface is under test (`canif list scenarios`,
/// `canif certify`): `device` or `plc`, the catalogue's own words.
pub(crate) fn side_arg(text: &str) -> Result<canif_spec::Side, String> {
    match text {
        "device" => Ok(canif_spec::Side::Device),
        "plc" => Ok(canif_spec::Side::Plc),
        _ => Err("a side is `device` (the EL6751 or what behaves like one) or `plc` (the client that fills and reads the image)".into()),
    }
}

/// `canif run`: a side of the interface, or the CANopen suite; with no side
/// named, the device.
#[derive(Args)]
#[command(args_conflicts_with_subcommands = true)]
pub(crate) struct RunCommand {
    #[command(subcommand)]
    side: Option<RunTarget>,
    #[command(flatten)]
    device: DeviceRunArgs,
}

impl RunCommand {
    /// What is run: the side named, or the device.
    pub(crate) fn target(self) -> RunTarget {
        self.side.unwrap_or(RunTarget::Device(self.device))
    }
}

/// What `canif run` checks: a side of the interface, or a CANopen node.
// Parsed once per process: the size of its largest variant costs nothing.
#[allow(clippy::large_enum_variant)]
#[derive(Subcommand)]
pub(crate) enum RunTarget {
    /// The device under test (EL6751, FC51xx, CCAT, FC532x or what behaves
    /// like one); canif plays the PLC and the other nodes. The default.
    Device(DeviceRunArgs),
    /// A PLC-side client under test; canif plays the device, the EtherCAT
    /// master and the application.
    Plc(PlcRunArgs),
    /// A CANopen node (002, 004): the simulated coupler, or a node on --bus.
    Canopen(CanopenRunArgs),
}

/// What every run has: where it reports, what it selects.
#[derive(Args, Debug, Clone)]
pub(crate) struct RunCommon {
    #[arg(long, default_value_t = 1)]
    pub(crate) seed: u64,
    #[command(flatten)]
    pub(crate) product: ProductOptions,
    /// Where to write junit.xml, report.json, summary.md and report.html.
    #[arg(long, default_value = "reports/latest")]
    pub(crate) report: PathBuf,
    /// Only checks whose name contains this text (repeatable: any of them):
    /// lockstep and Gherkin scenarios, as `canif list scenarios` names them.
    #[arg(long, value_name = "TEXT")]
    pub(crate) scenario: Vec<String>,
    /// Only checks that exercise this requirement (repeatable).
    #[arg(long, value_name = "ID")]
    pub(crate) requirement: Vec<String>,
}

/// A run of a side of the interface over profiles: which, how many at
/// once, and what share of a campaign.
#[derive(Args, Debug, Clone)]
pub(crate) struct CampaignArgs {
    /// A profile name (see `canif profiles`; repeatable) or `all`.
    #[arg(long, default_value = "all")]
    pub(crate) profile: Vec<String>,
    /// Profiles run at once, each on a thread of its own; the verdicts are
    /// a serial run's. On the simulated bus only, and not for a library in
    /// canif's process or an EtherCAT terminal (they share one process or link).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u16).range(1..=256))]
    pub(crate) jobs: u16,
    /// Run again only what failed or erred in a report (default the last
    /// run's, reports/latest/report.json), on the profiles it failed on. A
    /// check that failed there and passes now is reported FLAKY, exit 1:
    /// never a pass.
    #[arg(
        long,
        value_name = "REPORT",
        num_args = 0..=1,
        default_missing_value = "reports/latest/report.json",
        conflicts_with_all = ["scenario", "requirement", "shard"]
    )]
    pub(crate) rerun_failed: Option<PathBuf>,
    /// Only shard K of N (such as 2/4): a deterministic share of the
    /// (profile, check) pairs, the same on every machine. `canif merge`
    /// joins the shards' reports into one verdict.
    #[arg(long, value_name = "K/N", value_parser = canif_harness::run::Shard::parse)]
    pub(crate) shard: Option<canif_harness::run::Shard>,
    /// Leave out the 65,540-cycle RxCounter wrap.
    #[arg(long)]
    pub(crate) no_counter_wrap: bool,
}

/// `canif run device`.
#[derive(Args, Debug, Clone)]
pub(crate) struct DeviceRunArgs {
    #[command(flatten)]
    pub(crate) iut: IutOptions,
    #[command(flatten)]
    pub(crate) common: RunCommon,
    #[command(flatten)]
    pub(crate) campaign: CampaignArgs,
    /// Generated scenarios per interface [default: 4].
    #[arg(long, value_parser = clap::value_parser!(u64).range(0..=10_000))]
    pub(crate) cases: Option<u64>,
    /// Virtual seconds of generated traffic per scenario (a soak run).
    #[arg(long, value_parser = seconds)]
    pub(crate) duration: Option<f64>,
    /// Also write every scenario's bus as a candump log and a pcapng file here.
    #[arg(long, value_name = "DIR")]
    pub(crate) trace: Option<PathBuf>,
    /// The time the candump log's and pcapng's first frame is stamped with,
    /// in seconds since the Unix epoch (default: when the run started).
    #[arg(long, value_name = "SECONDS")]
    pub(crate) trace_epoch: Option<u64>,
    /// `sim` (the simulated bus, virtual time) or `socketcan:IFACE` (a Linux
    /// SocketCAN interface, real time; `socketcan:IUT_IFACE,OTHER_IFACE` for
    /// two controllers on one bus).
    #[arg(long, default_value = "sim", value_parser = bus_arg)]
    pub(crate) bus: BusArg,
    #[command(flatten)]
    pub(crate) real_time: RealTimeOptions,
    /// After the IUT breaks, still start it for every remaining scenario
    /// (by default they are reported as skipped, and the Gherkin stage is left out).
    #[arg(long)]
    pub(crate) no_fail_fast: bool,
}

/// `canif run plc`.
#[derive(Args, Debug, Clone)]
pub(crate) struct PlcRunArgs {
    #[command(flatten)]
    pub(crate) iut: IutOptions,
    #[command(flatten)]
    pub(crate) common: RunCommon,
    #[command(flatten)]
    pub(crate) campaign: CampaignArgs,
    /// Only these EtherCAT master models (repeatable; see `canif faults`);
    /// all by default.
    #[arg(long, value_name = "NAME")]
    pub(crate) master: Vec<String>,
    /// `sim` (the simulated bus, virtual time) or `socketcan:IFACE` (one
    /// Linux SocketCAN interface the played device and the other nodes share).
    #[arg(long, default_value = "sim", value_parser = bus_arg)]
    pub(crate) bus: BusArg,
    #[command(flatten)]
    pub(crate) frame_timeout: FrameTimeout,
}

/// `canif run canopen`.
#[derive(Args, Debug, Clone)]
pub(crate) struct CanopenRunArgs {
    #[command(flatten)]
    pub(crate) common: RunCommon,
    /// `sim` (the simulated coupler) or `socketcan:IFACE` (a node on that interface).
    #[arg(long, default_value = "sim", value_parser = bus_arg)]
    pub(crate) bus: BusArg,
    #[command(flatten)]
    pub(crate) frame_timeout: FrameTimeout,
    /// The node id to check.
    #[arg(long, default_value_t = 5)]
    pub(crate) node: u8,
    /// On the simulated bus: a coupler fault (toggle-stuck, sdo-size-always-4, no-abort).
    #[arg(long)]
    pub(crate) coupler_fault: Option<String>,
}

/// The spellings of `canif run` before each side had its own arguments
/// (`--side plc`, `canif run canopen`), rewritten to `canif run plc` and
/// `canif run canopen` for one release, each with a line that says so.
pub(crate) fn deprecated_spellings(args: Vec<String>) -> (Vec<String>, Vec<String>) {
    // The command is the first word that is no option (after `--spec DIR`).
    let mut at = 1;
    while let Some(arg) = args.get(at) {
        match arg.as_str() {
            "--spec" => at += 2,
            a if a.starts_with('-') => at += 1,
            _ => break,
        }
    }
    if args.get(at).map(String::as_str) != Some("run") {
        return (args, Vec::new());
    }
    let mut kept: Vec<String> = args[..=at].to_vec();
    let mut side = None;
    let mut said = Vec::new();
    let mut rest = args[at + 1..].iter();
    while let Some(arg) = rest.next() {
        let (flag, value) = match arg.split_once('=') {
            Some((flag, value)) if flag == "--side" || flag == "--suite" => {
                (flag.to_string(), Some(value.to_string()))
            }
            _ if arg == "--side" || arg == "--suite" => (arg.clone(), rest.next().cloned()),
            _ => {
                kept.push(arg.clone());
                continue;
            }
        };
        let new: &'static str = match (flag.as_str(), value.as_deref()) {
            ("--side", Some("device")) => "device",
            ("--side", Some("plc")) => "plc",
            ("--suite", Some("canopen")) => "canopen",
            ("--suite", Some("interface")) => "device",
            _ => {
                // Not a spelling this knows: clap says what is wrong with it.
                kept.push(flag);
                kept.extend(value);
                continue;
            }
        };
        said.push(format!(
            "canif: `{flag} {}` is deprecated and goes in the next release: write `canif run {new}`",
            value.as_deref().unwrap_or_default()
        ));
        // `--side plc --suite interface` is the PLC side.
        if side.is_none() || new != "device" {
            side = Some(new);
        }
    }
    if let Some(side) = side {
        kept.insert(at + 1, side.to_string());
    }
    (kept, said)
}
