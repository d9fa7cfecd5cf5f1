//! `canif certify` and `canif compare`: what a certifier signs and a CI gate checks.

use std::path::Path;
use std::process::ExitCode;

use crate::stop::{stop, Stop};

use canif_harness::certificate::{self, Certificate};
use canif_harness::compare::CompareOptions;
use canif_harness::device::suite::Options;
use canif_harness::report::{Product, ReportFile};
use canif_spec::Catalogue;

use canif_harness::client::suite::ClientOptions;

use super::run::{finish, profiles, Progress};
use super::{client_kind, declared, iut_kind};
use crate::cli::{CompareFormat, IutOptions};
use canif_runner::Plan;

/// How to check a certificate without canif, for the output and the docs.
fn ssh_keygen_command(certificate: &Path) -> String {
    format!(
        "echo \"certifier namespaces=\\\"{ns}\\\" $(cat KEY.pub)\" > allowed_signers && ssh-keygen -Y verify -f allowed_signers -I certifier -n {ns} -s {sig} < {cert}",
        ns = certificate::NAMESPACE,
        sig = certificate.with_extension("json.sig").display(),
        cert = certificate.display()
    )
}

/// What `canif certify` runs: the implementation, on which side and profiles.
pub(crate) struct CertifyRun<'a> {
    pub profile_names: &'a [String],
    pub iut: &'a IutOptions,
    pub side: canif_spec::Side,
    pub product: Option<Product>,
    pub seed: u64,
}

pub(crate) fn certify(
    catalogue: &Catalogue,
    run: CertifyRun<'_>,
    out: &Path,
    key: Option<&Path>,
) -> Result<ExitCode, Stop> {
    let CertifyRun {
        profile_names,
        iut,
        side,
        product,
        seed,
    } = run;
    // A certificate vouches for a named product: it must name what it
    // tested, never sign canif's own built-in implementation by default.
    if let (Some(product), None) = (&product, &iut.iut) {
        return Err(stop!(
            "--product \"{}\" names what the certificate vouches for: say which implementation that is with --iut \
             (exec:'COMMAND', lib:PATH, ethercat:…), or --iut softdevice / --iut reference to certify canif's own on purpose",
            product.name
        ));
    }
    let profiles = profiles(catalogue, profile_names)?;
    if let Some(key) = key {
        // A key that cannot sign is found out before the run, not after it.
        if let Err(error) = certificate::sign(b"", key) {
            return Err(stop!("--key {error}"));
        }
    }
    let report = match side {
        canif_spec::Side::Device => {
            let kind = iut_kind(iut)?;
            // What the device declares on the command line: the certificate rests on it.
            let declared = declared(&iut.declare)?;
            let options = Options {
                seed,
                declared,
                ..Options::default()
            };
            let plan = Plan::new(profiles, options, product)?;
            plan.run(catalogue, &kind, &Progress::new(catalogue))?
        }
        canif_spec::Side::Plc => {
            let kind = client_kind(iut)?;
            // What the client declares, on the command line and of itself.
            let declared = declared(&iut.declare)?;
            let options = ClientOptions {
                declared: Ok(declared),
                ..ClientOptions::new(seed)
            }
            .declared_by(&kind);
            let plan = Plan::new(profiles, options, product)?;
            plan.run(catalogue, &kind, &Progress::new(catalogue))?
        }
    };
    let code = finish(catalogue, &report, &out.join("run"));
    write_certificate(catalogue, &report, out, key)?;
    code
}

/// certificate.json, .html and (with a key) .json.sig of a run's report, in `out`.
pub(crate) fn write_certificate(
    catalogue: &Catalogue,
    report: &canif_harness::report::RunReport,
    out: &Path,
    key: Option<&Path>,
) -> Result<(), Stop> {
    let mut cert = Certificate::of(report);
    // The signer is named inside what it signs, so that the page and the
    // JSON say whose key vouches for them.
    if let Some(key) = key {
        cert.signer = Some(certificate::signer(key).map_err(|e| stop!("--key {e}"))?);
    }
    let page = certificate::html(&cert, catalogue);
    cert.html_sha256 = certificate::sha256_hex(page.as_bytes());
    let bytes = cert.canonical();
    let json = out.join("certificate.json");
    let sig = out.join("certificate.json.sig");
    let written = std::fs::create_dir_all(out)
        .and_then(|()| std::fs::write(out.join("certificate.html"), &page))
        .and_then(|()| std::fs::write(&json, &bytes));
    if let Err(error) = written {
        return Err(stop!(
            "cannot write the certificate to {}: {error}",
            out.display()
        ));
    }
    match key {
        Some(key) => match certificate::sign(&bytes, key).map(|s| std::fs::write(&sig, s)) {
            Ok(Ok(())) => sayln!(
                "certificate: {} — signed by {} in {}; check it without canif:\n  {}",
                if cert.conforms {
                    "CONFORMS"
                } else {
                    "DOES NOT CONFORM"
                },
                cert.signer
                    .as_ref()
                    .map_or_else(String::new, ToString::to_string),
                sig.display(),
                ssh_keygen_command(&json)
            ),
            Ok(Err(error)) => {
                return Err(stop!("cannot write {}: {error}", sig.display()));
            }
            Err(error) => {
                return Err(stop!("--key {error}"));
            }
        },
        None => {
            // A stale signature beside a new certificate would verify nothing.
            let _ = std::fs::remove_file(&sig);
            sayln!(
                "certificate: {} — UNSIGNED (no --key): anyone could have written {}",
                if cert.conforms {
                    "CONFORMS"
                } else {
                    "DOES NOT CONFORM"
                },
                json.display()
            );
        }
    }
    Ok(())
}

