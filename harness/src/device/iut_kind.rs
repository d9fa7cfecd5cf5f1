//! Which device a run puts under test, and how it is built for each
//! configuration: in process (the model, the soft device) or behind a door.

use canif_model::config::{Capabilities, InterfaceConfig, TxQueueAccounting};
use canif_model::device::Device;
use canif_softdevice::{Fault, Freedom, SoftDevice};

use crate::declare::choices::Declared;
use crate::door::adapter::protocol::OwnedBus;
use crate::door::iut::{soft_settings, BuildError, Iut, ModelIut, SoftDeviceIut};
use crate::door::{Configurer, Door};
use canif_model::freedoms::{BadTxLength, OversizeBatch, RxIdleCount, StaleRxSlots};

/// Which implementation to run: one of canif's own in its process, or one
/// behind a [`Door`].
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum IutKind {
    SoftDevice {
        faults: Vec<Fault>,
        /// Freedoms the documents leave: the device still conforms.
        choices: Vec<Freedom>,
    },
    Model,
    Door(Door),
}

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
            IutKind::SoftDevice { faults, choices } => {
                let mut device = SoftDevice::with_faults(soft_settings(caps, config), faults)
                    .map_err(|e| refused(&e))?;
                for choice in choices {
                    device.choose(*choice);
                }
                Ok(Box::new(SoftDeviceIut(device)))
            }
            IutKind::Door(door) => door.device(caps, config, bus),
        }
    }

    /// Something that answers configuration after configuration; for an
    /// external process, one process answers them all.
    pub fn configurer(&self) -> Configurer {
        match self {
            IutKind::Door(door) => door.configurer(),
            other => {
                let kind = other.clone();
                Box::new(move |caps, config| kind.build(caps, config).map(|_| ()))
            }
        }
    }

    /// Whether the IUT's CAN controller is out of the harness's reach: it opens
    /// its own socket, or it is a terminal on a real bus.
    pub fn owns_its_bus(&self) -> bool {
        matches!(self, IutKind::Door(door) if door.owns_its_bus())
    }

    /// Where `told` (the command line's `--declare`) contradicts what this
    /// IUT declares itself: the same words as for an IUT that declares it in
    /// its `configured` answer, so that every route says it alike. A device
    /// that declares nothing contradicts nothing here (its own answer is
    /// checked when it gives it).
    pub fn contradicts(&self, told: &Declared) -> Option<String> {
        let (choice, said, declares) = told.contradiction(&self.declared())?;
        Some(format!(
            "{} declares `{choice}={declares}` itself, where canif was told `{choice}={said}` (--declare): one of them is wrong",
            self.name()
        ))
    }

    /// What this IUT declares where the documents leave a choice. The soft
    /// device and the model know their own (the soft device's `--choice`); a
    /// device elsewhere declares on the command line, or not at all.
    pub fn declared(&self) -> Declared {
        let soft = |choices: &[Freedom]| {
            let chose = |choice| choices.contains(&choice);
            Declared {
                tx_queue_accounting: Some(if chose(Freedom::CountsFrameOnWire) {
                    TxQueueAccounting::WireInQueue
                } else {
                    TxQueueAccounting::WireOutsideQueue
                }),
                // It starts at SYNC1 (`sync1-jitter`: within the 500 ns after).
                sync1_output_delay: Some(0),
                sync1_jitter: None,
                // Its send queue is the profile's (it is built from the same).
                tx_queue_depth: None,
                oversize_batch: Some(if chose(Freedom::RefusesOversizeBatch) {
                    OversizeBatch::DropsTheBatch
                } else {
                    OversizeBatch::SendsTheSlots
                }),
                bad_tx_length: Some(if chose(Freedom::DropsMessageWithBadLength) {
                    BadTxLength::DropsTheMessage
                } else {
                    BadTxLength::Clamps
                }),
                rx_idle_count: Some(if chose(Freedom::ClearsRxCountWhenIdle) {
                    RxIdleCount::WritesZero
                } else {
                    RxIdleCount::KeepsTheLast
                }),
                stale_rx_slots: Some(if chose(Freedom::KeepsStaleRxSlots) {
                    StaleRxSlots::Kept
                } else {
                    StaleRxSlots::Zeroed
                }),
            }
        };
        match self {
            IutKind::Model => soft(&[]),
            IutKind::SoftDevice { choices, .. } => soft(choices),
            IutKind::Door(door) => match door.transport().soft_device_choices() {
                Some(choices) => soft(choices),
                None => Declared::default(),
            },
        }
    }

    /// This IUT for `profile` (a terminal is checked against the profile's identity).
    pub fn for_profile(&self, profile: &canif_spec::Profile) -> IutKind {
        match self {
            IutKind::Door(door) => IutKind::Door(door.for_profile(profile)),
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
            IutKind::Door(door) => door.name(),
        }
    }
}
