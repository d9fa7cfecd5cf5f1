//! `canif spec plan` publishes what the suite tests before it tests it:
//! every requirement and every case of both sides' runs appears, each case
//! with what it checks, and the plan follows the catalogue it is made from.

use std::path::{Path, PathBuf};
use std::process::Command;

fn canif(args: &[&str]) -> String {
    let output = Command::new(env!("CARGO_BIN_EXE_canif"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("canif runs");
    assert!(
        output.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&output.stderr)
    );
    String::from_utf8_lossy(&output.stdout).into_owned()
}

fn temp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("canif-plan-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

fn plan(spec: Option<&Path>, name: &str) -> (String, String) {
    let dir = temp(name);
    let dir_text = dir.display().to_string();
    let mut args = Vec::new();
    let spec_text;
    if let Some(spec) = spec {
        spec_text = spec.display().to_string();
        args.extend(["--spec", spec_text.as_str()]);
    }
    args.extend(["spec", "plan", "--out", dir_text.as_str()]);
    canif(&args);
    (
        std::fs::read_to_string(dir.join("test-plan.md")).unwrap(),
        std::fs::read_to_string(dir.join("test-plan.html")).unwrap(),
    )
}

/// The markdown escapes what Markdown would read as markup.
fn escaped(name: &str) -> String {
    name.chars()
        .flat_map(|c| match c {
            '[' | ']' | '<' | '>' | '*' | '_' | '|' | '#' | '`' | '\\' => vec!['\\', c],
            c => vec![c],
        })
        .collect()
}

#[test]
fn every_requirement_and_every_case_of_both_sides_appears() {
    let (md, html) = plan(None, "embedded");
    for line in canif(&["spec", "list"]).lines() {
        let id = line.split_whitespace().next().unwrap();
        assert!(md.contains(&format!("\n#### {id}\n")), "{id} has no entry");
        assert!(
            html.contains(&format!("id=\"req-{}\"", id.to_ascii_lowercase())),
            "{id} in the HTML"
        );
    }
    let mut cases = 0;
    for side in ["device", "plc"] {
        for line in canif(&["list", "scenarios", "--profile", "all", "--side", side]).lines() {
            let name = line.split('\t').nth(1).unwrap();
            assert!(
                md.contains(&format!("\n#### {}\n", escaped(name))),
                "{side} case `{name}` is missing"
            );
            cases += 1;
        }
    }
    assert!(cases > 500, "{cases} cases listed");
    // A case says what it checks and what it expects; a Gherkin one its steps.
    let refusals = md
        .split("\n#### configuration refusals\n")
        .nth(1)
        .expect("the refusal grid");
    let entry = &refusals[..refusals.find("\n#### ").unwrap()];
    assert!(entry.contains("[PROF-001](#req-prof-001)") && entry.contains("**Expected:**"));
    assert!(
        md.contains("*(expected)*"),
        "Then steps are marked as expected results"
    );
    // A requirement names its source, rulings, profiles, cases and faults.
    let r1 = md.split("\n#### FD-LEN-003\n").nth(1).expect("FD-LEN-003");
    let entry = &r1[..r1.find("\n#### ").unwrap()];
    for part in [
        "**Source:**",
        "**Ruling R1**",
        "32",
        "**Profiles:** cx-m530",
        "**Checked by:**",
        "device fault `fd-length-rounds-down`",
    ] {
        assert!(entry.contains(part), "FD-LEN-003 lacks `{part}`:\n{entry}");
    }
    assert!(md.contains("## 5. Traceability matrix") && html.contains("<table>"));
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for entry in std::fs::read_dir(from).unwrap() {
        let entry = entry.unwrap();
        let target = to.join(entry.file_name());
        if entry.file_type().unwrap().is_dir() {
            copy_dir(&entry.path(), &target);
        } else {
            std::fs::copy(entry.path(), target).unwrap();
        }
    }
}

#[test]
fn the_plan_follows_the_catalogue() {
    let spec = temp("spec");
    copy_dir(&Path::new(env!("CARGO_MANIFEST_DIR")).join("spec"), &spec);
    let file = spec.join("requirements/handshake-tx.yaml");
    let text = std::fs::read_to_string(&file).expect("the Tx handshake's requirements");
    let statement = "In every cycle the device checks whether Outputs.TxCounter has changed";
    assert!(text.contains(statement));
    std::fs::write(
        &file,
        text.replace(
            statement,
            "In every cycle the edited device checks whether Outputs.TxCounter has changed",
        ),
    )
    .unwrap();
    let (before, _) = plan(None, "before");
    let (after, _) = plan(Some(&spec), "after");
    assert_ne!(before, after);
    assert!(after.contains("the edited device checks") && !before.contains("the edited device"));
}
