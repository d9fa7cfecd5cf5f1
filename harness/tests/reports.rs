//! The reports a certifier reads and signs: verdicts that merge every check,
//! JUnit that a JUnit reader accepts with counts that match, a compare gate
//! that does not pass when checks vanish, a signed certificate that
//! `ssh-keygen` verifies, and an HTML page that draws the failing frame.

use std::path::{Path, PathBuf};
use std::process::Command;

use canif_harness::compare::{compare, CompareOptions};
use canif_harness::device::suite::Options;
use canif_harness::device::IutKind;
use canif_harness::report::{ProfileReport, ReportFile, RunMeta, RunReport};
use canif_harness::run::run_profile;
use canif_harness::verdict::Reach;
use canif_harness::{GherkinOutcome, GherkinRun, VerdictKind};
use canif_softdevice::Fault;
use canif_spec::Catalogue;

fn temp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("canif-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// One profile's lockstep run with `faults`, plus `gherkin`, as a report.
fn report(profile: &str, faults: Vec<Fault>, seed: u64, gherkin: Vec<GherkinRun>) -> RunReport {
    let catalogue = Catalogue::embedded().unwrap();
    let profile = catalogue.profile(profile).unwrap();
    let options = Options::quick(seed);
    let run = run_profile(
        profile,
        &IutKind::SoftDevice {
            faults,
            choices: vec![],
        },
        &options,
        |_| {},
    );
    let reach = Reach {
        here: canif_harness::device::suite::exercised(&profile.model_capabilities(), &options)
            .into_iter()
            .collect(),
        ..Reach::default()
    };
    RunReport {
        meta: RunMeta::new("softdevice".into(), "sim".into(), seed, &catalogue),
        profiles: vec![ProfileReport::new(
            &catalogue,
            profile,
            run,
            gherkin,
            Vec::new(),
            &reach,
        )],
        wall_time_ms: 1,
        interrupted: false,
        flaky: Vec::new(),
        part: None,
    }
}

fn gherkin(id: &str, requirements: &[&str], outcome: GherkinOutcome) -> GherkinRun {
    GherkinRun {
        id: id.into(),
        file: "x.feature".into(),
        line: 1,
        requirements: requirements.iter().map(|s| s.to_string()).collect(),
        outcome,
        elapsed: std::time::Duration::from_millis(3),
    }
}

fn json(report: &RunReport) -> ReportFile {
    report.json(&Catalogue::embedded().unwrap())
}

/// Problem 1: a failing Gherkin scenario fails the requirements it is tagged
/// with, even when every lockstep scenario passed them; a pass names evidence.
#[test]
fn a_failing_gherkin_scenario_fails_its_requirement() {
    let failing = gherkin(
        "fd-length.feature: padding",
        &["FD-LEN-003"],
        GherkinOutcome::Fail {
            step: "Then the padding bytes are 0x00: expected 00, got FF".into(),
            report: "✘ Then the padding bytes are 0x00".into(),
            rest: canif_harness::verdict::Rest::Stopped,
            blamed: vec!["FD-LEN-003".into()],
        },
    );
    let run = report("fc532x", vec![], 1, vec![failing]);
    let verdict = &run.profiles[0].verdicts["FD-LEN-003"];
    assert_eq!(verdict.kind(), VerdictKind::Fail);
    assert!(verdict.reason().unwrap().contains("expected 00, got FF"));
    assert_eq!(run.exit_code(), 1);
    let file = json(&run);
    let entry = &file.profiles[0].verdicts["HS-TX-001"];
    assert_eq!(entry.verdict, VerdictKind::Pass);
    assert!(
        entry.evidence.iter().any(|e| e.starts_with("scenario: ")),
        "a pass names the scenarios it rests on: {entry:?}"
    );
}

/// Problem 2: a run that exercised nothing is not "conforms".
#[test]
fn a_run_that_checked_nothing_does_not_conform() {
    let catalogue = Catalogue::embedded().unwrap();
    let profile = catalogue.profile("fc532x").unwrap();
    let options = Options {
        selection: canif_harness::run::Selection {
            scenarios: vec!["no-such-scenario-xyz".into()],
            requirements: vec![],
            shard: None,
        },
        ..Options::quick(1)
    };
    let run = run_profile(
        profile,
        &IutKind::SoftDevice {
            faults: vec![],
            choices: vec![],
        },
        &options,
        |_| {},
    );
    assert!(run.runs.is_empty());
    let reach = Reach {
        here: ["HS-TX-001".to_string()].into(),
        left_out: options.selection.not_run(),
        ..Reach::default()
    };
    let report = RunReport {
        meta: RunMeta {
            complete: false,
            left_out: Some(options.selection.describe()),
            ..RunMeta::new("softdevice".into(), "sim".into(), 1, &catalogue)
        },
        profiles: vec![ProfileReport::new(
            &catalogue,
            profile,
            run,
            vec![],
            vec![],
            &reach,
        )],
        wall_time_ms: 1,
        interrupted: false,
        flaky: Vec::new(),
        part: None,
    };
    assert_eq!(report.exit_code(), 2);
    assert_eq!(report.headline(), "NOTHING CHECKED");
    assert_eq!(
        report.profiles[0].verdicts["HS-TX-001"].kind(),
        VerdictKind::NotRun
    );
    // Its certificate does not conform, and says what was left out.
    let certificate = canif_harness::certificate::Certificate::of(&report);
    assert!(!certificate.conforms);
    assert_eq!(certificate.left_out, report.meta.left_out);
    assert!(certificate
        .left_out
        .is_some_and(|l| l.contains("no-such-scenario-xyz")));
}

#[test]
fn the_same_seed_gives_the_same_verdicts() {
    let strip = |mut file: ReportFile| {
        file.meta.started_unix = 0;
        for p in &mut file.profiles {
            for c in &mut p.checks {
                c.elapsed_ms = 0.0;
            }
        }
        serde_json::to_string(&file).unwrap()
    };
    let faults = || vec![Fault::HeadDropWhenFull];
    let first = strip(json(&report("el6751-mdp", faults(), 7, vec![])));
    assert_eq!(
        first,
        strip(json(&report("el6751-mdp", faults(), 7, vec![])))
    );
    assert_ne!(
        first,
        strip(json(&report("el6751-mdp", faults(), 8, vec![])))
    );
}

/// Problem 3: a gate that goes quietly green when checks vanish.
#[test]
fn compare_counts_vanished_checks_and_refuses_other_runs() {
    let base = json(&report("fc510x", vec![], 3, vec![]));
    let same = compare(&base, &base, CompareOptions::default()).unwrap();
    assert!(!same.regressed() && same.unchanged > 100);

    let mut fewer = base.clone();
    fewer.profiles[0].checks.truncate(1);
    for v in fewer.profiles[0]
        .verdicts
        .values_mut()
        .filter(|v| v.verdict == VerdictKind::Pass)
        .take(5)
    {
        v.verdict = VerdictKind::NotRun;
    }
    let gate = compare(&base, &fewer, CompareOptions::default()).unwrap();
    assert!(gate.regressed(), "checks that vanished stop the gate");
    assert!(gate.removed.len() >= 5);
    assert!(gate.markdown().contains("REGRESSED"));
    let allowed = compare(
        &base,
        &fewer,
        CompareOptions {
            allow_removed: true,
            force: false,
        },
    )
    .unwrap();
    assert!(!allowed.regressed());

    let mut empty = base.clone();
    empty.profiles.clear();
    let refused = compare(&base, &empty, CompareOptions::default()).unwrap_err();
    assert!(
        refused.iter().any(|m| m.starts_with("profiles")),
        "{refused:?}"
    );
    let forced = compare(
        &base,
        &empty,
        CompareOptions {
            allow_removed: false,
            force: true,
        },
    )
    .unwrap();
    assert!(forced.regressed() && !forced.forced_despite.is_empty());

    let mut other = base.clone();
    other.meta.iut = "exec:./other".into();
    assert!(compare(&base, &other, CompareOptions::default()).is_err());

    let mut value = serde_json::to_value(&base).unwrap();
    value.as_object_mut().unwrap().remove("format");
    let old = ReportFile::parse(&value.to_string()).unwrap_err();
    assert!(old.contains("format 1"), "{old}");
}

/// Problem 4: JUnit read back by a JUnit reader: counts match the cases,
/// names are `profile::REQ-ID`, a failure says expected and actual, and the
/// properties carry seed, catalogue hash and version.
#[test]
fn junit_is_read_back_with_matching_counts() {
    let run = report(
        "el6751-mdp",
        vec![Fault::OverwritesUnacknowledgedRx],
        2,
        vec![],
    );
    let catalogue = Catalogue::embedded().unwrap();
    let xml = run.junit(&catalogue).unwrap();
    let suites =
        junit_parser::from_reader(std::io::Cursor::new(xml.as_bytes())).expect("JUnit parses");
    let mut cases = 0;
    let mut failures = 0;
    for suite in &suites.suites {
        assert_eq!(suite.tests as usize, suite.cases.len(), "{}", suite.name);
        let failed = suite.cases.iter().filter(|c| c.status.is_failure()).count();
        assert_eq!(suite.failures as usize, failed, "{}", suite.name);
        cases += suite.cases.len();
        failures += failed;
        let props = &suite.properties.hashmap;
        assert_eq!(props.get("seed").map(String::as_str), Some("2"));
        assert_eq!(props.get("catalogue_sha256"), Some(&catalogue.sha256));
        assert!(props.contains_key("canif_version"));
    }
    assert_eq!(suites.tests as usize, cases);
    assert_eq!(suites.failures as usize, failures);
    assert!(failures > 0);
    let verdicts = &suites.suites[0];
    assert!(
        verdicts
            .cases
            .iter()
            .all(|c| c.original_name.starts_with("el6751-mdp::") && !c.original_name.contains(" ")),
        "{:?}",
        verdicts.cases[0].original_name
    );
    let failed = verdicts
        .cases
        .iter()
        .find(|c| c.status.is_failure())
        .unwrap();
    let text = &failed.status.failure_as_ref().text;
    assert!(
        text.contains("expected:") && text.contains("actual:"),
        "{text}"
    );
    assert!(
        suites.suites[1].cases.iter().any(|c| c.time > 0.0),
        "real times"
    );
}

/// A fresh Ed25519 key pair `dir/NAME`, `dir/NAME.pub`, with `comment`.
fn key_pair(dir: &Path, name: &str, comment: &str) -> std::path::PathBuf {
    let key = dir.join(name);
    let made = Command::new("ssh-keygen")
        .args(["-q", "-t", "ed25519", "-N", "", "-C", comment, "-f"])
        .arg(&key)
        .status()
        .expect("ssh-keygen (.ci/run installs openssh-client; elsewhere these tests are ignored without it)");
    assert!(made.success());
    key
}

fn external_verify(dir: &Path, certificate: &Path) -> bool {
    let allowed = dir.join("allowed_signers");
    let public = std::fs::read_to_string(dir.join("key.pub")).unwrap();
    std::fs::write(
        &allowed,
        format!("certifier namespaces=\"canif-certificate\" {public}"),
    )
    .unwrap();
    Command::new("ssh-keygen")
        .args(["-Y", "verify", "-f"])
        .arg(&allowed)
        .args(["-I", "certifier", "-n", "canif-certificate", "-s"])
        .arg(certificate.with_extension("json.sig"))
        .stdin(std::fs::File::open(certificate).unwrap())
        .output()
        .unwrap()
        .status
        .success()
}

/// Problem 5: the certificate is signed with Ed25519 (SSHSIG); ssh-keygen,
/// not canif, accepts the genuine one and rejects a tampered one.
#[test]
#[cfg_attr(
    canif_no_ssh_keygen,
    ignore = "ssh-keygen is not installed (apt-get install openssh-client; .ci/run does)"
)]
fn ssh_keygen_verifies_a_genuine_certificate_and_rejects_a_tampered_one() {
    use canif_harness::certificate::{sign, verify, Certificate};
    let dir = temp("certificate");
    let key = key_pair(&dir, "key", "certifier");
    let run = report("fc510x", vec![], 9, vec![]);
    let cert = Certificate::of(&run);
    assert_eq!(cert.catalogue_sha256, Catalogue::embedded().unwrap().sha256);
    assert!(cert
        .verdicts
        .values()
        .all(|v| v.verdict == VerdictKind::Pass || v.reason.is_some()));
    let bytes = cert.canonical();
    assert_eq!(
        Certificate::parse(&bytes).unwrap().canonical(),
        bytes,
        "canonical form is stable"
    );
    let path = dir.join("certificate.json");
    std::fs::write(&path, &bytes).unwrap();
    std::fs::write(path.with_extension("json.sig"), sign(&bytes, &key).unwrap()).unwrap();
    assert!(
        external_verify(&dir, &path),
        "ssh-keygen accepts the genuine certificate"
    );
    verify(
        &bytes,
        &std::fs::read_to_string(path.with_extension("json.sig")).unwrap(),
        &dir.join("key.pub"),
    )
    .unwrap();

    let text = String::from_utf8(bytes).unwrap();
    let tampered = text
        .replacen("\"conforms\":true", "\"conforms\":false", 1)
        .replacen("\"verdict\":\"pass\"", "\"verdict\":\"fail\"", 1);
    assert_ne!(tampered, text);
    std::fs::write(&path, &tampered).unwrap();
    assert!(
        !external_verify(&dir, &path),
        "ssh-keygen rejects a tampered certificate"
    );
    let sig = std::fs::read_to_string(path.with_extension("json.sig")).unwrap();
    assert!(verify(tampered.as_bytes(), &sig, &dir.join("key.pub")).is_err());
    let _ = std::fs::remove_dir_all(dir);
}

