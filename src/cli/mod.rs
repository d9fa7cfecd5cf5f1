//! The command line as types: every value is parsed and checked by clap before
//! a command runs, so a command never sees a malformed one.

use std::path::PathBuf;

use canif_harness::door::Timeouts;
use clap::{Args, Parser, Subcommand};

mod plc;
mod run;
mod spec;
pub(crate) use plc::{CheckLayoutArgs, ExportArgs, FrameArg, InterfaceArgs, LanguageArg};
pub(crate) use run::{
    side_arg, CampaignArgs, CanopenRunArgs, DeviceRunArgs, FrameTimeout, PlcRunArgs,
    RealTimeOptions, RunCommand, RunCommon, RunTarget,
};
pub(crate) use spec::SpecCommand;

#[derive(Parser)]
#[command(
    name = "canif",
    version,
    about = "Conformance suite for the Beckhoff CAN interface"
)]
pub(crate) struct Cli {
    /// A catalogue folder of the shape of spec/ instead of the embedded one.
    #[arg(long, global = true, value_name = "DIR")]
    pub spec: Option<PathBuf>,
    #[command(subcommand)]
    pub command: Command,
}

impl Cli {
    /// The command line of this process, old spellings rewritten (each
    /// said on stderr once), parsed; clap ends the process on a mistake.
    pub(crate) fn from_env() -> Self {
        let (args, said) = run::deprecated_spellings(std::env::args().collect());
        for line in said {
            errln!("{line}");
        }
        Cli::parse_from(args)
    }
}

/// The implementation under test, as the command line names it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum IutArg {
    SoftDevice,
    Model,
    /// The reference client of 001 §6 (`canif run plc`).
    Reference,
    /// The independent soft client, with `--fault` its client faults (`canif run plc`).
    SoftClient,
    /// Behind a door (`exec:COMMAND`, `lib:PATH`, `ethercat:LINK`; see
    /// `canif_harness::door`), with the default settings until the other
    /// flags are read.
    Door(canif_harness::door::Door),
}

fn iut_arg(text: &str) -> Result<IutArg, String> {
    match text {
        "softdevice" => Ok(IutArg::SoftDevice),
        "model" => Ok(IutArg::Model),
        "reference" => Ok(IutArg::Reference),
        "softclient" => Ok(IutArg::SoftClient),
        _ => match canif_harness::door::Door::parse(text) {
            Some(door) => door.map(IutArg::Door),
            None => Err(
                "use softdevice, model, exec:'COMMAND', lib:PATH or ethercat:emulated (device side), \
                 reference or softclient (canif run plc)"
                    .into(),
            ),
        },
    }
}

/// The bus, as the command line names it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum BusArg {
    Sim,
    /// `socketcan:IFACE` or `socketcan:IUT_IFACE,OTHER_IFACE`.
    #[cfg(feature = "socketcan")]
    SocketCan(canif_kernel::BusSpec),
}

fn bus_arg(text: &str) -> Result<BusArg, String> {
    if text == "sim" {
        return Ok(BusArg::Sim);
    }
    #[cfg(feature = "socketcan")]
    {
        canif_kernel::BusSpec::parse(text).map(BusArg::SocketCan)
    }
    #[cfg(not(feature = "socketcan"))]
    {
        Err(format!(
            "`{text}`: this canif was built without SocketCAN (cargo feature `socketcan`); use sim"
        ))
    }
}

/// Virtual seconds: finite, above 0, at most a virtual day (86.4 million cycles).
fn seconds(text: &str) -> Result<f64, String> {
    let value: f64 = text.parse().map_err(|e| format!("{e}"))?;
    if value.is_finite() && value > 0.0 && value <= 86_400.0 {
        Ok(value)
    } else {
        Err(format!(
            "{text}: a duration is a number of virtual seconds above 0 and at most 86400"
        ))
    }
}

