//! Clients in other processes over the adapter protocol's client role
//! (docs/adapter-protocol.md, "The client role"): the Python example written
//! from the document conforms, its traffic fits the JSON Schema, and a client
//! that breaks the protocol is an `error` that says what happened, never a `fail`.

use std::time::{Duration, Instant};

use canif_harness::client::application;
use canif_harness::client::master::Master;
use canif_harness::client::rig;
use canif_harness::client::suite::{ClientKind, ClientOptions};
use canif_harness::declare::Declaration;
use canif_harness::door::Door;
use canif_harness::run::run_profile;
use canif_harness::{Outcome, RunError};
use canif_model::config::{Capabilities, FrameFormat, InterfaceConfig};
use canif_spec::Catalogue;

const SCRIPT: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/examples/python/minimal_client.py"
);

fn exec(command: &str, timeout_ms: u64) -> ClientKind {
    ClientKind::Door(Door::Exec(canif_harness::door::ExecDoor {
        command: command.to_string(),
        timeouts: canif_harness::door::Timeouts::with_request(std::time::Duration::from_millis(
            timeout_ms,
        )),
        same_cpu: true,
    }))
}

/// Covers: CL-TX-001, CL-TX-003, CL-RX-001, CL-RX-002, CL-FQ-001, CL-RST-001, CL-RST-002, CL-TN-002
#[test]
fn the_python_example_client_written_from_the_document_conforms() {
    let catalogue = Catalogue::embedded().unwrap();
    let options = ClientOptions {
        counter_wrap: false,
        ..ClientOptions::new(1)
    };
    let kind = exec(&format!("python3 {SCRIPT}"), 5_000);
    // FD, 11- and 29-bit with transaction numbers and time stamps; the Fast CAN Queue.
    for profile in ["fc532x", "el6751-mdp"] {
        let profile = catalogue.profile(profile).unwrap();
        let run = run_profile(profile, &kind, &options, |_| {});
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
        assert!(run.runs.len() >= 90, "{} runs", run.runs.len());
        // It tells which messages were sent (`sent`), and that is judged.
        let verdicts = run.verdicts(&catalogue, profile);
        assert_eq!(
            verdicts["CL-TN-002"].kind(),
            canif_harness::VerdictKind::Pass,
            "{}: {:?}",
            profile.name,
            verdicts["CL-TN-002"]
        );
    }
}

/// One scenario against a client command.
fn run_one(command: &str, timeout_ms: u64) -> canif_harness::ScenarioRun {
    let config = InterfaceConfig::new(FrameFormat::Base11, 4);
    let scenario = application::steady_traffic(&config, 1);
    let kind = exec(command, timeout_ms);
    let build = |layout| kind.build(&config, layout);
    rig::run(
        &Capabilities::everything(),
        &scenario,
        Master::ALL[0],
        &build,
        &rig::simulated,
    )
}

/// One broken client: the error it must produce, in words.
fn broken(command: &str, expected: &[&str]) {
    let started = Instant::now();
    let run = run_one(command, 400);
    assert!(
        started.elapsed() < Duration::from_secs(25),
        "{:?}",
        started.elapsed()
    );
    let Outcome::Error(RunError::Iut(error)) = run.outcome else {
        panic!("`{command}` gave {:?}, not the client's error", run.outcome)
    };
    let said = error.to_string();
    for words in expected {
        assert!(said.contains(words), "`{command}`: {words:?} not in {said}");
    }
}

const STARTED: &str = r#"read l; echo '{"type":"started","protocol":1}'"#;