/// Problem 6: the failing frame is drawn in the failing cycle with its
/// differing bytes marked, in the page a browser renders.
/// The failing fc532x run's report.html, written into a folder of its own.
fn failing_page(name: &str) -> (std::path::PathBuf, String) {
    let run = report("fc532x", vec![Fault::FdPaddingFf], 2, vec![]);
    assert_eq!(run.exit_code(), 1);
    let dir = temp(name);
    run.write(&Catalogue::embedded().unwrap(), &dir).unwrap();
    let page = std::fs::read_to_string(dir.join("report.html")).unwrap();
    (dir, page)
}

#[test]
fn the_html_report_marks_the_failing_frame_and_loads_nothing() {
    let (dir, page) = failing_page("html");
    for needle in [
        "class=\"failing-cycle\"",
        "class=\"failing-frame\"",
        "class=\"failing-frame-bytes\"",
        "class=\"differs\"",
        "id=\"problems\"",
    ] {
        assert!(page.contains(needle), "{needle} is not in the page");
    }
    for external in ["src=\"http", "href=\"http", "@import"] {
        assert!(!page.contains(external), "the page loads {external}");
    }
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
#[cfg_attr(
    canif_no_chromium,
    ignore = "no Chromium on this machine (apt-get install chromium; .ci/run does)"
)]
fn the_html_report_draws_the_failing_frame_in_a_browser() {
    let (dir, _) = failing_page("browser");
    let browser = ["chromium", "chromium-browser", "google-chrome"]
        .into_iter()
        .find(|b| {
            Command::new(b)
                .arg("--version")
                .output()
                .is_ok_and(|o| o.status.success())
        })
        .expect("a Chromium (.ci/run installs it; elsewhere this test is ignored without one)");
    let out = Command::new(browser)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--disable-quic",
            "--no-first-run",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
        ])
        .arg(format!(
            "--user-data-dir={}",
            dir.join("browser-profile").display()
        ))
        .arg("--dump-dom")
        .arg(format!("file://{}", dir.join("report.html").display()))
        .output()
        .expect("the browser runs");
    let dom = String::from_utf8_lossy(&out.stdout);
    assert!(
        dom.contains("data-ready=\"yes\""),
        "the script did not finish: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(!dom.contains("data-errors"), "script errors in the page");
    assert!(
        dom.contains("failing-frame-bytes") && dom.contains("class=\"differs\""),
        "the failing frame's differing bytes are in the rendered page"
    );
    let _ = std::fs::remove_dir_all(dir);
}

