//! `canif certify` and `canif compare`: what a certifier signs and a CI gate checks.

use std::path::Path;
use std::process::ExitCode;

use canif_harness::certificate::{self, Certificate};
use canif_harness::compare::CompareOptions;
use canif_harness::device::suite::Options;
use canif_harness::report::{Product, ReportFile};
use canif_spec::Catalogue;

use canif_harness::client::suite::ClientOptions;

use super::run::{device, finish, plc, profiles, Plan};
use super::{client_declaration, declared_choices, resolve_client, resolve_iut};
use crate::cli::{CompareFormat, IutOptions, SideArg};

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
    pub side: SideArg,
    pub product: Option<Product>,
    pub seed: u64,
}

pub(crate) fn certify(
    catalogue: &Catalogue,
    run: CertifyRun<'_>,
    out: &Path,
    key: Option<&Path>,
) -> ExitCode {
    let CertifyRun {
        profile_names,
        iut,
        side,
        product,
        seed,
    } = run;
    let profiles = match profiles(catalogue, profile_names) {
        Ok(p) => p,
        Err(code) => return code,
    };
    if let Some(key) = key {
        // A key that cannot sign is found out before the run, not after it.
        if let Err(error) = certificate::sign(b"", key) {
            errln!("--key {error}");
            return ExitCode::from(2);
        }
    }
    let report = match side {
        SideArg::Device => {
            let kind = match resolve_iut(iut) {
                Ok(kind) => kind,
                Err(code) => return code,
            };
            // What the device declares on the command line: the certificate rests on it.
            let declared = match declared_choices(&iut.declare) {
                Ok(declared) => declared,
                Err(code) => return code,
            };
            let options = Options {
                seed,
                declared,
                ..Options::default()
            };
            let plan = match Plan::new(profiles, options, product) {
                Ok(plan) => plan,
                Err(code) => return code,
            };
            if let Err(code) = plan.check_selection(catalogue) {
                return code;
            }
            device::execute(
                catalogue,
                &kind,
                &plan,
                canif_harness::door::ethercat::Pace::Unpaced(device::SURVEY_CYCLES),
            )
        }
        SideArg::Plc => {
            let kind = match resolve_client(iut) {
                Ok(kind) => kind,
                Err(code) => return code,
            };
            // What the client declares, on the command line and of itself.
            let declared = match client_declaration(&iut.declare) {
                Ok(declared) => declared,
                Err(code) => return code,
            };
            let options = ClientOptions {
                declared: Ok(declared),
                ..ClientOptions::new(seed)
            }
            .declared_by(&kind);
            let plan = match Plan::new(profiles, options, product) {
                Ok(plan) => plan,
                Err(code) => return code,
            };
            plc::execute(catalogue, &kind, &plan)
        }
    };
    let code = finish(catalogue, &report, &out.join("run"));
    let mut cert = Certificate::of(&report);
    let page = certificate::html(&cert, catalogue);
    cert.html_sha256 = certificate::sha256_hex(page.as_bytes());
    let bytes = cert.canonical();
    let json = out.join("certificate.json");
    let sig = out.join("certificate.json.sig");
    let written = std::fs::create_dir_all(out)
        .and_then(|()| std::fs::write(out.join("certificate.html"), &page))
        .and_then(|()| std::fs::write(&json, &bytes));
    if let Err(error) = written {
        errln!("cannot write the certificate to {}: {error}", out.display());
        return ExitCode::from(2);
    }
    match key {
        Some(key) => match certificate::sign(&bytes, key).map(|s| std::fs::write(&sig, s)) {
            Ok(Ok(())) => sayln!(
                "certificate: {} — signed in {}; check it without canif:\n  {}",
                if cert.conforms {
                    "CONFORMS"
                } else {
                    "DOES NOT CONFORM"
                },
                sig.display(),
                ssh_keygen_command(&json)
            ),
            Ok(Err(error)) => {
                errln!("cannot write {}: {error}", sig.display());
                return ExitCode::from(2);
            }
            Err(error) => {
                errln!("--key {error}");
                return ExitCode::from(2);
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
    code
}

/// `certify --verify CERT --pubkey KEY.pub`: the signature, and the HTML's hash.
pub(crate) fn verify_certificate(path: &Path, pubkey: &Path) -> ExitCode {
    let bytes = match std::fs::read(path) {
        Ok(bytes) => bytes,
        Err(error) => {
            errln!("{}: {error}", path.display());
            return ExitCode::from(2);
        }
    };
    let cert = match Certificate::parse(&bytes) {
        Ok(cert) => cert,
        Err(error) => {
            errln!("{}: {error}", path.display());
            return ExitCode::from(2);
        }
    };
    let sig_path = path.with_extension("json.sig");
    let Ok(signature) = std::fs::read_to_string(&sig_path) else {
        sayln!(
            "{}: UNSIGNED — there is no {} beside it",
            path.display(),
            sig_path.display()
        );
        return ExitCode::from(1);
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
                    return ExitCode::from(1);
                }
                Err(_) => format!("no {} to check", html.display()),
            };
            sayln!(
                "{}: good signature by {fingerprint}; {}, {} on {}; {page}",
                path.display(),
                if cert.conforms {
                    "CONFORMS"
                } else {
                    "DOES NOT CONFORM"
                },
                cert.iut,
                cert.profiles.join(", ")
            );
            ExitCode::SUCCESS
        }
        Err(error) => {
            sayln!("{}: {error}", path.display());
            ExitCode::from(1)
        }
    }
}

pub(crate) fn compare(
    base: &Path,
    new: &Path,
    options: CompareOptions,
    format: CompareFormat,
    out: &mut String,
) -> ExitCode {
    let load = |path: &Path| -> Result<ReportFile, String> {
        let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
        ReportFile::parse(&text).map_err(|e| format!("{}: {e}", path.display()))
    };
    let (base, new) = match (load(base), load(new)) {
        (Ok(base), Ok(new)) => (base, new),
        (Err(e), _) | (_, Err(e)) => {
            errln!("{e}");
            return ExitCode::from(2);
        }
    };
    let comparison = match canif_harness::compare::compare(&base, &new, options) {
        Ok(comparison) => comparison,
        Err(mismatches) => {
            errln!("the two reports do not describe the same run (--force compares them anyway):");
            for mismatch in mismatches {
                errln!("  {mismatch}");
            }
            return ExitCode::from(2);
        }
    };
    match format {
        CompareFormat::Markdown => out.push_str(&comparison.markdown()),
        CompareFormat::Json => {
            out.push_str(&serde_json::to_string_pretty(&comparison).unwrap_or_default());
            out.push('\n');
        }
    }
    ExitCode::from(u8::from(comparison.regressed()))
}
