//! One harness cycle as the telegrams a real master sends (003, "EtherCAT
//! Update"): an **LRW**, whose inputs are the previous SyncManager 2 event's
//! (the PLC sees a TxCounter confirmed two task cycles later), then a read of
//! the input SyncManager for what this cycle's event produced; or, for
//! **separate input update**, an LWR of the outputs (the event) and an LRD of
//! the inputs it produced (confirmed one task cycle later). The played PLC
//! names the mode (`Iut::exchange_with`).

use canif_ethercat::register::{Fmmu, FMMU_BASE, FMMU_LEN};
use canif_model::exchange::ExchangeMode;
use ethercrab::{Command, Reads};

use super::start_up::master_error;
use super::{EthercatIut, LRW_WORKING_COUNTER, SM3};
use crate::device::blame;
use crate::device::iut::Deviation;
use crate::error::{IutCause, IutError};

/// FMMUs an ESC may have; the terminal's SII says 4.
const FMMUS: u16 = 4;

/// Where the master's logical image maps the terminal's process data.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct Windows {
    pub(super) outputs: u32,
    pub(super) inputs: u32,
}

impl EthercatIut {
    /// The logical addresses of the outputs and inputs, as the master
    /// configured the terminal's FMMUs (read back from the terminal).
    pub(super) fn windows(&self) -> Result<Windows, IutError> {
        let (md, station) = (self.master.maindevice(), self.station);
        let fmmus = self.master.drive(async {
            let mut fmmus = Vec::new();
            for n in 0..FMMUS {
                let raw = Command::fprd(station, FMMU_BASE + n * FMMU_LEN)
                    .receive_slice(md, FMMU_LEN)
                    .await?;
                fmmus.push(Fmmu::parse(&raw));
            }
            Ok::<_, ethercrab::error::Error>(fmmus)
        });
        let fmmus = fmmus.map_err(|e| master_error(e, "reading the FMMUs"))?;
        let window = |writes: bool| {
            fmmus
                .iter()
                .find(|f| f.active && f.length > 0 && f.writes() == writes && f.reads() != writes)
                .map(|f| f.logical_start)
        };
        match (window(true), window(false)) {
            (Some(outputs), Some(inputs)) => Ok(Windows { outputs, inputs }),
            _ => Err(IutError::new(
                IutCause::Impossible,
                "the terminal has no active FMMU for its outputs and one for its inputs",
            )),
        }
    }

    /// One cycle's telegrams in `mode`: the inputs this cycle's SyncManager 2 event produced.
    pub(super) fn exchange(
        &mut self,
        mode: ExchangeMode,
        outputs: &[u8],
    ) -> Result<Vec<u8>, IutError> {
        match mode {
            ExchangeMode::Lrw => self.lrw(outputs),
            ExchangeMode::SeparateInputUpdate => self.lwr_lrd(outputs),
        }
    }

    fn lrw(&mut self, outputs: &[u8]) -> Result<Vec<u8>, IutError> {
        let md = self.master.maindevice();
        let sub = self
            .group
            .subdevice(md, self.position)
            .map_err(|e| master_error(e, "finding the terminal"))?;
        sub.outputs_raw_mut().copy_from_slice(outputs);
        let response = self
            .master
            .drive(self.group.tx_rx(md))
            .map_err(|e| master_error(e, "LRW"))?;
        if response.working_counter != LRW_WORKING_COUNTER {
            return Err(IutError::new(
                IutCause::Protocol,
                format!(
                    "LRW came back with working counter {}, {LRW_WORKING_COUNTER} expected (inputs read, outputs written)",
                    response.working_counter
                ),
            ));
        }
        let confirmed = sub.inputs_raw().to_vec();
        // 003: what an LRW reads is what the previous SyncManager 2 event
        // left; other inputs are the terminal's deviation from the exchange,
        // a failure of it, not a broken telegram.
        if let Some(previous) = &self.previous_inputs {
            if &confirmed != previous {
                let head = |bytes: &[u8]| format!("{:02X?}", &bytes[..bytes.len().min(8)]);
                self.deviation = Some(Deviation {
                    candidates: blame::CONFIRMATION,
                    what: "the inputs the LRW read (the previous cycle's SyncManager 2 event)"
                        .into(),
                    expected: head(previous),
                    actual: head(&confirmed),
                });
            }
        }
        let station = self.station;
        let fresh = self.master.drive(async {
            let sm = Command::fprd(station, SM3).receive_slice(md, 8).await?;
            let sm = canif_ethercat::register::SyncManager::parse(&sm);
            Command::fprd(station, sm.start)
                .receive_slice(md, sm.length)
                .await
                .map(|inputs| inputs.to_vec())
        });
        let fresh = fresh.map_err(|e| master_error(e, "reading the input SyncManager"))?;
        self.previous_inputs = Some(fresh.clone());
        Ok(fresh)
    }

