//! `canif run`'s arguments.

use std::path::PathBuf;

use clap::Args;

use super::{bus_arg, seconds, BusArg, Cli, IutOptions, ProductOptions};

/// How a SocketCAN bus is run (ignored on the simulated bus).
#[derive(Args, Debug, Clone)]
pub(crate) struct RealTimeOptions {
    /// On a SocketCAN bus: the real cycle time in microseconds.
    #[arg(long, default_value_t = 2000, value_parser = clap::value_parser!(u64).range(100..=10_000_000))]
    pub cycle_us: u64,
    /// On a SocketCAN bus: how far the IUT's receive time stamps may be from the harness's, in µs.
    #[arg(long, default_value_t = 1000, value_parser = clap::value_parser!(u64).range(0..=10_000_000))]
    pub time_stamp_tolerance_us: u64,
    /// On a SocketCAN bus: how long a frame may take to cross the kernel, in ms.
    #[arg(long, default_value_t = 2000, value_parser = clap::value_parser!(u64).range(1..=600_000))]
    pub frame_timeout_ms: u64,
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

/// Which side of the interface is under test.
#[derive(clap::ValueEnum, Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum SideArg {
    /// The device (EL6751, FC51xx, CCAT, FC532x or what behaves like one).
    Device,
    /// The PLC-side client that fills and reads the image.
    Plc,
}

/// Which suite `canif run` runs.
#[derive(clap::ValueEnum, Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Suite {
    /// The CAN interface (the default).
    Interface,
    /// The CANopen node checks (002, 004).
    Canopen,
}

/// Flags of `canif run` that only one side has: given with the other side,
/// they are refused as a conflict, never ignored.
pub(crate) fn side_conflicts(
    side: SideArg,
    device_only: &[(bool, &str)],
    plc_only: &[(bool, &str)],
) -> Result<(), clap::Error> {
    use clap::CommandFactory;
    let (given, other) = match side {
        SideArg::Plc => (device_only, "the device side, not to --side plc"),
        SideArg::Device => (plc_only, "--side plc"),
    };
    match given.iter().find(|(present, _)| *present) {
        Some((_, flag)) => Err(Cli::command().error(
            clap::error::ErrorKind::ArgumentConflict,
            format!("{flag} applies to {other}"),
        )),
        None => Ok(()),
    }
}

/// `canif run`'s arguments, converted once by clap.
#[derive(clap::Args)]
pub(crate) struct RunArgs {
    #[command(flatten)]
    pub(crate) iut: IutOptions,
    /// A profile name (see `canif profiles`; repeatable) or `all`.
    #[arg(long, default_value = "all")]
    pub(crate) profile: Vec<String>,
    #[arg(long, default_value_t = 1)]
    pub(crate) seed: u64,
    #[command(flatten)]
    pub(crate) product: ProductOptions,
    /// Generated scenarios per interface [default: 4].
    #[arg(long, value_parser = clap::value_parser!(u64).range(0..=10_000))]
    pub(crate) cases: Option<u64>,
    /// Virtual seconds of generated traffic per scenario (a soak run).
    #[arg(long, value_parser = seconds)]
    pub(crate) duration: Option<f64>,
    /// Leave out the 65,540-cycle RxCounter wrap.
    #[arg(long)]
    pub(crate) no_counter_wrap: bool,
    /// Where to write junit.xml, report.json and summary.md.
    #[arg(long, default_value = "reports/latest")]
    pub(crate) report: PathBuf,
    /// Also write every scenario's bus as a candump log and a pcapng file here.
    #[arg(long, value_name = "DIR")]
    pub(crate) trace: Option<PathBuf>,
    /// What to check: the CAN interface, or a CANopen node.
    #[arg(long, value_enum, default_value = "interface")]
    pub(crate) suite: Suite,
    /// Which side is under test: the device, or a PLC-side client (the
    /// harness then plays the device, the master and the application).
    #[arg(long, value_enum, default_value = "device")]
    pub(crate) side: SideArg,
    /// With --side plc: only these EtherCAT master models (repeatable; see
    /// `canif faults`); all by default.
    #[arg(long, value_name = "NAME")]
    pub(crate) master: Vec<String>,
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
    /// Only checks whose name contains this text (repeatable: any of them):
    /// lockstep and Gherkin scenarios, as `canif list scenarios` names them.
    #[arg(long, value_name = "TEXT")]
    pub(crate) scenario: Vec<String>,
    /// Only checks that exercise this requirement (repeatable).
    #[arg(long, value_name = "ID")]
    pub(crate) requirement: Vec<String>,
    /// Only shard K of N (such as 2/4): a deterministic share of the
    /// (profile, check) pairs, the same on every machine. `canif merge`
    /// joins the shards' reports into one verdict.
    #[arg(long, value_name = "K/N", value_parser = canif_harness::run::Shard::parse)]
    pub(crate) shard: Option<canif_harness::run::Shard>,
    /// The time the candump log's and pcapng's first frame is stamped with,
    /// in seconds since the Unix epoch (default: when the run started).
    #[arg(long, value_name = "SECONDS")]
    pub(crate) trace_epoch: Option<u64>,
    /// With --suite canopen: the node id to check.
    #[arg(long, default_value_t = 5)]
    pub(crate) node: u8,
    /// With --suite canopen on the simulated bus: a coupler fault (toggle-stuck, sdo-size-always-4, no-abort).
    #[arg(long)]
    pub(crate) coupler_fault: Option<String>,
}
