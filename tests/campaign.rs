//! A campaign in shards, as docs/campaigns.md runs one: `canif run --shard
//! K/N` on each machine, `canif merge` joining them. The merged verdicts are
//! the single run's, requirement by requirement, on both sides; shards that
//! are not one campaign are refused, naming what differs or is missing.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use canif_harness::report::ReportFile;

fn canif(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_canif"))
        .args(args)
        .output()
        .expect("canif runs")
}

fn stderr(output: &Output) -> String {
    String::from_utf8_lossy(&output.stderr).into_owned()
}

fn report(dir: &Path) -> ReportFile {
    let text = std::fs::read_to_string(dir.join("report.json")).expect("report.json is written");
    ReportFile::parse(&text).expect("report.json reads back")
}

fn temp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("canif-campaign-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The run of `args` once whole and once in `count` shards, merged:
/// (the single run's folder, the shards' folders, the merged folder).
fn single_and_merged(name: &str, args: &[&str], count: u32) -> (PathBuf, Vec<PathBuf>, PathBuf) {
    let dir = temp(name);
    let single = dir.join("single");
    let whole = canif(&[args, &["--report", single.to_str().unwrap()]].concat());
    let mut shards = Vec::new();
    for index in 1..=count {
        let shard = dir.join(format!("shard-{index}"));
        let share = format!("{index}/{count}");
        let output = canif(
            &[
                args,
                &["--shard", &share, "--report", shard.to_str().unwrap()],
            ]
            .concat(),
        );
        assert!(
            shard.join("shard.json").is_file(),
            "shard {share} wrote no shard.json: {}",
            stderr(&output)
        );
        shards.push(shard);
    }
    let merged = dir.join("merged");
    let mut merge_args = vec!["merge".to_string()];
    // Given in any order.
    merge_args.extend(shards.iter().rev().map(|s| s.display().to_string()));
    merge_args.extend(["--report".into(), merged.display().to_string()]);
    merge_args.extend([
        "--certificate".into(),
        dir.join("certificate").display().to_string(),
    ]);
    let merge_args: Vec<&str> = merge_args.iter().map(String::as_str).collect();
    let joined = canif(&merge_args);
    assert_eq!(
        joined.status.code(),
        whole.status.code(),
        "the merge's exit code is the single run's: {}",
        stderr(&joined)
    );
    (single, shards, merged)
}

/// The merged report says what the single run says: every verdict with its
/// evidence and reason, every check in the plan's order, every failure.
fn assert_same_run(single: &Path, shards: &[PathBuf], merged: &Path) {
    let (one, joined) = (report(single), report(merged));
    assert_eq!(joined.totals, one.totals);
    assert_eq!(joined.meta.complete, one.meta.complete);
    assert_eq!(joined.meta.shard, None);
    assert_eq!(joined.profiles.len(), one.profiles.len());
    for (a, b) in one.profiles.iter().zip(&joined.profiles) {
        assert_eq!(a.verdicts, b.verdicts, "{}: the verdicts", a.profile);
        let names = |p: &canif_harness::report::ProfileEntry| {
            p.checks
                .iter()
                .map(|c| (c.check.clone(), c.outcome))
                .collect::<Vec<_>>()
        };
        assert_eq!(names(a), names(b), "{}: the checks, in order", a.profile);
        assert_eq!(a.failures, b.failures, "{}: the failures", a.profile);
        assert_eq!((a.cycles, a.frames_checked), (b.cycles, b.frames_checked));
    }
    // Each shard ran a share: fewer checks than the whole, and together all of them once.
    let mut ran = 0;
    for shard in shards {
        let part = report(shard);
        assert!(part.meta.shard.is_some() && !part.meta.complete);
        let checks: usize = part.profiles.iter().map(|p| p.checks.len()).sum();
        ran += checks;
    }
    let whole: usize = one.profiles.iter().map(|p| p.checks.len()).sum();
    assert_eq!(ran, whole, "the shards ran every check once");
    // The certificate is the merged run's.
    let certificate = std::fs::read_to_string(
        merged
            .parent()
            .unwrap()
            .join("certificate/certificate.json"),
    )
    .expect("the merge wrote the certificate");
    let certificate: serde_json::Value = serde_json::from_str(&certificate).unwrap();
    let verdicts = certificate["verdicts"].as_object().expect("verdicts");
    for p in &one.profiles {
        for (id, verdict) in &p.verdicts {
            let key = format!("{}::{id}", p.profile);
            assert_eq!(
                verdicts[&key]["verdict"],
                serde_json::to_value(verdict.verdict).unwrap(),
                "{key} in the certificate"
            );
        }
    }
}

#[test]
fn merged_device_shards_are_the_single_run_failures_and_all() {
    let args = [
        "run",
        "--profile",
        "el6751-mdp",
        "--fault",
        "ack-before-accept",
        "--fault",
        "rtr-bit-misplaced",
    ];
    let (single, shards, merged) = single_and_merged("device", &args, 3);
    let one = report(&single);
    assert!(
        one.totals.fail > 0,
        "the faults fail requirements: the check can tell"
    );
    assert!(
        one.profiles.iter().any(|p| !p.failures.is_empty()),
        "lockstep failures, re-indexed by the merge"
    );
    assert_same_run(&single, &shards, &merged);
}

#[test]
fn merged_plc_shards_are_the_single_run() {
    let args = [
        "run",
        "plc",
        "--iut",
        "softclient",
        "--fault",
        "acknowledges-with-tx-counter",
        "--profile",
        "el6751-mdp",
        "--profile",
        "fc532x",
    ];
    let (single, shards, merged) = single_and_merged("plc", &args, 2);
    assert!(report(&single).totals.fail > 0);
    assert_same_run(&single, &shards, &merged);
}

#[test]
fn a_complete_campaign_conforms_and_its_shards_alone_do_not() {
    let (single, shards, merged) =
        single_and_merged("clean", &["run", "--profile", "el6751-mdp"], 2);
    assert!(report(&single).meta.complete);
    assert!(
        report(&merged).meta.complete,
        "all shards: nothing left out"
    );
    for shard in &shards {
        let summary = std::fs::read_to_string(shard.join("summary.md")).unwrap();
        assert!(
            summary.contains("PASSES WHAT RAN"),
            "a shard alone: {summary}"
        );
        assert!(summary.contains("--shard"), "{summary}");
    }
    let summary = std::fs::read_to_string(merged.join("summary.md")).unwrap();
    assert!(summary.contains("**CONFORMS**"), "{summary}");
}

#[test]
fn shards_that_are_not_one_campaign_are_refused() {
    let dir = temp("refused");
    let shard = |name: &str, extra: &[&str]| {
        let out = dir.join(name);
        let args = [
            &["run", "--profile", "el6751-mdp"],
            extra,
            &["--report", out.to_str().unwrap()],
        ]
        .concat();
        let output = canif(&args);
        assert!(out.join("report.json").is_file(), "{}", stderr(&output));
        out.display().to_string()
    };
    let one = shard("one", &["--shard", "1/3"]);
    let three = shard("three", &["--shard", "3/3"]);
    let two_other_seed = shard("two-seed", &["--shard", "2/3", "--seed", "7"]);
    let whole = shard("whole", &[]);
    let merged = dir.join("merged").display().to_string();
    let refused = |args: &[&str], says: &str| {
        let output = canif(&[&["merge"], args, &["--report", &merged]].concat());
        assert_eq!(output.status.code(), Some(2), "{args:?}");
        let text = stderr(&output);
        assert!(text.contains(says), "{args:?} should say `{says}`: {text}");
        assert!(
            !Path::new(&merged).join("report.json").exists(),
            "nothing merged"
        );
    };
    refused(&[&one, &three], "shard 2/3 is missing");
    refused(&[&one, &one, &three], "shard 1/3 is given twice");
    refused(&[&one, &two_other_seed, &three], "the seed is `1`");
    // What the run's flags shape (here the generated cases) is one campaign's too.
    let two_more_cases = shard("two-cases", &["--shard", "2/3", "--cases", "6"]);
    refused(&[&one, &two_more_cases, &three], "the command line");
    // Written in another order, and with reports and jobs of its own, it is the same.
    let two = dir.join("two");
    let output = canif(&[
        "run",
        "--jobs",
        "2",
        "--report",
        two.to_str().unwrap(),
        "--shard=2/3",
        "--profile",
        "el6751-mdp",
    ]);
    assert!(two.join("shard.json").is_file(), "{}", stderr(&output));
    let output = canif(&[
        "merge",
        &one,
        two.to_str().unwrap(),
        &three,
        "--report",
        &merged,
    ]);
    assert_eq!(output.status.code(), Some(0), "{}", stderr(&output));
    std::fs::remove_dir_all(&merged).unwrap();
    refused(&[&whole], "shard.json");
    let garbage = dir.join("garbage.json");
    std::fs::write(&garbage, "{\"format\": 1, \"shard\": 3}").unwrap();
    refused(
        &[garbage.to_str().unwrap()],
        "garbage.json: not a canif shard.json",
    );
    // A part that says it is shard 0 of 3 is no shard.
    let part = std::fs::read_to_string(Path::new(&one).join("shard.json")).unwrap();
    let mut part: serde_json::Value = serde_json::from_str(&part).unwrap();
    part["shard"]["index"] = 0.into();
    let zero = dir.join("zero.json");
    std::fs::write(&zero, part.to_string()).unwrap();
    refused(
        &[zero.to_str().unwrap()],
        "shard 0/3: shards count from 1 to N",
    );
    // A shard that runs again where a whole run was leaves no part behind.
    let again = dir.join("one");
    canif(&[
        "run",
        "--profile",
        "el6751-mdp",
        "--report",
        again.to_str().unwrap(),
    ]);
    assert!(
        !again.join("shard.json").exists(),
        "a stale shard.json would merge a run that is gone"
    );
    // The CANopen suite's node profile is made for its run: it has no
    // --shard, and clap says so.
    let output = canif(&["run", "canopen", "--shard", "1/2"]);
    assert_eq!(output.status.code(), Some(2));
    assert!(
        stderr(&output).contains("unexpected argument '--shard'"),
        "{}",
        stderr(&output)
    );
    // A shard is K of N.
    let output = canif(&["run", "--shard", "4/3"]);
    assert_eq!(output.status.code(), Some(2));
    assert!(
        stderr(&output).contains("shards count from 1 to N"),
        "{}",
        stderr(&output)
    );
}

/// Every flag docs/campaigns.md gives `canif run` or `canif merge` is one
/// the command has: the doc cannot drift from the CLI unnoticed.
#[test]
fn the_campaign_doc_uses_flags_canif_has() {
    let doc = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/docs/campaigns.md"))
        .expect("docs/campaigns.md");
    let help = |sub: &str| {
        let output = canif(&[sub, "--help"]);
        String::from_utf8_lossy(&output.stdout).into_owned()
    };
    let (run, merge) = (help("run"), help("merge"));
    let mut checked = 0;
    for line in doc.lines() {
        // The flags after the subcommand, not cargo's before it.
        let found = ["canif run ", "-- run ", "canif merge ", "-- merge "]
            .iter()
            .find_map(|at| Some((*at, line.split_once(at)?.1)));
        let Some((at, flags)) = found else { continue };
        let sub = if at.ends_with("run ") { &run } else { &merge };
        for flag in flags
            .split_whitespace()
            .filter(|t| t.starts_with("--") && t.len() > 2)
        {
            let flag: String = flag
                .chars()
                .take_while(|c| c.is_ascii_alphanumeric() || *c == '-')
                .collect();
            assert!(
                sub.contains(&flag),
                "docs/campaigns.md: `{flag}` in `{line}`"
            );
            checked += 1;
        }
    }
    assert!(
        checked >= 10,
        "the doc's commands were found ({checked} flags)"
    );
}
