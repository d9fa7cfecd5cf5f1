//! The client role of `include/canif.h`: a PLC-side client in a shared
//! library, loaded and offered as safe calls like the device role.

use std::ffi::{c_int, c_void};
use std::path::Path;
use std::sync::Arc;

use crate::{open_checked, symbol, CConfig, CFrame, Config};

/// `canif_message`.
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct CMessage {
    pub frame: CFrame,
    pub transaction_number: u16,
    pub time_stamp_ns: u64,
}

type Start = unsafe extern "C" fn(*const CConfig) -> *mut c_void;
type Stop = unsafe extern "C" fn(*mut c_void);
type Task = unsafe extern "C" fn(
    *mut c_void,
    *const u8,
    usize,
    *mut u8,
    usize,
    *const CMessage,
    usize,
    *mut u8,
    *mut CMessage,
    usize,
    *mut usize,
) -> c_int;

type Sent = unsafe extern "C" fn(*mut c_void, *mut u16, usize) -> usize;
type ClientDeclares = unsafe extern "C" fn() -> *const std::ffi::c_char;

#[derive(Clone, Copy)]
struct Functions {
    start: Start,
    stop: Stop,
    task: Task,
    /// Optional: a client that does not tell what was sent leaves it out.
    sent: Option<Sent>,
    /// Optional: a client that declares nothing leaves it out.
    declares: Option<ClientDeclares>,
}

/// Room for the transaction numbers one task may tell: more than any
/// interface has Tx messages in flight.
const SENT_CAPACITY: usize = 1024;

/// A loaded client library. Clients keep it loaded while they live.
pub struct ClientLibrary {
    functions: Functions,
    library: Arc<libloading::Library>,
}

impl ClientLibrary {
    /// Loads `path` and checks its ABI version and the client role's symbols.
    pub fn open(path: &Path) -> Result<Self, String> {
        let library = open_checked(path)?;
        let functions = Functions {
            start: symbol(&library, "canif_client_start")?,
            stop: symbol(&library, "canif_client_stop")?,
            task: symbol(&library, "canif_client_task")?,
            sent: symbol(&library, "canif_client_sent").ok(),
            declares: symbol(&library, "canif_client_declares").ok(),
        };
        Ok(ClientLibrary {
            functions,
            library: Arc::new(library),
        })
    }

    /// The lines `canif_client_declares` gave ("name=value"), none without it.
    pub fn declares(&self) -> Vec<String> {
        let Some(declares) = self.functions.declares else {
            return Vec::new();
        };
        // SAFETY: the function takes nothing and returns NULL or a
        // NUL-terminated string valid while the library is loaded.
        let text = unsafe { declares() };
        if text.is_null() {
            return Vec::new();
        }
        // SAFETY: non-null and NUL-terminated (the ABI's promise above).
        let text = unsafe { std::ffi::CStr::from_ptr(text) }.to_string_lossy();
        text.lines()
            .map(str::trim)
            .filter(|l| !l.is_empty())
            .map(String::from)
            .collect()
    }

    /// A program for `config`.
    pub fn start(&self, config: &Config) -> Result<ClientProgram, String> {
        let raw = config.raw();
        // SAFETY: `raw` and its filter rows live through the call.
        let handle = unsafe { (self.functions.start)(&raw) };
        if handle.is_null() {
            return Err("canif_client_start returned NULL".into());
        }
        Ok(ClientProgram {
            handle,
            functions: self.functions,
            _library: self.library.clone(),
        })
    }
}

/// What one task gave back.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct TaskResult {
    pub delivered: Vec<CMessage>,
    /// Indices of the requests the client cannot send.
    pub refused: Vec<usize>,
    /// What `canif_client_sent` told (empty without it).
    pub sent: Vec<u16>,
}

/// One running program; stopped when dropped.
pub struct ClientProgram {
    handle: *mut c_void,
    functions: Functions,
    _library: Arc<libloading::Library>,
}

impl ClientProgram {
    /// Whether the library tells its application which Tx messages were
    /// sent: it exports the optional `canif_client_sent`.
    pub fn tells_sent(&self) -> bool {
        self.functions.sent.is_some()
    }

    /// One task. `inputs` and `outputs` run on past the images (the master's
    /// neighbour bytes): the library is given the image sizes, and the
    /// pointers into the larger buffers, as a master would.
    pub fn task(
        &mut self,
        (inputs, input_size): (&[u8], usize),
        (outputs, output_size): (&mut [u8], usize),
        requests: &[CMessage],
        capacity: usize,
    ) -> Result<TaskResult, String> {
        if inputs.len() < input_size || outputs.len() < output_size {
            return Err("images shorter than their sizes".into());
        }
        let mut refused = vec![0u8; requests.len()];
        let mut delivered = vec![CMessage::default(); capacity];
        let mut count = 0usize;
        // SAFETY: every pointer is valid for the length passed with it (the
        // images for at least their sizes, checked above); the handle is live.
        let result = unsafe {
            (self.functions.task)(
                self.handle,
                inputs.as_ptr(),
                input_size,
                outputs.as_mut_ptr(),
                output_size,
                requests.as_ptr(),
                requests.len(),
                refused.as_mut_ptr(),
                delivered.as_mut_ptr(),
                capacity,
                &mut count,
            )
        };
        if result != 0 {
            return Err(format!("canif_client_task returned {result}"));
        }
        if count > capacity {
            return Err(format!(
                "canif_client_task delivered {count} messages into room for {capacity}"
            ));
        }
        delivered.truncate(count);
        let mut sent = Vec::new();
        if let Some(told) = self.functions.sent {
            sent = vec![0u16; SENT_CAPACITY];
            // SAFETY: `sent` holds SENT_CAPACITY numbers; the handle is live.
            let count = unsafe { told(self.handle, sent.as_mut_ptr(), SENT_CAPACITY) };
            if count > SENT_CAPACITY {
                return Err(format!(
                    "canif_client_sent told {count} numbers into room for {SENT_CAPACITY}"
                ));
            }
            sent.truncate(count);
        }
        Ok(TaskResult {
            delivered,
            refused: (0..requests.len()).filter(|i| refused[*i] != 0).collect(),
            sent,
        })
    }
}

impl Drop for ClientProgram {
    fn drop(&mut self) {
        // SAFETY: the handle came from canif_client_start and is stopped once.
        unsafe { (self.functions.stop)(self.handle) }
    }
}
