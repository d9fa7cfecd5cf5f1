//! `canif export` and `canif check-layout`: the image in the PLC
//! programmer's own language, generated from the model, and hand-written
//! declarations held against it (crate canif-plctypes).

use std::process::ExitCode;

use canif_model::config::{FrameFormat, InterfaceConfig};
use canif_model::image::ImageLayout;
use canif_plctypes::export::{export as write_types, Language};
use canif_plctypes::{check_files, ImageTypes, Roots, INPUTS, OUTPUTS};
use canif_spec::Catalogue;

use super::did_you_mean;
use crate::cli::{CheckLayoutArgs, ExportArgs, FrameArg, InterfaceArgs, LanguageArg};
use crate::stop::{stop, Stop};

/// The image types of the interface the arguments name, checked against the profile.
fn image_types(catalogue: &Catalogue, args: &InterfaceArgs) -> Result<ImageTypes, Stop> {
    let Some(name) = args.profile.as_deref() else {
        return Err(stop!(
            "--profile NAME is needed: the image is a profile's (`canif profiles` lists them)"
        ));
    };
    let profile = catalogue.profile(name).ok_or_else(|| {
        let near = did_you_mean(name, catalogue.profiles.iter().map(|p| p.name.as_str()));
        stop!("unknown profile `{name}`{near}; `canif profiles` lists them")
    })?;
    let caps = profile.model_capabilities();
    let format = match args.frame {
        None => caps.first_format(),
        Some(FrameArg::Base11) => FrameFormat::Base11,
        Some(FrameArg::Extended29) => FrameFormat::Extended29,
        Some(FrameArg::Fd) => FrameFormat::Fd,
    };
    let mut config = InterfaceConfig::new(format, args.tx_slots);
    config.rx_slots = args.rx_slots;
    config.transaction_number |= args.transaction_number;
    config.time_stamp |= args.time_stamp;
    config
        .validate(&caps)
        .map_err(|e| stop!("{name} does not offer this interface: {e}"))?;
    let layout = ImageLayout::new(&config, caps.info_data);
    let options: Vec<&str> = [
        (config.transaction_number, "transaction numbers"),
        (config.time_stamp, "time stamps"),
        (caps.info_data, "InfoData"),
    ]
    .iter()
    .filter(|(on, _)| *on)
    .map(|(_, what)| *what)
    .collect();
    let title = format!(
        "The CAN interface of {name}: {} messages{}, {} Tx and {} Rx slots.",
        match format {
            FrameFormat::Base11 => "11-bit",
            FrameFormat::Extended29 => "29-bit",
            FrameFormat::Fd => "CAN FD",
        },
        match options.is_empty() {
            true => String::new(),
            false => format!(" with {}", options.join(", ")),
        },
        config.tx_slots,
        config.rx_slots
    );
    Ok(ImageTypes::of(&layout, title))
}

/// `canif export`.
pub(crate) fn export(
    catalogue: &Catalogue,
    args: &ExportArgs,
    out: &mut String,
) -> Result<ExitCode, Stop> {
    let types = match args.messages {
        true => ImageTypes::messages(),
        false => image_types(catalogue, &args.interface)?,
    };
    let language = match args.language {
        LanguageArg::St => Language::StructuredText,
        LanguageArg::C => Language::C,
        LanguageArg::Rust => Language::Rust,
    };
    let origin = format!("canif export {}", env!("CARGO_PKG_VERSION"));
    out.push_str(&write_types(&types, language, &origin));
    Ok(ExitCode::SUCCESS)
}

/// `canif check-layout`: 0 when the declarations match, 1 on a difference.
pub(crate) fn check_layout(
    catalogue: &Catalogue,
    args: &CheckLayoutArgs,
    out: &mut String,
) -> Result<ExitCode, Stop> {
    let types = image_types(catalogue, &args.interface)?;
    let roots = Roots {
        outputs: args.outputs.clone(),
        inputs: args.inputs.clone(),
    };
    let checked =
        check_files(&args.files, &types, &roots, args.pack_mode).map_err(|e| stop!("{e}"))?;
    if checked.matched.is_empty() {
        return Err(stop!(
            "no structure in the files declares the image: a member NoOfTxMessages or NoOfRxMessages names one, or --outputs/--inputs TYPE"
        ));
    }
    for defect in &checked.defects {
        outln!(out, "{defect}");
    }
    for root in &checked.unmatched {
        let (what, marker, flag) = match root.as_str() {
            OUTPUTS => ("outputs", "NoOfTxMessages", "--outputs"),
            INPUTS => ("inputs", "NoOfRxMessages", "--inputs"),
            _ => (root.as_str(), "", ""),
        };
        outln!(
            out,
            "not checked: the {what} (no structure has a member {marker}; name it with {flag} TYPE)"
        );
    }
    let pairs: Vec<String> = checked
        .matched
        .iter()
        .map(|(image, user)| format!("{user} as {image}"))
        .collect();
    outln!(out, "{}", types.title);
    outln!(
        out,
        "checked {} members of {}: {}",
        checked.members_checked,
        pairs.join(", "),
        match checked.defects.len() {
            0 => "they match the image byte for byte".to_string(),
            1 => "1 difference".to_string(),
            n => format!("{n} differences"),
        }
    );
    if !checked.defects.is_empty() && args.interface.frame.is_none() {
        outln!(
            out,
            "(checked against the profile's first frame format; --frame, --transaction-number and the slot counts choose the interface your declarations are for)"
        );
    }
    Ok(match checked.defects.is_empty() {
        true => ExitCode::SUCCESS,
        false => ExitCode::from(1),
    })
}
