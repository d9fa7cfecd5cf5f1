//! PLC-side clients in shared libraries, through the client role of the C
//! ABI (include/canif.h): the C example conforms, and the same code without
//! its bound on NoOfRxMessages reads past its image and is caught (CL-IMG-001).

use std::path::PathBuf;
use std::process::Command;

use canif_harness::client::suite::{ClientKind, ClientOptions};
use canif_harness::door::Door;
use canif_harness::run::run_profile;
use canif_harness::{Outcome, VerdictKind};
use canif_spec::Catalogue;

/// Compiles the C example client with `flags` into a shared library.
fn build(name: &str, flags: &[&str]) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("c-abi-client");
    std::fs::create_dir_all(&dir).unwrap();
    let library = dir.join(format!("lib{name}.so"));
    let status = Command::new("cc")
        .args(["-shared", "-fPIC", "-O2", "-Wall", "-Wextra", "-Werror"])
        .args(flags)
        .arg("-I")
        .arg(concat!(env!("CARGO_MANIFEST_DIR"), "/include"))
        .arg("-o")
        .arg(&library)
        .arg(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/examples/c/minimal_client.c"
        ))
        .status()
        .expect("cc runs (the machine has gcc)");
    assert!(status.success(), "cc failed");
    library
}

fn options() -> ClientOptions {
    ClientOptions {
        counter_wrap: false,
        ..ClientOptions::new(1)
    }
}

/// `canif run plc --profile PROFILE [--master lrw] --iut lib:LIBRARY`
/// as a new user runs it, reports into a fresh folder named `name`: the exit
/// code (with stderr for a message) and report.json.
fn canif_run(
    name: &str,
    library: &std::path::Path,
    profile: &str,
    lrw_only: bool,
) -> (Option<i32>, String, PathBuf, serde_json::Value) {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(format!("c-abi-client-{name}"));
    let _ = std::fs::remove_dir_all(&dir);
    let mut command = Command::new(env!("CARGO_BIN_EXE_canif"));
    command.args(["run", "plc", "--profile", profile]);
    if lrw_only {
        command.args(["--master", "lrw"]);
    }
    let out = command
        .arg(format!("--iut=lib:{}", library.display()))
        .arg("--report")
        .arg(&dir)
        .output()
        .expect("canif runs");
    let json = std::fs::read_to_string(dir.join("report.json"))
        .ok()
        .and_then(|text| serde_json::from_str(&text).ok())
        .unwrap_or_default();
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    (out.status.code(), stderr, dir, json)
}

/// Covers: CL-TX-001, CL-TX-003, CL-TX-004, CL-RX-001, CL-RX-002, CL-RX-003, CL-FQ-001, CL-TN-002
#[test]
fn the_c_example_client_conforms_in_process() {
    let catalogue = Catalogue::embedded().unwrap();
    let kind = ClientKind::Door(Door::Lib(canif_harness::door::LibDoor {
        path: build("minimal_client", &[]),
        host: None,
    }));
    for profile in ["fc532x", "el6751-mdp"] {
        let profile = catalogue.profile(profile).unwrap();
        let run = run_profile(profile, &kind, &options(), |_| {});
        let bad: Vec<String> = run
            .runs
            .iter()
            .filter_map(|r| match &r.outcome {
                Outcome::Pass => None,
                Outcome::Fail(f) => Some(f.details()),
                Outcome::Error(e) => Some(format!("{}: {e}", r.scenario)),
            })
            .collect();
        assert!(bad.is_empty(), "{}:\n{}", profile.name, bad.join("\n\n"));
        assert!(run.runs.len() >= 90);
        // canif_client_sent tells which messages were sent, and that is judged.
        assert_eq!(
            run.verdicts(&catalogue, profile)["CL-TN-002"].kind(),
            VerdictKind::Pass,
            "{}",
            profile.name
        );
    }
}

/// canif_client_sent is optional: a library without it declares that it
/// tells its application nothing of what was sent, so CL-TN-002 and
/// CL-TN-001 are not applicable to it, and the verdicts say why.
#[test]
fn a_c_client_that_tells_nothing_sent_is_not_judged_on_it() {
    let catalogue = Catalogue::embedded().unwrap();
    let kind = ClientKind::Door(Door::Lib(canif_harness::door::LibDoor {
        path: build("without_sent", &["-DCANIF_WITHOUT_SENT"]),
        host: None,
    }));
    let profile = catalogue.profile("fc532x").unwrap();
    let run = run_profile(profile, &kind, &options(), |_| {});
    assert!(run.failed_requirements(&catalogue, profile).is_empty());
    for id in ["CL-TN-001", "CL-TN-002"] {
        let verdict = &run.verdicts(&catalogue, profile)[id];
        assert_eq!(verdict.kind(), VerdictKind::NotApplicable, "{id}");
        assert!(
            verdict
                .reason()
                .is_some_and(|r| r.contains("declares it tells its application nothing")),
            "{verdict:?}"
        );
    }
}

