//! `canif device` and `canif coupler`: the soft device and the simulated
//! coupler served to others.

use std::io::Write as _;
use std::process::ExitCode;

use crate::stop::{stop, Stop};

use canif_harness::device::IutKind;
use canif_harness::door::adapter::CONTROL_FDS;
use canif_harness::door::serve::device::{self as server, Build};

use super::{soft_device_choices, soft_device_faults};

/// `canif device --stdio [--bus socketcan:IFACE]`: the soft device behind the
/// adapter protocol.
pub(crate) fn device(
    stdio: bool,
    (faults, choices, declare): (&[String], &[String], &[String]),
    protocol: u64,
    bus: Option<&str>,
) -> Result<ExitCode, Stop> {
    if !stdio {
        return Err(stop!("canif device needs --stdio: its process image is served over the adapter protocol (docs/adapter-protocol.md)"));
    }
    let kind = IutKind::SoftDevice {
        faults: soft_device_faults(faults)?,
        choices: soft_device_choices(choices)?,
    };
    // Checked as `run --declare` checks them, then said as the protocol says them.
    let declared: canif_harness::declare::choices::Declared = crate::commands::declared(declare)?;
    let build: &Build<'_> = &|caps, config| kind.build(caps, config);
    let served = match bus {
        None => server::serve(
            server::Server::new(build, true)
                .at_most(protocol)
                .declaring(declared.entries()),
            std::io::stdin().lock(),
            0,
            std::io::stdout(),
        )
        .map_err(|e| e.to_string()),
        Some(bus) => serve_on_bus(build, bus),
    };
    match served {
        Ok(()) => Ok(ExitCode::SUCCESS),
        Err(error) => Err(stop!("canif device: {error}")),
    }
}

/// `canif device --ethercat IFACE [--bus socketcan:CANIFACE]`: the soft
/// device behind an emulated EtherCAT terminal on a network interface, its
/// CAN side on a SocketCAN interface, until interrupted.
#[cfg(feature = "socketcan")]
pub(crate) fn ethercat_terminal(
    catalogue: &canif_spec::Catalogue,
    (interface, bus): (&str, Option<&str>),
    profile: &str,
    (faults, choices): (&[String], &[String]),
) -> Result<ExitCode, Stop> {
    use canif_harness::door::ethercat::{emulated_terminal, served, Emulated};
    let Some(profile) = catalogue.profile(profile) else {
        let near = super::did_you_mean(profile, catalogue.profiles.iter().map(|p| p.name.as_str()));
        return Err(stop!(
            "unknown profile `{profile}`{near}; `canif profiles` lists them"
        ));
    };
    let Some(identity) = profile.ethercat else {
        return Err(stop!(
            "--profile {}: no EtherCAT terminal (it gives no identity)",
            profile.name
        ));
    };
    let (faults, choices) = (soft_device_faults(faults)?, soft_device_choices(choices)?);
    let emulated = Emulated {
        faults,
        choices,
        ..Emulated::default()
    };
    let can = match bus.map(canif_kernel::BusSpec::parse).transpose() {
        Ok(spec) => spec.map(|spec| spec.iut),
        Err(error) => {
            return Err(stop!("--bus {error}"));
        }
    };
    if let (Some(can), Err(error)) = (&can, canif_kernel::probe()) {
        return Err(stop!("--bus socketcan:{can}: {error}"));
    }
    let mut terminal = emulated_terminal(&profile.model_capabilities(), &identity, &emulated);
    // Said once both interfaces are open: from here a master finds it.
    let ready = || {
        errln!(
            "canif device: {} ({}) on {interface}, vendor {:#010x} product {:#010x} revision {:#010x}, CAN side {}; Ctrl-C stops",
            profile.name,
            profile.device,
            identity.vendor_id,
            identity.product_code,
            identity.revision,
            can.as_deref()
                .map_or("printed here (candump format)".to_string(), |c| format!("on {c}"))
        )
    };
    let stop = canif_harness::interrupt::requested;
    let mut log = std::io::stdout();
    match served::serve(
        interface,
        &mut terminal,
        (can.as_deref(), &mut log),
        (&ready, &stop),
    ) {
        Ok(served) => {
            errln!(
                "canif device: {} EtherCAT frames answered, {} cycles ({} SYNC0 events missed), {} CAN frames sent",
                served.frames, served.cycles, served.missed_sync0, served.can_frames
            );
            Ok(ExitCode::SUCCESS)
        }
        Err(error) => Err(stop!("canif device --ethercat {interface}: {error}")),
    }
}

#[cfg(not(feature = "socketcan"))]
pub(crate) fn ethercat_terminal(
    _: &canif_spec::Catalogue,
    (interface, _): (&str, Option<&str>),
    _: &str,
    _: (&[String], &[String]),
) -> Result<ExitCode, Stop> {
    Err(stop!("--ethercat {interface}: this canif was built without Linux sockets (cargo feature `socketcan`)"))
}

#[cfg(feature = "socketcan")]
fn serve_on_bus(build: &Build<'_>, bus: &str) -> Result<(), String> {
    let spec = canif_kernel::BusSpec::parse(bus).map_err(|e| format!("--bus {e}"))?;
    canif_kernel::probe().map_err(|e| format!("--bus {bus}: {e}"))?;
    canif_harness::door::serve::can_side::serve_on_bus(build, Some(&spec.iut))
        .map_err(|e| e.to_string())
}

