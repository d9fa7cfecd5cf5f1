//! Socket options at SOL_PACKET (packet(7)).

use std::os::fd::{AsRawFd, OwnedFd};

/// Sets `option` to `value` on the packet socket `fd`; whether the kernel
/// took it.
pub(super) fn set<T>(fd: &OwnedFd, option: libc::c_int, value: &T) -> bool {
    // SAFETY: `value` is a valid `T` for the call, and its size is passed.
    let set = unsafe {
        libc::setsockopt(
            fd.as_raw_fd(),
            libc::SOL_PACKET,
            option,
            std::ptr::from_ref(value).cast(),
            std::mem::size_of::<T>() as libc::socklen_t,
        )
    };
    set == 0
}
