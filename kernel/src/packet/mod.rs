//! An AF_PACKET raw socket for one EtherType on one interface (packet(7)):
//! how EtherCAT frames leave and reach this machine on a NIC or a veth.

use std::io;
use std::os::fd::{AsRawFd, FromRawFd, OwnedFd};
use std::time::Duration;

use crate::error::{KernelError, Operation, OsError};

mod option;
mod ring;

/// Frames of one EtherType on one interface.
#[derive(Debug)]
pub struct PacketSocket {
    /// Where frames arrive when the kernel gave a ring; else recvfrom(2).
    ring: Option<ring::Ring>,
    fd: OwnedFd,
}

/// The interface's index, or the error naming it.
fn index_of(interface: &str) -> Result<libc::c_int, KernelError> {
    let name = std::ffi::CString::new(interface).map_err(|_| KernelError::NoInterface {
        name: interface.to_string(),
    })?;
    // SAFETY: `name` is a valid NUL-terminated string for the call's duration.
    let index = unsafe { libc::if_nametoindex(name.as_ptr()) };
    if index == 0 {
        return Err(KernelError::NoInterface {
            name: interface.to_string(),
        });
    }
    Ok(index as libc::c_int)
}

impl PacketSocket {
    /// Opens and binds a socket on `interface` for frames of `ethertype`
    /// (needs CAP_NET_RAW).
    pub fn open(interface: &str, ethertype: u16) -> Result<PacketSocket, KernelError> {
        let failed = |error: io::Error| KernelError::Interface {
            interface: interface.to_string(),
            operation: Operation::Open,
            error: OsError::from(error),
        };
        let index = index_of(interface)?;
        let protocol = ethertype.to_be();
        // SAFETY: a plain socket(2) call; the descriptor is owned right after.
        let raw = unsafe {
            libc::socket(
                libc::AF_PACKET,
                libc::SOCK_RAW | libc::SOCK_CLOEXEC,
                libc::c_int::from(protocol),
            )
        };
        if raw < 0 {
            return Err(failed(io::Error::last_os_error()));
        }
        // SAFETY: `raw` is a fresh descriptor nobody else owns.
        let fd = unsafe { OwnedFd::from_raw_fd(raw) };
        let ring = ring::Ring::attach(&fd);
        // SAFETY: sockaddr_ll is plain data; zeroed is a valid start.
        let mut address: libc::sockaddr_ll = unsafe { std::mem::zeroed() };
        address.sll_family = libc::AF_PACKET as u16;
        address.sll_protocol = protocol;
        address.sll_ifindex = index;
        // SAFETY: `address` is a valid sockaddr_ll of the size passed.
        let bound = unsafe {
            libc::bind(
                fd.as_raw_fd(),
                std::ptr::addr_of!(address).cast(),
                std::mem::size_of::<libc::sockaddr_ll>() as libc::socklen_t,
            )
        };
        if bound < 0 {
            return Err(failed(io::Error::last_os_error()));
        }
        // What this machine sends is not queued back to it (Linux 4.20 on):
        // each frame otherwise cost each end a copy and a recvfrom(2) more.
        // An older kernel refuses the option; `receive` still leaves those out.
        let on: libc::c_int = 1;
        let _ = option::set(&fd, libc::PACKET_IGNORE_OUTGOING, &on);
        Ok(PacketSocket { ring, fd })
    }

    /// Sends one whole Ethernet frame.
    pub fn send(&self, frame: &[u8]) -> io::Result<()> {
        // SAFETY: `frame` is valid for reads of its length.
        let sent =
            unsafe { libc::send(self.fd.as_raw_fd(), frame.as_ptr().cast(), frame.len(), 0) };
        if sent < 0 {
            return Err(io::Error::last_os_error());
        }
        Ok(())
    }

    /// As [`PacketSocket::recv`], but looks without sleeping for `spin`
    /// first: a thread asleep in poll(2) takes tens of microseconds to wake
    /// on a virtual machine, as long as the frame's whole round trip.
    pub fn recv_spinning(
        &self,
        buffer: &mut [u8],
        spin: Duration,
        timeout: Duration,
    ) -> io::Result<Option<usize>> {
        // How many looks between readings of the clock: a look at the ring
        // is a read of memory, far cheaper than the clock.
        const LOOKS: u32 = 16;
        // Awake, but not in the way: on a busy machine another thread (the
        // other end, a test beside it) runs before the spin goes on. Often:
        // a thread this one's frame woke from poll(2) tends to be queued on
        // this core, and waits for the yield (every 20 µs took a 1 ms-paced
        // veth cycle from 40 to 105 µs; every 2 µs, 30 µs). Not at every
        // look: sched_yield(2) is a system call.
        const YIELD_EVERY: Duration = Duration::from_micros(2);
        let began = std::time::Instant::now();
        let mut yielded = began;
        loop {
            for _ in 0..LOOKS {
                if let Some(n) = self.receive(buffer)? {
                    return Ok(Some(n));
                }
            }
            let now = std::time::Instant::now();
            if now - began >= spin {
                break;
            }
            if now - yielded >= YIELD_EVERY {
                std::thread::yield_now();
                yielded = now;
            }
        }
        self.recv(buffer, timeout)
    }