#[cfg(not(feature = "socketcan"))]
fn serve_on_bus(_: &Build<'_>, bus: &str) -> Result<(), String> {
    Err(format!(
        "--bus {bus}: this canif was built without SocketCAN (cargo feature `socketcan`)"
    ))
}

/// `canif coupler`: the simulated coupler behind socketcand on loopback TCP,
/// or as a node on a SocketCAN interface.
pub(crate) fn coupler(
    socketcand: Option<u16>,
    bus: Option<&str>,
    node: u8,
    fault: Option<&str>,
) -> Result<ExitCode, Stop> {
    let mut coupler = simulated_coupler(node_id(node)?, coupler_fault(fault)?);
    match (socketcand, bus) {
        (Some(port), _) => {
            let listener = match std::net::TcpListener::bind(("127.0.0.1", port)) {
                Ok(listener) => listener,
                Err(error) => {
                    return Err(stop!("cannot listen on 127.0.0.1:{port}: {error}"));
                }
            };
            // The port goes to stdout first, so a caller that asked for port 0 learns it.
            sayln!(
                "{}",
                listener.local_addr().map(|a| a.port()).unwrap_or(port)
            );
            let _ = std::io::stdout().flush();
            // A socketcand server keeps serving: tools connect and disconnect.
            loop {
                if let Err(error) =
                    canif_harness::canopen::socketcand::serve(&listener, &mut coupler)
                {
                    return Err(stop!("canif coupler --socketcand: {error}"));
                }
            }
        }
        (None, Some(bus)) => coupler_on_bus(bus, &mut coupler),
        (None, None) => unreachable!("clap requires --socketcand or --bus"),
    }
}

#[cfg(feature = "socketcan")]
fn coupler_on_bus(
    bus: &str,
    coupler: &mut canif_model::canopen::coupler::Coupler,
) -> Result<ExitCode, Stop> {
    let opened = canif_kernel::BusSpec::parse(bus)
        .and_then(|spec| canif_kernel::probe().map(|()| spec).map_err(String::from))
        .and_then(|spec| canif_kernel::KernelSocket::open(&spec.iut, false).map_err(String::from));
    let socket = match opened {
        Ok(socket) => socket,
        Err(error) => {
            return Err(stop!("canif coupler --bus {bus}: {error}"));
        }
    };
    sayln!(
        "ready: node {} on {}",
        coupler.node().get(),
        socket.interface
    );
    let _ = std::io::stdout().flush();
    let error = canif_harness::canopen::on_bus::serve(&socket, coupler);
    Err(stop!("{error}"))
}

#[cfg(not(feature = "socketcan"))]
fn coupler_on_bus(
    bus: &str,
    _: &mut canif_model::canopen::coupler::Coupler,
) -> Result<ExitCode, Stop> {
    Err(stop!("canif coupler --bus {bus}: this canif was built without SocketCAN (cargo feature `socketcan`)"))
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
pub(crate) fn node_id(node: u8) -> Result<canif_model::canopen::NodeId, Stop> {
    canif_model::canopen::NodeId::new(node).ok_or_else(|| stop!("node ids are 1..63, not {node}"))
}

/// The coupler fault named on the command line, or the exit code of a usage error.
pub(crate) fn coupler_fault(
    name: Option<&str>,
) -> Result<Option<canif_model::canopen::coupler::CouplerFault>, Stop> {
    use canif_model::canopen::coupler::CouplerFault;
    match name {
        None => Ok(None),
        Some(name) => CouplerFault::from_name(name).map(Some).ok_or_else(|| {
            let known: Vec<&str> = CouplerFault::ALL.iter().map(|f| f.name()).collect();
            stop!("unknown coupler fault `{name}`: {}", known.join(", "))
        }),
    }
}

/// `canif lib-host --role ROLE PATH`: the library in this process, served
/// over the adapter protocol (what `--iut lib:PATH` starts).
pub(crate) fn lib_host(
    role: crate::cli::LibRole,
    path: &std::path::Path,
    control: bool,
) -> Result<ExitCode, Stop> {
    use std::io::{BufRead, Write};
    // With --control the protocol runs on descriptors 3 and 4, and the
    // library's stdout and stderr are its own to print on.
    let (input, output): (Box<dyn BufRead>, Box<dyn Write>) = match control {
        false => (
            Box::new(std::io::stdin().lock()),
            Box::new(std::io::stdout().lock()),
        ),
        true => match canif_harness::door::serve::control_channel() {
            Ok((requests, answers)) => (Box::new(requests), Box::new(answers)),
            Err(error) => {
                return Err(stop!(
                    "canif lib-host --control: descriptors {} and {} are not open: {error}",
                    CONTROL_FDS.0,
                    CONTROL_FDS.1
                ));
            }
        },
    };
    // The requests' descriptor, watched while version 3 runs in shared memory.
    let line_fd = if control { CONTROL_FDS.0 } else { 0 };
    let served = match role {
        crate::cli::LibRole::Device => {
            canif_harness::door::serve::device::serve_library(path, input, line_fd, output)
        }
        crate::cli::LibRole::Client => {
            canif_harness::door::serve::client::serve_library(path, input, line_fd, output)
        }
    };
    match served {
        Ok(()) => Ok(ExitCode::SUCCESS),
        Err(error) => Err(stop!("canif lib-host {}: {error}", path.display())),
    }
}
