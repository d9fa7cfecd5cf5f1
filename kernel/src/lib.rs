//! # canif-kernel
//!
//! A Linux SocketCAN interface as the harness's bus: frames cross the kernel
//! (vcan, vxcan or a real controller's driver) instead of the simulated bus.
//!
//! Sockets are opened and configured with the `socketcan` crate; frames are
//! read with `recvmsg(2)` here because the harness needs, in one call, the
//! kernel's receive time stamp and `MSG_CONFIRM` (this socket's own frame,
//! echoed when the controller finished sending it).

mod error;
mod packet;
mod veth;

pub use error::{KernelError, Operation, OsError};
pub use packet::PacketSocket;
pub use veth::VethPair;

use std::io;
use std::os::fd::AsRawFd;
use std::time::{Duration, SystemTime, UNIX_EPOCH};

use canif_model::frame::{CanId, Frame, FrameKind};
use canif_model::Nanos;
use socketcan::{CanFdSocket, CanFilter, Socket, SocketOptions};

/// Whether this kernel has CAN_RAW sockets; the error says why not, with the errno.
pub fn probe() -> Result<(), KernelError> {
    // SAFETY: a plain socket(2) call; the descriptor is closed right away.
    let (fd, error) = unsafe {
        let fd = libc::socket(libc::AF_CAN, libc::SOCK_RAW, libc::CAN_RAW);
        (fd, io::Error::last_os_error())
    };
    if fd < 0 {
        return Err(KernelError::NoCan {
            release: kernel_release(),
            error: error.into(),
        });
    }
    // SAFETY: closing the descriptor just opened.
    unsafe { libc::close(fd) };
    Ok(())
}

/// `uname -r` of the running kernel, for reports.
pub fn kernel_release() -> String {
    std::fs::read_to_string("/proc/sys/kernel/osrelease")
        .map(|s| s.trim().to_string())
        .unwrap_or_else(|_| "unknown kernel".into())
}

/// The kernel's clock for receive time stamps (CLOCK_REALTIME), in nanoseconds.
pub fn realtime_ns() -> Nanos {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0, |d| d.as_nanos() as Nanos)
}

/// `socketcan:IFACE` or `socketcan:IUT_IFACE,TESTER_IFACE`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct BusSpec {
    /// Where the implementation under test's controller sits.
    pub iut: String,
    /// Where the harness plays the other nodes (the same interface for vcan).
    pub tester: String,
}

impl BusSpec {
    pub fn parse(text: &str) -> Result<Self, String> {
        let rest = text
            .strip_prefix("socketcan:")
            .ok_or_else(|| format!("`{text}`: a bus is `sim` or `socketcan:IFACE[,IFACE]`"))?;
        let names: Vec<&str> = rest.split(',').map(str::trim).collect();
        let valid = |n: &&str| !n.is_empty() && n.len() < 16 && !n.contains('/');
        match names.as_slice() {
            [one] if valid(one) => Ok(BusSpec {
                iut: one.to_string(),
                tester: one.to_string(),
            }),
            [iut, tester] if valid(iut) && valid(tester) => Ok(BusSpec {
                iut: iut.to_string(),
                tester: tester.to_string(),
            }),
            _ => Err(format!(
                "`{text}`: a bus is `socketcan:IFACE` or `socketcan:IFACE,IFACE` (names of 1..15 characters)"
            )),
        }
    }

    pub fn describe(&self) -> String {
        if self.iut == self.tester {
            format!("socketcan:{}", self.iut)
        } else {
            format!(
                "socketcan:{} (IUT) and {} (other nodes)",
                self.iut, self.tester
            )
        }
    }
}

/// What one read from a socket gave.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Received {
    Frame {
        frame: Frame,
        /// The kernel's receive time stamp, CLOCK_REALTIME nanoseconds.
        at: Nanos,
        /// This socket sent it (MSG_CONFIRM): the controller finished sending it.
        own: bool,
    },
    /// The driver reported a bus problem (an error frame, CAN_ERR_FLAG).
    Error {
        class: u32,
        data: [u8; 8],
        at: Nanos,
    },
}

/// One CAN_RAW socket bound to an interface, non-blocking, with CAN FD frames
/// and receive time stamps switched on.
pub struct KernelSocket {
    socket: CanFdSocket,
    pub interface: String,
}

/// The error-frame class bit for bus-off (linux/can/error.h).
pub const CAN_ERR_BUSOFF: u32 = 0x0040;
/// The errno of a full send queue.
pub const ENOBUFS: i32 = libc::ENOBUFS;

