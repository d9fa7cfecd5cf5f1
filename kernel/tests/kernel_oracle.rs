//! The Linux kernel as an independent oracle for the model: its CAN_RAW
//! filters and its CAN FD length handling were written by others, and must
//! agree with the model's reading of the manual on generated cases. Frames also
//! cross a real kernel unchanged, with time stamps in order.
//!
//! These need AF_CAN and a CAN FD interface (`CANIF_LANE_FD`, default vcan0);
//! without them every trial is listed as ignored with the kernel's own errno.
//! `scripts/kernel-can-lane` runs them under Debian's kernel in QEMU.

use std::time::{Duration, Instant};

use canif_kernel::{test_interface, KernelError, KernelSocket, Received};
use canif_model::dlc::fd_round_up;
use canif_model::filter::{accepts, FilterAction, FilterMatch, FilterRow};
use canif_model::frame::{CanId, Frame};
use libtest_mimic::{Arguments, Failed, Trial};

/// xorshift64*: the same cases on every run.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }
    fn below(&mut self, n: u64) -> u64 {
        self.next() % n
    }
}

/// Reads frames from `socket` until `count` arrived or `timeout` passed.
fn collect(socket: &KernelSocket, count: usize, timeout: Duration) -> Vec<(Frame, u64)> {
    let started = Instant::now();
    let mut frames = Vec::new();
    while frames.len() < count && started.elapsed() < timeout {
        match socket.recv() {
            Ok(Some(Received::Frame { frame, at, .. })) => frames.push((frame, at)),
            Ok(Some(_)) => {}
            Ok(None) => {
                let _ = KernelSocket::wait(&[socket], Duration::from_millis(5));
            }
            Err(_) => break,
        }
    }
    frames
}

fn random_frame(rng: &mut Rng, fd: bool) -> Frame {
    let id = if rng.below(2) == 0 {
        CanId::Standard(rng.below(0x800) as u16)
    } else {
        CanId::Extended(rng.below(0x2000_0000) as u32)
    };
    let sizes = canif_model::dlc::FD_DATA_SIZES;
    let data: Vec<u8> = (0..64).map(|_| rng.next() as u8).collect();
    match rng.below(if fd { 4 } else { 3 }) {
        0 => Frame::remote(id, rng.below(9) as u8).unwrap(),
        3 => {
            let len = usize::from(sizes[rng.below(sizes.len() as u64) as usize]);
            Frame::fd(id, rng.below(2) == 0, rng.below(2) == 0, &data[..len]).unwrap()
        }
        _ => Frame::classic(id, &data[..rng.below(9) as usize]).unwrap(),
    }
}

/// The transport itself (no requirement of the manual): what the harness
/// writes arrives unchanged, with time stamps in order, and how fast.
fn frames_cross_the_kernel(interface: &str) -> Result<(), Failed> {
    let sender = KernelSocket::open(interface, false)?;
    let receiver = KernelSocket::open(interface, false)?;
    let mut rng = Rng(0x5EED_CAFE);
    let frames: Vec<Frame> = (0..400).map(|_| random_frame(&mut rng, true)).collect();
    let before = canif_kernel::realtime_ns();
    let started = Instant::now();
    // In batches: a burst larger than the receiver's socket buffer is dropped by design.
    let mut got = Vec::new();
    for batch in frames.chunks(40) {
        for frame in batch {
            sender
                .send(frame)
                .map_err(|e| format!("{interface}: send {frame}: {e}"))?;
        }
        got.extend(collect(&receiver, batch.len(), Duration::from_secs(5)));
    }
    let elapsed = started.elapsed();
    let after = canif_kernel::realtime_ns();
    if got.len() != frames.len() {
        return Err(format!("{} of {} frames arrived", got.len(), frames.len()).into());
    }
    for (sent, (received, _)) in frames.iter().zip(&got) {
        if sent != received {
            return Err(format!("sent {sent}, the kernel delivered {received}").into());
        }
    }
    let stamps: Vec<u64> = got.iter().map(|(_, at)| *at).collect();
    if stamps.windows(2).any(|w| w[0] > w[1])
        || stamps[0] < before
        || stamps[stamps.len() - 1] > after
    {
        return Err(
            format!("receive time stamps out of order or outside [{before}, {after}]").into(),
        );
    }
    eprintln!(
        "{interface}: {} frames across the kernel in {elapsed:?} ({:.0} frames/s)",
        frames.len(),
        frames.len() as f64 / elapsed.as_secs_f64()
    );
    Ok(())
}

