//! A certificate of a run: what ran, against which catalogue, by which canif,
//! for which product, and every requirement's verdict with its reason — as
//! canonical JSON, signed with an OpenSSH Ed25519 key in the SSH signature
//! format (SSHSIG), so that `ssh-keygen -Y verify` checks it without canif.

use std::collections::BTreeMap;
use std::path::Path;

use canif_spec::Side;
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};
use ssh_key::{HashAlg, LineEnding, PrivateKey, PublicKey, SshSig};

use crate::report::{Product, RunReport, SuiteKind, TotalsEntry};
use crate::verdict::VerdictKind;

/// The namespace of canif's signatures (`ssh-keygen -Y … -n`): a signature
/// made for anything else does not verify as a certificate.
pub const NAMESPACE: &str = "canif-certificate";

/// SHA-256 as lower-case hex.
pub fn sha256_hex(bytes: &[u8]) -> String {
    Sha256::digest(bytes)
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

/// One requirement's verdict on one profile, as certified.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct CertifiedVerdict {
    pub evidence: Vec<String>,
    pub reason: Option<String>,
    pub verdict: VerdictKind,
}

/// What is signed. Fields are in alphabetical order, maps are sorted, and
/// the file is written without whitespace: one run gives one byte string.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Certificate {
    /// The bus the run used, with the kernel when it was SocketCAN.
    #[serde(default)]
    pub bus: String,
    pub canif_commit: String,
    pub canif_version: String,
    pub catalogue_sha256: String,
    pub certificate: String,
    /// The choices the documents leave that the verdicts rest on: declared,
    /// or shown by the device where it declared none.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub choices: Vec<String>,
    pub conforms: bool,
    /// When the run started, RFC 3339 in UTC.
    pub date: String,
    /// SHA-256 of `certificate.html` written beside it.
    pub html_sha256: String,
    pub iut: String,
    /// What the run left out and why: a certificate of an incomplete run does
    /// not conform, and says what is missing.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub left_out: Option<String>,
    /// What the profiles offer and the implementation declares it does not
    /// serve, `profile: what — why`: never run, never certified.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub not_served: Vec<String>,
    /// The EtherCAT master models a PLC-side run drove the client under.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub masters: Vec<String>,
    pub product: Option<Product>,
    pub profiles: Vec<String>,
    pub seed: u64,
    pub side: Side,
    /// The key that signs it, named inside what it signs.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub signer: Option<Signer>,
    pub suite: SuiteKind,
    pub totals: TotalsEntry,
    /// Keyed `profile::REQ-ID`.
    pub verdicts: BTreeMap<String, CertifiedVerdict>,
}

/// Who signed a certificate: the key's SHA-256 fingerprint (as `ssh-keygen
/// -l` prints it) and its comment (`ssh-keygen -C`, often user@host).
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Signer {
    pub comment: String,
    pub fingerprint: String,
}

impl std::fmt::Display for Signer {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.comment.is_empty() {
            true => f.write_str(&self.fingerprint),
            false => write!(f, "{} ({})", self.fingerprint, self.comment),
        }
    }
}

impl Certificate {
    /// The certificate of `report`; `html_sha256` is filled in once the page is written.
    pub fn of(report: &RunReport) -> Self {
        let m = &report.meta;
        Certificate {
            bus: m.bus.clone(),
            canif_commit: m.canif_commit.clone(),
            canif_version: m.canif_version.clone(),
            catalogue_sha256: m.catalogue_sha256.clone(),
            certificate: "canif conformance certificate".into(),
            choices: m.choices.iter().map(ToString::to_string).collect(),
            conforms: report.exit_code() == 0 && m.complete,
            date: crate::report::utc(m.started_unix),
            html_sha256: String::new(),
            iut: m.iut.clone(),
            left_out: (!m.complete).then(|| {
                m.left_out
                    .clone()
                    .unwrap_or_else(|| "interrupted".to_string())
            }),
            masters: m.masters.clone(),
            not_served: report.not_served(),
            product: m.product.clone(),
            profiles: report.profiles.iter().map(|p| p.profile.clone()).collect(),
            seed: m.seed,
            side: m.side,
            signer: None,
            suite: m.suite,
            totals: TotalsEntry::of(&report.totals()),
            verdicts: report
                .profiles
                .iter()
                .flat_map(|p| {
                    p.verdicts.iter().map(move |(id, v)| {
                        (
                            format!("{}::{id}", p.profile),
                            CertifiedVerdict {
                                evidence: v.evidence().iter().map(|e| e.key()).collect(),
                                reason: v.reason(),
                                verdict: v.kind(),
                            },
                        )
                    })
                })
                .collect(),
        }
    }

