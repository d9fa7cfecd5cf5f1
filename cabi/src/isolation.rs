//! What an implementation under test starts stays within canif's reach.
//!
//! The first process of an IUT is made a child subreaper (prctl(2),
//! `PR_SET_CHILD_SUBREAPER`, kept across execve): a process its tree
//! orphans — a daemon's double fork, a child that calls `setsid`, whatever
//! its environment — is re-parented to that first process instead of to
//! init, so the tree below it is every process the IUT started, and
//! [`end_tree`] ends all of them. canif is a subreaper too
//! ([`adopt_orphans`]): what an IUT's first process leaves when it exits
//! comes to canif, not to init, with its own tree whole, and [`Snapshot`]
//! finds it again.

use std::collections::BTreeSet;
use std::os::unix::process::CommandExt;
use std::process::Command;

/// Makes the process `command` starts a child subreaper.
pub fn as_subreaper(command: &mut Command) -> &mut Command {
    // SAFETY: between fork and exec only prctl(2), which is async-signal-safe,
    // is called; it allocates nothing and takes no lock.
    unsafe {
        command.pre_exec(|| {
            if libc::prctl(libc::PR_SET_CHILD_SUBREAPER, 1, 0, 0, 0) == 0 {
                Ok(())
            } else {
                Err(std::io::Error::last_os_error())
            }
        })
    }
}

/// Hands the process `command` starts each `(fd, number)`: the file `fd`
/// as descriptor `number` (a control channel apart from stdin and stdout).
/// The caller keeps each `fd` open until the process is started.
pub fn hand_over(command: &mut Command, fds: &[(std::os::fd::BorrowedFd<'_>, i32)]) {
    use std::os::fd::AsRawFd;
    let fds: Vec<(i32, i32)> = fds.iter().map(|(fd, to)| (fd.as_raw_fd(), *to)).collect();
    // SAFETY: between fork and exec only dup2(2), async-signal-safe; the
    // vector was allocated before the fork and is only read.
    unsafe {
        command.pre_exec(move || {
            // Out of the way first: a source may be numbered like a target.
            let mut high = [0; 8];
            for (at, (from, _)) in fds.iter().enumerate().take(high.len()) {
                high[at] = libc::fcntl(*from, libc::F_DUPFD, 100);
                if high[at] < 0 {
                    return Err(std::io::Error::last_os_error());
                }
            }
            for (at, (_, to)) in fds.iter().enumerate().take(high.len()) {
                if libc::dup2(high[at], *to) < 0 {
                    return Err(std::io::Error::last_os_error());
                }
                libc::close(high[at]);
            }
            Ok(())
        });
    }
}

/// Makes this process a child subreaper: an orphan of a process it started
/// comes to it instead of to init.
pub fn adopt_orphans() {
    // SAFETY: prctl(2) with integer arguments only.
    unsafe { libc::prctl(libc::PR_SET_CHILD_SUBREAPER, 1, 0, 0, 0) };
}

/// Whether `pid` is a process that has not ended (a zombie has).
fn running(pid: i32) -> bool {
    std::fs::read_to_string(format!("/proc/{pid}/stat")).is_ok_and(|stat| {
        let state = stat.rfind(')').map(|at| stat[at + 1..].trim_start());
        state.is_some_and(|state| !state.starts_with('Z') && !state.starts_with('X'))
    })
}

/// A process's start time in clock ticks since boot (`/proc/PID/stat`
/// field 22): with the pid, it names one process, never a later one that
/// reuses the pid.
fn started(pid: i32) -> Option<u64> {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).ok()?;
    let after = &stat[stat.rfind(')')? + 1..];
    after.split_whitespace().nth(19)?.parse().ok()
}

/// The processes below a root at one moment, each named by pid and start time.
#[derive(Debug, Clone, Default)]
pub struct Snapshot(Vec<(i32, u64)>);

impl Snapshot {
    /// Every process below `root` now.
    pub fn below(root: u32) -> Snapshot {
        let Ok(root) = i32::try_from(root) else {
            return Snapshot::default();
        };
        let all = parents();
        let mut tree = BTreeSet::from([root]);
        loop {
            let found: Vec<i32> = all
                .iter()
                .filter(|(pid, ppid)| tree.contains(ppid) && !tree.contains(pid))
                .map(|(pid, _)| *pid)
                .collect();
            if found.is_empty() {
                break;
            }
            tree.extend(found);
        }
        tree.remove(&root);
        Snapshot(
            tree.into_iter()
                .filter_map(|pid| Some((pid, started(pid)?)))
                .collect(),
        )
    }

    /// Ends each process of the snapshot that still runs (the same process:
    /// same pid, same start time) with everything below it.
    pub fn end(&self) {
        for (pid, at) in &self.0 {
            if started(*pid) == Some(*at) {
                end_tree(*pid as u32);
            }
        }
    }
}

/// Every process's parent, read from /proc (a process that ends while it is
/// read is left out).
fn parents() -> Vec<(i32, i32)> {
    let Ok(entries) = std::fs::read_dir("/proc") else {
        return Vec::new();
    };
    entries
        .filter_map(|entry| entry.ok()?.file_name().to_str()?.parse::<i32>().ok())
        .filter_map(|pid| {
            let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).ok()?;
            // `pid (comm) state ppid …`: comm may hold spaces and parentheses.
            let after = &stat[stat.rfind(')')? + 1..];
            let ppid = after.split_whitespace().nth(1)?.parse().ok()?;
            Some((pid, ppid))
        })
        .collect()
}

/// Ends `root` and every process below it: each is stopped first, round by
/// round until a round finds no new one (so none can fork past the count),
/// then all are killed. A process of another user cannot be signalled and is
/// left as it is.
pub fn end_tree(root: u32) {
    let Ok(root) = i32::try_from(root) else {
        return;
    };
    let signal = |pid: i32, signal: i32| {
        // SAFETY: kill(2) with a pid this tree held; no memory is passed.
        unsafe { libc::kill(pid, signal) };
    };
    let mut tree = BTreeSet::from([root]);
    signal(root, libc::SIGSTOP);
    for _ in 0..1000 {
        let found: Vec<i32> = parents()
            .into_iter()
            .filter(|(pid, ppid)| tree.contains(ppid) && !tree.contains(pid))
            .map(|(pid, _)| pid)
            .collect();
        if found.is_empty() {
            break;
        }
        for pid in found {
            signal(pid, libc::SIGSTOP);
            tree.insert(pid);
        }
    }
    for pid in tree.iter().rev() {
        signal(*pid, libc::SIGKILL);
    }
    // SIGKILL is sure, but not at once: on a busy machine a process may
    // still run a moment after it. Wait until each is gone or a zombie, so
    // that nothing of the tree outlives this call.
    for _ in 0..5_000 {
        if tree.iter().all(|pid| !running(*pid)) {
            break;
        }
        std::thread::sleep(std::time::Duration::from_millis(1));
    }
    // What was re-parented to this process (see `adopt_orphans`) is reaped
    // here, the root by whoever started it.
    for pid in tree.iter().filter(|pid| **pid != root) {
        // SAFETY: waitpid(2) on one pid, no status kept.
        unsafe { libc::waitpid(*pid, std::ptr::null_mut(), libc::WNOHANG) };
    }
}