#[test]
fn a_client_that_breaks_the_protocol_is_an_error_naming_what_it_did() {
    broken("echo 'starting…' >&2; exit 3", &["exited", "starting…"]);
    broken(
        &format!("{STARTED}; sleep 5"),
        &["no answer to `task`", "killed"],
    );
    broken(
        &format!("{STARTED}; read l; echo 'hello'"),
        &["not a JSON object"],
    );
    broken(
        r#"read l; echo '{"type":"started","protocol":7}'"#,
        &["client protocol version 7"],
    );
    broken(
        r#"read l; echo '{"type":"started","protocol":1,"declares":{"slots":"40"}}'"#,
        &["declares what cannot be taken", "slots=40: expected"],
    );
    broken(
        r#"read l; echo '{"type":"started","protocol":1,"declares":{"colour":"red"}}'"#,
        &["`colour` is no client declaration"],
    );
    broken(
        &format!(
            r#"{STARTED}; read l; echo '{{"type":"tasked","outputs":"00","delivered":[],"refused":[]}}'"#
        ),
        &["output image of 1 bytes"],
    );
    broken(
        &format!(
            r#"{STARTED}; read l; echo '{{"type":"tasked","outputs":"{}","delivered":[],"refused":[5]}}'"#,
            "00".repeat(46)
        ),
        &["refused request 5"],
    );
}

fn schema() -> jsonschema::Validator {
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/docs/adapter-protocol.schema.json"
    ))
    .unwrap();
    jsonschema::validator_for(&serde_json::from_str(&text).unwrap()).unwrap()
}

/// Every line of a real client session, both ways, fits the schema (the
/// example keeps to version 1 with `--lines`, so that every task is a line;
/// without it, it agrees on version 3, and only `start` is).
#[test]
fn real_client_traffic_fits_the_schema() {
    let dir = std::env::temp_dir().join(format!("canif-client-traffic-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (requests, answers) = (dir.join("requests.log"), dir.join("answers.log"));
    let command = format!(
        "tee {} | python3 {SCRIPT} --lines | tee {}",
        requests.display(),
        answers.display()
    );
    assert_eq!(run_one(&command, 5_000).outcome, Outcome::Pass);
    std::thread::sleep(Duration::from_millis(100));
    let schema = schema();
    let mut lines = 0;
    for file in [&requests, &answers] {
        for line in std::fs::read_to_string(file).unwrap().lines() {
            let value: serde_json::Value = serde_json::from_str(line).unwrap();
            let errors: Vec<String> = schema.iter_errors(&value).map(|e| e.to_string()).collect();
            assert!(errors.is_empty(), "{line}\nviolates the schema: {errors:?}");
            lines += 1;
        }
    }
    let sent = std::fs::read_to_string(&requests).unwrap();
    assert!(sent.contains(r#""type":"start""#) && sent.contains(r#""requests":[{"#));
    assert!(lines > 300, "{lines} lines");
    let command = format!(
        "tee {} | python3 {SCRIPT} | tee {}",
        requests.display(),
        answers.display()
    );
    assert_eq!(run_one(&command, 5_000).outcome, Outcome::Pass);
    std::thread::sleep(Duration::from_millis(100));
    let answers = std::fs::read_to_string(&answers).unwrap();
    assert!(answers.contains(r#""protocol":3"#), "{answers}");
    assert!(!answers.contains(r#""type":"tasked""#), "{answers}");
    let _ = std::fs::remove_dir_all(dir);
}

/// The example declares itself in `started`, and canif reads it before the run.
#[test]
fn the_python_example_declares_what_it_is() {
    let kind = exec(&format!("python3 {SCRIPT}"), 5_000);
    let declared = ClientOptions::new(1).declared_by(&kind).declared.unwrap();
    assert_eq!(
        declared.lines(),
        [
            "slots=1..32",
            "direction=both",
            "application=one-stream",
            "restart=delivers-twice",
            "tells-sent=yes"
        ]
    );
    // The command line declaring otherwise is an error naming both.
    let options = ClientOptions {
        declared: Ok(
            canif_harness::client::ClientDeclaration::parse(&["restart=drops-once"]).unwrap(),
        ),
        ..ClientOptions::new(1)
    };
    let error = options.declared_by(&kind).declared.unwrap_err().to_string();
    assert!(
        error.contains("restart=drops-once") && error.contains("restart=delivers-twice"),
        "{error}"
    );
}
