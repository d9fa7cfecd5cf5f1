//! `canif certify` and `canif compare`: what a certifier signs and a CI gate checks.

use std::path::Path;
use std::process::ExitCode;

use canif_harness::suite::{run_profile, Options};
use canif_spec::Catalogue;

use super::resolve_iut;
use super::run::run_features;
use crate::cli::IutOptions;

pub fn certify(
    catalogue: &Catalogue,
    profile: &str,
    iut: &IutOptions,
    seed: u64,
    out: &Path,
) -> ExitCode {
    let kind = match resolve_iut(iut) {
        Ok(kind) => kind,
        Err(code) => return code,
    };
    let Some(profile) = catalogue.profile(profile) else {
        eprintln!("unknown profile `{profile}`; `canif profiles` lists them");
        return ExitCode::from(2);
    };
    let options = Options {
        seed,
        ..Options::default()
    };
    let run = run_profile(catalogue, profile, &kind, &options, |r| {
        eprintln!("  {}", r.scenario)
    });
    let scenarios = match run_features(&kind, &[profile]) {
        Ok(scenarios) => scenarios,
        Err(error) => {
            eprintln!("the feature files do not parse: {error}");
            return ExitCode::from(2);
        }
    };
    let failed = scenarios.iter().filter(|s| s.outcome.is_err()).count();
    let files: Vec<(String, String)> = canif_spec::embedded_files()
        .iter()
        .map(|(p, t)| (p.to_string(), t.to_string()))
        .collect();
    let hash = canif_harness::certificate::catalogue_hash(&files);
    let certificate = canif_harness::certificate::certificate(
        catalogue,
        &hash,
        &run,
        &kind.name(),
        seed,
        (scenarios.len(), failed),
    );
    let written = std::fs::create_dir_all(out)
        .and_then(|_| {
            std::fs::write(
                out.join("certificate.json"),
                serde_json::to_string_pretty(&certificate).unwrap_or_default(),
            )
        })
        .and_then(|_| {
            std::fs::write(
                out.join("certificate.html"),
                canif_harness::certificate::html(&certificate, catalogue),
            )
        });
    if let Err(error) = written {
        eprintln!("cannot write the certificate to {}: {error}", out.display());
        return ExitCode::from(2);
    }
    println!(
        "{} {} on {}: {} — {}/certificate.{{json,html}}, seal {}",
        kind.name(),
        if certificate["conforms"] == serde_json::json!(true) {
            "CONFORMS"
        } else {
            "DOES NOT CONFORM"
        },
        profile.name,
        certificate["totals"],
        out.display(),
        certificate["result_sha256"].as_str().unwrap_or("")
    );
    let errors = run
        .verdicts
        .values()
        .any(|v| matches!(v, canif_harness::Verdict::Error(_)));
    ExitCode::from(if errors {
        2
    } else {
        u8::from(certificate["conforms"] != serde_json::json!(true))
    })
}

pub fn verify_certificate(path: &Path) -> ExitCode {
    let certificate: serde_json::Value = match std::fs::read_to_string(path)
        .map_err(|e| e.to_string())
        .and_then(|t| serde_json::from_str(&t).map_err(|e| e.to_string()))
    {
        Ok(value) => value,
        Err(error) => {
            eprintln!("{}: {error}", path.display());
            return ExitCode::from(2);
        }
    };
    match canif_harness::certificate::verify(&certificate) {
        Ok(()) => {
            println!(
                "{}: the seal matches ({})",
                path.display(),
                certificate["result_sha256"].as_str().unwrap_or("")
            );
            ExitCode::SUCCESS
        }
        Err(error) => {
            println!("{}: {error}", path.display());
            ExitCode::from(1)
        }
    }
}

pub fn compare(base: &Path, new: &Path) -> ExitCode {
    let load = |path: &Path| -> Result<std::collections::BTreeMap<String, String>, String> {
        let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
        let report = canif_harness::report::ReportFile::parse(&text)
            .map_err(|e| format!("{}: {e}", path.display()))?;
        Ok(canif_harness::compare::verdicts(&report))
    };
    let (base, new) = match (load(base), load(new)) {
        (Ok(base), Ok(new)) => (base, new),
        (Err(e), _) | (_, Err(e)) => {
            eprintln!("{e}");
            return ExitCode::from(2);
        }
    };
    let comparison = canif_harness::compare::compare(&base, &new);
    print!("{}", comparison.markdown());
    ExitCode::from(u8::from(!comparison.regressions.is_empty()))
}
