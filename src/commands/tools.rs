//! `canif size` and `canif frame-time`: the manual's sizing and timing, as tools.

use std::process::ExitCode;

use crate::stop::{stop, Stop};

use canif_model::frame::{CanId, Frame};
use canif_model::sizing::{self, FrameTimeBasis};
use canif_model::timing::{frame_bits, frame_duration, BitRates, Stuffing};

/// `canif size`: the manual's figure and the safe figure, the safe one
/// recommended, and why (ruling R4, amended).
pub(crate) fn size(
    bitrate: u32,
    cycle_us: u64,
    payload: u8,
    out: &mut String,
) -> Result<ExitCode, Stop> {
    let cycle = cycle_us * 1_000;
    let Some(advice) = sizing::advise(bitrate, cycle, payload) else {
        return Err(stop!(
            "cannot size: payload must be 0..=8 and the bit rate above 0"
        ));
    };
    outln!(
        out,
        "{bitrate} bit/s, {cycle_us} µs cycle, {payload}-byte 11-bit frames at 100 % bus load:"
    );
    let line = |out: &mut String, label: &str, s: &sizing::Sizing, note: &str| {
        outln!(
            out,
            "  {label:<35} frame time {:>8.1} µs -> {:>4} slots{note}",
            s.frame_time as f64 / 1000.0,
            s.slots
        );
    };
    match &advice.manual {
        Some(manual) => line(out, "the manual's figure (CiA table)", manual, ""),
        None => outln!(
            out,
            "  the manual's figure (CiA table)     none: the table has no cell for this bit rate"
        ),
    }
    line(
        out,
        "safe (shortest frame, no stuffing)",
        &advice.safe,
        "  <- recommended",
    );
    if let Some(worst) = sizing::size(bitrate, cycle, payload, FrameTimeBasis::WorstCase) {
        line(out, "longest frame (all stuff bits)", &worst, "");
    }
    let safe = advice.recommended();
    if advice.manual_can_overflow() {
        outln!(
            out,
            "  why: frames without stuff bits are shorter than the CiA times, so {} can end in one cycle; {} slots can overflow (ruling R4)",
            safe.slots,
            advice.manual.map_or(0, |m| m.slots)
        );
    } else {
        outln!(
            out,
            "  why: at most {} frames can end in one cycle, even without stuff bits (ruling R4)",
            safe.slots
        );
    }
    if safe.slots > 32 {
        outln!(
            out,
            "  more than 32 slots cannot be configured: shorten the cycle time (000 §4)"
        );
    }
    Ok(ExitCode::SUCCESS)
}

pub(crate) fn frame_time(
    bitrate: u32,
    data_bitrate: Option<u32>,
    payload: u8,
    extended: bool,
    fd: bool,
    out: &mut String,
) -> Result<ExitCode, Stop> {
    let id = if extended {
        CanId::Extended(0)
    } else {
        CanId::Standard(0)
    };
    let frame = if fd {
        let Some(size) = canif_model::dlc::fd_round_up(payload) else {
            return Err(stop!("a CAN FD frame carries at most 64 bytes"));
        };
        Frame::fd(
            id,
            data_bitrate.is_some(),
            false,
            &vec![0; usize::from(size)],
        )
    } else {
        Frame::classic(id, &vec![0; usize::from(payload)])
    };
    let frame = match frame {
        Ok(frame) => frame,
        Err(error) => {
            return Err(stop!("{error}"));
        }
    };
    let rates = BitRates {
        nominal: bitrate,
        data: data_bitrate.unwrap_or(bitrate),
    };
    let bits = frame_bits(&frame);
    outln!(
        out,
        "{} frame, {} data bytes: {} bits nominal, {} worst case (arbitration {}/{}, data phase {}/{})",
        if fd { "CAN FD" } else { "classic" },
        frame.len(),
        bits.arbitration.nominal + bits.data.nominal,
        bits.arbitration.worst_case + bits.data.worst_case,
        bits.arbitration.nominal,
        bits.arbitration.worst_case,
        bits.data.nominal,
        bits.data.worst_case
    );
    for stuffing in [Stuffing::Nominal, Stuffing::WorstCase] {
        outln!(
            out,
            "  {:<10} {:>9.2} µs",
            format!("{stuffing:?}"),
            frame_duration(&frame, rates, stuffing) as f64 / 1000.0
        );
    }
    if let Some(cell) =
        canif_model::cia_table::frame_time(bitrate, payload).filter(|_| !fd && !extended)
    {
        outln!(
            out,
            "  CiA table  {:>9.2} µs (000 §4)",
            cell as f64 / 1000.0
        );
    }
    Ok(ExitCode::SUCCESS)
}

