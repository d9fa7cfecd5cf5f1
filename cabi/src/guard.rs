//! Process images with a guard page behind them, for a library run in a
//! process of its own (`canif lib-host`): a read or write past the image's
//! end stops at the guard page, and the fault handler says which image was
//! touched and at which offset before the process dies of the signal: on
//! the host's control channel ([`report_to`]), where the library's own
//! printing does not go, or else on stderr. canif reads that line back
//! ([`OutsideImage::parse`]) and judges the access (CL-IMG-001 for a client)
//! instead of dying with the library.

use std::sync::atomic::{AtomicI32, AtomicUsize, Ordering};
use std::sync::Once;

/// The line's start: what canif looks for in a dead host's stderr.
const PREFIX: &str = "canif-lib-host: access outside the image: ";

/// An image of `len` bytes ending where an inaccessible page begins.
pub struct GuardedImage {
    map: *mut u8,
    map_len: usize,
    start: usize,
    len: usize,
}

impl GuardedImage {
    /// Zeros, `len` bytes; `None` when the system refuses the mapping.
    pub fn new(len: usize) -> Option<GuardedImage> {
        // SAFETY: sysconf has no preconditions.
        let page = usize::try_from(unsafe { libc::sysconf(libc::_SC_PAGESIZE) }).ok()?;
        let data_pages = len.div_ceil(page).max(1);
        let map_len = (data_pages + 1) * page;
        // SAFETY: an anonymous private mapping of `map_len` bytes; checked below.
        let map = unsafe {
            libc::mmap(
                std::ptr::null_mut(),
                map_len,
                libc::PROT_READ | libc::PROT_WRITE,
                libc::MAP_PRIVATE | libc::MAP_ANONYMOUS,
                -1,
                0,
            )
        };
        if map == libc::MAP_FAILED {
            return None;
        }
        let map = map.cast::<u8>();
        // SAFETY: the last page lies inside the mapping just made.
        let guarded =
            unsafe { libc::mprotect(map.add(data_pages * page).cast(), page, libc::PROT_NONE) };
        let image = GuardedImage {
            map,
            map_len,
            start: data_pages * page - len,
            len,
        };
        (guarded == 0).then_some(image)
    }

    pub fn as_slice(&self) -> &[u8] {
        // SAFETY: `start..start + len` lies in the mapping's readable pages.
        unsafe { std::slice::from_raw_parts(self.map.add(self.start), self.len) }
    }

    pub fn as_mut_slice(&mut self) -> &mut [u8] {
        // SAFETY: as above, and `&mut self` makes the borrow unique.
        unsafe { std::slice::from_raw_parts_mut(self.map.add(self.start), self.len) }
    }

    fn address(&self) -> usize {
        self.map as usize + self.start
    }
}

impl Drop for GuardedImage {
    fn drop(&mut self) {
        // SAFETY: the mapping made in `new`, unmapped once.
        unsafe { libc::munmap(self.map.cast(), self.map_len) };
    }
}

/// The images the fault handler knows: (address, length) of each, by the
/// index of [`IMAGE_NAMES`].
static IMAGES: [(AtomicUsize, AtomicUsize); 2] = [
    (AtomicUsize::new(0), AtomicUsize::new(0)),
    (AtomicUsize::new(0), AtomicUsize::new(0)),
];
const IMAGE_NAMES: [&str; 2] = ["input", "output"];

/// Which image a fault names, and where.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct OutsideImage {
    /// `input` or `output`.
    pub image: String,
    /// Bytes from the image's start (at or past its length).
    pub offset: usize,
    pub size: usize,
}

impl OutsideImage {
    /// The handler's line, read back.
    pub fn parse(line: &str) -> Option<OutsideImage> {
        let rest = line.trim().strip_prefix(PREFIX)?;
        let mut words = rest.split(' ');
        let image = words.next()?.to_string();
        let offset = words.next()?.strip_prefix("offset=")?.parse().ok()?;
        let size = words.next()?.strip_prefix("size=")?.parse().ok()?;
        Some(OutsideImage {
            image,
            offset,
            size,
        })
    }
}

impl std::fmt::Display for OutsideImage {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{PREFIX}{} offset={} size={}",
            self.image, self.offset, self.size
        )
    }
}

/// Where the fault handler writes its line: stderr until told otherwise.
static REPORT_FD: AtomicI32 = AtomicI32::new(2);

/// The fault handler writes its line to `fd` (the host's control channel,
/// which the library is not given and does not print to).
pub fn report_to(fd: &impl std::os::fd::AsRawFd) {
    REPORT_FD.store(fd.as_raw_fd(), Ordering::SeqCst);
}