/// `certify --verify CERT --pubkey KEY.pub`: the signature, and the HTML's hash.
pub(crate) fn verify_certificate(path: &Path, pubkey: &Path) -> Result<ExitCode, Stop> {
    let bytes = match std::fs::read(path) {
        Ok(bytes) => bytes,
        Err(error) => {
            return Err(stop!("{}: {error}", path.display()));
        }
    };
    let cert = match Certificate::parse(&bytes) {
        Ok(cert) => cert,
        Err(error) => {
            return Err(stop!("{}: {error}", path.display()));
        }
    };
    let sig_path = path.with_extension("json.sig");
    let Ok(signature) = std::fs::read_to_string(&sig_path) else {
        sayln!(
            "{}: UNSIGNED — there is no {} beside it",
            path.display(),
            sig_path.display()
        );
        return Ok(ExitCode::from(1));
    };
    match certificate::verify(&bytes, &signature, pubkey) {
        Ok(fingerprint) => {
            let html = path.with_file_name("certificate.html");
            let page = match std::fs::read(&html) {
                Ok(page) if certificate::sha256_hex(&page) == cert.html_sha256 => {
                    "the HTML beside it matches".to_string()
                }
                Ok(_) => {
                    sayln!(
                        "{}: the signature is good, but {} is not the page it was signed with",
                        path.display(),
                        html.display()
                    );
                    return Ok(ExitCode::from(1));
                }
                Err(_) => format!("no {} to check", html.display()),
            };
            let by = match &cert.signer {
                Some(signer) if signer.fingerprint == fingerprint => signer.to_string(),
                _ => fingerprint,
            };
            sayln!(
                "{}: good signature by {by}; {}, {} on {}; {page}",
                path.display(),
                if cert.conforms {
                    "CONFORMS"
                } else {
                    "DOES NOT CONFORM"
                },
                cert.iut,
                cert.profiles.join(", ")
            );
            Ok(ExitCode::SUCCESS)
        }
        Err(error) => {
            sayln!("{}: {error}", path.display());
            if let certificate::SignatureError::DoesNotVerify(_) = error {
                say_what_changed(path, &cert);
            }
            Ok(ExitCode::from(1))
        }
    }
}

/// For a certificate that changed after it was signed: what differs from
/// the run report it was made from (`run/report.json` beside it).
fn say_what_changed(path: &Path, cert: &Certificate) {
    let run = path.with_file_name("run").join("report.json");
    let Some(report) = std::fs::read_to_string(&run)
        .ok()
        .and_then(|text| ReportFile::parse(&text).ok())
    else {
        sayln!("  (no {} beside it to tell what changed)", run.display());
        return;
    };
    let changes = certificate::differences_from_run(cert, &report);
    if changes.is_empty() {
        sayln!(
            "  its verdicts still match {}: what changed is elsewhere in it (a field the run does not hold)",
            run.display()
        );
    }
    for change in changes.iter().take(20) {
        sayln!("  changed: {change}");
    }
}

pub(crate) fn compare(
    base: &Path,
    new: &Path,
    options: CompareOptions,
    format: CompareFormat,
    out: &mut String,
) -> Result<ExitCode, Stop> {
    let load = |path: &Path| -> Result<ReportFile, String> {
        let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
        ReportFile::parse(&text).map_err(|e| format!("{}: {e}", path.display()))
    };
    let (base, new) = (
        load(base).map_err(|e| stop!("{e}"))?,
        load(new).map_err(|e| stop!("{e}"))?,
    );
    let comparison = canif_harness::compare::compare(&base, &new, options).map_err(|mismatches| {
        let listed: String = mismatches.iter().map(|m| format!("\n  {m}")).collect();
        stop!("the two reports do not describe the same run (--force compares them anyway):{listed}")
    })?;
    match format {
        CompareFormat::Markdown => out.push_str(&comparison.markdown()),
        CompareFormat::Json => {
            out.push_str(&serde_json::to_string_pretty(&comparison).unwrap_or_default());
            out.push('\n');
        }
    }
    Ok(ExitCode::from(u8::from(comparison.regressed())))
}