/// 000 §5.2 lets a client enter any transaction number. One that leaves
/// every number at 0 and tells its application nothing of what was sent
/// conforms; the same numbers in a client that does tell (it exports
/// canif_client_sent) leave it unable to, and fail CL-TN-001.
#[test]
fn zero_transaction_numbers_are_a_fault_only_of_a_client_that_tells_what_was_sent() {
    let catalogue = Catalogue::embedded().unwrap();
    let profile = catalogue.profile("el6751-mdp").unwrap();
    let silent = ClientKind::Door(Door::Lib(canif_harness::door::LibDoor {
        path: build(
            "zero_numbers_silent",
            &["-DCANIF_ZERO_NUMBERS", "-DCANIF_WITHOUT_SENT"],
        ),
        host: None,
    }));
    let run = run_profile(profile, &silent, &options(), |_| {});
    assert_eq!(
        run.failed_requirements(&catalogue, profile),
        Vec::<String>::new()
    );
    assert_eq!(
        run.verdicts(&catalogue, profile)["CL-TN-001"].kind(),
        VerdictKind::NotApplicable
    );
    let telling = ClientKind::Door(Door::Lib(canif_harness::door::LibDoor {
        path: build("zero_numbers_telling", &["-DCANIF_ZERO_NUMBERS"]),
        host: None,
    }));
    let run = run_profile(profile, &telling, &options(), |_| {});
    assert!(
        run.failed_requirements(&catalogue, profile)
            .contains(&"CL-TN-001".to_string()),
        "{:?}",
        run.failed_requirements(&catalogue, profile)
    );
}

/// The same, as a new user meets it: `canif run plc --iut lib:…`
/// writes the reason into report.json (it said "not selected" while the
/// command line judged the profile a second time without it).
#[test]
fn the_reason_a_client_is_not_judged_on_sent_messages_reaches_report_json() {
    let library = build("without_sent_cli", &["-DCANIF_WITHOUT_SENT"]);
    let (code, stderr, _, report) = canif_run("report", &library, "el6751-mdp", false);
    assert_eq!(code, Some(0), "{stderr}");
    let verdict = &report["profiles"][0]["verdicts"]["CL-TN-002"];
    assert_eq!(verdict["verdict"], "not applicable", "{verdict}");
    assert!(
        verdict["reason"]
            .as_str()
            .is_some_and(|r| r.contains("declares it tells its application nothing")),
        "{verdict}"
    );
}

/// Covers: CL-IMG-001
#[test]
fn a_c_client_that_reads_past_its_image_is_caught() {
    let catalogue = Catalogue::embedded().unwrap();
    let kind = ClientKind::Door(Door::Lib(canif_harness::door::LibDoor {
        path: build("no_bound", &["-DCANIF_FAULT_NO_BOUND"]),
        host: None,
    }));
    let profile = catalogue.profile("fc510x").unwrap();
    let run = run_profile(profile, &kind, &options(), |_| {});
    // What it reads past the slots it delivers: messages the device never
    // entered and no frames, seen since the judge goes on after a breach.
    assert_eq!(
        run.failed_requirements(&catalogue, profile),
        ["CL-IMG-001", "CL-RX-002", "CL-RX-003"]
    );
    assert!(run
        .runs
        .iter()
        .all(|r| !matches!(r.outcome, Outcome::Error(_))));
}

#[test]
fn a_library_without_the_client_role_is_an_error_naming_the_symbol() {
    let device = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("c-abi-client/libdevice_only.so");
    let status = Command::new("cc")
        .args(["-shared", "-fPIC", "-O2", "-I"])
        .arg(concat!(env!("CARGO_MANIFEST_DIR"), "/include"))
        .arg("-o")
        .arg(&device)
        .arg(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/examples/c/minimal_device.c"
        ))
        .status()
        .unwrap();
    assert!(status.success());
    let catalogue = Catalogue::embedded().unwrap();
    let run = run_profile(
        catalogue.profile("fc510x").unwrap(),
        &ClientKind::Door(Door::Lib(canif_harness::door::LibDoor {
            path: device,
            host: None,
        })),
        &options(),
        |_| {},
    );
    let Outcome::Error(error) = &run.runs[0].outcome else {
        panic!("{:?}", run.runs[0].outcome)
    };
    assert!(error.to_string().contains("canif_client_start"), "{error}");
}

