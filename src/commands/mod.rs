//! The commands, one module each; `main.rs` only parses and dispatches.

pub mod certify;
pub mod device;
pub mod run;
pub mod spec;
pub mod tools;

use std::process::ExitCode;

use canif_harness::IutKind;
use canif_softdevice::{Choice, Fault};

use crate::cli::{IutArg, IutOptions};

/// The soft-device faults named on the command line, or the exit code of a usage error.
pub fn soft_device_faults(names: &[String]) -> Result<Vec<Fault>, ExitCode> {
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
pub fn resolve_iut(iut: &IutOptions) -> Result<IutKind, ExitCode> {
    let choices = soft_device_choices(&iut.choice)?;
    if !choices.is_empty() && !matches!(iut.iut, IutArg::SoftDevice) {
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
    Ok(match &iut.iut {
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
            IutKind::Lib { path: path.clone() }
        }
        IutArg::SoftDevice => IutKind::SoftDevice {
            faults: chosen,
            choices,
        },
        IutArg::Model => {
            only_soft(&chosen)?;
            IutKind::Model
        }
    })
}
