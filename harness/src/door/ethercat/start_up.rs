//! The terminal's start-up in PREOP, as the EL6751 documentation orders it,
//! and what its answers mean: SDO aborts and AL status codes are refusals
//! of a configuration or errors naming what the terminal did.

use canif_ethercat::register;
use canif_model::config::{Capabilities, InterfaceConfig, Synchronization};
use ethercrab::Command;

use super::coe::{CoeError, Mailboxes};
use super::objects;
use crate::door::iut::BuildError;
use crate::error::{IutCause, IutError};

/// The AL status's error flag.
const AL_ERROR: u16 = 0x10;
/// AL status codes with which a terminal refuses a configuration (not a broken exchange).
const REFUSALS: [u16; 4] = [0x001D, 0x001E, 0x0030, 0x0035];

/// The meaning of the AL status codes ETG.1000.6 Table 11 gives.
fn al_status_text(code: u16) -> &'static str {
    match code {
        0x0000 => "no error",
        0x0011 => "invalid requested state change",
        0x0012 => "unknown requested state",
        0x0013 => "bootstrap not supported",
        0x0016 => "invalid mailbox configuration",
        0x001B => "sync manager watchdog",
        0x001D => "invalid output configuration",
        0x001E => "invalid input configuration",
        0x0030 => "invalid DC SYNC configuration",
        0x0035 => "invalid DC sync cycle time",
        _ => "no meaning in ETG.1000.6",
    }
}

pub(super) fn master_error(error: ethercrab::error::Error, during: &str) -> IutError {
    use ethercrab::error::Error;
    let cause = match error {
        Error::Timeout(_) => IutCause::Silent,
        Error::SubDevice(_) => IutCause::Reported,
        _ => IutCause::Protocol,
    };
    IutError::new(cause, format!("EtherCAT, {during}: {error}"))
}

fn coe_error(error: CoeError, during: &str) -> BuildError {
    match error {
        CoeError::Abort { .. } => BuildError::Refused(format!("{during}: {error}")),
        CoeError::Timeout(_) => BuildError::Failed(IutError::new(
            IutCause::Silent,
            format!("{during}: {error}"),
        )),
        _ => BuildError::Failed(IutError::new(
            IutCause::Protocol,
            format!("{during}: {error}"),
        )),
    }
}

/// PREOP → SAFEOP, watched here: the terminal's AL status says at once
/// whether it refuses (error flag and code), where ethercrab would wait out
/// its timeout for a state that does not come.
pub(super) async fn request_safe_op(
    md: &ethercrab::MainDevice<'_>,
    station: u16,
) -> Result<(), BuildError> {
    const SAFE_OP: u16 = 4;
    let failed = |e| BuildError::Failed(master_error(e, "PREOP → SAFEOP"));
    Command::fpwr(station, register::AL_CONTROL)
        .send(md, SAFE_OP)
        .await
        .map_err(failed)?;
    let began = std::time::Instant::now();
    loop {
        let status = Command::fprd(station, register::AL_STATUS)
            .receive::<u16>(md)
            .await
            .map_err(failed)?;
        if status & AL_ERROR != 0 {
            let code = Command::fprd(station, register::AL_STATUS_CODE)
                .receive::<u16>(md)
                .await
                .map_err(failed)?;
            let what = format!(
                "PREOP → SAFEOP: AL status {status:#06x}, code {code:#06x} ({})",
                al_status_text(code)
            );
            // Acknowledge, so that the next configuration starts from a clean PREOP.
            let _ = Command::fpwr(station, register::AL_CONTROL)
                .send(md, 2u16 | AL_ERROR)
                .await;
            return Err(if REFUSALS.contains(&code) {
                BuildError::Refused(what)
            } else {
                BuildError::Failed(IutError::new(IutCause::Reported, what))
            });
        }
        if status & 0x0F == SAFE_OP {
            return Ok(());
        }
        if began.elapsed() > SAFE_OP_TIMEOUT {
            return Err(BuildError::Failed(IutError::new(
                IutCause::Silent,
                format!("PREOP → SAFEOP: AL status still {status:#06x} after {SAFE_OP_TIMEOUT:?}"),
            )));
        }
        embassy_time::Timer::after_micros(200).await;
    }
}

/// The SYNC0 cycle: the harness's cycle (every scenario runs at 1 ms).
pub(super) const SYNC0_CYCLE_NS: u32 = 1_000_000;

/// How far ahead of the system time read the first SYNC0 of a real terminal lies.
const SYNC0_LEAD_NS: u64 = 10 * SYNC0_CYCLE_NS as u64;