/// `canif probe`: each profile's scenarios that tell a choice's values
/// apart, under each; the findings written to `out`.
pub(crate) fn probe(
    kind: &canif_harness::device::IutKind,
    profiles: &[&canif_spec::Profile],
    (given, out): (canif_harness::declare::choices::Declared, &std::path::Path),
) -> Result<ExitCode, Stop> {
    use canif_harness::declare::choices::Choice;
    use canif_harness::device::probe::{declaration, finding, probe, Finding};
    if let Some(contradiction) = kind.contradicts(&given) {
        return Err(stop!("canif probe: {contradiction}"));
    }
    // What the command line declares is not probed, and is in the file.
    let options = canif_harness::device::Options {
        declared: given,
        ..canif_harness::device::Options::quick(1)
    };
    let mut probes = Vec::new();
    for profile in profiles {
        for probed in probe(kind, profile, &options) {
            let passes = match probed.passes.as_slice() {
                [] => "none".to_string(),
                passes => passes.join(", "),
            };
            let errors: String = probed.errors.iter().map(|e| format!("; {e}")).collect();
            errln!(
                "{:<16} {:<22} {:<40} passes under: {passes}{errors}",
                probed.profile,
                probed.choice,
                probed.scenario,
            );
            probes.push(probed);
        }
    }
    // A device that broke showed no choice: what it would have shown is
    // unknown, so nothing is found and nothing written.
    let broke: std::collections::BTreeSet<&String> = probes.iter().flat_map(|p| &p.broke).collect();
    if let Some(first) = broke.first() {
        return Err(stop!(
            "canif probe: the IUT broke, so no choice was found and {} was not written: {first}{}",
            out.display(),
            match broke.len() {
                1 => String::new(),
                n => format!(" (and {} other errors, above)", n - 1),
            }
        ));
    }
    let mut code = ExitCode::SUCCESS;
    for choice in Choice::ALL.into_iter().filter(|c| c.settled_by().is_some()) {
        if let Some(value) = given.value(choice) {
            sayln!("{choice}={value} (declared, not probed)");
            continue;
        }
        let said = match finding(&probes, choice) {
            Finding::Takes(value) => format!("{choice}={value}"),
            Finding::Undecided => {
                format!("{choice}: no scenario told the values apart; nothing to declare")
            }
            Finding::Neither => {
                code = ExitCode::from(1);
                format!("{choice}: a scenario passed under no documented value (the device breaks it either way)")
            }
            Finding::Inconsistent => {
                code = ExitCode::from(1);
                format!("{choice}: the scenarios disagree (one passed only under one value, another only under another)")
            }
        };
        sayln!("{said}");
    }
    let declared = (code == ExitCode::SUCCESS).then(|| given.or(declaration(&probes)));
    if let Some(declared) = declared {
        let text = serde_json::to_string_pretty(&declared.entries()).expect("a JSON object") + "\n";
        if let Err(error) = std::fs::write(out, text) {
            return Err(stop!("cannot write {}: {error}", out.display()));
        }
        errln!(
            "written to {} (canif run --declare @{})",
            out.display(),
            out.display()
        );
    }
    Ok(code)
}

/// `canif esi --profile P`: the emulated terminal's ESI file on stdout.
pub(crate) fn esi(
    catalogue: &canif_spec::Catalogue,
    name: &str,
    out: &mut String,
) -> Result<ExitCode, Stop> {
    use canif_harness::door::ethercat::{emulated_terminal, esi, Emulated};
    let terminals = catalogue.terminal_names();
    let Some((profile, identity)) = catalogue
        .profile(name)
        .and_then(|p| Some((p, p.ethercat.as_ref()?)))
    else {
        return Err(stop!(
            "canif esi: `{name}` is no EtherCAT terminal profile; the terminals are {}",
            terminals.join(", ")
        ));
    };
    let terminal = emulated_terminal(
        &profile.model_capabilities(),
        identity,
        &Emulated::default(),
    );
    out.push_str(&esi::esi(identity, &terminal));
    out.push('\n');
    Ok(ExitCode::SUCCESS)
}

/// `canif faults`: every deliberate defect and documented choice of the soft
/// device and client, and the master models.
pub(crate) fn faults(out: &mut String) -> ExitCode {
    for fault in canif_softdevice::Fault::ALL {
        outln!(out, "{:<36} {}", fault.name(), fault.description());
    }
    outln!(
        out,
        "\nchoices the documents leave (--choice; the device still conforms):"
    );
    for choice in canif_softdevice::Freedom::ALL {
        outln!(out, "{:<36} {}", choice.name(), choice.description());
    }
    outln!(
        out,
        "\nclient faults (canif run plc --fault; the soft client):"
    );
    for fault in canif_harness::client::soft_client::ClientFault::ALL {
        outln!(out, "{:<36} {}", fault.name(), fault.description());
    }
    outln!(
        out,
        "\nclient ways of working (canif run plc --choice; the soft client takes one and declares it):"
    );
    for shape in canif_harness::client::soft_client::ClientShape::ALL {
        outln!(out, "{:<36} declares {}", shape.name(), shape.declares());
    }
    outln!(out, "\nmaster models (canif run plc --master):");
    for master in canif_harness::client::master::Master::ALL {
        outln!(out, "{:<36} {}", master.name, master.description());
    }
    ExitCode::SUCCESS
}
