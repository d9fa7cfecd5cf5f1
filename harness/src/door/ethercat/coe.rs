//! What ethercrab's CoE lacks and a terminal needs: downloads longer than
//! four bytes (normal and segmented, ETG.1000.6 §5.6.2.2–3) with complete
//! access, and uploads of one entry, through the SubDevice's mailbox
//! SyncManagers, datagram by datagram.

use std::fmt;
use std::time::{Duration, Instant};

use canif_ethercat::mailbox::{capacity, MailboxError, SdoRequest, SdoResponse};
use canif_ethercat::register::{self, SyncManager};
use ethercrab::{Command, MainDevice};

/// How long a terminal may take to put an answer in its mailbox.
const ANSWER_TIMEOUT: Duration = Duration::from_secs(2);

/// Why a transfer did not complete.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(super) enum CoeError {
    /// The terminal refused: its abort code.
    Abort { index: u16, sub: u8, code: u32 },
    /// The answer is no SDO message, or not the one asked for.
    Answer(String),
    /// No answer in time.
    Timeout(Duration),
    /// The master could not exchange the datagrams.
    Master(String),
}

impl fmt::Display for CoeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            CoeError::Abort { index, sub, code } => write!(
                f,
                "SDO {index:#06x}:{sub:02x} aborted with {code:#010x} ({})",
                abort_text(*code)
            ),
            CoeError::Answer(what) => write!(f, "mailbox answer: {what}"),
            CoeError::Timeout(after) => write!(f, "no mailbox answer within {after:?}"),
            CoeError::Master(what) => write!(f, "EtherCAT master: {what}"),
        }
    }
}

impl std::error::Error for CoeError {}

/// The meaning of the abort codes ETG.1000.6 Table 41 gives.
pub(super) fn abort_text(code: u32) -> &'static str {
    match code {
        0x0503_0000 => "toggle bit not changed",
        0x0504_0001 => "command specifier not valid",
        0x0601_0000 => "unsupported access",
        0x0601_0002 => "write to a read-only object",
        0x0602_0000 => "object does not exist",
        0x0604_0043 => "general parameter incompatibility",
        0x0607_0010 => "data type or length does not match",
        0x0609_0011 => "sub-index does not exist",
        0x0609_0030 => "value range exceeded",
        0x0800_0000 => "general error",
        0x0800_0022 => "not in the present device state",
        _ => "no meaning in ETG.1000.6",
    }
}

fn master(error: ethercrab::error::Error) -> CoeError {
    CoeError::Master(error.to_string())
}

/// The mailboxes of one SubDevice, as its SyncManager registers say.
pub(super) struct Mailboxes {
    station: u16,
    out: SyncManager,
    input: SyncManager,
    counter: u8,
}

impl Mailboxes {
    /// Reads SM0 and SM1 of the SubDevice at `station`.
    pub(super) async fn of(
        maindevice: &MainDevice<'_>,
        station: u16,
    ) -> Result<Mailboxes, CoeError> {
        let read = |n: u16| async move {
            let bytes = Command::fprd(station, register::SYNC_MANAGER_BASE + n * 8)
                .receive_slice(maindevice, 8)
                .await
                .map_err(master)?;
            Ok::<_, CoeError>(SyncManager::parse(&bytes))
        };
        let (out, input) = (read(0).await?, read(1).await?);
        if !out.enabled() || !input.enabled() || !out.mailbox() || !input.mailbox() {
            return Err(CoeError::Answer(format!(
                "no mailbox SyncManagers configured (SM0 {out:?}, SM1 {input:?})"
            )));
        }
        Ok(Mailboxes {
            station,
            out,
            input,
            counter: 0,
        })
    }

    fn size(&self) -> usize {
        usize::from(self.out.length.min(self.input.length))
    }