const CAN_MTU: usize = 16;
const CANFD_MTU: usize = 72;
const CANFD_BRS: u8 = 0x01;
const CANFD_ESI: u8 = 0x02;
const CANFD_FDF: u8 = 0x04;
const CAN_EFF_FLAG: u32 = 0x8000_0000;
const CAN_RTR_FLAG: u32 = 0x4000_0000;
const CAN_ERR_FLAG: u32 = 0x2000_0000;

/// The kernel's `struct canfd_frame` (a `struct can_frame` is its first 16 bytes).
#[repr(C)]
#[derive(Clone, Copy)]
struct RawFrame {
    can_id: u32,
    len: u8,
    flags: u8,
    reserved: [u8; 2],
    data: [u8; 64],
}

impl KernelSocket {
    /// Opens a socket on `interface`; `own_frames` also delivers this socket's
    /// own frames back (as `own`) once they are on the bus.
    pub fn open(interface: &str, own_frames: bool) -> Result<Self, KernelError> {
        let context = |e: io::Error| KernelError::Interface {
            interface: interface.to_string(),
            operation: Operation::Open,
            error: e.into(),
        };
        let socket = CanFdSocket::open(interface).map_err(context)?;
        socket.set_nonblocking(true).map_err(context)?;
        socket.set_recv_timestamp(true).map_err(context)?;
        socket.set_recv_own_msgs(own_frames).map_err(context)?;
        socket.set_error_filter_accept_all().map_err(context)?;
        Ok(KernelSocket {
            socket,
            interface: interface.to_string(),
        })
    }

    /// Only frames matching one of these (`can_id`, `can_mask`) pairs reach the
    /// socket (the kernel's CAN_RAW_FILTER; `inverted` is CAN_INV_FILTER).
    pub fn set_filters(&self, filters: &[(u32, u32)], inverted: bool) -> io::Result<()> {
        let filters: Vec<CanFilter> = filters
            .iter()
            .map(|&(id, mask)| {
                if inverted {
                    CanFilter::new_inverted(id, mask)
                } else {
                    CanFilter::new(id, mask)
                }
            })
            .collect();
        self.socket.set_filters(&filters)?;
        self.socket.set_error_filter_drop_all()
    }

    /// Writes `frame` as the kernel's structure; `ENOBUFS` means the
    /// interface's queue is full (try again), `ENETDOWN` that it is down.
    pub fn send(&self, frame: &Frame) -> io::Result<()> {
        let (raw, size) = to_raw(frame);
        // SAFETY: `raw` is a plain-old-data struct of at least `size` bytes.
        let written = unsafe {
            libc::write(
                self.socket.as_raw_fd(),
                (&raw as *const RawFrame).cast(),
                size,
            )
        };
        match written {
            n if n as usize == size => Ok(()),
            n if n >= 0 => Err(io::Error::other(format!("short write: {n} of {size}"))),
            _ => Err(io::Error::last_os_error()),
        }
    }

    /// The next frame, if one is waiting.
    pub fn recv(&self) -> io::Result<Option<Received>> {
        let mut raw = RawFrame {
            can_id: 0,
            len: 0,
            flags: 0,
            reserved: [0; 2],
            data: [0; 64],
        };
        let mut iov = libc::iovec {
            iov_base: (&mut raw as *mut RawFrame).cast(),
            iov_len: std::mem::size_of::<RawFrame>(),
        };
        let mut control = [0u64; 16];
        // SAFETY: msghdr is plain data; every pointer set below outlives the call.
        let mut message: libc::msghdr = unsafe { std::mem::zeroed() };
        message.msg_iov = &mut iov;
        message.msg_iovlen = 1;
        message.msg_control = control.as_mut_ptr().cast();
        message.msg_controllen = std::mem::size_of_val(&control) as _;
        // SAFETY: a recvmsg(2) into buffers owned by this frame.
        let n = unsafe { libc::recvmsg(self.socket.as_raw_fd(), &mut message, 0) };
        if n < 0 {
            let error = io::Error::last_os_error();
            return match error.kind() {
                io::ErrorKind::WouldBlock => Ok(None),
                _ => Err(error),
            };
        }
        let mut at = realtime_ns();
        // SAFETY: walking the control messages the kernel wrote into `control`.
        unsafe {
            let mut cmsg = libc::CMSG_FIRSTHDR(&message);
            while !cmsg.is_null() {
                if (*cmsg).cmsg_level == libc::SOL_SOCKET
                    && (*cmsg).cmsg_type == libc::SCM_TIMESTAMPNS
                {
                    let stamp: libc::timespec =
                        std::ptr::read_unaligned(libc::CMSG_DATA(cmsg).cast());
                    at = stamp.tv_sec as Nanos * 1_000_000_000 + stamp.tv_nsec as Nanos;
                }
                cmsg = libc::CMSG_NXTHDR(&message, cmsg);
            }
        }
        let own = message.msg_flags & libc::MSG_CONFIRM != 0;
        if raw.can_id & CAN_ERR_FLAG != 0 {
            let mut data = [0; 8];
            data.copy_from_slice(&raw.data[..8]);
            return Ok(Some(Received::Error {
                class: raw.can_id & 0x1FFF_FFFF,
                data,
                at,
            }));
        }
        let frame = from_raw(&raw, n as usize).map_err(|e| {
            io::Error::new(
                io::ErrorKind::InvalidData,
                format!("{}: {e}", self.interface),
            )
        })?;
        Ok(Some(Received::Frame { frame, at, own }))
    }

