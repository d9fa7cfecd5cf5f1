//! # canif-cabi — a CAN interface device in a shared library
//!
//! The C ABI of `include/canif.h`, loaded with `libloading` and offered as
//! safe calls. Every `unsafe` block calls a function the header declares, with
//! arguments of the sizes it promises; what the library does inside is the
//! library's business (run it under AddressSanitizer to check).

mod client;
pub mod guard;
pub mod isolation;
pub mod shared;

use std::ffi::{c_char, c_int, c_void, CStr};
use std::path::Path;

pub use client::{CMessage, ClientLibrary, ClientProgram, TaskResult};

/// The ABI version this crate speaks (`CANIF_ABI_VERSION`).
pub const ABI_VERSION: u32 = 1;

/// `canif_frame`.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CFrame {
    pub id: u32,
    pub extended: u8,
    pub rtr: u8,
    pub fd: u8,
    pub brs: u8,
    pub esi: u8,
    pub len: u8,
    pub data: [u8; 64],
}

impl Default for CFrame {
    fn default() -> Self {
        CFrame {
            id: 0,
            extended: 0,
            rtr: 0,
            fd: 0,
            brs: 0,
            esi: 0,
            len: 0,
            data: [0; 64],
        }
    }
}

/// `canif_planned`: a frame of a transmit plan.
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct CPlanned {
    pub frame: CFrame,
    pub not_before_ns: u64,
}

/// `canif_filter`.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CFilter {
    pub accept: u8,
    pub is_range: u8,
    pub from_or_code: u32,
    pub to_or_mask: u32,
}

/// `canif_capabilities`.
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct CCapabilities {
    pub base11: u8,
    pub ext29: u8,
    pub fd: u8,
    pub fast_queue: u8,
    pub optimized_queue: u8,
    pub transaction_number: u8,
    pub transaction_number_only_ext29: u8,
    pub time_stamp: u8,
    pub filters: u8,
    pub info_data: u8,
    pub distributed_clocks: u8,
    pub max_slots: u8,
    pub rx_queue_depth: u32,
    pub tx_queue_depth: u32,
}

/// `canif_config`, owning its filter rows.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Config {
    pub format: u8,
    pub queue: u8,
    pub transaction_number: u8,
    pub time_stamp: u8,
    pub tx_slots: u8,
    pub rx_slots: u8,
    pub distributed_clocks: u8,
    pub sync1_shift_ns: u64,
    pub nominal_timing: u32,
    pub data_timing: u32,
    pub output_size: u32,
    pub input_size: u32,
    pub filters: Vec<CFilter>,
}

#[repr(C)]
pub(crate) struct CConfig {
    format: u8,
    queue: u8,
    transaction_number: u8,
    time_stamp: u8,
    tx_slots: u8,
    rx_slots: u8,
    distributed_clocks: u8,
    sync1_shift_ns: u64,
    nominal_timing: u32,
    data_timing: u32,
    output_size: u32,
    input_size: u32,
    filter_count: u32,
    filters: *const CFilter,
}

/// `canif_status`.
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct CStatus {
    pub bus_off: u8,
    pub error_passive: u8,
    pub node_active: u8,
    pub warning_limit: u8,
    pub overload: u8,
    pub bus_idle: u8,
    pub core_running: u8,
    pub transceiver_delay: u32,
    pub ack_errors: u32,
    pub bit_errors: u32,
    pub crc_errors: u32,
    pub form_errors: u32,
    pub stuff_errors: u32,
    pub receive_error_counter: u32,
    pub transmit_error_counter: u32,
}

pub(crate) type Version = unsafe extern "C" fn() -> u32;
type Create =
    unsafe extern "C" fn(*const CConfig, *const CCapabilities, *mut c_char, usize) -> *mut c_void;
type Destroy = unsafe extern "C" fn(*mut c_void);
type Cycle = unsafe extern "C" fn(*mut c_void, u64, *const u8, usize, *mut u8, usize) -> c_int;
type Receive = unsafe extern "C" fn(*mut c_void, *const CFrame, u64);
type Poll = unsafe extern "C" fn(*mut c_void, u64, *mut CFrame, *mut u64) -> c_int;
type Complete = unsafe extern "C" fn(*mut c_void);
type Status = unsafe extern "C" fn(*mut c_void, *const CStatus);
type Declares = unsafe extern "C" fn(*mut c_void) -> *const c_char;
type Plan = unsafe extern "C" fn(*mut c_void, u64, *mut CPlanned, usize) -> c_int;