/// Issue 36: every report names the documents by title and edition beside
/// the file a requirement's source cites.
#[test]
fn the_reports_name_each_document_by_title() {
    let catalogue = Catalogue::embedded().unwrap();
    let run = report("el6751-mdp", vec![], 1, vec![]);
    let title = "CAN-Interface manual, version 1.7 (Chinese; the later document)";
    let summary = run.summary(&catalogue);
    assert!(
        summary.contains(&format!("| {title} | `001_c68c573893220081.txt` |")),
        "{summary}"
    );
    assert!(run.html(&catalogue).contains(&format!(
        "<tr><td>{title}</td><td>001_c68c573893220081.txt</td></tr>"
    )));
    let certificate = canif_harness::certificate::Certificate::of(&run);
    let page = canif_harness::certificate::html(&certificate, &catalogue);
    assert!(
        page.contains(&format!("{title} (001_c68c573893220081.txt)")),
        "{page}"
    );
}

/// Issue 37: a key file that cannot be read is named with why, not "entity
/// not found".
#[test]
fn a_missing_key_file_is_named_with_why() {
    use canif_harness::certificate::{sign, verify};
    let missing = std::path::Path::new("/nonexistent/canif-key");
    let error = sign(b"x", missing).unwrap_err().to_string();
    assert!(
        error.starts_with("/nonexistent/canif-key: cannot read the key file: "),
        "{error}"
    );
    assert!(!error.contains("entity not found"), "{error}");
    let error = verify(b"x", "", missing).unwrap_err().to_string();
    assert!(error.contains("cannot read the key file"), "{error}");
}

