//! Which implementation a run puts under test, and how it is built for each
//! configuration: in process (the model, the soft device) or as another
//! process over the adapter protocol.

use std::time::Duration;

use canif_model::config::{Capabilities, InterfaceConfig, TxQueueAccounting};
use canif_model::device::Device;
use canif_softdevice::{Choice, Fault, SoftDevice};

use crate::adapter::protocol::OwnedBus;
use crate::device::choices::Declared;
use crate::device::ethercat::EthercatLink;
use crate::device::exec_iut::{Configured, ExecIut};
use crate::device::iut::{soft_settings, BuildError, Iut, ModelIut, SoftDeviceIut};
use crate::error::{IutCause, IutError};
use canif_model::freedoms::{BadTxLength, OversizeBatch, RxIdleCount, StaleRxSlots};

/// Which implementation to run.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum IutKind {
    SoftDevice {
        faults: Vec<Fault>,
        /// Freedoms the documents leave: the device still conforms.
        choices: Vec<Choice>,
    },
    Model,
    /// Another process speaking the adapter protocol (docs/adapter-protocol.md).
    Exec {
        command: String,
        timeout_ms: u64,
        /// Run the IUT on the CPU of the harness's thread: the exchange strictly
        /// alternates, and a wake-up across CPUs costs ten times one on the same
        /// CPU on a virtual machine (measured in benches/external_iut.rs).
        same_cpu: bool,
    },
    /// A shared library built against include/canif.h (the C ABI): in
    /// canif's process, or with `host` in a `canif lib-host` of its own,
    /// where a crash or an access past its images ends that process only.
    Lib {
        path: std::path::PathBuf,
        host: Option<LibHost>,
    },
    /// A terminal over EtherCAT: canif's master (ethercrab) and, in memory,
    /// the soft device behind an emulated ESC (`ethercat:emulated`).
    Ethercat {
        /// The identity the profile gives (set per profile by the suite).
        identity: Option<canif_spec::EthercatIdentity>,
        link: crate::device::ethercat::EthercatLink,
    },
}

/// The canif executable that hosts a library (`canif lib-host`), and how
/// long the host may take to answer.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct LibHost {
    pub canif: std::path::PathBuf,
    pub timeout_ms: u64,
}

impl LibHost {
    /// The host of the library at `path` in `role`, as a command for `sh`.
    pub fn command(&self, role: &str, path: &std::path::Path) -> String {
        let quoted =
            |p: &std::path::Path| format!("'{}'", p.display().to_string().replace('\'', "'\\''"));
        format!(
            "exec {} lib-host --role {role} {}",
            quoted(&self.canif),
            quoted(path)
        )
    }
}

/// Asks an IUT, configuration after configuration, whether it accepts.
pub type Configurer = Box<dyn FnMut(&Capabilities, &InterfaceConfig) -> Result<(), BuildError>>;

impl IutKind {
    /// Builds the IUT for a configuration.
    pub fn build(
        &self,
        caps: &Capabilities,
        config: &InterfaceConfig,
    ) -> Result<Box<dyn Iut>, BuildError> {
        self.build_on(caps, config, None)
    }

    /// Builds the IUT; with `bus`, an external IUT is told to open that
    /// interface itself (in-process IUTs are attached by the harness instead).
    pub fn build_on(
        &self,
        caps: &Capabilities,
        config: &InterfaceConfig,
        bus: Option<&OwnedBus>,
    ) -> Result<Box<dyn Iut>, BuildError> {
        let refused = |e: &dyn std::fmt::Display| BuildError::Refused(e.to_string());
        match self {
            // The model as an IUT takes its own choices, whatever canif
            // judges it by (what it declares: `IutKind::declared`).
            IutKind::Model => {
                let own = Capabilities {
                    tx_queue_accounting: TxQueueAccounting::default(),
                    freedoms: Default::default(),
                    ..caps.clone()
                };
                Ok(Box::new(ModelIut(
                    Device::new(&own, config.clone()).map_err(|e| refused(&e))?,
                )))
            }
            IutKind::Lib { path, host: None } => {
                Ok(Box::new(crate::device::lib_iut::build(path, caps, config)?))
            }
            // The harness drives the host's CAN side through the protocol.
            IutKind::Lib { host: Some(_), .. } => {
                self.hosted().expect("a host").build_on(caps, config, None)
            }
            IutKind::SoftDevice { faults, choices } => {
                let mut device =
                    SoftDevice::new(soft_settings(caps, config)).map_err(|e| refused(&e))?;
                for fault in faults {
                    device.inject(*fault);
                }
                for choice in choices {
                    device.choose(*choice);
                }
                Ok(Box::new(SoftDeviceIut(device)))
            }
            IutKind::Ethercat { identity, link } => {
                let identity = identity.as_ref().ok_or_else(|| {
                    BuildError::Failed(IutError::new(
                        IutCause::NotStarted,
                        "this profile is no EtherCAT terminal: it gives no identity to check",
                    ))
                })?;
                Ok(Box::new(crate::device::ethercat::build(
                    caps, config, identity, link,
                )?))
            }
            IutKind::Exec {
                command,
                timeout_ms,
                same_cpu,
            } => {
                let mut iut =
                    ExecIut::spawn(command, Duration::from_millis(*timeout_ms), *same_cpu)
                        .map_err(BuildError::Failed)?;
                match iut
                    .configure(caps, config, bus)
                    .map_err(BuildError::Failed)?
                {
                    Configured::Accepted => Ok(Box::new(iut)),
                    Configured::Refused(reason) => Err(BuildError::Refused(reason)),
                }
            }
        }
    }