    /// The canonical bytes: compact JSON with every object's keys sorted, and a newline.
    pub fn canonical(&self) -> Vec<u8> {
        // serde_json's Value keeps objects in a BTreeMap: sorted at every depth.
        let value = serde_json::to_value(self).expect("a certificate is plain data");
        let mut bytes = serde_json::to_vec(&value).expect("a certificate is plain data");
        bytes.push(b'\n');
        bytes
    }

    pub fn parse(bytes: &[u8]) -> Result<Self, String> {
        serde_json::from_slice(bytes).map_err(|e| format!("not a canif certificate: {e}"))
    }
}

/// Why a certificate cannot be signed or verified.
#[derive(Debug)]
pub enum SignatureError {
    /// The key file cannot be read at all (missing, a folder, no permission).
    Unreadable {
        path: String,
        cause: String,
    },
    Key {
        path: String,
        cause: String,
    },
    Encrypted(String),
    NotEd25519(String),
    Signature(String),
    /// The certificate changed after it was signed (the key is the signer's).
    DoesNotVerify(String),
    /// The signature is another key's than the one given.
    OtherKey {
        signed_by: String,
        given: String,
    },
}

impl std::fmt::Display for SignatureError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            SignatureError::Unreadable { path, cause } => write!(f, "{path}: cannot read the key file: {cause}"),
            SignatureError::Key { path, cause } => write!(f, "{path}: not an OpenSSH key: {cause}"),
            SignatureError::Encrypted(path) => write!(f, "{path}: the key is encrypted; canif signs with an unencrypted key (ssh-keygen -t ed25519 -N '')"),
            SignatureError::NotEd25519(path) => write!(f, "{path}: certificates are signed with Ed25519 keys (ssh-keygen -t ed25519)"),
            SignatureError::Signature(cause) => write!(f, "not an SSH signature: {cause}"),
            SignatureError::DoesNotVerify(cause) => write!(f, "the signature does not verify: the certificate changed after it was signed ({cause})"),
            SignatureError::OtherKey { signed_by, given } => write!(f, "signed by the key {signed_by}, not by the one given ({given})"),
        }
    }
}

impl std::error::Error for SignatureError {}

/// Signs `bytes` with the OpenSSH Ed25519 private key at `key`: an armored SSHSIG.
pub fn sign(bytes: &[u8], key: &Path) -> Result<String, SignatureError> {
    let path = key.display().to_string();
    let key = PrivateKey::from_openssh(read_key(key)?).map_err(|e| SignatureError::Key {
        path: path.clone(),
        cause: e.to_string(),
    })?;
    if key.is_encrypted() {
        return Err(SignatureError::Encrypted(path));
    }
    if key.algorithm() != ssh_key::Algorithm::Ed25519 {
        return Err(SignatureError::NotEd25519(path));
    }
    key.sign(NAMESPACE, HashAlg::Sha512, bytes)
        .and_then(|sig| sig.to_pem(LineEnding::LF))
        .map_err(|e| SignatureError::Signature(e.to_string()))
}

/// The text of the key file at `path`, or why it cannot be read.
fn read_key(path: &Path) -> Result<String, SignatureError> {
    std::fs::read_to_string(path).map_err(|e| SignatureError::Unreadable {
        path: path.display().to_string(),
        cause: e.to_string(),
    })
}

