//! `canif device --stdio` refuses every request the protocol's JSON Schema
//! refuses (issue 34: a status of `[]`, a `configure` without a data bit
//! timing, protocol 127 taken as 2, … were answered as valid). Each request
//! kind of a real session, in protocol 1 and 2, is mutated field by field —
//! a value of every JSON type, a field left out, a field added — and every
//! mutant the schema rejects must be answered with an `error`.

use std::io::{BufRead, BufReader, Write};
use std::process::{Command, Stdio};

use canif_harness::device::run_scenario;
use canif_harness::device::scenario;
use canif_harness::device::IutKind;
use canif_harness::door::{Door, Timeouts};
use canif_model::config::{Capabilities, FrameFormat, InterfaceConfig};
use serde_json::{json, Value};

const CANIF: &str = env!("CARGO_BIN_EXE_canif");

fn schema() -> jsonschema::Validator {
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/docs/adapter-protocol.schema.json"
    ))
    .unwrap();
    jsonschema::validator_for(&serde_json::from_str(&text).unwrap()).unwrap()
}

/// The requests the harness sends the soft device in a real session of
/// `version`, as sent.
fn session(version: u64) -> Vec<Value> {
    let dir = std::env::temp_dir().join(format!("canif-schema-{version}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let requests = dir.join("requests.log");
    let command = format!(
        "tee {} | {CANIF} device --stdio --protocol {version}",
        requests.display()
    );
    let kind = IutKind::Door(Door::Exec(canif_harness::door::ExecDoor {
        command,
        timeouts: Timeouts::default(),
        same_cpu: false,
    }));
    let mut config = InterfaceConfig::new(FrameFormat::Fd, 4);
    config.transaction_number = true;
    config.time_stamp = true;
    let scenario = scenario::info_data(&config);
    let run = run_scenario(
        &kind,
        &Capabilities::everything(),
        &scenario,
        scenario.steps(),
    );
    drop(run);
    let text = std::fs::read_to_string(&requests).unwrap();
    let _ = std::fs::remove_dir_all(dir);
    text.lines()
        .map(|line| serde_json::from_str(line).unwrap())
        .collect()
}

/// Every way to break one value: each JSON type and the edges of numbers.
fn replacements() -> Vec<Value> {
    vec![
        Value::Null,
        json!(true),
        json!([]),
        json!({}),
        json!("x"),
        json!(""),
        json!(-1),
        json!(0),
        json!(1.5),
        json!(127),
        json!(u64::MAX),
    ]
}

/// `value` with one change each: every field (at any depth) replaced by
/// each of [`replacements`], left out, or joined by an unknown one.
fn mutants(value: &Value) -> Vec<Value> {
    let mut out = Vec::new();
    match value {
        Value::Object(map) => {
            let mut added = map.clone();
            added.insert("no_such_field".into(), json!(1));
            out.push(Value::Object(added));
            for (key, inner) in map {
                let mut without = map.clone();
                without.remove(key);
                out.push(Value::Object(without));
                for replacement in replacements().into_iter().chain(mutants(inner)) {
                    let mut changed = map.clone();
                    changed.insert(key.clone(), replacement);
                    out.push(Value::Object(changed));
                }
            }
        }
        Value::Array(items) => {
            for (at, inner) in items.iter().enumerate().take(2) {
                for replacement in replacements().into_iter().chain(mutants(inner)) {
                    let mut changed = items.clone();
                    changed[at] = replacement;
                    out.push(Value::Array(changed));
                }
            }
        }
        _ => {}
    }
    out
}

#[test]
fn every_request_the_schema_refuses_is_refused() {
    let schema = schema();
    let mut refused_by_schema = 0;
    let mut taken = Vec::new();
    for version in [1, 2] {
        let requests = session(version);
        let configure = requests
            .iter()
            .find(|r| r["type"] == "configure")
            .expect("a session starts with configure")
            .clone();
        // One request of each kind is enough: the mutants cover its fields.
        let mut kinds: Vec<&Value> = Vec::new();
        for request in &requests {
            if !kinds.iter().any(|k| k["type"] == request["type"]) {
                kinds.push(request);
            }
        }
        let mut device = Command::new(CANIF)
            .args(["device", "--stdio", "--protocol", &version.to_string()])
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        let mut input = device.stdin.take().unwrap();
        let mut output = BufReader::new(device.stdout.take().unwrap());
        let mut ask = |request: &Value| -> Option<Value> {
            writeln!(input, "{request}").ok()?;
            let mut line = String::new();
            output.read_line(&mut line).ok()?;
            serde_json::from_str(&line).ok()
        };
        for kind in kinds {
            for mutant in mutants(kind) {
                if schema.is_valid(&mutant) {
                    continue;
                }
                refused_by_schema += 1;
                // A fresh, valid configuration before each, so that the
                // mutant is judged alone.
                if mutant["type"] != "configure" || kind["type"] != "configure" {
                    ask(&configure);
                }
                match ask(&mutant) {
                    Some(answer) if answer["type"] == "error" => {}
                    answer => taken.push(format!(
                        "protocol {version}: {mutant}\n    answered {answer:?}"
                    )),
                }
            }
        }
        drop(input);
        let _ = device.wait();
    }
    assert!(refused_by_schema > 200, "only {refused_by_schema} mutants");
    assert!(
        taken.is_empty(),
        "{} of {refused_by_schema} requests the schema refuses were taken:\n{}",
        taken.len(),
        taken.join("\n")
    );
}