/// The functions of one loaded library.
#[derive(Clone, Copy)]
struct Functions {
    create: Create,
    destroy: Destroy,
    cycle: Cycle,
    receive: Receive,
    poll: Poll,
    complete: Complete,
    status: Status,
    /// Optional: a device that declares nothing leaves it out.
    declares: Option<Declares>,
    /// Optional: a device polled frame by frame leaves it out.
    plan: Option<Plan>,
}

/// Loads `path` and checks that it speaks this ABI version.
pub(crate) fn open_checked(path: &Path) -> Result<libloading::Library, String> {
    let name = path.display();
    // SAFETY: loading runs the library's initialisers; a library is code the
    // user chose to put under test, as `exec:` runs a process.
    let library = unsafe { libloading::Library::new(path) }
        .map_err(|e| format!("cannot load {name}: {e}"))?;
    let version: Version = symbol(&library, "canif_abi_version")?;
    // SAFETY: canif_abi_version takes nothing and returns a number.
    let found = unsafe { version() };
    if found != ABI_VERSION {
        return Err(format!(
            "{name} speaks canif ABI version {found}; this canif speaks {ABI_VERSION}"
        ));
    }
    Ok(library)
}

/// The function `name` of `library`; `T` must be its type in include/canif.h.
pub(crate) fn symbol<T: Copy>(library: &libloading::Library, name: &str) -> Result<T, String> {
    // SAFETY: the callers name `T` as the function type include/canif.h
    // declares for `name`.
    unsafe { library.get::<T>(name.as_bytes()) }
        .map(|symbol| *symbol)
        .map_err(|e| format!("the library has no `{name}` ({e})"))
}

impl Config {
    /// As the library reads it; borrows the filter rows.
    pub(crate) fn raw(&self) -> CConfig {
        CConfig {
            format: self.format,
            queue: self.queue,
            transaction_number: self.transaction_number,
            time_stamp: self.time_stamp,
            tx_slots: self.tx_slots,
            rx_slots: self.rx_slots,
            distributed_clocks: self.distributed_clocks,
            sync1_shift_ns: self.sync1_shift_ns,
            nominal_timing: self.nominal_timing,
            data_timing: self.data_timing,
            output_size: self.output_size,
            input_size: self.input_size,
            filter_count: self.filters.len() as u32,
            filters: self.filters.as_ptr(),
        }
    }
}

/// A loaded device library. Devices keep it loaded while they live.
pub struct Library {
    functions: Functions,
    // Declared last: dropped after every function pointer taken from it.
    _library: std::sync::Arc<libloading::Library>,
}

impl Library {
    /// Loads `path` and checks its ABI version and every symbol.
    pub fn open(path: &Path) -> Result<Self, String> {
        let library = open_checked(path)?;
        let functions = Functions {
            create: symbol(&library, "canif_create")?,
            destroy: symbol(&library, "canif_destroy")?,
            cycle: symbol(&library, "canif_cycle")?,
            receive: symbol(&library, "canif_receive")?,
            poll: symbol(&library, "canif_poll_transmit")?,
            complete: symbol(&library, "canif_transmit_complete")?,
            status: symbol(&library, "canif_controller_status")?,
            declares: symbol(&library, "canif_declares").ok(),
            plan: symbol(&library, "canif_transmit_plan").ok(),
        };
        Ok(Library {
            functions,
            _library: std::sync::Arc::new(library),
        })
    }

    /// Whether its devices tell their transmit plan (`canif_transmit_plan`).
    pub fn plans(&self) -> bool {
        self.functions.plan.is_some()
    }

    /// A device for `config`; `Err` carries the device's reason for refusing it.
    pub fn create(&self, config: &Config, caps: &CCapabilities) -> Result<Device, String> {
        let raw = config.raw();
        let mut reason = [0 as c_char; 512];
        // SAFETY: `raw` and its filter rows live through the call; `reason`
        // has the size passed; the library returns a handle or NULL.
        let handle =
            unsafe { (self.functions.create)(&raw, caps, reason.as_mut_ptr(), reason.len()) };
        if handle.is_null() {
            reason[reason.len() - 1] = 0; // a reason the library did not end
                                          // SAFETY: `reason` is NUL-terminated within its length (set above).
            let text = unsafe { CStr::from_ptr(reason.as_ptr()) };
            return Err(text.to_string_lossy().into_owned());
        }
        Ok(Device {
            handle,
            functions: self.functions,
            input_size: config.input_size as usize,
            _library: self._library.clone(),
        })
    }
}