/// Checks an armored SSHSIG over `bytes` against the public key at `pubkey`
/// (an `ssh-ed25519 …` line); returns the key's SHA-256 fingerprint.
pub fn verify(bytes: &[u8], signature: &str, pubkey: &Path) -> Result<String, SignatureError> {
    let path = pubkey.display().to_string();
    let key = PublicKey::from_openssh(&read_key(pubkey)?).map_err(|e| SignatureError::Key {
        path,
        cause: e.to_string(),
    })?;
    let signature =
        SshSig::from_pem(signature).map_err(|e| SignatureError::Signature(e.to_string()))?;
    let given = key.fingerprint(HashAlg::Sha256).to_string();
    // The signature names the key that made it: a wrong key is told apart
    // from a certificate that changed.
    let signed_by = signature
        .public_key()
        .fingerprint(HashAlg::Sha256)
        .to_string();
    if signed_by != given {
        return Err(SignatureError::OtherKey { signed_by, given });
    }
    key.verify(NAMESPACE, bytes, &signature)
        .map_err(|e| SignatureError::DoesNotVerify(e.to_string()))?;
    Ok(given)
}

/// The signer the private key at `key` makes: its fingerprint and comment.
pub fn signer(key: &Path) -> Result<Signer, SignatureError> {
    let path = key.display().to_string();
    let key = PrivateKey::from_openssh(read_key(key)?).map_err(|e| SignatureError::Key {
        path,
        cause: e.to_string(),
    })?;
    Ok(Signer {
        comment: key.comment().to_string(),
        fingerprint: key.public_key().fingerprint(HashAlg::Sha256).to_string(),
    })
}

/// What differs between a certificate and the run report it was made from
/// (`run/report.json` beside it): what an edit changed, for a certificate
/// whose signature no longer verifies. Keys as the certificate's.
pub fn differences_from_run(
    certificate: &Certificate,
    run: &crate::report::ReportFile,
) -> Vec<String> {
    let mut found = Vec::new();
    if certificate.iut != run.meta.iut {
        found.push(format!(
            "implementation: `{}` in the certificate, `{}` in the run",
            certificate.iut, run.meta.iut
        ));
    }
    let mut in_run = BTreeMap::new();
    for profile in &run.profiles {
        for (id, verdict) in &profile.verdicts {
            in_run.insert(format!("{}::{id}", profile.profile), verdict.verdict);
        }
    }
    for (key, verdict) in &certificate.verdicts {
        match in_run.remove(key) {
            Some(kind) if kind == verdict.verdict => {}
            Some(kind) => found.push(format!(
                "{key}: {} in the certificate, {} in the run",
                verdict.verdict.label(),
                kind.label()
            )),
            None => found.push(format!("{key}: in the certificate, not in the run")),
        }
    }
    found.extend(
        in_run
            .keys()
            .map(|key| format!("{key}: in the run, not in the certificate")),
    );
    let run_conforms = run
        .profiles
        .iter()
        .all(|p| p.verdicts.values().all(|v| !v.verdict.is_bad()));
    if certificate.conforms && !run_conforms {
        found.push(
            "conforms: true in the certificate, but the run has a failure or an error".into(),
        );
    }
    found
}

