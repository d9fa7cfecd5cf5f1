//! Finds the tools some of the command line's tests need, so that a test
//! whose tool is missing shows as ignored with the reason instead of
//! passing; never in CI (`CI` set), where each must run, and fails without it.

use std::process::Command;

fn succeeds(program: &str, args: &[&str]) -> bool {
    Command::new(program)
        .args(args)
        .output()
        .is_ok_and(|o| o.status.success())
}

fn main() {
    println!("cargo::rustc-check-cfg=cfg(canif_no_libasan)");
    println!("cargo::rustc-check-cfg=cfg(canif_no_python_canopen)");
    println!("cargo:rerun-if-env-changed=PATH");
    println!("cargo:rerun-if-env-changed=CI");
    println!("cargo:rerun-if-changed=build.rs");
    if std::env::var_os("CI").is_some() {
        return;
    }
    let asan = Command::new("cc")
        .arg("-print-file-name=libasan.so")
        .output()
        .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
        .unwrap_or_default();
    if !std::path::Path::new(&asan).exists() {
        println!("cargo:rustc-cfg=canif_no_libasan");
    }
    if !succeeds("python3", &["-c", "import canopen, can"]) {
        println!("cargo:rustc-cfg=canif_no_python_canopen");
    }
}
