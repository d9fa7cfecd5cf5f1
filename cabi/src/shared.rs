//! Memory two processes share, and the wake-ups between them: what the
//! adapter protocol's version 3 runs on (docs/adapter-protocol.md, "Protocol
//! 3"). A [`SharedMap`] is a memfd both map; a [`Wake`] is an eventfd. The
//! layout and the records are the harness's (`door::adapter::shared`); this
//! module only holds the `unsafe` that reaching them needs, behind calls
//! that check every offset.

use std::io;
use std::os::fd::{AsFd, AsRawFd, BorrowedFd, FromRawFd, OwnedFd};
use std::sync::atomic::AtomicU32;
use std::time::Duration;

/// A shared mapping of a memfd: created by the harness, opened from the
/// descriptor it hands over by the implementation under test.
pub struct SharedMap {
    ptr: *mut u8,
    len: usize,
    fd: OwnedFd,
}

// SAFETY: the mapping lives as long as the value; every access goes through
// the bounds-checked copies and atomics below.
unsafe impl Send for SharedMap {}

impl SharedMap {
    /// A new memfd of `len` zero bytes (`name` shows in /proc/PID/fd), mapped.
    pub fn create(name: &str, len: usize) -> io::Result<SharedMap> {
        let name = std::ffi::CString::new(name).map_err(io::Error::other)?;
        // SAFETY: a NUL-terminated name and flags; the result is checked.
        let raw = unsafe { libc::memfd_create(name.as_ptr(), libc::MFD_CLOEXEC) };
        if raw < 0 {
            return Err(io::Error::last_os_error());
        }
        // SAFETY: memfd_create returned a descriptor this process owns alone.
        let fd = unsafe { OwnedFd::from_raw_fd(raw) };
        let size = libc::off_t::try_from(len).map_err(io::Error::other)?;
        // SAFETY: a descriptor this process owns, a size checked above.
        if unsafe { libc::ftruncate(fd.as_raw_fd(), size) } != 0 {
            return Err(io::Error::last_os_error());
        }
        SharedMap::map(fd, len)
    }

    /// Maps the memfd `fd` another process created (its whole size).
    pub fn open(fd: OwnedFd) -> io::Result<SharedMap> {
        // SAFETY: fstat into a zeroed struct of the right type.
        let mut stat: libc::stat = unsafe { std::mem::zeroed() };
        // SAFETY: `fd` is an open descriptor we own; fstat(2) writes only `stat`.
        if unsafe { libc::fstat(fd.as_raw_fd(), &mut stat) } != 0 {
            return Err(io::Error::last_os_error());
        }
        let len = usize::try_from(stat.st_size).map_err(io::Error::other)?;
        SharedMap::map(fd, len)
    }

    fn map(fd: OwnedFd, len: usize) -> io::Result<SharedMap> {
        if len == 0 {
            return Err(io::Error::other("an empty shared mapping"));
        }
        // SAFETY: a shared mapping of `len` bytes of an open descriptor; checked below.
        let ptr = unsafe {
            libc::mmap(
                std::ptr::null_mut(),
                len,
                libc::PROT_READ | libc::PROT_WRITE,
                libc::MAP_SHARED,
                fd.as_raw_fd(),
                0,
            )
        };
        if ptr == libc::MAP_FAILED {
            return Err(io::Error::last_os_error());
        }
        Ok(SharedMap {
            ptr: ptr.cast(),
            len,
            fd,
        })
    }

    pub fn len(&self) -> usize {
        self.len
    }

    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The memfd, to hand to another process.
    pub fn fd(&self) -> BorrowedFd<'_> {
        self.fd.as_fd()
    }

    #[inline]
    fn check(&self, at: usize, len: usize) {
        assert!(
            at.checked_add(len).is_some_and(|end| end <= self.len),
            "{len} bytes at {at} lie outside the shared mapping of {} bytes",
            self.len
        );
    }

    /// Copies `into.len()` bytes from offset `at`. Panics outside the mapping.
    #[inline]
    pub fn read(&self, at: usize, into: &mut [u8]) {
        self.check(at, into.len());
        // SAFETY: inside the mapping (checked); the protocol's turns keep the
        // other process from writing these bytes meanwhile, and a byte copy
        // is sound whatever they hold.
        unsafe { std::ptr::copy_nonoverlapping(self.ptr.add(at), into.as_mut_ptr(), into.len()) }
    }

    /// Copies `from` to offset `at`. Panics outside the mapping.
    #[inline]
    pub fn write(&self, at: usize, from: &[u8]) {
        self.check(at, from.len());
        // SAFETY: as for `read`.
        unsafe { std::ptr::copy_nonoverlapping(from.as_ptr(), self.ptr.add(at), from.len()) }
    }

    /// The 32-bit word at `at` (4-aligned), as an atomic both processes see.
    #[inline]
    pub fn word(&self, at: usize) -> &AtomicU32 {
        self.check(at, 4);
        assert_eq!(at % 4, 0, "a word at {at} is not aligned");
        // SAFETY: inside the mapping, aligned (the mapping is page-aligned),
        // and only ever accessed as an atomic by either process.
        unsafe { &*self.ptr.add(at).cast::<AtomicU32>() }
    }
}

impl Drop for SharedMap {
    fn drop(&mut self) {
        // SAFETY: the mapping made in `map`, unmapped once.
        unsafe { libc::munmap(self.ptr.cast(), self.len) };
    }
}