/// Whose clock the terminal's local time is, for placing the first SYNC0.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Sync0Clock {
    /// The harness's virtual time (in memory, or the veth terminal): local
    /// time `now` at start-up, and the first SYNC0 at local `first_sync0`,
    /// the first cycle's start.
    Virtual { now: u64, first_sync0: u64 },
    /// A real terminal's own clock.
    Real,
}

/// How long a terminal may take to reach SAFEOP.
const SAFE_OP_TIMEOUT: std::time::Duration = std::time::Duration::from_secs(5);

/// The PREOP start-up: the interface's downloads, Distributed Clocks where
/// the configuration asks for them, and the local cycle-time measurement.
/// `mailboxes` are read from the terminal the first time and kept: PREOP
/// does not move them, and the refusal grid writes thousands of lists.
pub(super) async fn configure(
    md: &ethercrab::MainDevice<'_>,
    station: u16,
    mailboxes: &mut Option<Mailboxes>,
    (caps, config): (&Capabilities, &InterfaceConfig),
    clock: Sync0Clock,
) -> Result<(), BuildError> {
    let mailboxes = match mailboxes {
        Some(known) => known,
        None => mailboxes.insert(
            Mailboxes::of(md, station)
                .await
                .map_err(|e| coe_error(e, "mailbox"))?,
        ),
    };
    for download in objects::downloads(caps, config) {
        mailboxes
            .download_complete(md, download.index, &download.data)
            .await
            .map_err(|e| coe_error(e, &format!("{} ({:#06x})", download.name, download.index)))?;
    }
    if let Synchronization::DistributedClocks { sync1_shift } = config.synchronization {
        use canif_ethercat::register::{
            DC_START_TIME, DC_SYNC0_CYCLE, DC_SYNC1_CYCLE, DC_SYNC_ACTIVATION, DC_SYSTEM_TIME,
        };
        let shift = u32::try_from(sync1_shift).map_err(|_| {
            BuildError::Refused(format!("SYNC1 shift {sync1_shift} ns exceeds the register"))
        })?;
        let failed = |e| BuildError::Failed(master_error(e, "writing the DC registers"));
        Command::fpwr(station, DC_SYNC0_CYCLE)
            .send(md, SYNC0_CYCLE_NS)
            .await
            .map_err(failed)?;
        Command::fpwr(station, DC_SYNC1_CYCLE)
            .send(md, shift)
            .await
            .map_err(failed)?;
        // The first SYNC0 in the terminal's system time: read its clock,
        // then count on from it (ETG.1000.4 §9.3: the start time must lie ahead).
        let system = Command::fprd(station, DC_SYSTEM_TIME)
            .receive::<u64>(md)
            .await
            .map_err(failed)?;
        let start = match clock {
            Sync0Clock::Virtual { now, first_sync0 } => system - now + first_sync0,
            Sync0Clock::Real => system + SYNC0_LEAD_NS,
        };
        Command::fpwr(station, DC_START_TIME)
            .send(md, start)
            .await
            .map_err(failed)?;
        // Cyclic operation, SYNC0 and SYNC1 on.
        Command::fpwr(station, DC_SYNC_ACTIVATION)
            .send(md, 0b111u8)
            .await
            .map_err(failed)?;
    }
    // The process-data watchdog off: a harness that stalls (a busy
    // machine) is no fault of the terminal's, and must not take it to
    // SAFEOP with 0x001B in the middle of a run.
    Command::fpwr(station, register::WATCHDOG_TIME_PROCESS_DATA)
        .send(md, 0u16)
        .await
        .map_err(|e| BuildError::Failed(master_error(e, "turning the watchdog off")))?;
    // 000 §5: with 0x1C32:08 set the terminal measures its cycle into 0x1C32:05,
    // read back for the report; a terminal that refuses it reports none.
    let _ = mailboxes
        .download(md, objects::SYNC_OUTPUTS, objects::MEASURE_SUB, &[1, 0])
        .await;
    Ok(())
}

/// SyncManagers 0–3 as configured: start, length, control byte (for the
/// report; a terminal that does not answer shows none).
pub(super) async fn sync_managers(md: &ethercrab::MainDevice<'_>, station: u16) -> Vec<[u16; 3]> {
    let mut out = Vec::new();
    for n in 0..4 {
        let at = register::SYNC_MANAGER_BASE + n * register::SYNC_MANAGER_LEN;
        let Ok(raw) = Command::fprd(station, at).receive_slice(md, 8).await else {
            return Vec::new();
        };
        let sm = register::SyncManager::parse(&raw);
        out.push([sm.start, sm.length, u16::from(sm.control)]);
    }
    out
}
