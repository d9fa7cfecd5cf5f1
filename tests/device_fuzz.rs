//! `canif device --stdio` against 120,000 generated requests, seeded: valid
//! ones, ones with a field mutated (dropped, added, retyped, out of range),
//! random JSON and random bytes. Every request gets exactly one answer, in
//! time, valid against docs/adapter-protocol.schema.json; the device never
//! panics, hangs or exits early. The binary is the test profile's, so
//! arithmetic overflow panics instead of wrapping.

use std::io::{BufRead, BufReader, Write};
use std::process::{Command, Stdio};
use std::sync::mpsc;
use std::time::Duration;

use serde_json::{json, Value};

/// xorshift64*: the same seed, the same requests.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }
    fn below(&mut self, n: u64) -> u64 {
        self.next() % n.max(1)
    }
    fn pick<'a, T>(&mut self, items: &'a [T]) -> &'a T {
        &items[self.below(items.len() as u64) as usize]
    }
}

fn hex(rng: &mut Rng, bytes: usize) -> String {
    (0..bytes)
        .map(|_| format!("{:02x}", rng.below(256)))
        .collect()
}

fn frame(rng: &mut Rng) -> Value {
    let fd = rng.below(3) == 0;
    let len = if fd {
        *rng.pick(&[0, 8, 12, 20, 64])
    } else {
        rng.below(9) as usize
    };
    json!({"id": rng.below(0x800), "extended": false, "rtr": false, "fd": fd,
           "brs": fd && rng.below(2) == 0, "esi": false, "len": len, "data": hex(rng, len)})
}

/// What the generator configured last: the output image size of an accepted
/// 11-bit interface, so that most cycles carry an image of the right size.
struct Session {
    now: u64,
    output_size: usize,
}

fn configure(rng: &mut Rng, session: &mut Session) -> Value {
    if rng.below(4) != 0 {
        // An interface every profile of this capability set accepts.
        let slots = 1 + rng.below(32);
        session.output_size = 6 + 10 * slots as usize;
        return json!({"type": "configure", "protocol": 1,
            "config": {"format": "11-bit", "queue": "standard", "transaction_number": false,
                "time_stamp": false, "tx_slots": slots, "rx_slots": 1 + rng.below(32), "filters": [],
                "sync1_shift_ns": null, "nominal_timing": 0, "data_timing": 0,
                "output_size": session.output_size, "input_size": 0},
            "capabilities": {"base11": true, "ext29": true, "fd": true, "fast_queue": true,
                "optimized_queue": true, "transaction_number": true,
                "transaction_number_only_ext29": false, "timestamp": true, "filters": true,
                "info_data": true, "distributed_clocks": true, "max_slots": 32,
                "rx_queue_depth": 64, "tx_queue_depth": 64}});
    }
    let format = *rng.pick(&["11-bit", "29-bit", "fd"]);
    let queue = *rng.pick(&["standard", "optimized", "fast"]);
    json!({"type": "configure", "protocol": 1,
        "config": {"format": format, "queue": queue,
            "transaction_number": rng.below(2) == 0, "time_stamp": rng.below(2) == 0,
            "tx_slots": rng.below(34), "rx_slots": rng.below(34),
            "filters": if rng.below(3) == 0 { json!([{"action": "accept", "kind": "range", "from": 0, "to": 0x7FF}]) } else { json!([]) },
            "sync1_shift_ns": if rng.below(5) == 0 { json!(rng.below(1_000_000)) } else { Value::Null },
            "nominal_timing": rng.below(1 << 32), "data_timing": rng.below(1 << 32),
            "output_size": 0, "input_size": 0},
        "capabilities": {"base11": true, "ext29": true, "fd": true, "fast_queue": true,
            "optimized_queue": true, "transaction_number": true, "transaction_number_only_ext29": false,
            "timestamp": true, "filters": true, "info_data": true, "distributed_clocks": true,
            "max_slots": 32, "rx_queue_depth": 64, "tx_queue_depth": 64}})
}

fn valid(rng: &mut Rng, session: &mut Session) -> Value {
    session.now += rng.below(2_000_000);
    let now = session.now;
    match rng.below(9) {
        0 => configure(rng, session),
        1..=3 => {
            // Mostly the configured size, with arbitrary content: counters,
            // NoOfTxMessages beyond the slots, lengths above 8 (G3).
            let size = if rng.below(8) == 0 {
                rng.below(600) as usize
            } else {
                session.output_size
            };
            json!({"type": "cycle", "now_ns": now, "outputs": hex(rng, size)})
        }
        4 | 5 => json!({"type": "receive", "frame": frame(rng), "end_ns": now}),
        6 => json!({"type": "poll_transmit", "now_ns": now}),
        7 => json!({"type": "transmit_complete"}),
        _ => json!({"type": "controller_status", "status": {"bus_off": rng.below(2) == 0,
            "crc_errors": rng.below(1 << 32), "transceiver_delay": rng.below(1000)}}),
    }
}

