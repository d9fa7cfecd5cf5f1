//! The commands, one module each; `main.rs` only parses and dispatches.

pub(crate) mod certify;
pub(crate) mod device;
pub(crate) mod run;
pub(crate) mod spec;
pub(crate) mod tools;

use std::process::ExitCode;

use canif_harness::client::faulty::{ClientFault, ClientShape};
use canif_harness::client::suite::ClientKind;
use canif_harness::device::IutKind;
use canif_softdevice::{Choice, Fault};

use crate::cli::{IutArg, IutOptions};

/// The soft-device faults named on the command line, or the exit code of a usage error.
pub(crate) fn soft_device_faults(names: &[String]) -> Result<Vec<Fault>, ExitCode> {
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

/// The soft-device choices named on the command line, or the exit code of a usage error.
fn soft_device_choices(names: &[String]) -> Result<Vec<Choice>, ExitCode> {
    names
        .iter()
        .map(|name| {
            Choice::from_name(name).ok_or_else(|| {
                eprintln!("unknown choice `{name}`; `canif faults` lists them");
                ExitCode::from(2)
            })
        })
        .collect()
}

/// The IUT named on the command line, or the exit code of a usage error.
pub(crate) fn resolve_iut(iut: &IutOptions) -> Result<IutKind, ExitCode> {
    let choices = soft_device_choices(&iut.choice)?;
    let arg = iut.iut.clone().unwrap_or(IutArg::SoftDevice);
    if !choices.is_empty() && !matches!(arg, IutArg::SoftDevice | IutArg::Ethercat(_)) {
        eprintln!("--choice applies to the soft device only");
        return Err(ExitCode::from(2));
    }
    let chosen = soft_device_faults(&iut.fault)?;
    let only_soft = |chosen: &[Fault]| {
        if chosen.is_empty() {
            Ok(())
        } else {
            eprintln!("--fault applies to the soft device only (pass it to the IUT's own command)");
            Err(ExitCode::from(2))
        }
    };
    Ok(match &arg {
        IutArg::Exec(command) => {
            only_soft(&chosen)?;
            IutKind::Exec {
                command: command.clone(),
                timeout_ms: iut.timeout_ms,
                same_cpu: !iut.iut_cpu_free,
            }
        }
        IutArg::Lib(path) => {
            only_soft(&chosen)?;
            IutKind::Lib {
                path: path.clone(),
                host: lib_host(iut),
            }
        }
        IutArg::SoftDevice => IutKind::SoftDevice {
            faults: chosen,
            choices,
        },
        IutArg::Ethercat(link) => {
            let mut link = link.clone();
            match link.emulated_mut() {
                Some(emulated) => {
                    emulated.faults = chosen;
                    emulated.choices = choices;
                }
                None => only_soft(&chosen)?,
            }
            IutKind::Ethercat {
                identity: None,
                link,
            }
        }
        IutArg::Model => {
            only_soft(&chosen)?;
            IutKind::Model
        }
        IutArg::Reference | IutArg::SoftClient => {
            eprintln!("--iut reference and softclient are PLC-side clients: add --side plc");
            return Err(ExitCode::from(2));
        }
    })
}

/// The values `names` name, or the exit code of a usage error naming the
/// first that names none.
fn named<T>(
    names: &[String],
    from_name: fn(&str) -> Option<T>,
    what: &str,
) -> Result<Vec<T>, ExitCode> {
    names
        .iter()
        .map(|name| {
            from_name(name).ok_or_else(|| {
                eprintln!("unknown {what} `{name}`; `canif faults` lists them");
                ExitCode::from(2)
            })
        })
        .collect()
}

/// The client named on the command line for `--side plc`, or the exit code
/// of a usage error. A fault without `--iut` picks the soft client.
pub(crate) fn resolve_client(iut: &IutOptions) -> Result<ClientKind, ExitCode> {
    let faults = named(&iut.fault, ClientFault::from_name, "client fault")?;
    if faults.len() > 1 {
        eprintln!("--side plc: one --fault at a time (the soft client has one defect)");
        return Err(ExitCode::from(2));
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
            eprintln!("--side plc: --choice takes the soft client (--iut softclient), one at a time, without --fault");
            return Err(ExitCode::from(2));
        }
    }
    match (&iut.iut, faults.first()) {
        (None | Some(IutArg::SoftClient), fault) if fault.is_some() || iut.iut.is_some() => {
            Ok(ClientKind::Faulty(fault.copied()))
        }
        (None | Some(IutArg::Reference), None) => Ok(ClientKind::Reference),
        (Some(IutArg::Reference), Some(_)) => {
            eprintln!("--fault applies to the soft client (--iut softclient), not the reference");
            Err(ExitCode::from(2))
        }
        (Some(IutArg::Exec(command)), None) => Ok(ClientKind::Exec {
            command: command.clone(),
            timeout_ms: iut.timeout_ms,
        }),
        (Some(IutArg::Lib(path)), None) => Ok(ClientKind::Lib {
            path: path.clone(),
            host: lib_host(iut),
        }),
        (Some(IutArg::Exec(_) | IutArg::Lib(_)), Some(_)) => {
            eprintln!("--fault applies to the soft client (pass it to the client's own command)");
            Err(ExitCode::from(2))
        }
        (Some(other), _) => {
            eprintln!(
                "--side plc runs a client: --iut reference, softclient, exec:'COMMAND' or lib:PATH, not {other:?}"
            );
            Err(ExitCode::from(2))
        }
        (None, Some(_)) => unreachable!("a fault without --iut is the soft client"),
    }
}

