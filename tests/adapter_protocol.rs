//! IUTs in other processes over the adapter protocol (docs/adapter-protocol.md):
//! a conforming one passes, a faulty one is caught on its requirement, and
//! every way of breaking the protocol is an `error` that says what happened —
//! never a hang, never a `fail`.

use std::time::{Duration, Instant};

use canif_harness::device::run_scenario;
use canif_harness::device::scenario;
use canif_harness::device::suite::Options;
use canif_harness::device::IutKind;
use canif_harness::door::Door;
use canif_harness::report::{ProfileReport, RunMeta, RunReport};
use canif_harness::run::run_profile;
use canif_harness::{Outcome, VerdictKind};
use canif_model::config::{Capabilities, FrameFormat, InterfaceConfig};
use canif_spec::Catalogue;

fn quick() -> Options {
    Options::quick(3)
}

fn exec(command: &str, timeout_ms: u64) -> IutKind {
    IutKind::Door(Door::Exec(canif_harness::door::ExecDoor {
        command: command.to_string(),
        timeouts: canif_harness::door::Timeouts::with_request(std::time::Duration::from_millis(
            timeout_ms,
        )),
        same_cpu: false,
    }))
}

fn soft_device(args: &str) -> IutKind {
    exec(
        &format!("{} device --stdio {args}", env!("CARGO_BIN_EXE_canif")),
        5_000,
    )
}

fn failures_and_errors(kind: &IutKind, profile: &str) -> (Vec<String>, Vec<String>) {
    let catalogue = Catalogue::embedded().unwrap();
    let profile = catalogue.profile(profile).unwrap();
    let run = run_profile(profile, kind, &quick(), |_| {});
    let failed = run.failed_requirements(&catalogue, profile);
    let errors = run
        .runs
        .iter()
        .filter_map(|r| match &r.outcome {
            Outcome::Error(e) => Some(format!("{}: {e}", r.scenario)),
            _ => None,
        })
        .collect();
    (failed, errors)
}

#[test]
fn the_soft_device_behind_the_protocol_conforms() {
    let (failed, errors) = failures_and_errors(&soft_device(""), "fc532x");
    assert!(
        failed.is_empty() && errors.is_empty(),
        "failed {failed:?}, errors {errors:?}"
    );
}

#[test]
fn a_fault_behind_the_protocol_is_caught_on_its_requirement() {
    let (failed, errors) =
        failures_and_errors(&soft_device("--fault head-drop-when-full"), "el6751-mdp");
    assert!(errors.is_empty(), "{errors:?}");
    assert!(failed.contains(&"RXQ-004".to_string()), "{failed:?}");
}

#[test]
fn the_python_example_written_from_the_document_is_certified() {
    let script = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/examples/python/minimal_iut.py"
    );
    let (failed, errors) = failures_and_errors(
        &exec(&format!("python3 {script}"), 5_000),
        "fc510x-before-fw2.14",
    );
    assert!(
        failed.is_empty() && errors.is_empty(),
        "failed {failed:?}, errors {errors:?}"
    );
}