    /// LWR, then LRD: each with working counter 1 (the one terminal).
    fn lwr_lrd(&mut self, outputs: &[u8]) -> Result<Vec<u8>, IutError> {
        let windows = match self.windows {
            Some(windows) => windows,
            None => {
                let windows = self.windows()?;
                self.windows = Some(windows);
                windows
            }
        };
        let md = self.master.maindevice();
        let input_len = self
            .group
            .subdevice(md, self.position)
            .map_err(|e| master_error(e, "finding the terminal"))?
            .inputs_raw()
            .len() as u16;
        self.master
            .drive(Command::lwr(windows.outputs).send_receive_slice(md, outputs))
            .map_err(|e| master_error(e, "LWR"))?;
        let inputs = self
            .master
            .drive(async {
                Reads::Lrd {
                    address: windows.inputs,
                }
                .wrap()
                .receive_slice(md, input_len)
                .await
                .map(|inputs| inputs.to_vec())
            })
            .map_err(|e| master_error(e, "LRD"))?;
        // The next LRW, if the played PLC goes back to it, compares with these.
        self.previous_inputs = Some(inputs.clone());
        Ok(inputs)
    }
}

#[cfg(test)]
mod tests {
    use canif_model::config::{FrameFormat, InterfaceConfig};
    use canif_model::exchange::ExchangeMode;
    use canif_model::image::ImageLayout;
    use canif_spec::Catalogue;

    use super::super::{build, lock, EthercatLink};
    use crate::device::iut::Iut;

    /// The played master's exchange reaches the terminal as its telegrams:
    /// LWR then LRD for separate input update, one LRW otherwise, and the
    /// inputs either way are those of this cycle's SyncManager 2 event.
    #[test]
    fn separate_input_update_is_lwr_then_lrd_and_lrw_is_one_lrw() {
        let catalogue = Catalogue::embedded().unwrap();
        let profile = catalogue.profile("el6751-mdp").unwrap();
        let caps = profile.model_capabilities();
        let config = InterfaceConfig::new(FrameFormat::Base11, 4);
        let link = EthercatLink::parse("emulated").unwrap();
        let mut iut = build(&caps, &config, &profile.ethercat.unwrap(), &link).unwrap();
        let layout = ImageLayout::new(&config, caps.info_data);
        let mut outputs = vec![0; layout.output_size()];
        let telegrams = |iut: &super::EthercatIut| lock(iut.terminal.as_ref().unwrap()).telegrams;
        let before = telegrams(&iut);
        iut.exchange_with(ExchangeMode::SeparateInputUpdate);
        // TxCounter 1 with no messages: acknowledged in the same SM2 event.
        outputs[0] = 1;
        let inputs = iut.cycle(&outputs, 1_000_000).unwrap();
        let after = telegrams(&iut);
        assert_eq!(
            (
                after.lwr - before.lwr,
                after.lrd - before.lrd,
                after.lrw - before.lrw
            ),
            (1, 1, 0)
        );
        assert_eq!(inputs[0], 1, "the LRD read this cycle's acknowledge");
        iut.exchange_with(ExchangeMode::Lrw);
        outputs[0] = 2;
        let inputs = iut.cycle(&outputs, 2_000_000).unwrap();
        let last = telegrams(&iut);
        assert_eq!(
            (last.lwr, last.lrd, last.lrw - after.lrw),
            (after.lwr, after.lrd, 1)
        );
        assert_eq!(inputs[0], 2, "read back after the LRW's event");
    }
}