/// Issue 37: a profile's zero fail and error counts are not drawn red; a
/// count that is not zero is.
#[test]
fn only_a_count_that_is_not_zero_is_coloured() {
    let catalogue = Catalogue::embedded().unwrap();
    let html = report("el6751-mdp", vec![], 1, vec![]).html(&catalogue);
    assert!(!html.contains("<td class=\"fail\">0</td>"), "{html}");
    assert!(!html.contains("<td class=\"error\">0</td>"), "{html}");
    assert!(html.contains("<td class=\"pass\">"), "{html}");
}

/// Issue 37: the verdicts are grouped by area, the areas with a failure
/// first and open, their failing rows before the folded passes, each row
/// with the requirement's text.
#[test]
fn verdicts_are_grouped_by_area_with_failures_first_and_passes_folded() {
    let catalogue = Catalogue::embedded().unwrap();
    let html = report("fc532x", vec![Fault::FdPaddingFf], 2, vec![]).html(&catalogue);
    let section = &html[html.find("<div id=\"verdicts\">").expect("the verdicts")..];
    let section = &section[..section.find("</div>").unwrap()];
    let folds: Vec<&str> = section.split("<details class=\"area\"").skip(1).collect();
    assert!(folds.len() > 5, "one fold per area");
    assert!(
        folds[0].starts_with(" open><summary>FD"),
        "{}",
        &folds[0][..80]
    );
    assert!(
        folds[0].contains("<span class=\"fail\">"),
        "the count says fail"
    );
    let fail_row = folds[0].find("<tr class=\"fail\">").expect("a failing row");
    let others = folds[0]
        .find("<details class=\"others\">")
        .expect("the passes folded");
    assert!(fail_row < others, "failures before the folded passes");
    assert!(
        folds[0].contains("Bytes added by rounding up are sent as 0x00"),
        "the statement inline"
    );
    let last = folds.last().unwrap();
    assert!(
        last.starts_with("><summary>"),
        "an area without failures is closed"
    );
    assert!(!last.contains("<tr class=\"fail\">"));
}