/// What `--declare` says of a client (NAME=VALUE lines, or @FILE of such
/// lines, docs/plc-side.md), or the exit code of a usage error naming the
/// line that cannot be taken.
pub(crate) fn client_declaration(
    declare: &[String],
) -> Result<canif_harness::client::ClientDeclaration, ExitCode> {
    let mut declared = canif_harness::client::ClientDeclaration::default();
    for argument in declare {
        let (lines, origin) = match argument.strip_prefix('@') {
            Some(path) => match std::fs::read_to_string(path) {
                Ok(text) => (text.lines().map(String::from).collect(), path.to_string()),
                Err(error) => {
                    eprintln!("--declare @{path}: {error}");
                    return Err(ExitCode::from(2));
                }
            },
            None => (vec![argument.clone()], String::new()),
        };
        for (n, line) in lines.iter().enumerate() {
            if let Err(error) = declared.declare(line) {
                match origin.is_empty() {
                    true => eprintln!("--declare {line}: {error}"),
                    false => eprintln!("--declare @{origin}, line {}: {error}", n + 1),
                }
                return Err(ExitCode::from(2));
            }
        }
    }
    Ok(declared)
}

/// The choices `--declare` names (NAME=VALUE, or @FILE as `canif probe`
/// writes it: a JSON object of NAME: VALUE), or the exit code of a usage error.
pub(crate) fn declared_choices(
    declare: &[String],
) -> Result<canif_harness::device::choices::Declared, ExitCode> {
    let mut declared = canif_harness::device::choices::Declared::default();
    for text in declare {
        let lines: Vec<String> = match text.strip_prefix('@') {
            None => vec![text.clone()],
            Some(path) => {
                let read = std::fs::read_to_string(path)
                    .map_err(|e| e.to_string())
                    .and_then(|json| {
                        serde_json::from_str::<std::collections::BTreeMap<String, String>>(&json)
                            .map_err(|e| {
                                format!("not a JSON object of choice names and values: {e}")
                            })
                    });
                match read {
                    Ok(choices) => choices.iter().map(|(n, v)| format!("{n}={v}")).collect(),
                    Err(error) => {
                        eprintln!("--declare @{path}: {error}");
                        return Err(ExitCode::from(2));
                    }
                }
            }
        };
        for line in lines {
            if let Err(error) = declared.declare(&line) {
                eprintln!("--declare {text}: {error}");
                return Err(ExitCode::from(2));
            }
        }
    }
    Ok(declared)
}

/// Where a lib:PATH IUT runs: a `canif lib-host` of this executable, unless
/// `--lib-in-process` (or this executable cannot be found: then in process,
/// said on stderr).
fn lib_host(iut: &crate::cli::IutOptions) -> Option<canif_harness::device::iut_kind::LibHost> {
    if iut.lib_in_process {
        return None;
    }
    match std::env::current_exe() {
        Ok(canif) => Some(canif_harness::device::iut_kind::LibHost {
            canif,
            timeout_ms: iut.timeout_ms,
        }),
        Err(error) => {
            eprintln!("canif: cannot find its own executable ({error}); the library runs in canif's process");
            None
        }
    }
}
