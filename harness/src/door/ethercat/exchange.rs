//! One harness cycle as the telegrams a real master sends (003, "EtherCAT
//! Update"): an **LRW**, whose inputs are the previous SyncManager 2 event's
//! (the PLC sees a TxCounter confirmed two task cycles later), then a read of
//! the input SyncManager for what this cycle's event produced; or, for
//! **separate input update**, an LWR of the outputs (the event) and an LRD of
//! the inputs it produced (confirmed one task cycle later). The played PLC
//! names the mode (`Telegrams::exchange_with`).
//!
//! With Distributed Clocks SYNC0, not the telegram, starts the terminal's
//! cycle (003, PDX-005), and the master plays the two patterns that tell the
//! difference: a task at half the CAN cycle (an LWR of the outputs half a
//! cycle before SYNC0, after which the inputs must not have moved, then the
//! cycle's own telegram just before SYNC0) and overruns (every second cycle
//! whose outputs did not change sends no process-data telegram at all: the
//! terminal's cycle must run on SYNC0 regardless). The cycle's inputs are
//! read just after SYNC0.

use canif_ethercat::register::{Fmmu, FMMU_BASE, FMMU_LEN};
use canif_model::exchange::ExchangeMode;
use ethercrab::{Command, Reads};

use super::start_up::master_error;
use super::{EthercatIut, LRW_WORKING_COUNTER, SM3, SYNC0_CYCLE_NS};
use crate::door::iut::{Deviated, Deviation};
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

    /// One cycle's telegrams in `mode` at `now`: the inputs this cycle's
    /// SyncManager 2 event produced (or, with Distributed Clocks, its SYNC0
    /// event at `now`: they are read just after it).
    pub(super) fn exchange(
        &mut self,
        mode: ExchangeMode,
        outputs: &[u8],
        now: u64,
    ) -> Result<Vec<u8>, IutError> {
        match mode {
            ExchangeMode::Lrw => self.lrw(outputs, now),
            ExchangeMode::SeparateInputUpdate => self.lwr_lrd(outputs, now),
        }
    }

    /// With Distributed Clocks: the half-cycle LWR and its check, or an
    /// overrun, then the cycle's telegrams around the SYNC0 event at `now`.
    pub(super) fn exchange_around_sync0(
        &mut self,
        outputs: &[u8],
        now: u64,
    ) -> Result<Vec<u8>, IutError> {
        let dc = self.dc.as_mut().expect("a DC master");
        let unchanged = dc.last_outputs.as_deref() == Some(outputs);
        dc.unchanged = if unchanged { dc.unchanged + 1 } else { 0 };
        dc.last_outputs = Some(outputs.to_vec());
        if dc.unchanged % 2 == 1 {
            // An overrun: no telegram; the terminal's SYNC0 cycle runs on
            // the outputs it has. canif reads what it produced.
            dc.overruns += 1;
            self.set_clock(now + 1);
            let inputs = self.read_input_sync_manager()?;
            self.previous_inputs = Some(inputs.clone());
            return Ok(inputs);
        }
        dc.half_cycles += 1;
        self.set_clock(now.saturating_sub(u64::from(SYNC0_CYCLE_NS) / 2));
        let windows = self.windows_once()?;
        let md = self.master.maindevice();
        self.master
            .drive(Command::lwr(windows.outputs).send_receive_slice(md, outputs))
            .map_err(|e| master_error(e, "LWR (half cycle)"))?;
        // Only where canif keeps the terminal's clock is it sure that no
        // SYNC0 came between: a real terminal's may at any moment.
        let between = match self.terminal.is_some() {
            true => Some(self.read_input_sync_manager()?),
            false => None,
        };
        let moved = |previous: &&Vec<u8>| between.as_ref().is_some_and(|b| b != *previous);
        if let Some(previous) = self.previous_inputs.as_ref().filter(moved) {
            let between = between.as_deref().unwrap_or_default();
            let head = |bytes: &[u8]| format!("{:02X?}", &bytes[..bytes.len().min(8)]);
            self.deviation = Some(Deviation {
                kind: Deviated::Sync0StartsTheCycle,
                what: "the inputs half a cycle before SYNC0, after the outputs' telegram (Distributed Clocks: SYNC0 starts the cycle, not the SyncManager 2 event)".into(),
                expected: head(previous),
                actual: head(between),
            });
        }
        self.set_clock(now);
        self.exchange(self.telegrams, outputs, now)
    }

    /// The input SyncManager's bytes (FPRD), where its registers say it
    /// lies: read once, since a master does not move it in OP (a round trip
    /// less per cycle).
    fn read_input_sync_manager(&mut self) -> Result<Vec<u8>, IutError> {
        let (md, station) = (self.master.maindevice(), self.station);
        let known = self.input_sync_manager;
        let fresh = self.master.drive(async {
            let (start, length) = match known {
                Some(at) => at,
                None => {
                    let sm = Command::fprd(station, SM3).receive_slice(md, 8).await?;
                    let sm = canif_ethercat::register::SyncManager::parse(&sm);
                    (sm.start, sm.length)
                }
            };
            Command::fprd(station, start)
                .receive_slice(md, length)
                .await
                .map(|inputs| ((start, length), inputs.to_vec()))
        });
        let (at, inputs) = fresh.map_err(|e| master_error(e, "reading the input SyncManager"))?;
        self.input_sync_manager = Some(at);
        Ok(inputs)
    }

    /// The logical windows, read from the terminal the first time.
    fn windows_once(&mut self) -> Result<Windows, IutError> {
        if let Some(windows) = self.windows {
            return Ok(windows);
        }
        let windows = self.windows()?;
        self.windows = Some(windows);
        Ok(windows)
    }

    /// The time the cycle's inputs are read: just after SYNC0 with
    /// Distributed Clocks (an event at the telegram's own time comes after it).
    fn read_after(&self, now: u64) -> u64 {
        now + u64::from(self.dc.is_some())
    }

    fn lrw(&mut self, outputs: &[u8], now: u64) -> Result<Vec<u8>, IutError> {
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
                    kind: Deviated::Confirmation,
                    what: "the inputs the LRW read (the previous cycle's SyncManager 2 event)"
                        .into(),
                    expected: head(previous),
                    actual: head(&confirmed),
                });
            }
        }
        self.set_clock(self.read_after(now));
        let fresh = self.read_input_sync_manager()?;
        self.previous_inputs = Some(fresh.clone());
        Ok(fresh)
    }

    /// LWR, then LRD: each with working counter 1 (the one terminal).
    fn lwr_lrd(&mut self, outputs: &[u8], now: u64) -> Result<Vec<u8>, IutError> {
        let windows = self.windows_once()?;
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
        self.set_clock(self.read_after(now));
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

/// What a master with Distributed Clocks did around the SYNC0 events.
#[derive(Debug, Clone, Default)]
pub(super) struct DcMaster {
    last_outputs: Option<Vec<u8>>,
    /// Cycles in a row whose outputs did not change.
    unchanged: u64,
    /// Cycles with the half-cycle LWR, and cycles with no telegram.
    pub(super) half_cycles: u64,
    pub(super) overruns: u64,
}

#[cfg(test)]
mod tests {
    use crate::door::iut::Telegrams;
    use canif_model::config::{FrameFormat, InterfaceConfig};
    use canif_model::exchange::ExchangeMode;
    use canif_model::image::ImageLayout;
    use canif_spec::Catalogue;

    use super::super::{build, lock, EthercatLink};
    use crate::door::iut::Iut;

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

    /// With Distributed Clocks the master sends half a cycle early and skips
    /// a telegram where the outputs stand still, and the terminal runs one
    /// cycle per SYNC0 event whatever the telegrams: its acknowledge comes
    /// with the SYNC0 after the outputs, also when no telegram carried them
    /// that cycle.
    #[test]
    fn with_distributed_clocks_sync0_not_the_telegram_runs_the_cycle() {
        use canif_model::config::{QueueMode, Synchronization};
        let catalogue = Catalogue::embedded().unwrap();
        let profile = catalogue.profile("el6751-mdp").unwrap();
        let caps = profile.model_capabilities();
        let mut config = InterfaceConfig::new(FrameFormat::Base11, 4);
        config.queue = QueueMode::Fast;
        config.synchronization = Synchronization::DistributedClocks {
            sync1_shift: 100_000,
        };
        let link = EthercatLink::parse("emulated").unwrap();
        let mut iut = build(&caps, &config, &profile.ethercat.unwrap(), &link).unwrap();
        let layout = ImageLayout::new(&config, caps.info_data);
        let mut outputs = vec![0; layout.output_size()];
        let cycles = |iut: &super::EthercatIut| lock(iut.terminal.as_ref().unwrap()).cycles;
        let telegrams = |iut: &super::EthercatIut| lock(iut.terminal.as_ref().unwrap()).telegrams;
        outputs[0] = 1;
        for k in 0..4u64 {
            let inputs = iut.cycle(&outputs, k * 1_000_000).unwrap();
            assert_eq!(inputs[0], 1, "cycle {k}: acknowledged at the first SYNC0");
            assert_eq!(cycles(&iut), k + 1, "one cycle per SYNC0 event");
            assert!(iut.take_deviation().is_none());
        }
        let dc = iut.dc.as_ref().unwrap();
        // Cycles 1 and 3 repeat their outputs: the first of each such run is
        // an overrun (no telegram), the next is sent.
        assert_eq!((dc.half_cycles, dc.overruns), (2, 2));
        let seen = telegrams(&iut);
        assert_eq!(
            (seen.lwr, seen.lrw),
            (2, 2),
            "a half-cycle LWR and an LRW per sent cycle"
        );
        // 3-buffer mode: a write that stops short of the SyncManager's end
        // (TxCounter 2, nothing after it) is never handed to the cycle.
        let windows = iut.windows_once().unwrap();
        iut.set_clock(4_500_000);
        let md = iut.master.maindevice();
        iut.master
            .drive(ethercrab::Command::lwr(windows.outputs).send_receive_slice(md, &[2, 0]))
            .unwrap();
        iut.set_clock(5_000_001);
        let inputs = iut.read_input_sync_manager().unwrap();
        assert_eq!(
            cycles(&iut),
            6,
            "the SYNC0 events of 4 and 5 ms ran their cycles"
        );
        assert_eq!(
            inputs[0], 1,
            "on the last complete buffer, not the half-written one"
        );
        outputs[0] = 2;
        let inputs = iut.cycle(&outputs, 6_000_000).unwrap();
        assert_eq!(inputs[0], 2, "the complete buffer is acknowledged");
    }
}