/// Two controllers on one emulated bus (SJA1000, or CTU CAN FD with `fd`):
/// frames cross a real driver both ways, one at a time (each waits for the one
/// before). On the SJA1000 data frames only:
/// after a remote frame with a length, QEMU's SJA1000 emulation garbles the
/// frames that follow (seen here: `5F9#R5`, then `000#` for `45A#4A0265D50484`).
fn frames_cross_two_controllers(pair: &str, fd: bool) -> Result<(), Failed> {
    let (a, b) = pair
        .split_once(',')
        .ok_or("CANIF_LANE_CONTROLLERS is IFACE,IFACE")?;
    let mut rng = Rng(0xC0_117E);
    for (from, to) in [(a, b), (b, a)] {
        let sender = KernelSocket::open(from, false)?;
        let receiver = KernelSocket::open(to, false)?;
        let started = Instant::now();
        let count = 200;
        for n in 0..count {
            let mut frame = random_frame(&mut rng, fd);
            while frame.is_remote() && !fd {
                frame = random_frame(&mut rng, fd);
            }
            // ESI on the wire is the sending controller's error state, not the
            // frame's flag (seen here: 45A##2… sent by can2 arrives as 45A##0…).
            if let canif_model::frame::FrameKind::Fd { brs, esi: true } = frame.kind {
                frame = Frame::fd(frame.id, brs, false, frame.data()).unwrap();
            }
            sender
                .send(&frame)
                .map_err(|e| format!("{from}: send {frame}: {e}"))?;
            let got = collect(&receiver, 1, Duration::from_secs(2));
            match got.first() {
                Some((received, _)) if *received == frame => {}
                Some((received, _)) => {
                    return Err(
                        format!("frame {n}: {from} sent {frame}, {to} received {received}").into(),
                    )
                }
                None => {
                    return Err(format!("frame {n}: {frame} from {from} never reached {to}").into())
                }
            }
        }
        let elapsed = started.elapsed();
        eprintln!(
            "{from} -> {to}: {count} frames one at a time in {elapsed:?} ({:.0} frames/s)",
            f64::from(count) / elapsed.as_secs_f64()
        );
    }
    Ok(())
}