/// The crash of issue 27: a client that reads every slot NoOfRxMessages names
/// reads far past its input image. `canif run` hosts a library in a process
/// of its own (`canif lib-host`) whose images end at a guard page, so the
/// read stops there: a FAIL of CL-IMG-001 naming the image and the offset,
/// every report written, canif's own exit 1, no process left.
/// Covers: CL-IMG-001
#[test]
fn a_library_client_that_reads_far_past_its_image_fails_cl_img_001_with_every_report() {
    let library = build("trusts_count", &["-DCANIF_FAULT_TRUSTS_COUNT"]);
    let (code, stderr, report, json) = canif_run("trusts-count", &library, "fc510x", true);
    assert_eq!(code, Some(1), "{stderr}");
    for file in ["report.json", "summary.md", "junit.xml", "report.html"] {
        assert!(report.join(file).is_file(), "{file} written");
    }
    let verdicts = &json["profiles"][0]["verdicts"];
    assert_eq!(
        verdicts["CL-IMG-001"]["verdict"], "fail",
        "{}",
        verdicts["CL-IMG-001"]
    );
    let text = verdicts["CL-IMG-001"].to_string();
    assert!(
        text.contains("input image at offset"),
        "the failure names where: {text}"
    );
    // Only that: the host passes every other task on as the library answered it.
    assert_eq!(json["totals"]["error"], 0, "{}", json["totals"]);
    assert_eq!(json["totals"]["fail"], 1, "{}", json["totals"]);
}

/// The C example, hosted as `canif run` hosts it, conforms exactly as in
/// process: the host adds nothing and hides nothing.
#[test]
fn the_c_example_client_conforms_in_its_host_as_in_process() {
    let library = build("example_hosted", &[]);
    let (code, stderr, _, _) = canif_run("hosted", &library, "fc510x", false);
    assert_eq!(code, Some(0), "{stderr}");
}

/// One defect no longer hides the next (issue 27): a client with two, one on
/// each side of the interface, shows both in the one scenario that meets
/// them, each with the task it first showed in.
#[test]
fn a_client_with_two_defects_in_one_scenario_shows_both() {
    let catalogue = Catalogue::embedded().unwrap();
    let profile = catalogue.profile("el6751-mdp").unwrap();
    let kind = ClientKind::Door(Door::Lib(canif_harness::door::LibDoor {
        path: build(
            "two_defects",
            &["-DCANIF_FAULT_SKIPS_LAST_RX", "-DCANIF_ZERO_NUMBERS"],
        ),
        host: None,
    }));
    let run = run_profile(profile, &kind, &options(), |_| {});
    let both = run.runs.iter().find_map(|r| match &r.outcome {
        Outcome::Fail(failure) => {
            let breaches = failure.breaches();
            let blamed: Vec<String> = breaches
                .iter()
                .flat_map(|b| b.requirements.iter().map(|id| id.to_string()))
                .collect();
            (blamed.iter().any(|id| id.starts_with("CL-RX-"))
                && blamed.contains(&"CL-TN-001".to_string()))
            .then_some((r.scenario.clone(), breaches))
        }
        _ => None,
    });
    let (scenario, breaches) = both.expect("a scenario that shows both defects");
    assert!(breaches.len() >= 2, "{scenario}");
    let failed = run.failed_requirements(&catalogue, profile);
    assert!(
        failed.iter().any(|id| id.starts_with("CL-RX-")),
        "{failed:?}"
    );
    assert!(failed.contains(&"CL-TN-001".to_string()), "{failed:?}");
}