/// Which implementation, and how an external one is run.
#[derive(Args, Debug, Clone)]
pub(crate) struct IutOptions {
    /// Device side: softdevice (the built-in soft EL6751, the default), model
    /// (the reference itself), exec:'COMMAND' (a process speaking the adapter
    /// protocol), or lib:PATH (a shared library built against include/canif.h).
    /// PLC side: reference (the reference client, the default) or softclient
    /// (the independent client; --fault picks it).
    #[arg(long, value_parser = iut_arg)]
    pub iut: Option<IutArg>,
    /// How long an external IUT may take to answer one request, in ms; past
    /// it, the IUT hung.
    #[arg(long, default_value_t = Timeouts::DEFAULT_REQUEST_MS, value_parser = clap::value_parser!(u64).range(1..=600_000))]
    pub timeout_ms: u64,
    /// How long an external IUT may take to start (its process, an
    /// interpreter, a library's load) up to its first answer, in ms; at least
    /// --timeout-ms. Default: CANIF_START_TIMEOUT_MS, or 60000.
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..=3_600_000))]
    pub start_timeout_ms: Option<u64>,
    /// Run a lib:PATH IUT in canif's own process instead of a `canif lib-host`
    /// of its own: faster, but a library that crashes or reads far past its
    /// image then ends the run with it.
    #[arg(long)]
    pub lib_in_process: bool,
    /// Switch on a soft-device fault, or with `canif run plc` a soft-client fault
    /// (repeatable; see `canif faults`).
    #[arg(long)]
    pub fault: Vec<String>,
    /// Let the soft device take a freedom the documents leave (repeatable; see
    /// `canif faults`): it must still conform. With `canif run plc`: the soft
    /// client takes one way of working and declares it.
    #[arg(long)]
    pub choice: Vec<String>,
    /// Device side: what the device does where the documents leave a choice,
    /// as NAME=VALUE (repeatable; `canif faults` lists the choices), or
    /// @FILE, the choices `canif probe` wrote. Undeclared, every documented
    /// choice passes, and the first scenario that tells them apart settles
    /// which one the device is held to. PLC side: what the client is
    /// (formats, queues, slots, direction, application, restart, tells-sent;
    /// docs/plc-side.md), or @FILE of NAME=VALUE lines.
    #[arg(long, value_name = "NAME=VALUE|@FILE")]
    pub declare: Vec<String>,
    /// Let an external IUT run on any CPU. By default it shares the harness's:
    /// the exchange strictly alternates, and on virtual machines a wake-up
    /// across CPUs costs about ten times one on the same CPU.
    #[arg(long)]
    pub iut_cpu_free: bool,
}

impl IutOptions {
    /// The start and per-request limits of an external IUT.
    pub(crate) fn timeouts(&self) -> Timeouts {
        let request = std::time::Duration::from_millis(self.timeout_ms);
        let mut timeouts = Timeouts::with_request(request);
        if let Some(start) = self.start_timeout_ms {
            timeouts.start = std::time::Duration::from_millis(start).max(request);
        }
        timeouts
    }
}

/// The role of a hosted library.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub(crate) enum LibRole {
    Device,
    Client,
}