/// One device made by a library; destroyed when dropped.
pub struct Device {
    handle: *mut c_void,
    functions: Functions,
    input_size: usize,
    _library: std::sync::Arc<libloading::Library>,
}

impl Device {
    /// One cycle; the new input image, or `Err` when the device said it broke.
    pub fn cycle(&mut self, now: u64, outputs: &[u8]) -> Result<Vec<u8>, String> {
        let mut inputs = vec![0u8; self.input_size];
        self.cycle_into(now, outputs, &mut inputs)?;
        Ok(inputs)
    }

    /// One cycle into `inputs` (the input image's size: [`Device::input_size`]).
    pub fn cycle_into(
        &mut self,
        now: u64,
        outputs: &[u8],
        inputs: &mut [u8],
    ) -> Result<(), String> {
        if inputs.len() != self.input_size {
            return Err(format!(
                "an input buffer of {} bytes for an image of {}",
                inputs.len(),
                self.input_size
            ));
        }
        // SAFETY: both buffers have the lengths passed; the handle is live.
        let result = unsafe {
            (self.functions.cycle)(
                self.handle,
                now,
                outputs.as_ptr(),
                outputs.len(),
                inputs.as_mut_ptr(),
                inputs.len(),
            )
        };
        if result == 0 {
            Ok(())
        } else {
            Err(format!("canif_cycle returned {result}"))
        }
    }

    pub fn input_size(&self) -> usize {
        self.input_size
    }

    pub fn receive(&mut self, frame: &CFrame, end_ns: u64) {
        // SAFETY: `frame` lives through the call; the handle is live.
        unsafe { (self.functions.receive)(self.handle, frame, end_ns) }
    }

    /// The lines `canif_declares` gave ("name=value"), none without it.
    pub fn declares(&self) -> Vec<String> {
        let Some(declares) = self.functions.declares else {
            return Vec::new();
        };
        // SAFETY: the handle is live; the library returns NULL or a
        // NUL-terminated string valid while the device lives.
        let text = unsafe { declares(self.handle) };
        if text.is_null() {
            return Vec::new();
        }
        // SAFETY: non-null and NUL-terminated (the ABI's promise above).
        let text = unsafe { CStr::from_ptr(text) }.to_string_lossy();
        text.lines()
            .map(str::trim)
            .filter(|line| !line.is_empty())
            .map(str::to_string)
            .collect()
    }

    /// The frame the controller starts at `now`, if any, and when a held one is due.
    pub fn poll_transmit(&mut self, now: u64) -> (Option<CFrame>, Option<u64>) {
        let mut frame = CFrame::default();
        let mut next = u64::MAX;
        // SAFETY: `frame` and `next` are writable and of the declared types.
        let started = unsafe { (self.functions.poll)(self.handle, now, &mut frame, &mut next) };
        (
            (started == 1).then_some(frame),
            (next != u64::MAX).then_some(next),
        )
    }

    /// Its transmit plan from `now` on, at most `most` frames; `None`
    /// without `canif_transmit_plan`, `Err` for a count no plan can have.
    pub fn transmit_plan(&self, now: u64, most: usize) -> Option<Result<Vec<CPlanned>, String>> {
        let plan = self.functions.plan?;
        let mut planned = vec![CPlanned::default(); most];
        // SAFETY: `planned` holds `most` writable entries; the handle is live.
        let count = unsafe { plan(self.handle, now, planned.as_mut_ptr(), most) };
        Some(match usize::try_from(count) {
            Ok(count) if count <= most => {
                planned.truncate(count);
                Ok(planned)
            }
            _ => Err(format!(
                "canif_transmit_plan returned {count} for room for {most}"
            )),
        })
    }

    pub fn transmit_complete(&mut self) {
        // SAFETY: the handle is live.
        unsafe { (self.functions.complete)(self.handle) }
    }

    pub fn controller_status(&mut self, status: &CStatus) {
        // SAFETY: `status` lives through the call; the handle is live.
        unsafe { (self.functions.status)(self.handle, status) }
    }
}

impl Drop for Device {
    fn drop(&mut self) {
        // SAFETY: the handle came from canif_create and is destroyed once.
        unsafe { (self.functions.destroy)(self.handle) }
    }
}