/// Covers: FLT-002, FLT-003, FLT-007
fn filters_agree_with_the_model(interface: &str) -> Result<(), Failed> {
    let sender = KernelSocket::open(interface, false)?;
    let filtered = KernelSocket::open(interface, false)?;
    let observer = KernelSocket::open(interface, false)?;
    let mut rng = Rng(0xF117_E125);
    let mut compared = 0;
    for case in 0..150 {
        let inverted = rng.below(4) == 0;
        let rows: Vec<(u32, u32)> = (0..if inverted { 1 } else { 1 + rng.below(3) })
            .map(|_| {
                let mask = match rng.below(4) {
                    0 => 0x7FF,
                    1 => 0x1FFF_FFFF,
                    2 => 0x700,
                    _ => rng.below(0x2000_0000) as u32,
                };
                (rng.below(0x2000_0000) as u32 & mask, mask)
            })
            .collect();
        filtered
            .set_filters(&rows, inverted)
            .map_err(|e| format!("setsockopt(CAN_RAW_FILTER): {e}"))?;
        let table: Vec<FilterRow> = rows
            .iter()
            .map(|&(code, mask)| FilterRow {
                action: if inverted {
                    FilterAction::Reject
                } else {
                    FilterAction::Accept
                },
                matches: FilterMatch::CodeMask { code, mask },
            })
            .collect();
        let frames: Vec<Frame> = (0..8)
            .map(|k| {
                let frame = random_frame(&mut rng, false);
                if k % 2 == 1 {
                    return frame;
                }
                // Half the frames are built to match a row, so both answers occur.
                let (code, mask) = rows[rng.below(rows.len() as u64) as usize];
                let standard = rng.below(2) == 0;
                let free = if standard { 0x7FF } else { 0x1FFF_FFFF };
                let raw = ((code & mask) | (rng.below(0x2000_0000) as u32 & !mask)) & free;
                let id = if standard {
                    CanId::Standard(raw as u16)
                } else {
                    CanId::Extended(raw)
                };
                Frame::classic(id, &[case as u8]).unwrap()
            })
            .collect();
        for frame in &frames {
            sender.send(frame)?;
        }
        // The kernel hands each frame to every socket before the next: once the
        // unfiltered observer has them all, the filtered socket has its share.
        let seen = collect(&observer, frames.len(), Duration::from_secs(5));
        if seen.len() != frames.len() {
            return Err(
                format!("the observer saw {} of {} frames", seen.len(), frames.len()).into(),
            );
        }
        let mut passed = Vec::new();
        while let Some(Received::Frame { frame, .. }) = filtered.recv()? {
            passed.push(frame);
        }
        for frame in &frames {
            let kernel = passed.contains(frame);
            let model = accepts(&table, frame.id);
            compared += 1;
            if kernel != model {
                return Err(format!(
                    "case {case}: {frame} with {} rows {rows:X?}: the kernel's CAN_RAW filter {}, the model {}",
                    if inverted { "CAN_INV_FILTER" } else { "accept" },
                    if kernel { "passes it" } else { "drops it" },
                    if model { "accepts it" } else { "rejects it" },
                )
                .into());
            }
        }
    }
    eprintln!("{interface}: {compared} frames, kernel filter and model agree");
    Ok(())
}

/// The kernel's ISO-TP stack pads CAN FD frames to the next valid length (its
/// own table, `padlen()` in net/can/isotp.c): the model must round the same way.
///
/// Covers: FD-LEN-003, FD-LEN-004, ERR-R1
fn fd_lengths_agree_with_the_model(interface: &str) -> Result<(), Failed> {
    let raw = KernelSocket::open(interface, false)?;
    raw.set_filters(&[(0x7E8, 0x7FF)], false)?;
    let isotp = isotp::Socket::open(interface, 0x7E0, 0x7E8)?;
    for payload in 1u8..=62 {
        let pci = if payload <= 7 { 1 } else { 2 };
        isotp
            .send(&vec![payload; usize::from(payload)])
            .map_err(|e| format!("ISO-TP write of {payload} bytes: {e}"))?;
        let got = collect(&raw, 1, Duration::from_secs(2));
        let Some((frame, _)) = got.first() else {
            return Err(format!("no frame for an ISO-TP payload of {payload} bytes").into());
        };
        let kernel = frame.len();
        let model = fd_round_up(payload + pci).ok_or("the model has no size")?;
        if kernel != model {
            return Err(format!(
                "{} bytes (payload {payload} + PCI {pci}): the kernel sends {kernel} bytes, the model rounds to {model}",
                payload + pci
            )
            .into());
        }
    }
    eprintln!("{interface}: 62 ISO-TP lengths, kernel padding and model rounding agree");
    Ok(())
}

mod isotp {
    //! Just enough of the kernel's ISO-TP socket (linux/can/isotp.h).
    use std::io;

    const CAN_ISOTP: i32 = 6;
    const SOL_CAN_ISOTP: i32 = 100 + CAN_ISOTP;
    const CAN_ISOTP_LL_OPTS: i32 = 5;

    #[repr(C)]
    struct LinkLayerOptions {
        mtu: u8,
        tx_dl: u8,
        tx_flags: u8,
    }

    /// `struct sockaddr_can` with the `tp` member of its union.
    #[repr(C)]
    struct Address {
        family: u16,
        ifindex: i32,
        rx_id: u32,
        tx_id: u32,
        rest: [u32; 2],
    }

    pub(crate) struct Socket(i32);