/// Issue 26: the same example on a profile that offers 29-bit, which it
/// refuses. Refusing an interface the profile offers is what the device did
/// wrong — a failure of PROF-001, once — and what the refused interface was
/// needed for is "not run" with the device's words, never an error and never
/// a failure of the scenarios' own requirements. The run says DOES NOT
/// CONFORM and exits 1.
/// Covers: PROF-001
#[test]
fn refusing_an_offered_interface_fails_prof_001_and_leaves_the_rest_not_run() {
    let script = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/examples/python/minimal_iut.py"
    );
    let dir = std::env::temp_dir().join(format!("canif-refuses-{}", std::process::id()));
    let output = std::process::Command::new(env!("CARGO_BIN_EXE_canif"))
        .args(["run", "--profile", "fc510x", "--cases", "1", "--report"])
        .arg(&dir)
        .arg("--iut")
        .arg(format!("exec:python3 {script}"))
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert_eq!(output.status.code(), Some(1), "{stdout}");
    assert!(stdout.contains("DOES NOT CONFORM"), "{stdout}");
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("report.json")).unwrap()).unwrap();
    let verdicts = report["profiles"][0]["verdicts"].as_object().unwrap();
    let of = |kind: &str| -> Vec<&String> {
        verdicts
            .iter()
            .filter(|(_, v)| v["verdict"] == kind)
            .map(|(id, _)| id)
            .collect()
    };
    assert_eq!(of("fail"), ["PROF-001"]);
    assert!(of("error").is_empty(), "{:?}", of("error"));
    // A 29-bit requirement the 11-bit scenarios cannot reach: not run, and why.
    let layout = &verdicts["LAY-29-005"];
    assert_eq!(layout["verdict"], "not run", "{layout}");
    assert!(
        layout["reason"].as_str().is_some_and(
            |r| r.contains("refuses the interface") && r.contains("11-bit interface only")
        ),
        "{layout}"
    );
    // What the 11-bit interface showed still passes.
    assert_eq!(verdicts["HS-TX-001"]["verdict"], "pass");
    let _ = std::fs::remove_dir_all(dir);
}

/// One broken IUT: the error it must produce, in words.
fn broken(command: &str, expected: &[&str]) {
    let caps = Capabilities::everything();
    let scenario = scenario::tx_batches(&InterfaceConfig::new(FrameFormat::Base11, 4), 1);
    let started = Instant::now();
    let run = run_scenario(&exec(command, 400), &caps, &scenario, scenario.steps());
    assert!(
        started.elapsed() < Duration::from_secs(25),
        "the harness waited {:?}",
        started.elapsed()
    );
    let Outcome::Error(error) = run.outcome else {
        panic!("`{command}` gave {:?}, not an error", run.outcome)
    };
    assert!(
        matches!(error, canif_harness::RunError::Iut(_)),
        "`{command}`: a broken IUT is the IUT's error, not {error:?}"
    );
    let message = error.to_string();
    for words in expected {
        assert!(
            message.contains(words),
            "`{command}`: the error does not say {words:?}: {message}"
        );
    }
}

/// An IUT that answers one request twice (both lines in one write, so the
/// stray one is waiting when the next request goes out) is an error naming
/// it, not a desynchronised run judged on the wrong answers (issue 26).
#[test]
fn an_iut_that_answers_twice_is_an_error() {
    broken(
        r#"read l; c='{"type":"configured","protocol":1,"accepted":true}'; printf '%s\n%s\n' "$c" "$c"; sleep 5"#,
        &[
            "answered twice",
            "before the `poll_transmit` request",
            "configured",
        ],
    );
}

/// Accepts the configuration, then answers the first request (the bus polls
/// the controller at t = 0, before the first cycle) with "nothing to send".
const CONFIGURED: &str = r#"read l; echo '{"type":"configured","protocol":1,"accepted":true}'; read l; echo '{"type":"transmit","frame":null}'"#;

#[test]
fn an_iut_that_exits_is_an_error_with_its_last_words() {
    broken(
        "echo 'segmentation fault in my driver' >&2; exit 3",
        &["exited", "segmentation fault in my driver"],
    );
}

#[test]
fn an_iut_that_hangs_is_killed_after_the_timeout() {
    broken(
        &format!("{CONFIGURED}; echo 'waiting for a bus that never comes' >&2; sleep 30"),
        &["no answer to `cycle` within 400 ms", "waiting for a bus"],
    );
}

#[test]
fn an_iut_that_prints_garbage_is_an_error() {
    broken(
        "echo 'Hello from my IUT!'; cat >/dev/null",
        &["not a JSON object", "Hello from my IUT!"],
    );
}

#[test]
fn another_protocol_version_is_an_error() {
    broken(
        r#"read l; echo '{"type":"configured","protocol":4,"accepted":true}'; cat >/dev/null"#,
        &["protocol version 4", "offered 1 to 3"],
    );
}