/// From now on a fault in the guard page behind `inputs` or `outputs` is
/// reported (see [`report_to`]) before the process dies of it.
pub fn watch(inputs: &GuardedImage, outputs: &GuardedImage) {
    for (slot, image) in IMAGES.iter().zip([inputs, outputs]) {
        slot.0.store(image.address(), Ordering::SeqCst);
        slot.1.store(image.len, Ordering::SeqCst);
    }
    static INSTALL: Once = Once::new();
    INSTALL.call_once(install);
}

/// The handler runs on a stack of its own (a fault may come from a stack
/// overflow too), once: it then falls back to the default action, so the
/// faulting access, tried again, kills the process with the signal.
fn install() {
    const STACK: usize = 64 * 1024;
    let stack = Box::leak(vec![0u8; STACK].into_boxed_slice());
    let alt = libc::stack_t {
        ss_sp: stack.as_mut_ptr().cast(),
        ss_flags: 0,
        ss_size: STACK,
    };
    // SAFETY: the stack is leaked, so it outlives the process's use of it;
    // the action is a plain SA_SIGINFO handler with an empty mask.
    unsafe {
        libc::sigaltstack(&alt, std::ptr::null_mut());
        let mut action: libc::sigaction = std::mem::zeroed();
        action.sa_sigaction = on_fault as *const () as usize;
        action.sa_flags = libc::SA_SIGINFO | libc::SA_ONSTACK | libc::SA_RESETHAND;
        libc::sigemptyset(&mut action.sa_mask);
        libc::sigaction(libc::SIGSEGV, &action, std::ptr::null_mut());
        libc::sigaction(libc::SIGBUS, &action, std::ptr::null_mut());
    }
}

/// Async-signal-safe: reads atomics, formats into a stack buffer, write(2).
extern "C" fn on_fault(_signal: libc::c_int, info: *mut libc::siginfo_t, _: *mut libc::c_void) {
    // SAFETY: the kernel passes a valid siginfo for SA_SIGINFO handlers.
    let address = unsafe { (*info).si_addr() } as usize;
    // The image the address lies nearest behind: past its end (its guard
    // page, or further on by a wild index), not before its start.
    let mut nearest: Option<(usize, usize, &str)> = None;
    for (slot, name) in IMAGES.iter().zip(IMAGE_NAMES) {
        let (start, len) = (slot.0.load(Ordering::SeqCst), slot.1.load(Ordering::SeqCst));
        if start == 0 || address < start || address - start > REACH {
            continue;
        }
        if nearest.is_none_or(|(offset, _, _)| address - start < offset) {
            nearest = Some((address - start, len, name));
        }
    }
    let Some((offset, len, name)) = nearest else {
        return;
    };
    let mut line = [0u8; 160];
    let mut at = 0;
    let mut put = |bytes: &[u8]| {
        let n = bytes.len().min(line.len() - at);
        line[at..at + n].copy_from_slice(&bytes[..n]);
        at += n;
    };
    put(PREFIX.as_bytes());
    put(name.as_bytes());
    put(b" offset=");
    put(decimal(offset, &mut [0u8; 20]));
    put(b" size=");
    put(decimal(len, &mut [0u8; 20]));
    put(b"\n");
    // SAFETY: write(2) of an initialised buffer; async-signal-safe.
    unsafe { libc::write(REPORT_FD.load(Ordering::SeqCst), line.as_ptr().cast(), at) };
}

/// How far past an image a fault is still taken for an access to it (a
/// client trusting NoOfRxMessages reads up to 0xFFFF slots of 78 bytes).
const REACH: usize = 16 << 20;

/// `n` in decimal, written into the end of `buffer`.
fn decimal(mut n: usize, buffer: &mut [u8; 20]) -> &[u8] {
    let mut at = buffer.len();
    loop {
        at -= 1;
        buffer[at] = b'0' + (n % 10) as u8;
        n /= 10;
        if n == 0 {
            return &buffer[at..];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_image_holds_its_bytes_and_ends_at_a_page_boundary() {
        let mut image = GuardedImage::new(70).unwrap();
        assert_eq!(image.as_slice(), &[0u8; 70]);
        image.as_mut_slice()[69] = 7;
        assert_eq!(image.as_slice()[69], 7);
        // SAFETY: sysconf has no preconditions.
        let page = unsafe { libc::sysconf(libc::_SC_PAGESIZE) } as usize;
        assert_eq!((image.address() + 70) % page, 0, "the guard page follows");
        assert!(GuardedImage::new(0).unwrap().as_slice().is_empty());
    }

    #[test]
    fn the_handlers_line_reads_back() {
        let outside = OutsideImage {
            image: "input".into(),
            offset: 931_000,
            size: 134,
        };
        assert_eq!(OutsideImage::parse(&outside.to_string()), Some(outside));
        assert_eq!(OutsideImage::parse("segfault"), None);
        assert_eq!(decimal(0, &mut [0; 20]), b"0");
        assert_eq!(decimal(1_234_567, &mut [0; 20]), b"1234567");
    }
}