// Parsed once per process: the size of its largest variant costs nothing.
#[allow(clippy::large_enum_variant)]
#[derive(Subcommand)]
pub(crate) enum Command {
    /// Certify an implementation against the model, per profile, on the
    /// simulated bus or a SocketCAN interface: `canif run` (the device),
    /// `canif run plc` (a PLC-side client), `canif run canopen` (a CANopen node).
    Run(RunCommand),
    /// Certify profiles: a certificate (canonical JSON + HTML) of every
    /// requirement's verdict, signed with an OpenSSH Ed25519 key.
    Certify {
        /// The profile to certify (repeatable, or `all`).
        #[arg(long, required_unless_present = "verify")]
        profile: Vec<String>,
        #[command(flatten)]
        iut: IutOptions,
        #[command(flatten)]
        product: ProductOptions,
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Which side is under test: the device, or a PLC-side client.
        #[arg(long, value_parser = side_arg, default_value = "device")]
        side: canif_spec::Side,
        /// Where to write certificate.json, .json.sig, .html and the run's reports.
        #[arg(long, default_value = "reports/certificate")]
        out: PathBuf,
        /// An unencrypted OpenSSH Ed25519 private key to sign with (without
        /// it the certificate is written unsigned, and says so).
        #[arg(long, value_name = "PRIVATE_KEY")]
        key: Option<PathBuf>,
        /// Check an existing certificate.json (and its .sig beside it) instead.
        #[arg(long, value_name = "CERTIFICATE", requires = "pubkey")]
        verify: Option<PathBuf>,
        /// With --verify: the signer's public key (an `ssh-ed25519 …` line).
        #[arg(long, value_name = "PUBLIC_KEY")]
        pubkey: Option<PathBuf>,
    },
    /// Join the shards of a campaign (`canif run --shard K/N`, each a report
    /// folder with its shard.json) into one run's reports and verdict.
    Merge {
        /// The shards' report folders (or their shard.json files): every K of N once.
        #[arg(required = true, value_name = "SHARD")]
        shards: Vec<PathBuf>,
        /// Where to write the merged junit.xml, report.json, summary.md and report.html.
        #[arg(long, default_value = "reports/merged")]
        report: PathBuf,
        /// Also write the merged run's certificate (certificate.json, .html) here.
        #[arg(long, value_name = "DIR")]
        certificate: Option<PathBuf>,
        /// With --certificate: sign it with this OpenSSH Ed25519 private key.
        #[arg(long, value_name = "PRIVATE_KEY", requires = "certificate")]
        key: Option<PathBuf>,
    },
    /// What changed between two report.json files; exit 1 on a regression,
    /// 2 when they do not describe the same run.
    Compare {
        base: PathBuf,
        new: PathBuf,
        /// A check that passed in the base and is gone now is not a regression.
        #[arg(long)]
        allow_removed: bool,
        /// Compare reports of different IUTs, sides, catalogues or profile sets, saying so.
        #[arg(long)]
        force: bool,
        #[arg(long, value_enum, default_value = "markdown")]
        format: CompareFormat,
    },
    /// Lists what a run can select.
    List {
        #[command(subcommand)]
        what: ListCommand,
    },
    /// The soft device's deliberate faults.
    Faults,
    /// Run a shared library of the C ABI in this process, served over the
    /// adapter protocol on stdin/stdout, its images behind guard pages: what
    /// `--iut lib:PATH` starts, so a library that crashes or reads past its
    /// image ends here and not in the run.
    LibHost {
        /// The role the library plays.
        #[arg(long, value_enum)]
        role: LibRole,
        /// Speak the protocol on descriptors 3 (requests) and 4 (answers),
        /// as canif starts a host: the library's stdout and stderr are then
        /// its own output, not the protocol.
        #[arg(long)]
        control: bool,
        /// The library (.so).
        path: PathBuf,
    },
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
        /// Take a freedom the documents leave (repeatable; see `canif faults`).
        /// Behind the protocol the device declares nothing (canif finds out)
        /// unless --declare says what to declare.
        #[arg(long)]
        choice: Vec<String>,
        /// With --stdio: declare NAME=VALUE in every `configured` answer
        /// (repeatable; docs/choices.md), as a device declares its choices.
        #[arg(long, value_name = "NAME=VALUE", requires = "stdio")]
        declare: Vec<String>,
        /// The highest adapter-protocol version to agree on (3 carries each
        /// cycle in shared memory; 2 batches a cycle's bus events into one
        /// line; 1 is one line per event).
        #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u64).range(1..=3))]
        protocol: u64,
        /// Put the device's CAN side on a SocketCAN interface (`socketcan:IFACE`):
        /// it sends and receives real frames there, and the adapter protocol
        /// carries only configure, cycle and controller_status. With
        /// --ethercat: the terminal's CAN side.
        #[arg(long)]
        bus: Option<String>,
        /// Be an EtherCAT terminal on this network interface (needs CAP_NET_RAW)
        /// for any master. Its CAN side is --bus socketcan:IFACE; without it
        /// the CAN frames it sends are printed in candump's format.
        #[arg(long, value_name = "IFACE", conflicts_with_all = ["stdio", "protocol"])]
        ethercat: Option<String>,
        /// The terminal profile whose identity and offer it has (with --ethercat).
        #[arg(long, default_value = "el6751-mdp", requires = "ethercat")]
        profile: String,
    },
    /// Which of the choices the documents leave a device takes: the scenarios
    /// that tell them apart, once under each choice. Writes the finding as a
    /// file `canif run --declare @FILE` takes; exit 1 when the device passes
    /// under no choice or under different ones.
    Probe {
        #[command(flatten)]
        iut: IutOptions,
        /// A profile name (see `canif profiles`; repeatable) or `all`.
        #[arg(long, default_value = "all")]
        profile: Vec<String>,
        /// Where to write the finding (JSON: choice name to value).
        #[arg(long, default_value = "choices.json")]
        out: PathBuf,
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
    /// The emulated terminal's ESI file (ETG.2000 EtherCATInfo XML), for a
    /// configurator to add canif's EL6751 offline; written to stdout.
    Esi {
        /// An EtherCAT terminal profile (see `canif profiles`).
        #[arg(long)]
        profile: String,
    },
    /// The process image's data types for one interface of a profile, as
    /// Structured Text, a C header or Rust (docs/plc-side.md); to stdout.
    Export(ExportArgs),
    /// Hold hand-written ST declarations of the image against it: every
    /// member's offset and size as TwinCAT lays it out. Exit 1 on a
    /// difference, 2 on a file canif cannot read or size.
    CheckLayout(CheckLayoutArgs),
    /// Message slots a cycle time needs (the manual's §4, ruling R4).
    Size {
        /// Bit rate in bit/s, e.g. 500000.
        #[arg(long, value_parser = clap::value_parser!(u32).range(1..))]
        bitrate: u32,
        /// PLC task / CAN interface cycle time in µs.
        #[arg(long = "cycle-us", value_parser = clap::value_parser!(u64).range(1..=10_000_000))]
        cycle_us: u64,
        /// Data bytes per frame (0..=8).
        #[arg(long, default_value_t = 8, value_parser = clap::value_parser!(u8).range(0..=8))]
        payload: u8,
    },
    /// How long one frame occupies the bus (nominal and worst-case stuffing).
    FrameTime {
        #[arg(long, value_parser = clap::value_parser!(u32).range(1..))]
        bitrate: u32,
        /// Data-phase bit rate for CAN FD with bit rate switch.
        #[arg(long = "data-bitrate", value_parser = clap::value_parser!(u32).range(1..))]
        data_bitrate: Option<u32>,
        #[arg(long, default_value_t = 8, value_parser = clap::value_parser!(u8).range(0..=64))]
        payload: u8,
        /// 29-bit identifier.
        #[arg(long)]
        extended: bool,
        /// CAN FD frame (payload rounds up to a valid size).
        #[arg(long)]
        fd: bool,
    },
}