#[test]
fn an_image_of_the_wrong_size_is_an_error() {
    broken(
        &format!(
            r#"{CONFIGURED}; read l; echo '{{"type":"inputs","inputs":"00"}}'; cat >/dev/null"#
        ),
        &["input image of 1 bytes", "the layout has 110"],
    );
}

#[test]
fn a_command_that_does_not_exist_is_an_error_and_the_report_says_error() {
    let catalogue = Catalogue::embedded().unwrap();
    let profile = catalogue.profile("fc510x-before-fw2.14").unwrap();
    let run = run_profile(profile, &exec("/nonexistent/iut", 400), &quick(), |_| {});
    let verdicts = run.verdicts(&catalogue, profile);
    assert!(verdicts.values().any(|v| v.kind() == VerdictKind::Error));
    assert!(
        !verdicts.values().any(|v| v.kind() == VerdictKind::Fail),
        "a broken IUT is an error, not a failure"
    );
    let reach = canif_harness::verdict::Reach::default();
    let report = RunReport {
        meta: RunMeta::new("exec".into(), "sim".into(), 3, &catalogue),
        profiles: vec![ProfileReport::new(
            &catalogue,
            profile,
            run,
            Vec::new(),
            Vec::new(),
            &reach,
        )],
        wall_time_ms: 0,
        interrupted: false,
        flaky: Vec::new(),
        part: None,
    };
    assert_eq!(report.exit_code(), 2);
    let dir = std::env::temp_dir().join(format!("canif-broken-{}", std::process::id()));
    report.write(&catalogue, &dir).unwrap();
    assert!(
        std::fs::read_to_string(dir.join("junit.xml"))
            .unwrap()
            .contains("<error message="),
        "the report is still written"
    );
    let _ = std::fs::remove_dir_all(dir);
}

fn schema() -> jsonschema::Validator {
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/docs/adapter-protocol.schema.json"
    ))
    .unwrap();
    jsonschema::validator_for(&serde_json::from_str(&text).unwrap())
        .expect("the schema is a valid JSON Schema")
}

fn check_lines(schema: &jsonschema::Validator, what: &str, lines: &[&str]) -> usize {
    for line in lines {
        let value: serde_json::Value =
            serde_json::from_str(line).unwrap_or_else(|e| panic!("{what}: not JSON ({e}): {line}"));
        let errors: Vec<String> = schema.iter_errors(&value).map(|e| e.to_string()).collect();
        assert!(
            errors.is_empty(),
            "{what}: {line}\nviolates the schema: {errors:?}"
        );
    }
    lines.len()
}

/// Every message of a real session (harness requests, soft-device answers),
/// in protocol 1 and in protocol 2, and every line of the document's example
/// session fit the JSON Schema.
#[test]
fn real_traffic_and_the_documented_session_fit_the_schema() {
    let schema = schema();
    for (version, kinds) in [
        (
            1,
            &[
                "configure",
                "cycle",
                "receive",
                "poll_transmit",
                "transmit_complete",
                "controller_status",
            ][..],
        ),
        (
            2,
            &[
                "configure",
                "step",
                "received",
                "started",
                "completed",
                "status",
            ][..],
        ),
    ] {
        let dir =
            std::env::temp_dir().join(format!("canif-traffic-{version}-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let (requests, answers) = (dir.join("requests.log"), dir.join("answers.log"));
        let command = format!(
            "tee {} | {} device --stdio --protocol {version} | tee {}",
            requests.display(),
            env!("CARGO_BIN_EXE_canif"),
            answers.display()
        );
        let mut config = InterfaceConfig::new(FrameFormat::Fd, 4);
        config.transaction_number = true;
        config.time_stamp = true;
        let scenario = scenario::info_data(&config);
        let run = run_scenario(
            &exec(&command, 5_000),
            &Capabilities::everything(),
            &scenario,
            scenario.steps(),
        );
        assert_eq!(run.outcome, Outcome::Pass, "protocol {version}");
        drop(run);
        std::thread::sleep(Duration::from_millis(100));
        let requests = std::fs::read_to_string(requests).unwrap();
        let answers = std::fs::read_to_string(answers).unwrap();
        let sent = check_lines(&schema, "request", &requests.lines().collect::<Vec<_>>());
        let answered = check_lines(&schema, "answer", &answers.lines().collect::<Vec<_>>());
        assert!(
            sent > 20 && answered + 1 >= sent,
            "protocol {version}: {sent} requests, {answered} answers"
        );
        for kind in kinds {
            assert!(
                requests.contains(&format!("\"type\":\"{kind}\""))
                    || requests.contains(&format!("\"event\":\"{kind}\"")),
                "protocol {version}: the session has no {kind}"
            );
        }
        if version == 2 {
            assert!(
                answers.contains("\"type\":\"stepped\""),
                "no stepped answer"
            );
            assert!(
                !requests.contains("\"type\":\"poll_transmit\""),
                "protocol 2 polls per frame"
            );
        }
        let _ = std::fs::remove_dir_all(dir);
    }
    let doc = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/docs/adapter-protocol.md"
    ))
    .unwrap();
    let documented: Vec<&str> = doc
        .lines()
        .filter_map(|l| l.strip_prefix("→ ").or_else(|| l.strip_prefix("← ")))
        .collect();
    assert!(check_lines(&schema, "the documented session", &documented) >= 10);
    // The schema says no to what the protocol forbids.
    assert!(!schema.is_valid(&serde_json::json!({"type": "inputs", "inputs": "0g"})));
    assert!(!schema
        .is_valid(&serde_json::json!({"type": "configured", "protocol": 4, "accepted": true})));
}