    /// Waits until one of `sockets` has something to read, at most `timeout`.
    pub fn wait(sockets: &[&KernelSocket], timeout: Duration) -> io::Result<()> {
        let mut fds: Vec<libc::pollfd> = sockets
            .iter()
            .map(|s| libc::pollfd {
                fd: s.socket.as_raw_fd(),
                events: libc::POLLIN,
                revents: 0,
            })
            .collect();
        let millis = timeout.as_millis().min(i32::MAX as u128) as i32;
        // SAFETY: poll(2) over descriptors owned by `sockets`.
        let n = unsafe { libc::poll(fds.as_mut_ptr(), fds.len() as _, millis) };
        if n < 0 {
            let error = io::Error::last_os_error();
            if error.kind() != io::ErrorKind::Interrupted {
                return Err(error);
            }
        }
        Ok(())
    }
}

fn can_id_bits(id: CanId) -> u32 {
    match id {
        CanId::Standard(id) => u32::from(id),
        CanId::Extended(id) => id | CAN_EFF_FLAG,
    }
}

fn to_raw(frame: &Frame) -> (RawFrame, usize) {
    let mut raw = RawFrame {
        can_id: can_id_bits(frame.id),
        len: frame.len(),
        flags: 0,
        reserved: [0; 2],
        data: [0; 64],
    };
    raw.data[..frame.data().len()].copy_from_slice(frame.data());
    match frame.kind {
        FrameKind::Classic { rtr } => {
            if rtr {
                raw.can_id |= CAN_RTR_FLAG;
            }
            (raw, CAN_MTU)
        }
        FrameKind::Fd { brs, esi } => {
            raw.flags =
                CANFD_FDF | if brs { CANFD_BRS } else { 0 } | if esi { CANFD_ESI } else { 0 };
            (raw, CANFD_MTU)
        }
    }
}

fn from_raw(raw: &RawFrame, size: usize) -> Result<Frame, String> {
    let id = if raw.can_id & CAN_EFF_FLAG != 0 {
        CanId::extended(raw.can_id & 0x1FFF_FFFF)
    } else {
        CanId::standard(raw.can_id & 0x7FF)
    }
    .ok_or_else(|| format!("identifier 0x{:X} out of range", raw.can_id))?;
    let len = raw.len;
    match size {
        CAN_MTU if raw.can_id & CAN_RTR_FLAG != 0 => Frame::remote(id, len.min(8)),
        CAN_MTU => Frame::classic(id, &raw.data[..usize::from(len.min(8))]),
        CANFD_MTU => Frame::fd(
            id,
            raw.flags & CANFD_BRS != 0,
            raw.flags & CANFD_ESI != 0,
            &raw.data[..usize::from(len.min(64))],
        ),
        other => return Err(format!("a read of {other} bytes is no CAN frame")),
    }
    .map_err(|e| format!("the kernel delivered a frame the model cannot hold: {e:?}"))
}

/// The interface a SocketCAN test uses, named by environment variable
/// `variable` (the kernel lane sets them), or why the test cannot run here:
/// the kernel's errno when it has no CAN, or the missing interface.
pub fn test_interface(variable: &str, default: &str) -> Result<String, KernelError> {
    let name = std::env::var(variable).unwrap_or_else(|_| default.to_string());
    interface_available(&name).map(|()| name)
}

