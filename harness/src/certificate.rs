//! A certificate of one profile's run: what was run, against which catalogue,
//! and every requirement's verdict, sealed with a SHA-256 over the result.
//!
//! The seal shows that the file was not changed after it was written (an
//! edited verdict no longer matches). It is not a signature: whoever can run
//! canif can write a new certificate, so a customer checks the seal and, for
//! trust in the run itself, re-runs `canif certify` with the same seed.

use serde_json::{json, Value};
use sha2::{Digest, Sha256};

use canif_spec::Catalogue;

use crate::suite::{ProfileRun, Verdict};

fn sha256_hex(bytes: &[u8]) -> String {
    Sha256::digest(bytes)
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

/// SHA-256 over the catalogue's files as embedded (path and text of each, in order).
pub fn catalogue_hash(files: &[(String, String)]) -> String {
    let mut hasher = Sha256::new();
    for (path, text) in files {
        hasher.update(path.as_bytes());
        hasher.update([0]);
        hasher.update(text.as_bytes());
        hasher.update([0]);
    }
    hasher
        .finalize()
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

fn verdict_word(verdict: &Verdict) -> &'static str {
    match verdict {
        Verdict::Pass => "pass",
        Verdict::Fail(_) => "fail",
        Verdict::Error(_) => "error",
        Verdict::NotApplicable(_) => "not applicable",
        Verdict::NotTestable(_) => "not testable",
    }
}

/// The certificate as JSON, sealed.
pub fn certificate(
    catalogue: &Catalogue,
    catalogue_sha256: &str,
    run: &ProfileRun,
    iut: &str,
    seed: u64,
    scenarios: (usize, usize),
) -> Value {
    let verdicts: serde_json::Map<String, Value> = catalogue
        .requirements()
        .filter_map(|r| {
            run.verdicts
                .get(&r.id)
                .map(|v| (r.id.clone(), json!(verdict_word(v))))
        })
        .collect();
    let count = |word: &str| verdicts.values().filter(|v| *v == word).count();
    let conforms = count("fail") == 0 && count("error") == 0 && scenarios.1 == 0;
    let mut body = json!({
        "certificate": "canif conformance certificate",
        "harness_version": env!("CARGO_PKG_VERSION"),
        "catalogue_sha256": catalogue_sha256,
        "profile": run.profile,
        "iut": iut,
        "seed": seed,
        "conforms": conforms,
        "totals": {
            "pass": count("pass"), "fail": count("fail"), "error": count("error"),
            "not applicable": count("not applicable"), "not testable": count("not testable"),
            "scenarios run": scenarios.0, "scenarios failed": scenarios.1,
        },
        "cycles": run.cycles(),
        "frames_checked": run.frames_checked(),
        "verdicts": verdicts,
    });
    let seal = sha256_hex(serde_json::to_string(&body).unwrap_or_default().as_bytes());
    body["result_sha256"] = json!(seal);
    body
}

/// Does the seal match the rest of the certificate?
pub fn verify(certificate: &Value) -> Result<(), String> {
    let mut body = certificate.clone();
    let claimed = body
        .as_object_mut()
        .and_then(|o| o.remove("result_sha256"))
        .ok_or("no result_sha256: not a canif certificate")?;
    let actual = sha256_hex(serde_json::to_string(&body).unwrap_or_default().as_bytes());
    if claimed.as_str() == Some(actual.as_str()) {
        Ok(())
    } else {
        Err(format!("the seal does not match: the certificate says {claimed}, its content hashes to {actual}"))
    }
}

/// The certificate for people: one self-contained page.
pub fn html(certificate: &Value, catalogue: &Catalogue) -> String {
    let esc = |s: &str| {
        s.replace('&', "&amp;")
            .replace('<', "&lt;")
            .replace('>', "&gt;")
    };
    let mut rows = String::new();
    for requirement in catalogue.requirements() {
        let Some(verdict) = certificate["verdicts"][&requirement.id].as_str() else {
            continue;
        };
        rows.push_str(&format!(
            "<tr class=\"{}\"><td>{}</td><td>{}</td><td>{}</td></tr>\n",
            verdict.replace(' ', "-"),
            requirement.id,
            esc(verdict),
            esc(&requirement.statement)
        ));
    }
    let field = |name: &str| esc(certificate[name].to_string().trim_matches('"'));
    format!(
        r#"<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>canif certificate — {profile}</title>
<style>body{{font-family:sans-serif;margin:2em}} table{{border-collapse:collapse}} td,th{{border:1px solid #ccc;padding:2px 6px;vertical-align:top}}
.pass td:nth-child(2){{color:#070}} .fail td:nth-child(2),.error td:nth-child(2){{color:#b00;font-weight:bold}} .not-applicable,.not-testable{{color:#777}}</style></head>
<body><h1>canif conformance certificate</h1>
<p><b>{verdict}</b> — profile <b>{profile}</b>, implementation <code>{iut}</code>, seed {seed}</p>
<table><tr><th>harness version</th><td>{version}</td></tr><tr><th>catalogue SHA-256</th><td><code>{catalogue}</code></td></tr>
<tr><th>totals</th><td>{totals}</td></tr><tr><th>result SHA-256</th><td><code>{seal}</code></td></tr></table>
<p>Check the seal with <code>canif certify --verify certificate.json</code>.</p>
<table><tr><th>requirement</th><th>verdict</th><th>statement</th></tr>
{rows}</table></body></html>
"#,
        profile = field("profile"),
        iut = field("iut"),
        seed = field("seed"),
        version = field("harness_version"),
        catalogue = field("catalogue_sha256"),
        totals = esc(&certificate["totals"].to_string()),
        seal = field("result_sha256"),
        verdict = if certificate["conforms"] == json!(true) {
            "CONFORMS"
        } else {
            "DOES NOT CONFORM"
        },
    )
}