/// How `canif compare` writes its answer.
#[derive(clap::ValueEnum, Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum CompareFormat {
    Markdown,
    Json,
}

/// The implementation's maker's own name and version for it, for reports and certificates.
#[derive(Args, Debug, Clone)]
pub(crate) struct ProductOptions {
    /// The product's name as its maker declares it.
    #[arg(long, requires = "product_version")]
    pub product: Option<String>,
    /// The product's version as its maker declares it.
    #[arg(long, requires = "product")]
    pub product_version: Option<String>,
}

impl ProductOptions {
    pub(crate) fn product(&self) -> Option<canif_harness::report::Product> {
        Some(canif_harness::report::Product {
            name: self.product.clone()?,
            version: self.product_version.clone()?,
        })
    }
}

#[derive(Subcommand)]
pub(crate) enum ListCommand {
    /// Every check `canif run` can select with --scenario, per profile, with
    /// the requirements each exercises (tab-separated).
    Scenarios {
        /// Profiles to list (repeatable, or `all`).
        #[arg(long, default_value = "all")]
        profile: Vec<String>,
        /// The device side's checks, or the PLC side's.
        #[arg(long, value_parser = side_arg, default_value = "device")]
        side: canif_spec::Side,
    },
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn absurd_numbers_are_refused_before_anything_runs() {
        for duration in ["inf", "nan", "-5", "0", "1e12"] {
            assert!(seconds(duration).is_err(), "--duration {duration}");
        }
        assert_eq!(seconds("60"), Ok(60.0));
        for args in [
            &["canif", "size", "--bitrate", "0", "--cycle-us", "1000"][..],
            &[
                "canif",
                "size",
                "--bitrate",
                "500000",
                "--cycle-us",
                "18446744073709551615",
            ],
            &["canif", "frame-time", "--bitrate", "0"],
            &["canif", "run", "--iut", "exec:"],
            &["canif", "run", "--iut", "firmware"],
            &["canif", "run", "--duration", "inf"],
        ] {
            assert!(Cli::try_parse_from(args).is_err(), "{args:?} was accepted");
        }
        assert!(Cli::try_parse_from(["canif", "run", "--iut", "exec:./my-iut"]).is_ok());
    }