/// A pair of interfaces named `A,B` by environment variable `variable`.
pub fn test_interface_pair(variable: &str) -> Result<(String, String), KernelError> {
    let pair = std::env::var(variable).map_err(|_| KernelError::NotNamed {
        variable: variable.to_string(),
        value: None,
    })?;
    let (a, b) = pair.split_once(',').ok_or_else(|| KernelError::NotNamed {
        variable: variable.to_string(),
        value: Some(pair.clone()),
    })?;
    interface_available(a)?;
    interface_available(b)?;
    Ok((a.to_string(), b.to_string()))
}

/// Whether a SocketCAN test can use interface `name` here, or why not.
pub fn interface_available(name: &str) -> Result<(), KernelError> {
    probe()?;
    if std::path::Path::new(&format!("/sys/class/net/{name}")).exists() {
        Ok(())
    } else {
        Err(KernelError::NoInterface {
            name: name.to_string(),
        })
    }
}

/// Inside the kernel lane (CANIF_LANE set) a test that cannot run is a
/// failure — the lane promised its interfaces — unless the lane said why it
/// could not provide them (`CANIF_LANE_MISSING`, e.g. a driver that did not build).
/// `CANIF_LANE_MISSING` is `VARIABLE: why`, the variable the lane could not set.
/// Outside the lane it is a skip.
pub fn skip_is_failure(why: &KernelError) -> Option<String> {
    let excused = std::env::var("CANIF_LANE_MISSING").unwrap_or_default();
    let excused = excused.split(':').next().unwrap_or_default();
    if matches!(why, KernelError::NotNamed { variable, .. } if !excused.is_empty() && variable == excused)
    {
        return None;
    }
    lane_failure(why)
}

/// Inside the kernel lane, something else a test needs and does not find
/// (a Python package) is a failure too; outside it, `None`: a skip.
pub fn lane_failure(why: &dyn std::fmt::Display) -> Option<String> {
    std::env::var("CANIF_LANE").ok()?;
    Some(format!("the kernel lane should provide this but: {why}"))
}

/// Why a SocketCAN test is skipped here, with where it does run.
pub fn skip_reason(why: &KernelError) -> String {
    match why {
        KernelError::NoCan { .. } => {
            format!("{why}; scripts/kernel-can-lane runs this under a kernel with CAN")
        }
        _ => why.to_string(),
    }
}

/// `ip link set INTERFACE up|down`, over netlink (needs CAP_NET_ADMIN).
pub fn set_link(interface: &str, up: bool) -> Result<(), KernelError> {
    let failed = |operation, error: String| KernelError::Interface {
        interface: interface.to_string(),
        operation,
        error: io::Error::other(error).into(),
    };
    let link = socketcan::CanInterface::open(interface)
        .map_err(|e| failed(Operation::Find, e.to_string()))?;
    if up {
        link.bring_up()
    } else {
        link.bring_down()
    }
    .map_err(|e| failed(Operation::SetLink(up), e.to_string()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bus_specs_parse_and_name_both_sides() {
        assert_eq!(
            BusSpec::parse("socketcan:vcan0").unwrap(),
            BusSpec {
                iut: "vcan0".into(),
                tester: "vcan0".into()
            }
        );
        let pair = BusSpec::parse("socketcan:can0,can1").unwrap();
        assert_eq!((pair.iut.as_str(), pair.tester.as_str()), ("can0", "can1"));
        assert!(pair.describe().contains("can1 (other nodes)"));
        assert!(BusSpec::parse("vcan0").is_err());
        assert!(BusSpec::parse("socketcan:").is_err());
        assert!(BusSpec::parse("socketcan:a,b,c").is_err());
    }

    #[test]
    fn frames_survive_the_kernel_structure() {
        for frame in [
            Frame::classic(CanId::Standard(0x123), &[1, 2, 3]).unwrap(),
            Frame::remote(CanId::Extended(0x1ABC_DEF0), 4).unwrap(),
            Frame::fd(CanId::Extended(0x1234), true, false, &[7; 48]).unwrap(),
            Frame::fd(CanId::Standard(0x7FF), false, true, &[]).unwrap(),
        ] {
            let (raw, size) = to_raw(&frame);
            assert_eq!(from_raw(&raw, size).unwrap(), frame);
        }
        let (raw, size) = to_raw(&Frame::remote(CanId::Standard(0x700), 1).unwrap());
        assert_eq!(
            (raw.can_id, raw.len, size),
            (0x700 | CAN_RTR_FLAG, 1, CAN_MTU)
        );
    }
}
