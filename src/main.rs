//! `canif`: the conformance suite's command line. Parsing is `cli`, each
//! command is a module of `commands`; this file only dispatches.

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

mod cli;
mod commands;

use std::io::Write as _;
use std::process::ExitCode;

use canif_softdevice::Fault;
use canif_spec::Catalogue;
use clap::Parser;

use cli::{Cli, Command, Suite};
use commands::{certify, device, run, spec, tools};

fn main() -> ExitCode {
    let cli = Cli::parse();
    // SIGINT, SIGTERM: the run stops at the next cycle and still writes its
    // reports; a second signal ends canif at once.
    let _ = ctrlc::set_handler(|| {
        if canif_harness::interrupt::requested() {
            std::process::exit(130);
        }
        canif_harness::interrupt::request();
    });
    let mut out = String::new();
    let code = match run(cli, &mut out) {
        Ok(code) => code,
        Err(error) => {
            eprint!("{error}");
            ExitCode::from(2)
        }
    };
    // A reader that has gone (a closed pipe) is not an error of canif's.
    let _ = std::io::stdout().lock().write_all(out.as_bytes());
    code
}

/// Loads the catalogue and runs the command; `Err` is a catalogue that does not load.
fn run(cli: Cli, out: &mut String) -> Result<ExitCode, canif_spec::SpecErrors> {
    let catalogue = match &cli.spec {
        Some(dir) => Catalogue::load_dir(dir)?,
        None => Catalogue::embedded()?,
    };
    Ok(match cli.command {
        Command::Run {
            iut,
            profile,
            seed,
            cases,
            duration,
            no_counter_wrap,
            report,
            trace,
            suite,
            bus,
            real_time,
            no_fail_fast,
            scenario,
            node,
            coupler_fault,
        } => {
            let bus = run::bus_choice(&bus, &real_time);
            if suite == Suite::Canopen {
                return Ok(device::canopen_suite(&bus, node, coupler_fault.as_deref()));
            }
            let options = canif_harness::Options {
                seed,
                cases: if duration.is_some() { 1 } else { cases },
                generated_cycles: duration.map_or(200, |s| (s * 1000.0).max(1.0) as u64),
                counter_wrap: !no_counter_wrap && bus.is_sim(),
                trace_dir: trace,
                bus,
                only: scenario,
                fail_fast: !no_fail_fast,
            };
            run::run(&catalogue, &iut, &profile, &options, &report)
        }
        Command::SelfCheck { seed } => run::self_check(&catalogue, seed),
        Command::Compare { base, new } => certify::compare(&base, &new),
        Command::Coupler {
            socketcand,
            bus,
            node,
            fault,
        } => device::coupler(socketcand, bus.as_deref(), node, fault.as_deref()),
        Command::Certify {
            profile,
            iut,
            seed,
            out: dir,
            verify,
        } => match verify {
            Some(path) => certify::verify_certificate(&path),
            None => certify::certify(
                &catalogue,
                profile.as_deref().unwrap_or_default(),
                &iut,
                seed,
                &dir,
            ),
        },
        Command::Device {
            stdio,
            fault,
            protocol,
            bus,
        } => device::device(stdio, &fault, protocol, bus.as_deref()),
        Command::Faults => {
            for fault in Fault::ALL {
                outln!(out, "{:<36} {}", fault.name(), fault.description());
            }
            ExitCode::SUCCESS
        }
        Command::Spec { command } => spec::spec(&catalogue, command, out),
        Command::Profiles => spec::profiles(&catalogue, out),
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
    })
}