/// Issue 37: a failure in the input image shows the members that differ,
/// named as `canif export` declares them, with both values' bytes.
#[test]
fn an_image_failure_names_the_members_whose_bytes_differ() {
    let catalogue = Catalogue::embedded().unwrap();
    let run = report("fc510x", vec![Fault::CobIdWordBigEndian], 1, vec![]);
    let summary = run.summary(&catalogue);
    let line = summary
        .lines()
        .find(|l| l.contains("Inputs.RxMessage[0].CobID: expected"))
        .unwrap_or_else(|| panic!("no member diff in:\n{summary}"));
    // The word's two bytes, swapped: the fault writes the COB ID big-endian.
    let expected = line
        .split("expected ")
        .nth(1)
        .unwrap()
        .split(',')
        .next()
        .unwrap();
    let actual = line.split("actual ").nth(1).unwrap().trim();
    let swapped: Vec<&str> = expected.split(' ').rev().collect();
    assert_eq!(actual, swapped.join(" "), "{line}");
    assert!(line.trim_start().starts_with("byte 6..8 "), "{line}");
}

/// Issue 37: a regression is shown with its reason, as the new report gives it.
#[test]
fn compare_shows_each_regression_with_its_reason() {
    let base = json(&report("fc532x", vec![], 1, vec![]));
    let new = json(&report("fc532x", vec![Fault::FdPaddingFf], 1, vec![]));
    let forced = CompareOptions {
        allow_removed: false,
        force: true,
    };
    let gate = compare(&base, &new, forced).unwrap();
    let regression = gate
        .regressions
        .iter()
        .find(|c| c.check == "fc532x::FD-LEN-005")
        .expect("FD-LEN-005 regressed");
    let why = regression.why.as_deref().expect("a reason");
    assert!(
        why.contains("frame handed to the controller differs"),
        "{why}"
    );
    assert!(gate.markdown().contains(&format!("| fail | {why} |")));
}