/// A value of another kind than a field should have.
fn wrong_value(rng: &mut Rng) -> Value {
    match rng.below(8) {
        0 => json!(-1),
        1 => json!(u64::MAX),
        2 => json!(1.5),
        3 => json!("+0"),
        4 => Value::Null,
        5 => json!([1, 2]),
        6 => json!({"x": 1}),
        _ => json!(4_294_967_304u64),
    }
}

/// Changes one field somewhere in `value`: drops it, adds one, or retypes it.
fn mutate(rng: &mut Rng, value: &mut Value) {
    let Value::Object(map) = value else { return };
    let keys: Vec<String> = map.keys().cloned().collect();
    let key = rng.pick(&keys).clone();
    match rng.below(4) {
        0 if key != "type" => {
            map.remove(&key);
        }
        1 => {
            map.insert("unexpected".into(), json!(true));
        }
        2 => {
            if let Some(inner) = map.get_mut(&key) {
                if inner.is_object() {
                    mutate(rng, inner);
                    return;
                }
            }
            map.insert(key, wrong_value(rng));
        }
        _ => {
            map.insert(key, wrong_value(rng));
        }
    }
}

fn request_line(rng: &mut Rng, session: &mut Session) -> Vec<u8> {
    match rng.below(10) {
        0..=6 => valid(rng, session).to_string().into_bytes(),
        7 | 8 => {
            let mut value = valid(rng, session);
            mutate(rng, &mut value);
            value.to_string().into_bytes()
        }
        _ => match rng.below(3) {
            0 => (0..rng.below(40))
                .map(|_| rng.below(256) as u8)
                .filter(|b| *b != b'\n')
                .collect(),
            1 => json!([1, {"type": "cycle"}]).to_string().into_bytes(),
            _ => b"{\"type\": \"no-such-request\"}".to_vec(),
        },
    }
}

fn schema() -> jsonschema::Validator {
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/docs/adapter-protocol.schema.json"
    ))
    .unwrap();
    jsonschema::validator_for(&serde_json::from_str(&text).unwrap()).unwrap()
}

/// One device process, `count` requests from `seed`: (answers, errors answered).
fn batch(seed: u64, count: usize, schema: &jsonschema::Validator) -> (usize, usize) {
    let mut device = Command::new(env!("CARGO_BIN_EXE_canif"))
        .args(["device", "--stdio"])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut stdin = device.stdin.take().unwrap();
    let (sender, answers) = mpsc::channel();
    let stdout = device.stdout.take().unwrap();
    std::thread::spawn(move || {
        for line in BufReader::new(stdout).lines() {
            if sender.send(line.unwrap()).is_err() {
                break;
            }
        }
    });
    let mut rng = Rng(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1);
    let mut session = Session {
        now: 0,
        output_size: 0,
    };
    let mut errors = 0;
    for n in 0..count {
        let mut line = request_line(&mut rng, &mut session);
        if line.iter().all(u8::is_ascii_whitespace) {
            line.push(b'x'); // a blank line is skipped, not answered (the protocol's rule)
        }
        line.push(b'\n');
        stdin.write_all(&line).unwrap();
        stdin.flush().unwrap();
        let Ok(answer) = answers.recv_timeout(Duration::from_secs(5)) else {
            let _ = device.kill();
            let mut stderr = String::new();
            let _ = std::io::Read::read_to_string(&mut device.stderr.take().unwrap(), &mut stderr);
            panic!(
                "seed {seed}, request {n}: no answer to {}\nstderr: {stderr}",
                String::from_utf8_lossy(&line)
            )
        };
        let value: Value = serde_json::from_str(&answer).unwrap();
        let invalid: Vec<String> = schema.iter_errors(&value).map(|e| e.to_string()).collect();
        assert!(
            invalid.is_empty(),
            "seed {seed}, request {n}: {}\nanswer {answer}\nviolates the schema: {invalid:?}",
            String::from_utf8_lossy(&line)
        );
        errors += usize::from(value["type"] == "error");
    }
    drop(stdin);
    let status = device.wait().unwrap();
    assert!(
        status.success(),
        "seed {seed}: the device ended with {status}"
    );
    (count, errors)
}

#[test]
fn the_soft_device_answers_every_request_within_the_schema() {
    let schema = schema();
    let (mut answered, mut errors) = (0, 0);
    for seed in 1..=12 {
        let (n, e) = batch(seed, 10_000, &schema);
        answered += n;
        errors += e;
    }
    eprintln!("{answered} requests answered, {errors} of them with an error answer");
    assert_eq!(answered, 120_000);
    // The generator is not trivial: a good share is refused, a good share served.
    assert!(errors > 10_000 && errors < 70_000, "{errors} error answers");
}
