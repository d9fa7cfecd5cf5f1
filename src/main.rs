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

use std::io::Write as _;
use std::process::ExitCode;

use canif_softdevice::Fault;
use canif_spec::Catalogue;
use clap::Parser;

use cli::{Cli, Command, ListCommand, SideArg, Suite};
use commands::run::{self, plc};
use commands::{certify, device, spec, tools};

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
            err!("{error}");
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
            product,
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
            requirement,
            trace_epoch,
            node,
            coupler_fault,
            side,
            master,
        } => {
            let bus = run::device::bus_choice(&bus, &real_time);
            let pace = run::device::pace(&real_time);
            let selection = canif_harness::run::Selection {
                scenarios: scenario,
                requirements: requirement,
            };
            let device_only = [
                (suite == Suite::Canopen, "--suite canopen"),
                (cases.is_some(), "--cases"),
                (duration.is_some(), "--duration"),
                (trace.is_some(), "--trace"),
                (no_fail_fast, "--no-fail-fast"),
                (real_time.ethercat_soak_s > 0, "--ethercat-soak-s"),
            ];
            let plc_only = [(!master.is_empty(), "--master")];
            if let Err(conflict) = cli::side_conflicts(side, &device_only, &plc_only) {
                let _ = conflict.print();
                return Ok(ExitCode::from(2));
            }
            if suite == Suite::Canopen {
                let canopen = device::CanopenRun {
                    bus: &bus,
                    node,
                    fault: coupler_fault.as_deref(),
                    seed,
                    product: product.product(),
                };
                return Ok(device::canopen_suite(
                    &catalogue, &iut, &selection, &canopen, &report,
                ));
            }
            let profiles = match run::profiles(&catalogue, &profile) {
                Ok(p) => p,
                Err(code) => return Ok(code),
            };
            if side == SideArg::Plc {
                let client_bus = match plc::client_bus(&bus) {
                    Ok(client_bus) => client_bus,
                    Err(code) => return Ok(code),
                };
                let kind = match commands::resolve_client(&iut) {
                    Ok(kind) => kind,
                    Err(code) => return Ok(code),
                };
                let masters = match plc::masters(&master) {
                    Ok(masters) => masters,
                    Err(code) => return Ok(code),
                };
                let declared = match commands::client_declaration(&iut.declare) {
                    Ok(declared) => declared,
                    Err(code) => return Ok(code),
                };
                let options = canif_harness::client::suite::ClientOptions {
                    seed,
                    bus: client_bus,
                    counter_wrap: !no_counter_wrap,
                    masters,
                    selection,
                    declared: Ok(declared),
                };
                // What the client declares of itself, asked once.
                let options = options.declared_by(&kind);
                return Ok(match run::Plan::new(profiles, options, product.product()) {
                    Ok(plan) => plc::run(&catalogue, &kind, &plan, &report),
                    Err(code) => code,
                });
            }
            if let Some(dir) = &trace {
                // A trace folder that cannot be written is said before the
                // run, not found missing after it.
                let writable = std::fs::create_dir_all(dir).and_then(|()| {
                    let probe = dir.join(".canif-trace-probe");
                    std::fs::write(&probe, b"").and_then(|()| std::fs::remove_file(probe))
                });
                if let Err(error) = writable {
                    errln!("--trace {}: cannot write there: {error}", dir.display());
                    return Ok(ExitCode::from(2));
                }
            }
            let declared = match commands::declared_choices(&iut.declare) {
                Ok(declared) => declared,
                Err(code) => return Ok(code),
            };
            let started = std::time::SystemTime::now()
                .duration_since(std::time::UNIX_EPOCH)
                .unwrap_or_default();
            let options = canif_harness::device::Options {
                seed,
                cases: if duration.is_some() {
                    1
                } else {
                    cases.unwrap_or(4)
                },
                generated_cycles: duration.map_or(200, |s| (s * 1000.0).max(1.0) as u64),
                counter_wrap: !no_counter_wrap && bus.is_sim(),
                trace_dir: trace,
                trace_epoch: trace_epoch.map_or(started.as_nanos() as u64, |s| {
                    s.saturating_mul(1_000_000_000)
                }),
                bus,
                selection,
                fail_fast: !no_fail_fast,
                declared,
                observed: Default::default(),
                iut_declared: Default::default(),
            };
            match run::Plan::new(profiles, options, product.product()) {
                Ok(plan) => run::device::run(&catalogue, &iut, &plan, pace, &report),
                Err(code) => code,
            }
        }
        Command::List {
            what: ListCommand::Scenarios { profile, side },
        } => match side {
            SideArg::Device => run::list_scenarios(
                &catalogue,
                &profile,
                canif_harness::device::Options::default(),
                out,
            ),
            SideArg::Plc => run::list_scenarios(
                &catalogue,
                &profile,
                canif_harness::client::suite::ClientOptions::new(1),
                out,
            ),
        },
        Command::SelfCheck { seed } => run::self_check(&catalogue, seed),
        Command::Probe { iut, profile, out } => {
            let profiles = match run::profiles(&catalogue, &profile) {
                Ok(profiles) => profiles,
                Err(code) => return Ok(code),
            };
            match commands::resolve_iut(&iut) {
                Ok(kind) => tools::probe(&kind, &profiles, &out),
                Err(code) => code,
            }
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
        Command::Faults => {
            for fault in Fault::ALL {
                outln!(out, "{:<36} {}", fault.name(), fault.description());
            }
            outln!(
                out,
                "\nchoices the documents leave (--choice; the device still conforms):"
            );
            for choice in canif_softdevice::Choice::ALL {
                outln!(out, "{:<36} {}", choice.name(), choice.description());
            }
            outln!(
                out,
                "\nclient faults (--side plc --fault; the soft client):"
            );
            for fault in canif_harness::client::faulty::ClientFault::ALL {
                outln!(out, "{:<36} {}", fault.name(), fault.description());
            }
            outln!(
                out,
                "\nclient ways of working (--side plc --choice; the soft client takes one and declares it):"
            );
            for shape in canif_harness::client::faulty::ClientShape::ALL {
                outln!(out, "{:<36} declares {}", shape.name(), shape.declares());
            }
            outln!(out, "\nmaster models (--side plc --master):");
            for master in canif_harness::client::master::Master::ALL {
                outln!(out, "{:<36} {}", master.name, master.description());
            }
            ExitCode::SUCCESS
        }
        Command::Spec { command } => spec::spec(&catalogue, command, out),
        Command::Profiles => spec::profiles(&catalogue, out),
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
    })
}
