//! The commands, one module each; `main.rs` only parses and dispatches.

pub(crate) mod certify;
pub(crate) mod device;
pub(crate) mod merge;
pub(crate) mod plan;
pub(crate) mod plc_types;
pub(crate) mod run;
pub(crate) mod spec;
pub(crate) mod tools;

use crate::stop::{stop, Stop};

use canif_harness::client::soft_client::{ClientFault, ClientShape};
use canif_harness::client::suite::ClientKind;
use canif_harness::declare::Declaration;
use canif_harness::device::IutKind;
use canif_harness::door::{Role, Settings};
use canif_softdevice::{Fault, Freedom};

use crate::cli::{IutArg, IutOptions};

/// ` (did you mean `NAME`?)` with the known name nearest `name`, where a
/// typo is likely; nothing otherwise.
pub(crate) fn did_you_mean<'a>(name: &str, known: impl IntoIterator<Item = &'a str>) -> String {
    canif_runner::nearest(name, known).map_or(String::new(), |k| format!(" (did you mean `{k}`?)"))
}

/// The soft-device faults named on the command line, or the exit code of a usage error.
pub(crate) fn soft_device_faults(names: &[String]) -> Result<Vec<Fault>, Stop> {
    names
        .iter()
        .map(|name| {
            Fault::from_name(name).ok_or_else(|| {
                let near = did_you_mean(name, Fault::ALL.iter().map(|f| f.name()));
                stop!("unknown fault `{name}`{near}; `canif faults` lists them")
            })
        })
        .collect()
}

/// The soft-device choices named on the command line, or the exit code of a usage error.
fn soft_device_choices(names: &[String]) -> Result<Vec<Freedom>, Stop> {
    names
        .iter()
        .map(|name| {
            Freedom::from_name(name).ok_or_else(|| {
                let near = did_you_mean(name, Freedom::ALL.iter().map(|c| c.name()));
                stop!("unknown choice `{name}`{near}; `canif faults` lists them")
            })
        })
        .collect()
}

/// The IUT named on the command line, started once to see that it can
/// start (what `canif probe` runs; a plan's run starts it in its preflight),
/// or the exit code of a usage error.
pub(crate) fn resolve_iut(iut: &IutOptions) -> Result<IutKind, Stop> {
    let kind = iut_kind(iut)?;
    if let IutKind::Door(door) = &kind {
        door.starts(Role::Device)
            .map_err(|error| Stop::from(canif_runner::PlanError::not_started(error)))?;
    }
    Ok(kind)
}

/// The device `--iut` names.
pub(crate) fn iut_kind(iut: &IutOptions) -> Result<IutKind, Stop> {
    let choices = soft_device_choices(&iut.choice)?;
    let faults = soft_device_faults(&iut.fault)?;
    let settings = settings(iut, faults, choices);
    Ok(match iut.iut.clone().unwrap_or(IutArg::SoftDevice) {
        IutArg::SoftDevice => IutKind::SoftDevice {
            faults: settings.faults,
            choices: settings.choices,
        },
        IutArg::Model => {
            settings.no_soft_device().map_err(|why| stop!("{why}"))?;
            IutKind::Model
        }
        IutArg::Door(door) => IutKind::Door(door.settled(&settings).map_err(|why| stop!("{why}"))?),
        IutArg::Reference | IutArg::SoftClient => {
            return Err(stop!(
                "--iut reference and softclient are PLC-side clients: use `canif run plc`"
            ));
        }
    })
}

/// How the command line asks a door's implementation to be run.
fn settings(iut: &IutOptions, faults: Vec<Fault>, choices: Vec<Freedom>) -> Settings {
    Settings {
        timeouts: iut.timeouts(),
        same_cpu: !iut.iut_cpu_free,
        host: lib_host(iut),
        faults,
        choices,
    }
}

/// The values `names` name, or the exit code of a usage error naming the
/// first that names none.
fn named<T>(
    names: &[String],
    from_name: fn(&str) -> Option<T>,
    what: &str,
) -> Result<Vec<T>, Stop> {
    names
        .iter()
        .map(|name| {
            from_name(name)
                .ok_or_else(|| stop!("unknown {what} `{name}`; `canif faults` lists them"))
        })
        .collect()
}

/// The client `--iut` names for `canif run plc`. A fault without `--iut` picks
/// the soft client.
pub(crate) fn client_kind(iut: &IutOptions) -> Result<ClientKind, Stop> {
    let faults = named(&iut.fault, ClientFault::from_name, "client fault")?;
    if faults.len() > 1 {
        return Err(stop!(
            "the PLC side: one --fault at a time (the soft client has one defect)"
        ));
    }
    let shapes = named(&iut.choice, ClientShape::from_name, "soft-client choice")?;
    match (shapes.as_slice(), faults.first(), &iut.iut) {
        ([], _, _) => {}
        ([shape], None, None | Some(IutArg::SoftClient)) => {
            return Ok(ClientKind::Shaped {
                shape: *shape,
                declared: true,
            })
        }
        _ => {
            return Err(stop!("the PLC side: --choice takes the soft client (--iut softclient), one at a time, without --fault"));
        }
    }
    match (&iut.iut, faults.first()) {
        (None | Some(IutArg::SoftClient), fault) if fault.is_some() || iut.iut.is_some() => {
            Ok(ClientKind::Faulty(fault.copied()))
        }
        (None | Some(IutArg::Reference), None) => Ok(ClientKind::Reference),
        (Some(IutArg::Reference), Some(_)) => {
            Err(stop!("--fault applies to the soft client (--iut softclient), not the reference"))
        }
        (Some(IutArg::Door(door)), None) => {
            let settings = settings(iut, Vec::new(), Vec::new());
            let door = door.clone().settled(&settings).map_err(|why| stop!("{why}"))?;
            match door.transport().serves_clients() {
                true => Ok(ClientKind::Door(door)),
                false => Err(stop!(
                    "the PLC side runs a client: --iut reference, softclient, exec:'COMMAND' or lib:PATH, not {}",
                    door.name()
                )),
            }
        }
        (Some(IutArg::Door(_)), Some(_)) => {
            Err(stop!("--fault applies to the soft client (pass it to the client's own command)"))
        }
        (Some(other), _) => {
            Err(stop!(
                "the PLC side runs a client: --iut reference, softclient, exec:'COMMAND' or lib:PATH, not {other:?}"
            ))
        }
        (None, Some(_)) => unreachable!("a fault without --iut is the soft client"),
    }
}

/// What `--declare` says, read as either side's [`Declaration`] reads it
/// (docs/choices.md, docs/plc-side.md), or the exit code of a usage error
/// naming the argument, file and line that cannot be taken.
pub(crate) fn declared<D: Declaration>(declare: &[String]) -> Result<D, Stop> {
    D::read(declare).map_err(|error| stop!("{error}"))
}

/// Where a lib:PATH IUT runs: a `canif lib-host` of this executable, unless
/// `--lib-in-process` (or this executable cannot be found: then in process,
/// said on stderr).
fn lib_host(iut: &crate::cli::IutOptions) -> Option<std::path::PathBuf> {
    if iut.lib_in_process {
        return None;
    }
    match std::env::current_exe() {
        Ok(canif) => Some(canif),
        Err(error) => {
            errln!("canif: cannot find its own executable ({error}); the library runs in canif's process");
            None
        }
    }
}