    /// One request, one answer.
    async fn exchange(
        &mut self,
        maindevice: &MainDevice<'_>,
        request: &SdoRequest,
    ) -> Result<SdoResponse, CoeError> {
        // Counters run 1..=7 (ETG.1000.4 §5.6): a repeated one may be dropped as a retry.
        self.counter = self.counter % 7 + 1;
        let bytes = request.emit(self.counter, usize::from(self.out.length));
        Command::fpwr(self.station, self.out.start)
            .send(maindevice, bytes.as_slice())
            .await
            .map_err(master)?;
        // The answer read at once: an ESC denies the read of a mailbox its
        // firmware has not filled (working counter 0), and only then is its
        // status polled. An emulated terminal has answered by now: two
        // frames an exchange instead of three.
        let mailbox = Command::fprd(self.station, self.input.start);
        let answer = match mailbox.receive_slice(maindevice, self.input.length).await {
            Ok(answer) => answer,
            Err(ethercrab::error::Error::WorkingCounter { .. }) => {
                self.await_answer(maindevice).await?;
                mailbox
                    .receive_slice(maindevice, self.input.length)
                    .await
                    .map_err(master)?
            }
            Err(e) => return Err(master(e)),
        };
        SdoResponse::parse(&answer).map_err(|e: MailboxError| CoeError::Answer(e.to_string()))
    }

    /// Polls the terminal's mailbox status until its answer is there.
    async fn await_answer(&self, maindevice: &MainDevice<'_>) -> Result<(), CoeError> {
        let status = register::SYNC_MANAGER_BASE + 8 + 5;
        let began = Instant::now();
        loop {
            let full = Command::fprd(self.station, status)
                .receive::<u8>(maindevice)
                .await
                .map_err(master)?;
            if full & SyncManager::STATUS_MAILBOX_FULL != 0 {
                return Ok(());
            }
            if began.elapsed() > ANSWER_TIMEOUT {
                return Err(CoeError::Timeout(ANSWER_TIMEOUT));
            }
            embassy_time::Timer::after_micros(200).await;
        }
    }

    /// Downloads `data` to `index` from sub-index 0 with complete access,
    /// in segments where one message cannot carry it.
    pub(super) async fn download_complete(
        &mut self,
        maindevice: &MainDevice<'_>,
        index: u16,
        data: &[u8],
    ) -> Result<(), CoeError> {
        let (first, segment) = capacity(self.size());
        let head = data.len().min(first);
        let request = SdoRequest::Download {
            index,
            sub: 0,
            complete_access: true,
            size: Some(data.len() as u32),
            data: data[..head].to_vec(),
        };
        expect_download(self.exchange(maindevice, &request).await?, index)?;
        let mut toggle = false;
        let chunks: Vec<&[u8]> = data[head..].chunks(segment).collect();
        for (n, chunk) in chunks.iter().enumerate() {
            let request = SdoRequest::DownloadSegment {
                toggle,
                last: n + 1 == chunks.len(),
                data: chunk.to_vec(),
            };
            match self.exchange(maindevice, &request).await? {
                SdoResponse::DownloadSegment { toggle: t } if t == toggle => {}
                SdoResponse::Abort { index, sub, code } => {
                    return Err(CoeError::Abort { index, sub, code })
                }
                other => return Err(CoeError::Answer(format!("{other:?} to a segment"))),
            }
            toggle = !toggle;
        }
        Ok(())
    }

    /// Downloads one entry (any length).
    pub(super) async fn download(
        &mut self,
        maindevice: &MainDevice<'_>,
        index: u16,
        sub: u8,
        data: &[u8],
    ) -> Result<(), CoeError> {
        let request = SdoRequest::Download {
            index,
            sub,
            complete_access: false,
            size: (data.len() > 4).then_some(data.len() as u32),
            data: data.to_vec(),
        };
        expect_download(self.exchange(maindevice, &request).await?, index)
    }

    /// Uploads one entry that fits one message.
    pub(super) async fn upload(
        &mut self,
        maindevice: &MainDevice<'_>,
        index: u16,
        sub: u8,
    ) -> Result<Vec<u8>, CoeError> {
        let request = SdoRequest::Upload {
            index,
            sub,
            complete_access: false,
        };
        match self.exchange(maindevice, &request).await? {
            SdoResponse::Upload {
                index: i,
                sub: s,
                data,
                ..
            } if (i, s) == (index, sub) => Ok(data),
            SdoResponse::Abort { index, sub, code } => Err(CoeError::Abort { index, sub, code }),
            other => Err(CoeError::Answer(format!("{other:?} to an upload"))),
        }
    }
}

fn expect_download(answer: SdoResponse, index: u16) -> Result<(), CoeError> {
    match answer {
        SdoResponse::Download { index: i, .. } if i == index => Ok(()),
        SdoResponse::Abort { index, sub, code } => Err(CoeError::Abort { index, sub, code }),
        other => Err(CoeError::Answer(format!(
            "{other:?} to a download of {index:#06x}"
        ))),
    }
}
