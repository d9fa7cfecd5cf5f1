//! `canif`: the conformance suite's command line. Parsing is `cli`, each
//! command is a module of `commands`; this file only dispatches.

#![forbid(unsafe_code)]

/// A line into a command's output buffer (written to stdout at the end, so a
/// reader that stops early — `canif spec list | head` — ends nothing badly).
macro_rules! outln {
    ($out:expr) => {{
        $out.push('\n');
    }};
    ($out:expr, $($arg:tt)*) => {{
        use std::fmt::Write as _;
        let _ = writeln!($out, $($arg)*);
    }};
}

/// `println!`, except that a reader that has gone (a closed pipe: `canif
/// run | head`) is no panic: the run goes on and still writes its reports.
macro_rules! sayln {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stdout().lock(), $($arg)*);
    }};
}

/// `eprintln!`, with a closed stderr ignored (`canif run 2>&1 | head`).
macro_rules! errln {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stderr().lock(), $($arg)*);
    }};
}

/// `eprint!`, with a closed stderr ignored as by [`errln!`].
macro_rules! err {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = write!(std::io::stderr().lock(), $($arg)*);
    }};
}

mod cli;
mod commands;
mod stop;

use std::io::Write as _;
use std::process::ExitCode;

use canif_spec::Catalogue;

use cli::{Cli, Command, ListCommand};
use commands::run;
use commands::{certify, device, merge, plc_types, spec, tools};
use stop::Stop;

fn main() -> ExitCode {
    let cli = Cli::from_env();
    // SIGINT, SIGTERM: the run stops at the next cycle and still writes its
    // reports; a second signal ends canif at once.
    let _ = ctrlc::set_handler(|| {
        if canif_harness::interrupt::requested() {
            std::process::exit(130);
        }
        canif_harness::interrupt::request();
    });
    let mut out = String::new();
    // The one error exit: every command's `Stop` is said here, once.
    let code = match run(cli, &mut out) {
        Ok(code) => code,
        Err(stop) => {
            stop.say();
            ExitCode::from(2)
        }
    };
    // A reader that has gone (a closed pipe) is not an error of canif's.
    let _ = std::io::stdout().lock().write_all(out.as_bytes());
    code
}

/// Loads the catalogue and runs the command: its exit status, or why it stopped.
fn run(cli: Cli, out: &mut String) -> Result<ExitCode, Stop> {
    let catalogue = match &cli.spec {
        Some(dir) => Catalogue::load_dir(dir)?,
        None => Catalogue::embedded()?,
    };
    match cli.command {
        Command::Run(args) => run::command(&catalogue, args),
        Command::List {
            what: ListCommand::Scenarios { profile, side },
        } => match side {
            canif_spec::Side::Device => run::list_scenarios(
                &catalogue,
                &profile,
                canif_harness::device::Options::default(),
                out,
            ),
            canif_spec::Side::Plc => run::list_scenarios(
                &catalogue,
                &profile,
                canif_harness::client::suite::ClientOptions::new(1),
                out,
            ),
        },
        Command::SelfCheck { seed } => run::self_check(&catalogue, seed),
        Command::Probe { iut, profile, out } => {
            let profiles = run::profiles(&catalogue, &profile)?;
            let given = commands::declared(&iut.declare)?;
            tools::probe(&commands::resolve_iut(&iut)?, &profiles, (given, &out))
        }
        Command::Compare {
            base,
            new,
            allow_removed,
            force,
            format,
        } => certify::compare(
            &base,
            &new,
            canif_harness::compare::CompareOptions {
                allow_removed,
                force,
            },
            format,
            out,
        ),
        Command::Coupler {
            socketcand,
            bus,
            node,
            fault,
        } => device::coupler(socketcand, bus.as_deref(), node, fault.as_deref()),
        Command::Certify {
            profile,
            iut,
            product,
            seed,
            out: dir,
            key,
            verify,
            pubkey,
            side,
        } => match (verify, pubkey) {
            (Some(path), Some(pubkey)) => certify::verify_certificate(&path, &pubkey),
            _ => certify::certify(
                &catalogue,
                certify::CertifyRun {
                    profile_names: &profile,
                    iut: &iut,
                    side,
                    product: product.product(),
                    seed,
                },
                &dir,
                key.as_deref(),
            ),
        },
        Command::Device {
            ethercat: Some(interface),
            fault,
            choice,
            profile,
            bus,
            ..
        } => device::ethercat_terminal(
            &catalogue,
            (&interface, bus.as_deref()),
            &profile,
            (&fault, &choice),
        ),
        Command::Device {
            stdio,
            fault,
            choice,
            declare,
            protocol,
            bus,
            ..
        } => device::device(stdio, (&fault, &choice, &declare), protocol, bus.as_deref()),
        Command::LibHost {
            role,
            path,
            control,
        } => device::lib_host(role, &path, control),
        Command::Merge {
            shards,
            report,
            certificate,
            key,
        } => merge::merge(
            &catalogue,
            merge::MergeArgs {
                shards: &shards,
                report: &report,
                certificate: certificate.as_deref(),
                key: key.as_deref(),
            },
        ),
        Command::Faults => Ok(tools::faults(out)),
        Command::Spec { command } => spec::spec(&catalogue, command, out),
        Command::Profiles => spec::profiles(&catalogue, out),
        Command::Export(args) => plc_types::export(&catalogue, &args, out),
        Command::CheckLayout(args) => plc_types::check_layout(&catalogue, &args, out),
        Command::Esi { profile } => tools::esi(&catalogue, &profile, out),
        Command::Size {
            bitrate,
            cycle_us,
            payload,
        } => tools::size(bitrate, cycle_us, payload, out),
        Command::FrameTime {
            bitrate,
            data_bitrate,
            payload,
            extended,
            fd,
        } => tools::frame_time(bitrate, data_bitrate, payload, extended, fd, out),
    }
}
