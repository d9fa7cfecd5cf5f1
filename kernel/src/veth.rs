//! A veth pair made for a test or a demonstration, removed when dropped: two
//! ends of a virtual Ethernet cable, one for an EtherCAT master and one for a
//! terminal. Made with iproute2 (`ip link`), which needs root (CAP_NET_ADMIN).

use std::process::Command;

/// The two ends; dropping the pair deletes both.
#[derive(Debug)]
pub struct VethPair {
    pub master: String,
    pub terminal: String,
}

impl VethPair {
    /// `cif{tag}m` and `cif{tag}t`, up; or why the pair cannot be made here
    /// (not root, no veth in this kernel, no `ip`).
    pub fn create(tag: &str) -> Result<VethPair, String> {
        let (master, terminal) = (format!("cif{tag}m"), format!("cif{tag}t"));
        // A pair left by a run that was killed goes first.
        let _ = ip(&["link", "del", &master]);
        ip(&[
            "link", "add", &master, "type", "veth", "peer", "name", &terminal,
        ])?;
        let pair = VethPair { master, terminal };
        ip(&["link", "set", &pair.master, "up"])?;
        ip(&["link", "set", &pair.terminal, "up"])?;
        Ok(pair)
    }

    /// The pair for `test`, or `None` after saying on stderr why the test
    /// is skipped; where CI requires veth pairs (`CANIF_VETH=required`, as
    /// root) a missing one fails the test instead of skipping it.
    pub fn for_test(tag: &str, test: &str) -> Option<VethPair> {
        match VethPair::create(tag) {
            Ok(pair) => Some(pair),
            Err(why) => {
                assert!(
                    std::env::var("CANIF_VETH").as_deref() != Ok("required"),
                    "CANIF_VETH=required, but no veth pair for {test}: {why}"
                );
                eprintln!("SKIP {test}: no veth pair here ({why})");
                None
            }
        }
    }
}

impl Drop for VethPair {
    fn drop(&mut self) {
        let _ = ip(&["link", "del", &self.master]);
    }
}

fn ip(args: &[&str]) -> Result<(), String> {
    let output = Command::new("ip")
        .args(args)
        .output()
        .map_err(|e| format!("ip: {e}"))?;
    match output.status.success() {
        true => Ok(()),
        false => Err(format!(
            "ip {}: {}",
            args.join(" "),
            String::from_utf8_lossy(&output.stderr).trim()
        )),
    }
}
