//! Stamps the commit canif was built from into the binary, for reports and
//! certificates (`unknown` outside a git checkout); and finds the tools some
//! tests need, so that a test whose tool is missing shows as ignored, with
//! the reason, instead of passing (never in CI, where it must run and fail).

use std::process::Command;

/// Whether `program --version` runs.
fn runs(program: &str) -> bool {
    Command::new(program)
        .arg("--version")
        .output()
        .is_ok_and(|o| o.status.success())
}

fn main() {
    println!("cargo::rustc-check-cfg=cfg(canif_no_tshark)");
    println!("cargo::rustc-check-cfg=cfg(canif_no_chromium)");
    println!("cargo::rustc-check-cfg=cfg(canif_no_ssh_keygen)");
    println!("cargo:rerun-if-env-changed=PATH");
    println!("cargo:rerun-if-env-changed=CI");
    if std::env::var_os("CI").is_none() {
        if !runs("tshark") {
            println!("cargo:rustc-cfg=canif_no_tshark");
        }
        if !["chromium", "chromium-browser", "google-chrome"]
            .into_iter()
            .any(runs)
        {
            println!("cargo:rustc-cfg=canif_no_chromium");
        }
    }
    let commit = Command::new("git")
        .args(["rev-parse", "--short=12", "HEAD"])
        .output()
        .ok()
        .filter(|o| o.status.success())
        .and_then(|o| String::from_utf8(o.stdout).ok())
        .map_or_else(|| "unknown".to_string(), |s| s.trim().to_string());
    println!("cargo:rustc-env=CANIF_COMMIT={commit}");
    for path in ["../.git/HEAD", "../.git/refs/heads"] {
        if std::path::Path::new(path).exists() {
            println!("cargo:rerun-if-changed={path}");
        }
    }
}