/// The certificate for people: one self-contained page.
pub fn html(certificate: &Certificate, catalogue: &canif_spec::Catalogue) -> String {
    let esc = |s: &str| {
        s.replace('&', "&amp;")
            .replace('<', "&lt;")
            .replace('>', "&gt;")
    };
    let mut rows = String::new();
    for profile in &certificate.profiles {
        for requirement in catalogue.requirements() {
            let Some(v) = certificate
                .verdicts
                .get(&format!("{profile}::{}", requirement.id))
            else {
                continue;
            };
            rows.push_str(&format!(
                "<tr class=\"{}\"><td>{profile}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>\n",
                v.verdict.label().replace(' ', "-"),
                requirement.id,
                v.verdict.label(),
                esc(&requirement.statement),
                esc(v.reason.as_deref().unwrap_or("")),
                esc(&v.evidence.join("; "))
            ));
        }
    }
    let list = |what: &str, lines: &[String]| match lines.is_empty() {
        true => String::new(),
        false => format!(
            "<tr><th>{what}</th><td>{}</td></tr>",
            lines
                .iter()
                .map(|l| esc(l))
                .collect::<Vec<_>>()
                .join("<br>")
        ),
    };
    let t = &certificate.totals;
    format!(
        r#"<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>canif certificate — {iut}</title>
<style>body{{font-family:sans-serif;margin:2em}} table{{border-collapse:collapse}} td,th{{border:1px solid #ccc;padding:2px 6px;vertical-align:top;text-align:left}}
.pass td:nth-child(3){{color:#070}} .fail td:nth-child(3),.error td:nth-child(3){{color:#b00;font-weight:bold}} .not-applicable,.not-testable,.not-run{{color:#777}}</style></head>
<body><h1>canif conformance certificate</h1>
<p><b>{verdict}</b> — <code>{iut}</code>{product}, {side} side, profiles {profiles}</p>
<table><tr><th>date</th><td>{date}</td></tr><tr><th>bus</th><td>{bus}</td></tr>{masters}{choices}{not_served}{left_out}<tr><th>canif</th><td>{version} ({commit})</td></tr>
<tr><th>catalogue SHA-256</th><td><code>{catalogue}</code></td></tr>{sources}<tr><th>seed</th><td>{seed}</td></tr>
<tr><th>signed by</th><td>{signer}</td></tr>
<tr><th>totals</th><td>{pass} pass, {fail} fail, {error} error, {na} not applicable, {nr} not run, {nt} not testable</td></tr></table>
<p>certificate.json carries this page's SHA-256 and is signed in certificate.json.sig; see docs/certificates.md for checking it with <code>ssh-keygen -Y verify</code>.</p>
<table><tr><th>profile</th><th>requirement</th><th>verdict</th><th>statement</th><th>reason</th><th>evidence</th></tr>
{rows}</table></body></html>
"#,
        iut = esc(&certificate.iut),
        // The documents by title and edition, each with the file it is kept in.
        sources = list(
            "sources",
            &catalogue
                .sources
                .iter()
                .map(|s| format!("{} ({})", s.title, s.file))
                .collect::<Vec<_>>()
        ),
        product = certificate
            .product
            .as_ref()
            .map_or(String::new(), |p| format!(
                " ({} {})",
                esc(&p.name),
                esc(&p.version)
            )),
        side = esc(certificate.side.as_str()),
        profiles = esc(&certificate.profiles.join(", ")),
        date = esc(&certificate.date),
        bus = esc(&certificate.bus),
        masters = if certificate.masters.is_empty() {
            String::new()
        } else {
            format!(
                "<tr><th>masters</th><td>{}</td></tr>",
                esc(&certificate.masters.join(", "))
            )
        },
        choices = list("declared (the verdicts rest on it)", &certificate.choices),
        not_served = list("not served (not run)", &certificate.not_served),
        left_out = certificate
            .left_out
            .as_ref()
            .map_or(String::new(), |l| format!(
                "<tr><th>left out</th><td>{}</td></tr>",
                esc(l)
            )),
        version = esc(&certificate.canif_version),
        commit = esc(&certificate.canif_commit),
        catalogue = esc(&certificate.catalogue_sha256),
        seed = certificate.seed,
        signer = certificate.signer.as_ref().map_or_else(
            || "nobody: unsigned".to_string(),
            |s| format!("<code>{}</code>", esc(&s.to_string()))
        ),
        pass = t.pass,
        fail = t.fail,
        error = t.error,
        na = t.not_applicable,
        nr = t.not_run,
        nt = t.not_testable,
        verdict = if certificate.conforms {
            "CONFORMS"
        } else {
            "DOES NOT CONFORM"
        },
    )
}