    impl Socket {
        pub(crate) fn open(interface: &str, rx_id: u32, tx_id: u32) -> io::Result<Self> {
            let name = std::ffi::CString::new(interface)?;
            // SAFETY: plain socket calls on a descriptor owned by the returned Socket.
            unsafe {
                let ifindex = libc::if_nametoindex(name.as_ptr());
                if ifindex == 0 {
                    return Err(io::Error::last_os_error());
                }
                let fd = libc::socket(libc::AF_CAN, libc::SOCK_DGRAM, CAN_ISOTP);
                if fd < 0 {
                    return Err(io::Error::last_os_error());
                }
                let socket = Socket(fd);
                let options = LinkLayerOptions {
                    mtu: 72,
                    tx_dl: 64,
                    tx_flags: 0,
                };
                if libc::setsockopt(
                    fd,
                    SOL_CAN_ISOTP,
                    CAN_ISOTP_LL_OPTS,
                    (&options as *const LinkLayerOptions).cast(),
                    std::mem::size_of::<LinkLayerOptions>() as u32,
                ) < 0
                {
                    return Err(io::Error::last_os_error());
                }
                let address = Address {
                    family: libc::AF_CAN as u16,
                    ifindex: ifindex as i32,
                    rx_id,
                    tx_id,
                    rest: [0; 2],
                };
                if libc::bind(
                    fd,
                    (&address as *const Address).cast(),
                    std::mem::size_of::<Address>() as u32,
                ) < 0
                {
                    return Err(io::Error::last_os_error());
                }
                Ok(socket)
            }
        }

        pub(crate) fn send(&self, payload: &[u8]) -> io::Result<()> {
            // SAFETY: writing from a live slice.
            let n = unsafe { libc::write(self.0, payload.as_ptr().cast(), payload.len()) };
            if n < 0 {
                return Err(io::Error::last_os_error());
            }
            Ok(())
        }
    }

    impl Drop for Socket {
        fn drop(&mut self) {
            // SAFETY: closing the descriptor this Socket owns.
            unsafe { libc::close(self.0) };
        }
    }
}

/// A trial that cannot run here: skipped with the reason, or failed inside the
/// kernel lane, which promised what it needs.
fn unavailable(name: &str, why: KernelError) -> Trial {
    match canif_kernel::skip_is_failure(&why) {
        Some(failure) => Trial::test(name, move || Err(failure.into())),
        None => Trial::test(name, || Ok(()))
            .with_kind(format!("skipped: {}", canif_kernel::skip_reason(&why)))
            .with_ignored_flag(true),
    }
}

fn main() {
    let args = Arguments::from_args();
    let fd_interface = test_interface("CANIF_LANE_FD", "vcan0");
    if let Err(why) = &fd_interface {
        eprintln!("kernel oracle tests skipped: {why}");
    }
    type Check = fn(&str) -> Result<(), Failed>;
    let checks: [(&str, Check); 3] = [
        ("frames_cross_the_kernel", frames_cross_the_kernel),
        (
            "can_raw_filters_agree_with_the_model",
            filters_agree_with_the_model,
        ),
        (
            "fd_lengths_agree_with_the_model",
            fd_lengths_agree_with_the_model,
        ),
    ];
    let mut trials: Vec<Trial> = checks
        .into_iter()
        .map(|(name, check)| match &fd_interface {
            Ok(interface) => {
                let interface = interface.clone();
                Trial::test(name, move || check(&interface))
            }
            Err(why) => unavailable(name, why.clone()),
        })
        .collect();
    for (name, variable, fd) in [
        (
            "frames_cross_two_controllers",
            "CANIF_LANE_CONTROLLERS",
            false,
        ),
        (
            "fd_frames_cross_two_fd_controllers",
            "CANIF_LANE_FD_CONTROLLERS",
            true,
        ),
    ] {
        let pair = canif_kernel::test_interface_pair(variable);
        trials.push(match pair {
            Ok((a, b)) => Trial::test(name, move || {
                frames_cross_two_controllers(&format!("{a},{b}"), fd)
            }),
            Err(why) => unavailable(name, why),
        });
    }
    libtest_mimic::run(&args, trials).exit();
}