/// A descriptor of our own for descriptor number `fd` that another process
/// handed over (a duplicate: the number itself stays as it was).
pub fn inherited(fd: i32) -> io::Result<OwnedFd> {
    // SAFETY: fcntl(2) on any number; an invalid one fails with EBADF.
    let raw = unsafe { libc::fcntl(fd, libc::F_DUPFD_CLOEXEC, 10) };
    if raw < 0 {
        return Err(io::Error::last_os_error());
    }
    // SAFETY: F_DUPFD_CLOEXEC made a new descriptor this value alone owns.
    Ok(unsafe { OwnedFd::from_raw_fd(raw) })
}

/// How many CPUs this thread may run on: where it is one, waiting for
/// another process by spinning only keeps that process from running.
pub fn cpus_allowed() -> usize {
    // SAFETY: a zeroed cpu_set_t filled in by sched_getaffinity(2).
    let mut set: libc::cpu_set_t = unsafe { std::mem::zeroed() };
    // SAFETY: sched_getaffinity(2) writes at most the size it is given into `set`.
    if unsafe { libc::sched_getaffinity(0, std::mem::size_of::<libc::cpu_set_t>(), &mut set) } != 0
    {
        return 1;
    }
    // SAFETY: CPU_COUNT reads the set just filled.
    usize::try_from(unsafe { libc::CPU_COUNT(&set) }).unwrap_or(1)
}

/// An eventfd: one process signals, the other wakes.
pub struct Wake(OwnedFd);

/// What a [`Wake::wait`] ended with.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Woken {
    /// The eventfd was signalled (perhaps earlier than this turn: look again).
    Signalled,
    /// The other descriptor waited on is readable, or closed.
    Other,
    /// Neither within the time given.
    TimedOut,
}

impl Wake {
    pub fn new() -> io::Result<Wake> {
        // SAFETY: eventfd(2) with flags; the result is checked.
        let raw = unsafe { libc::eventfd(0, libc::EFD_CLOEXEC | libc::EFD_NONBLOCK) };
        if raw < 0 {
            return Err(io::Error::last_os_error());
        }
        // SAFETY: a descriptor this process owns alone.
        Ok(Wake(unsafe { OwnedFd::from_raw_fd(raw) }))
    }

    /// The eventfd another process handed over.
    pub fn from_fd(fd: OwnedFd) -> Wake {
        Wake(fd)
    }

    pub fn fd(&self) -> BorrowedFd<'_> {
        self.0.as_fd()
    }

    /// Wakes the process waiting on it.
    pub fn signal(&self) {
        let one = 1u64.to_ne_bytes();
        // SAFETY: an 8-byte write to an eventfd; a full counter (EAGAIN) is
        // a wake-up already pending, which is all a signal is for.
        unsafe { libc::write(self.0.as_raw_fd(), one.as_ptr().cast(), one.len()) };
    }

    /// Waits until signalled, `other` is readable (or closed), or `timeout`
    /// passes; a signal is consumed.
    pub fn wait(&self, other: Option<BorrowedFd<'_>>, timeout: Duration) -> io::Result<Woken> {
        let mut fds = [
            libc::pollfd {
                fd: self.0.as_raw_fd(),
                events: libc::POLLIN,
                revents: 0,
            },
            libc::pollfd {
                fd: other.map_or(-1, |fd| fd.as_raw_fd()),
                events: libc::POLLIN,
                revents: 0,
            },
        ];
        let millis = libc::c_int::try_from(timeout.as_millis()).unwrap_or(libc::c_int::MAX);
        // SAFETY: two pollfd structs; a negative fd is ignored by poll(2).
        let ready = unsafe { libc::poll(fds.as_mut_ptr(), 2, millis) };
        if ready < 0 {
            let error = io::Error::last_os_error();
            return match error.kind() {
                io::ErrorKind::Interrupted => Ok(Woken::TimedOut),
                _ => Err(error),
            };
        }
        if fds[0].revents & libc::POLLIN != 0 {
            let mut count = [0u8; 8];
            // SAFETY: an 8-byte read from a non-blocking eventfd.
            unsafe { libc::read(self.0.as_raw_fd(), count.as_mut_ptr().cast(), count.len()) };
            return Ok(Woken::Signalled);
        }
        if fds[1].revents != 0 {
            return Ok(Woken::Other);
        }
        Ok(Woken::TimedOut)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::atomic::Ordering;

    #[test]
    fn two_mappings_of_one_memfd_see_each_others_bytes_and_words() {
        let a = SharedMap::create("canif-test", 8192).unwrap();
        let b = SharedMap::open(a.fd().try_clone_to_owned().unwrap()).unwrap();
        assert_eq!(b.len(), 8192);
        a.write(100, b"hello");
        let mut read = [0u8; 5];
        b.read(100, &mut read);
        assert_eq!(&read, b"hello");
        a.word(64).store(7, Ordering::SeqCst);
        assert_eq!(b.word(64).load(Ordering::SeqCst), 7);
    }

    #[test]
    #[should_panic(expected = "outside the shared mapping")]
    fn an_offset_past_the_end_is_refused() {
        let a = SharedMap::create("canif-test", 4096).unwrap();
        a.write(4090, &[0; 8]);
    }

    #[test]
    fn a_wake_is_signalled_once_and_times_out_after() {
        let wake = Wake::new().unwrap();
        wake.signal();
        wake.signal();
        assert_eq!(
            wake.wait(None, Duration::from_millis(0)).unwrap(),
            Woken::Signalled
        );
        assert_eq!(
            wake.wait(None, Duration::from_millis(1)).unwrap(),
            Woken::TimedOut
        );
    }
}