/// Advisories beside the verdicts (issue 27): a client that hands over a
/// batch of nothing whenever it may (000's sample without its `> 0` guard)
/// conforms (HS-TX-009 allows it), and report.json, the summary and the HTML
/// count its empty batches and the handshakes it spends per frame; the C
/// example with the guard hands over one only where a restarted program's
/// first image (all zeros) changes the counter.
#[test]
fn empty_batches_are_counted_beside_the_verdict_and_change_nothing() {
    let run = |name: &str, flags: &[&str]| {
        let library = build(name, flags);
        let (code, stderr, dir, json) = canif_run(name, &library, "fc510x", true);
        assert_eq!(code, Some(0), "{stderr}");
        let summary = std::fs::read_to_string(dir.join("summary.md")).unwrap();
        let html = std::fs::read_to_string(dir.join("report.html")).unwrap();
        (json["profiles"][0]["advisories"].clone(), summary, html)
    };
    let (advised, summary, html) = run("empty_batches", &["-DCANIF_EMPTY_BATCHES"]);
    let empty = advised["empty_batches"].as_u64().unwrap_or(0);
    let batches = advised["batches"].as_u64().unwrap_or(0);
    assert!(empty > 100 && batches > empty, "{advised}");
    assert!(
        summary.contains("## Advisories") && summary.contains("of nothing"),
        "{summary}"
    );
    assert!(html.contains("id=\"advisories\""));
    let (guarded, _, _) = run("guarded_batches", &[]);
    let restarts = 4 * 2; // two PLC and two module restarts, on each of the two interfaces
    assert!(
        guarded["empty_batches"].as_u64().unwrap_or(0) <= restarts,
        "{guarded}"
    );
    assert!(
        guarded["frames_sent"].as_u64().unwrap_or(0) > 0,
        "{guarded}"
    );
}

/// A library that only sends declares it through `canif_client_declares`:
/// certified on sending, reception not applicable; the same code without
/// the declaration fails reception.
#[test]
fn a_tx_only_library_is_certified_on_what_it_declares() {
    let catalogue = Catalogue::embedded().unwrap();
    let profile = catalogue.profile("el6751-mdp").unwrap();
    let verdicts = |name: &str, flags: &[&str]| {
        let kind = ClientKind::Door(Door::Lib(canif_harness::door::LibDoor {
            path: build(name, flags),
            host: None,
        }));
        let options = ClientOptions {
            counter_wrap: false,
            ..ClientOptions::new(1)
        }
        .declared_by(&kind);
        let run = run_profile(profile, &kind, &options, |_| {});
        run.verdicts(&catalogue, profile)
    };
    let declared = verdicts("tx_only", &["-DCANIF_TX_ONLY"]);
    let kinds = |id: &str| declared[id].kind();
    assert_eq!(kinds("CL-RX-001"), VerdictKind::NotApplicable);
    assert_eq!(kinds("CL-TX-003"), VerdictKind::Pass);
    assert!(declared
        .values()
        .all(|v| !matches!(v.kind(), VerdictKind::Fail | VerdictKind::Error)));
    let reason = declared["CL-RX-002"].reason().unwrap_or_default();
    assert!(reason.contains("direction=tx"), "{reason}");
    let undeclared = verdicts(
        "tx_only_undeclared",
        &["-DCANIF_TX_ONLY", "-DCANIF_UNDECLARED"],
    );
    assert_eq!(undeclared["CL-RX-001"].kind(), VerdictKind::Fail);
}

/// Issue 36: canif.h says `canif_client_declares` is asked before any start.
/// A library that starts only on 29-bit interfaces without transaction
/// numbers, and says so there, is run only on those (the profile offers
/// them with transaction numbers, which its declaration turns off) and
/// conforms, in process and in its host; it was once an error on every
/// check, asked only of a program that had started.
#[test]
fn a_library_declares_before_it_is_started() {
    let catalogue = Catalogue::embedded().unwrap();
    let profile = catalogue.profile("ccat").unwrap();
    let path = build("ext29_without_tn", &["-DCANIF_29BIT_NO_TN"]);
    let kind = ClientKind::Door(Door::Lib(canif_harness::door::LibDoor {
        path: path.clone(),
        host: None,
    }));
    let run = run_profile(profile, &kind, &options().declared_by(&kind), |_| {});
    let verdicts = run.verdicts(&catalogue, profile);
    let broken: Vec<_> = verdicts
        .iter()
        .filter(|(_, v)| matches!(v.kind(), VerdictKind::Fail | VerdictKind::Error))
        .map(|(id, v)| format!("{id}: {v:?}"))
        .collect();
    assert!(broken.is_empty(), "{broken:#?}");
    assert_eq!(verdicts["CL-TX-003"].kind(), VerdictKind::Pass);
    // Hosted, as `canif run` runs a library: the host is asked first too.
    let (code, stderr, _, json) = canif_run("ext29_without_tn", &path, "ccat", false);
    assert_eq!(code, Some(0), "{stderr}");
    assert!(
        json["totals"]["pass"].as_u64().unwrap_or(0) > 0,
        "{}",
        json["totals"]
    );
}