/// Issue 37: the certificate names its signer's key inside what is signed,
/// and a failed verification says which went wrong: another key signed it,
/// or it changed after signing, and then what changed against its run.
#[test]
#[cfg_attr(
    canif_no_ssh_keygen,
    ignore = "ssh-keygen is not installed (apt-get install openssh-client; .ci/run does)"
)]
fn a_certificate_names_its_signer_and_a_failed_check_says_what_went_wrong() {
    use canif_harness::certificate::{
        differences_from_run, sign, signer, verify, Certificate, SignatureError,
    };
    let dir = temp("signer");
    let key = key_pair(&dir, "key", "lab@certifier");
    let other = key_pair(&dir, "other", "someone@else");
    let run = report("fc510x", vec![], 9, vec![]);
    let mut cert = Certificate::of(&run);
    cert.signer = Some(signer(&key).unwrap());
    let page = canif_harness::certificate::html(&cert, &Catalogue::embedded().unwrap());
    let named = cert.signer.clone().unwrap();
    assert!(named.fingerprint.starts_with("SHA256:") && named.comment == "lab@certifier");
    assert!(
        page.contains(&named.to_string()),
        "the page names the signer"
    );
    let bytes = cert.canonical();
    assert!(
        String::from_utf8_lossy(&bytes).contains("lab@certifier"),
        "signed with the rest"
    );
    let sig = sign(&bytes, &key).unwrap();
    assert_eq!(
        verify(&bytes, &sig, &dir.join("key.pub")).unwrap(),
        named.fingerprint
    );

    match verify(&bytes, &sig, &dir.join("other.pub")) {
        Err(SignatureError::OtherKey { signed_by, given }) => {
            assert_eq!(signed_by, named.fingerprint);
            assert_eq!(given, signer(&other).unwrap().fingerprint);
        }
        other => panic!("another key's check: {other:?}"),
    }
    let mut edited = cert.clone();
    let (key_of_pass, _) = edited
        .verdicts
        .iter()
        .find(|(_, v)| v.verdict == VerdictKind::Pass)
        .map(|(k, v)| (k.clone(), v.clone()))
        .unwrap();
    edited.verdicts.get_mut(&key_of_pass).unwrap().verdict = VerdictKind::Fail;
    assert!(matches!(
        verify(&edited.canonical(), &sig, &dir.join("key.pub")),
        Err(SignatureError::DoesNotVerify(_))
    ));
    let changes = differences_from_run(&edited, &json(&run));
    assert_eq!(
        changes,
        [format!(
            "{key_of_pass}: fail in the certificate, pass in the run"
        )]
    );
    assert!(differences_from_run(&cert, &json(&run)).is_empty());
    let _ = std::fs::remove_dir_all(dir);
}