    /// Each side has its own flags: clap, not a table, refuses the others.
    #[test]
    fn each_side_of_canif_run_takes_its_own_flags_only() {
        let side = |args: &[&str]| match Cli::try_parse_from(args).map(|cli| cli.command) {
            Ok(Command::Run(run)) => Ok(match run.target() {
                RunTarget::Device(_) => "device",
                RunTarget::Plc(_) => "plc",
                RunTarget::Canopen(_) => "canopen",
            }),
            Ok(_) => panic!("{args:?} is no run"),
            Err(error) => Err(error.kind()),
        };
        assert_eq!(side(&["canif", "run", "--cases", "2"]), Ok("device"));
        assert_eq!(
            side(&["canif", "run", "device", "--trace", "t"]),
            Ok("device")
        );
        assert_eq!(side(&["canif", "run", "plc", "--master", "lrw"]), Ok("plc"));
        assert_eq!(
            side(&["canif", "run", "canopen", "--node", "3"]),
            Ok("canopen")
        );
        let unknown = Err(clap::error::ErrorKind::UnknownArgument);
        assert_eq!(side(&["canif", "run", "plc", "--cases", "2"]), unknown);
        assert_eq!(side(&["canif", "run", "plc", "--no-fail-fast"]), unknown);
        assert_eq!(
            side(&["canif", "run", "canopen", "--iut", "model"]),
            unknown
        );
        assert_eq!(
            side(&["canif", "run", "canopen", "--shard", "1/2"]),
            unknown
        );
        assert_eq!(
            side(&["canif", "run", "device", "--master", "lrw"]),
            unknown
        );
        // Flags before the side's name belong to no side.
        assert!(side(&["canif", "run", "--cases", "2", "plc"]).is_err());
    }

    /// The spellings before each side had its arguments still work for one
    /// release, each said to be deprecated.
    #[test]
    fn old_spellings_of_the_side_are_rewritten_and_said() {
        let rewrite = |args: &[&str]| {
            let (args, said) =
                run::deprecated_spellings(args.iter().map(|a| a.to_string()).collect());
            (args.join(" "), said.len())
        };
        assert_eq!(
            rewrite(&["canif", "run", "--side", "plc", "--profile", "fc510x"]),
            ("canif run plc --profile fc510x".into(), 1)
        );
        assert_eq!(
            rewrite(&[
                "canif",
                "--spec",
                "dir",
                "run",
                "--suite=canopen",
                "--node",
                "3"
            ]),
            ("canif --spec dir run canopen --node 3".into(), 1)
        );
        assert_eq!(
            rewrite(&["canif", "run", "--side", "device", "--suite", "interface"]),
            ("canif run device".into(), 2)
        );
        // Other commands keep their own --side; new spellings are untouched.
        for args in [
            &["canif", "list", "scenarios", "--side", "plc"][..],
            &["canif", "certify", "--side", "plc"],
            &["canif", "run", "plc", "--profile", "fc510x"],
        ] {
            assert_eq!(rewrite(args), (args.join(" "), 0));
        }
        // A value it does not know is left for clap to refuse.
        assert_eq!(
            rewrite(&["canif", "run", "--side", "gateway"]),
            ("canif run --side gateway".into(), 0)
        );
    }
}