    /// The next frame that arrived (not one this machine sent), waiting at
    /// most `timeout`; `None` when none came.
    pub fn recv(&self, buffer: &mut [u8], timeout: Duration) -> io::Result<Option<usize>> {
        let queued = self.receive(buffer)?;
        if queued.is_some() || timeout.is_zero() {
            return Ok(queued);
        }
        let mut poll = libc::pollfd {
            fd: self.fd.as_raw_fd(),
            events: libc::POLLIN,
            revents: 0,
        };
        let millis = timeout.as_millis().min(i32::MAX as u128) as libc::c_int;
        // SAFETY: one valid pollfd.
        let ready = unsafe { libc::poll(&mut poll, 1, millis) };
        if ready < 0 {
            let error = io::Error::last_os_error();
            return match error.kind() {
                io::ErrorKind::Interrupted => Ok(None),
                _ => Err(error),
            };
        }
        if ready == 0 {
            return Ok(None);
        }
        self.receive(buffer)
    }

    /// One look that does not wait: the frame, or `None` when none was
    /// queued or it was one this machine sent.
    fn receive(&self, buffer: &mut [u8]) -> io::Result<Option<usize>> {
        if let Some(ring) = &self.ring {
            return Ok(ring.take(buffer).flatten());
        }
        // SAFETY: sockaddr_ll is plain data.
        let mut from: libc::sockaddr_ll = unsafe { std::mem::zeroed() };
        let mut from_len = std::mem::size_of::<libc::sockaddr_ll>() as libc::socklen_t;
        // SAFETY: `buffer` is valid for writes of its length, `from` for its size.
        let got = unsafe {
            libc::recvfrom(
                self.fd.as_raw_fd(),
                buffer.as_mut_ptr().cast(),
                buffer.len(),
                libc::MSG_DONTWAIT,
                std::ptr::addr_of_mut!(from).cast(),
                &mut from_len,
            )
        };
        if got < 0 {
            let error = io::Error::last_os_error();
            return match error.kind() {
                io::ErrorKind::WouldBlock | io::ErrorKind::Interrupted => Ok(None),
                _ => Err(error),
            };
        }
        // A packet socket also sees what this machine sends on the interface
        // where the kernel does not know PACKET_IGNORE_OUTGOING.
        if from.sll_pkttype == libc::PACKET_OUTGOING {
            return Ok(None);
        }
        Ok(Some(got as usize))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Frames of three times the ring's slots cross a veth pair whole and in
    /// order (the ring wraps), and neither end sees what it sent itself.
    #[test]
    fn frames_cross_a_veth_pair_whole_in_order_and_not_back() {
        let tag = format!("r{}", std::process::id() % 10_000);
        let Some(pair) =
            crate::VethPair::for_test(&tag, "frames_cross_a_veth_pair_whole_in_order_and_not_back")
        else {
            return;
        };
        let (a, b) = (
            PacketSocket::open(&pair.master, 0x88A4).unwrap(),
            PacketSocket::open(&pair.terminal, 0x88A4).unwrap(),
        );
        assert!(
            a.ring.is_some() && b.ring.is_some(),
            "the kernel gave receive rings"
        );
        let wait = Duration::from_secs(2);
        let mut buffer = [0u8; 2048];
        for n in 0..3 * 64u16 {
            let mut frame = vec![0xFF; 6];
            frame.extend([0x02, 0, 0, 0, 0, 1, 0x88, 0xA4]);
            frame.extend((0..60 + n).map(|i| (i ^ n) as u8));
            a.send(&frame).unwrap();
            let got = b.recv_spinning(&mut buffer, wait, wait).unwrap();
            assert_eq!(
                got.map(|len| &buffer[..len]),
                Some(frame.as_slice()),
                "frame {n}"
            );
            assert_eq!(
                a.recv(&mut buffer, Duration::ZERO).unwrap(),
                None,
                "frame {n}"
            );
        }
    }

    #[test]
    fn an_interface_that_does_not_exist_is_named() {
        assert_eq!(
            PacketSocket::open("canif-nonesuch", 0x88A4).unwrap_err(),
            KernelError::NoInterface {
                name: "canif-nonesuch".into()
            }
        );
    }
}