    /// Something that answers configuration after configuration; for an
    /// external process, one process answers them all.
    pub fn configurer(&self) -> Configurer {
        if let Some(hosted) = self.hosted() {
            return hosted.configurer();
        }
        match self {
            IutKind::Exec {
                command,
                timeout_ms,
                same_cpu,
            } => {
                let (command, timeout) = (command.clone(), Duration::from_millis(*timeout_ms));
                let same_cpu = *same_cpu;
                let mut process: Option<ExecIut> = None;
                Box::new(move |caps, config| {
                    let iut = match process.as_mut() {
                        Some(iut) => iut,
                        None => process.insert(
                            ExecIut::spawn(&command, timeout, same_cpu)
                                .map_err(BuildError::Failed)?,
                        ),
                    };
                    match iut
                        .configure(caps, config, None)
                        .map_err(BuildError::Failed)?
                    {
                        Configured::Accepted => Ok(()),
                        Configured::Refused(reason) => Err(BuildError::Refused(reason)),
                    }
                })
            }
            other => {
                let kind = other.clone();
                Box::new(move |caps, config| kind.build(caps, config).map(|_| ()))
            }
        }
    }

    /// A hosted library as the process it runs in.
    fn hosted(&self) -> Option<IutKind> {
        let IutKind::Lib {
            path,
            host: Some(host),
        } = self
        else {
            return None;
        };
        Some(IutKind::Exec {
            command: host.command("device", path),
            timeout_ms: host.timeout_ms,
            same_cpu: true,
        })
    }

    /// Whether the IUT's CAN controller is out of the harness's reach: it opens
    /// its own socket, or it is a terminal on a real bus.
    pub fn owns_its_bus(&self) -> bool {
        matches!(
            self,
            IutKind::Exec { .. }
                | IutKind::Ethercat {
                    link: crate::device::ethercat::EthercatLink::Interface { .. },
                    ..
                }
        )
    }

    /// What this IUT declares where the documents leave a choice. The soft
    /// device and the model know their own (the soft device's `--choice`); a
    /// device elsewhere declares on the command line, or not at all.
    pub fn declared(&self) -> Declared {
        let soft = |choices: &[Choice]| {
            let chose = |choice| choices.contains(&choice);
            Declared {
                tx_queue_accounting: Some(if chose(Choice::CountsFrameOnWire) {
                    TxQueueAccounting::WireInQueue
                } else {
                    TxQueueAccounting::WireOutsideQueue
                }),
                // It starts at SYNC1 (`sync1-jitter`: within the 500 ns after).
                sync1_output_delay: Some(0),
                sync1_jitter: None,
                // Its send queue is the profile's (it is built from the same).
                tx_queue_depth: None,
                oversize_batch: Some(if chose(Choice::RefusesOversizeBatch) {
                    OversizeBatch::DropsTheBatch
                } else {
                    OversizeBatch::SendsTheSlots
                }),
                bad_tx_length: Some(if chose(Choice::DropsMessageWithBadLength) {
                    BadTxLength::DropsTheMessage
                } else {
                    BadTxLength::Clamps
                }),
                rx_idle_count: Some(if chose(Choice::ClearsRxCountWhenIdle) {
                    RxIdleCount::WritesZero
                } else {
                    RxIdleCount::KeepsTheLast
                }),
                stale_rx_slots: Some(if chose(Choice::KeepsStaleRxSlots) {
                    StaleRxSlots::Kept
                } else {
                    StaleRxSlots::Zeroed
                }),
            }
        };
        match self {
            IutKind::Model => soft(&[]),
            IutKind::SoftDevice { choices, .. } => soft(choices),
            IutKind::Ethercat {
                link: EthercatLink::Emulated(emulated) | EthercatLink::Veth { emulated, .. },
                ..
            } => soft(&emulated.choices),
            IutKind::Exec { .. }
            | IutKind::Lib { .. }
            | IutKind::Ethercat {
                link: EthercatLink::Interface { .. },
                ..
            } => Declared::default(),
        }
    }

    /// This IUT for `profile`: an EtherCAT terminal is checked against the profile's identity.
    pub fn for_profile(&self, profile: &canif_spec::Profile) -> IutKind {
        match self {
            IutKind::Ethercat { link, .. } => IutKind::Ethercat {
                identity: profile.ethercat,
                link: link.clone(),
            },
            other => other.clone(),
        }
    }

    pub fn name(&self) -> String {
        match self {
            IutKind::Model => "model".into(),
            IutKind::SoftDevice { faults, choices } => std::iter::once("softdevice")
                .chain(faults.iter().map(|f| f.name()))
                .chain(choices.iter().map(|c| c.name()))
                .collect::<Vec<_>>()
                .join("+"),
            IutKind::Exec { command, .. } => format!("exec:{command}"),
            IutKind::Lib { path, .. } => format!("lib:{}", path.display()),
            IutKind::Ethercat { link, .. } => link.name(),
        }
    }
}