/// On a SocketCAN bus `configure` names the interface and the epoch: the
/// message the harness really sends fits the schema.
#[test]
fn the_configure_of_a_socketcan_bus_fits_the_schema() {
    let dir = std::env::temp_dir().join(format!("canif-bus-configure-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let requests = dir.join("requests.log");
    let command = format!(
        "tee {} | {} device --stdio",
        requests.display(),
        env!("CARGO_BIN_EXE_canif")
    );
    let mut iut = canif_harness::door::exec::ExecIut::spawn(
        &command,
        canif_harness::door::Timeouts::default(),
        false,
    )
    .unwrap();
    let bus = canif_harness::door::adapter::protocol::OwnedBus {
        interface: "vcan0".into(),
        epoch_ns: 1_700_000_000_000_000_000,
    };
    let answer = iut
        .configure(
            &Capabilities::everything(),
            &InterfaceConfig::new(FrameFormat::Base11, 4),
            Some(&bus),
        )
        .unwrap();
    assert_eq!(answer, canif_harness::door::exec::Configured::Accepted);
    drop(iut);
    std::thread::sleep(Duration::from_millis(100));
    let requests = std::fs::read_to_string(&requests).unwrap();
    let line = requests.lines().next().expect("one configure");
    assert!(
        line.contains(r#""bus":{"epoch_ns":1700000000000000000,"socketcan":"vcan0"}"#),
        "{line}"
    );
    check_lines(&schema(), "configure on a SocketCAN bus", &[line]);
    let broken = line.replace(r#""socketcan":"vcan0""#, r#""socketcan":"""#);
    let value: serde_json::Value = serde_json::from_str(&broken).unwrap();
    assert!(
        !schema().is_valid(&value),
        "an empty interface name must not fit"
    );
    let _ = std::fs::remove_dir_all(dir);
}

/// Each way of breaking a well-formed request the schema refuses (a field
/// left out, of another type, out of range, one field too many), and
/// `canif device --stdio` refuses it too with an `error` answer: it used to
/// read a frame without its flags as a classic 11-bit data frame, and a
/// `transmit_complete` with a stray field as a plain one.
#[test]
fn canif_device_refuses_every_request_the_schema_refuses() {
    use serde_json::{json, Value};
    let schema = schema();
    let document = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/docs/adapter-protocol.md"
    ))
    .unwrap();
    let configure = document
        .lines()
        .find_map(|l| {
            l.strip_prefix("→ ")
                .filter(|l| l.contains("\"protocol\":2"))
        })
        .expect("the document's protocol-2 session configures");
    let frame = json!({"id": 0x123, "extended": false, "rtr": false, "fd": false,
                       "brs": false, "esi": false, "len": 2, "data": "0102"});
    let outputs = "00".repeat(46);
    let requests = [
        json!({"type": "cycle", "now_ns": 1000, "outputs": outputs}),
        json!({"type": "receive", "frame": frame, "end_ns": 1000}),
        json!({"type": "poll_transmit", "now_ns": 1000}),
        json!({"type": "transmit_complete"}),
        json!({"type": "bye"}),
    ];
    let bad_values = [
        json!(-1),
        json!(1.5),
        json!("x"),
        Value::Null,
        json!(1u64 << 40),
    ];
    let mut broken = Vec::new();
    for request in &requests {
        let fields: Vec<String> = request.as_object().unwrap().keys().cloned().collect();
        let mut with = |edit: &dyn Fn(&mut Value)| {
            let mut variant = request.clone();
            edit(&mut variant);
            broken.push(variant);
        };
        with(&|v| {
            v["extra"] = json!(1);
        });
        for field in fields.iter().filter(|f| *f != "type") {
            with(&|v| {
                v.as_object_mut().unwrap().remove(field);
            });
            for bad in &bad_values {
                with(&|v| v[field] = bad.clone());
            }
        }
        if request.get("frame").is_some() {
            for field in frame.as_object().unwrap().keys() {
                with(&|v| {
                    v["frame"].as_object_mut().unwrap().remove(field);
                });
                for bad in bad_values.iter().chain(&[json!(65), json!(0x2000_0000)]) {
                    with(&|v| v["frame"][field] = bad.clone());
                }
            }
        }
    }
    let refused_by_schema: Vec<&Value> = broken.iter().filter(|v| !schema.is_valid(v)).collect();
    assert!(refused_by_schema.len() > 60, "{}", refused_by_schema.len());
    let mut accepted = Vec::new();
    for request in refused_by_schema {
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_canif"))
            .args(["device", "--stdio"])
            .stdin(std::process::Stdio::piped())
            .stdout(std::process::Stdio::piped())
            .spawn()
            .and_then(|mut child| {
                use std::io::Write;
                let mut stdin = child.stdin.take().unwrap();
                writeln!(stdin, "{configure}\n{request}")?;
                drop(stdin);
                child.wait_with_output()
            })
            .unwrap();
        let text = String::from_utf8_lossy(&out.stdout);
        let answer: Option<Value> = text
            .lines()
            .nth(1)
            .and_then(|l| serde_json::from_str(l).ok());
        if answer.as_ref().and_then(|a| a["type"].as_str()) != Some("error") {
            accepted.push(format!("{request} -> {answer:?}"));
        }
    }
    assert!(
        accepted.is_empty(),
        "answered, not refused:\n{}",
        accepted.join("\n")
    );
}

/// Over version 3 a plan comes in parts (sixteen frames a record): a soak
/// at full load keeps more than that queued, so the harness must ask for
/// the rest as it starts them. Were a part lost, the soft device's frames
/// would go missing and the run fail; over versions 2 and 3 it passes alike.
#[test]
fn a_long_plan_comes_in_parts_and_nothing_is_lost() {
    use canif_model::timing::BitRates;
    let caps = canif_spec::Catalogue::embedded()
        .unwrap()
        .profile("el6751-mdp")
        .unwrap()
        .model_capabilities();
    let config = InterfaceConfig::new(FrameFormat::Base11, 32);
    let mut soak = scenario::generated(&config, 42, 5_000, 100);
    soak.bit_rates = BitRates::classic(1_000_000);
    for version in [3, 2] {
        let run = run_scenario(
            &soft_device(&format!("--protocol {version}")),
            &caps,
            &soak,
            soak.steps(),
        );
        assert_eq!(run.outcome, Outcome::Pass, "protocol {version}");
        assert!(run.frames_checked > 10_000, "{}", run.frames_checked);
    }
}
