//! What a PLC-side client declares it is (issue 27): the interfaces it
//! serves, its slot geometry, its direction, its application model, its
//! restart choice (P3) and whether it tells its application what was sent.
//! A client is judged on what it declares; what it does not serve is "not
//! applicable" with the declaration as the reason, never an error. A client
//! that declares nothing is held to everything the profile offers.
//!
//! Declarations are `name=value` lines (docs/plc-side.md), from the command
//! line (`--declare`), the protocol's `started` answer (`declares`), a
//! library's `canif_client_declares` or an in-process [`crate::door::client::Client`].

use std::fmt;

use super::Declaration;
pub use super::DeclarationError;

use canif_model::config::{FrameFormat, InterfaceConfig, QueueMode};
use canif_model::freedoms::Named;

/// Which way a client moves frames.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum Direction {
    /// It sends the application's frames and delivers the bus's.
    #[default]
    Both,
    /// It only sends: it never reads the Rx slots.
    Tx,
    /// It only receives: it never writes a Tx batch.
    Rx,
}

impl Direction {
    pub fn sends(self) -> bool {
        self != Direction::Rx
    }

    pub fn receives(self) -> bool {
        self != Direction::Tx
    }
}

/// How the application above the client hands it frames and takes them.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum Application {
    /// One stream: every frame in the order asked (CL-TX-003, CL-RX-002).
    #[default]
    OneStream,
    /// Several streams, one per CAN identifier, each in order; frames of
    /// different identifiers may pass each other (a module with a queue per
    /// identifier or priority). An assumption of this suite: the documents
    /// know one queue, and an identifier is what a CAN stream is named by.
    Streams,
    /// A byte stream per CAN identifier: the application hands the client
    /// bytes, and the client may cut them into frames as it likes (fill a
    /// frame from several requests, split one); the bytes of each identifier
    /// must arrive in order, once. Classic frames only: an FD frame's length
    /// is one of 16 sizes, so a stream of them cannot be cut at any byte.
    ByteStream,
}

impl Named for Direction {
    const ALL: &'static [Self] = &[Direction::Both, Direction::Tx, Direction::Rx];
    const NAMES: &'static [&'static str] = &["both", "tx", "rx"];

    fn name(self) -> &'static str {
        match self {
            Direction::Both => "both",
            Direction::Tx => "tx",
            Direction::Rx => "rx",
        }
    }
}

impl Named for Application {
    const ALL: &'static [Self] = &[
        Application::OneStream,
        Application::Streams,
        Application::ByteStream,
    ];
    const NAMES: &'static [&'static str] = &["one-stream", "streams", "byte-stream"];

    fn name(self) -> &'static str {
        match self {
            Application::OneStream => "one-stream",
            Application::Streams => "streams",
            Application::ByteStream => "byte-stream",
        }
    }
}

impl Named for RestartChoice {
    const ALL: &'static [Self] = &[RestartChoice::DeliversTwice, RestartChoice::DropsOnce];
    const NAMES: &'static [&'static str] = &["delivers-twice", "drops-once"];

    fn name(self) -> &'static str {
        match self {
            RestartChoice::DeliversTwice => "delivers-twice",
            RestartChoice::DropsOnce => "drops-once",
        }
    }
}

/// P3: what a restarted client does with the one batch the image may still
/// hold from before the restart.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RestartChoice {
    /// It delivers that batch (again, if the old program had).
    DeliversTwice,
    /// It acknowledges it without delivering (dropped, if the old program had not).
    DropsOnce,
}

/// What a client declares; `None` (or the default): it declares nothing there.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct ClientDeclaration {
    /// The frame formats whose interfaces it serves.
    pub formats: Option<Vec<FrameFormat>>,
    /// The queue modes it serves.
    pub queues: Option<Vec<QueueMode>>,
    /// Whether it serves interfaces with transaction numbers.
    pub transaction_numbers: Option<bool>,
    /// Whether it serves interfaces with time stamps.
    pub time_stamps: Option<bool>,
    /// The Tx slot counts it runs with (`tx-slots`, or `slots` for both).
    pub tx_slots: Option<SlotRange>,
    /// The Rx slot counts it runs with (`rx-slots`, or `slots` for both).
    pub rx_slots: Option<SlotRange>,
    pub direction: Option<Direction>,
    pub application: Option<Application>,
    /// P3; undeclared, either is accepted.
    pub restart: Option<RestartChoice>,
    /// Whether it tells its application which Tx messages were sent (CL-TN-*).
    pub tells_sent: Option<bool>,
}

/// What can be declared, by name.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Item {
    Formats,
    Queues,
    TransactionNumbers,
    TimeStamps,
    Slots,
    TxSlots,
    RxSlots,
    Direction,
    Application,
    Restart,
    TellsSent,
}

impl Item {
    const ALL: [Item; 11] = [
        Item::Formats,
        Item::Queues,
        Item::TransactionNumbers,
        Item::TimeStamps,
        Item::Slots,
        Item::TxSlots,
        Item::RxSlots,
        Item::Direction,
        Item::Application,
        Item::Restart,
        Item::TellsSent,
    ];

    fn name(self) -> &'static str {
        match self {
            Item::Formats => "formats",
            Item::Queues => "queues",
            Item::TransactionNumbers => "transaction-numbers",
            Item::TimeStamps => "time-stamps",
            Item::Slots => "slots",
            Item::TxSlots => "tx-slots",
            Item::RxSlots => "rx-slots",
            Item::Direction => "direction",
            Item::Application => "application",
            Item::Restart => "restart",
            Item::TellsSent => "tells-sent",
        }
    }

    fn expected(self) -> &'static str {
        match self {
            Item::Formats => "a list of 11-bit, 29-bit, fd (comma-separated)",
            Item::Queues => "a list of standard, optimized, fast (comma-separated)",
            Item::TransactionNumbers | Item::TimeStamps | Item::TellsSent => "yes or no",
            Item::Slots | Item::TxSlots | Item::RxSlots => {
                "a slot count N or a range MIN..MAX within 1..32"
            }
            Item::Direction => "tx, rx or both",
            Item::Application => "one-stream, streams or byte-stream",
            Item::Restart => "delivers-twice or drops-once",
        }
    }
}

fn format_name(format: FrameFormat) -> &'static str {
    match format {
        FrameFormat::Base11 => "11-bit",
        FrameFormat::Extended29 => "29-bit",
        FrameFormat::Fd => "fd",
    }
}

fn queue_name(queue: QueueMode) -> &'static str {
    match queue {
        QueueMode::Standard => "standard",
        QueueMode::Optimized => "optimized",
        QueueMode::Fast => "fast",
    }
}

fn list<T: Copy>(value: &str, named: impl Fn(&str) -> Option<T>) -> Option<Vec<T>> {
    value.split(',').map(|v| named(v.trim())).collect()
}

fn yes_no(value: &str) -> Option<bool> {
    match value {
        "yes" => Some(true),
        "no" => Some(false),
        _ => None,
    }
}

/// Sets `slot` to `value` unless it holds another value already.
fn set<T: PartialEq + fmt::Debug>(
    slot: &mut Option<T>,
    value: T,
    item: Item,
    line: &str,
    shown: impl Fn(&T) -> String,
) -> Result<(), DeclarationError> {
    match slot {
        Some(old) if *old != value => Err(DeclarationError::Conflict {
            name: item.name(),
            first: format!("{}={}", item.name(), shown(old)),
            second: line.to_string(),
        }),
        _ => {
            *slot = Some(value);
            Ok(())
        }
    }
}

/// Sets `slot` to the value `value` names.
fn named<T: Named + PartialEq + fmt::Debug>(
    slot: &mut Option<T>,
    value: &str,
    item: Item,
    line: &str,
) -> Result<(), DeclarationError> {
    let parsed = T::from_name(value).ok_or_else(|| bad_value(item, value))?;
    set(slot, parsed, item, line, |v| v.name().into())
}

/// Sets `slot` to `yes` or `no`.
fn yes_or_no(
    slot: &mut Option<bool>,
    value: &str,
    item: Item,
    line: &str,
) -> Result<(), DeclarationError> {
    let parsed = yes_no(value).ok_or_else(|| bad_value(item, value))?;
    set(slot, parsed, item, line, yes_no_name)
}

/// Sets `slot` to the comma-separated values `value` names, each one of
/// `all` by `name`.
fn listed<T: Copy + PartialEq + fmt::Debug>(
    slot: &mut Option<Vec<T>>,
    value: &str,
    item: Item,
    line: &str,
    (all, name): (&[T], fn(T) -> &'static str),
) -> Result<(), DeclarationError> {
    let values = list(value, |v| all.iter().copied().find(|x| name(*x) == v))
        .ok_or_else(|| bad_value(item, value))?;
    set(slot, values, item, line, |values| joined(values, name))
}

/// Values by name, comma-separated, as a declaration writes them.
fn joined<T: Copy>(values: &[T], name: fn(T) -> &'static str) -> String {
    values
        .iter()
        .map(|v| name(*v))
        .collect::<Vec<_>>()
        .join(",")
}

fn bad_value(item: Item, value: &str) -> DeclarationError {
    DeclarationError::BadValue {
        name: item.name(),
        value: value.into(),
        expected: item.expected().to_string(),
    }
}

impl ClientDeclaration {
    /// This declaration and `other`'s lines together; a value declared two
    /// ways is an error naming both.
    pub fn merged(&self, other: &ClientDeclaration) -> Result<Self, DeclarationError> {
        let mut merged = self.clone();
        for line in other.lines() {
            merged.declare(&line)?;
        }
        Ok(merged)
    }

    pub fn direction(&self) -> Direction {
        self.direction.unwrap_or_default()
    }

    pub fn application(&self) -> Application {
        self.application.unwrap_or_default()
    }

    /// The interface this client is run on where the profile offers
    /// `offered`: the same, without transaction numbers or time stamps where
    /// the client declines them and the interface lets them off; or why it
    /// does not serve it.
    pub fn serve(&self, offered: &InterfaceConfig) -> Result<InterfaceConfig, String> {
        let mut config = offered.clone();
        if let Some(formats) = &self.formats {
            if !formats.contains(&config.format) {
                return Err(self.declined(Item::Formats));
            }
        }
        if let Some(queues) = &self.queues {
            if !queues.contains(&config.queue) {
                return Err(self.declined(Item::Queues));
            }
        }
        // FD messages always carry both (LAY-FD); elsewhere they are options.
        let fixed = config.format == FrameFormat::Fd;
        if fixed && self.application == Some(Application::ByteStream) {
            return Err(format!(
                "{}: a byte stream is judged on classic frames (an FD frame cannot be cut at any byte)",
                self.declined(Item::Application)
            ));
        }
        if self.transaction_numbers == Some(false) && config.transaction_number {
            if fixed {
                return Err(self.declined(Item::TransactionNumbers));
            }
            config.transaction_number = false;
            config.time_stamp = false;
        }
        if self.time_stamps == Some(false) && config.time_stamp {
            if fixed {
                return Err(self.declined(Item::TimeStamps));
            }
            config.time_stamp = false;
        }
        // A client that serves only interfaces with them has nothing to
        // be judged on where they are not offered.
        if self.transaction_numbers == Some(true) && !config.transaction_number {
            return Err(self.declined(Item::TransactionNumbers));
        }
        if self.time_stamps == Some(true) && !config.time_stamp {
            return Err(self.declined(Item::TimeStamps));
        }
        Ok(config)
    }

    /// The (Tx, Rx) slot counts a client is run at on a profile with
    /// `max_slots`: the default, the edges of both ranges, and the edges apart.
    pub fn geometries(&self, max_slots: u8) -> Vec<(u8, u8)> {
        slots::geometries(
            self.tx_slots.unwrap_or(SlotRange::ANY),
            self.rx_slots.unwrap_or(SlotRange::ANY),
            max_slots,
        )
    }

    /// Whether the client runs with `tx` Tx slots and `rx` Rx slots.
    pub fn serves_slots(&self, tx: u8, rx: u8) -> bool {
        self.tx_slots.unwrap_or(SlotRange::ANY).contains(tx)
            && self.rx_slots.unwrap_or(SlotRange::ANY).contains(rx)
    }

    /// Why an interface is not served: the declaration's line.
    fn declined(&self, item: Item) -> String {
        let line = self
            .lines()
            .into_iter()
            .find(|l| l.starts_with(&format!("{}=", item.name())))
            .unwrap_or_default();
        format!("the client declares {line}")
    }

    /// Why no slot count of a profile with `max_slots` is served.
    pub fn declined_slots(&self, max_slots: u8) -> String {
        format!(
            "{}, outside the profile's 1..{max_slots}",
            self.declined_geometry()
        )
    }

    /// The declaration's slot lines, as a reason.
    pub fn declined_geometry(&self) -> String {
        let slots = [Item::Slots, Item::TxSlots, Item::RxSlots];
        let lines: Vec<String> = self
            .lines()
            .into_iter()
            .filter(|l| {
                slots
                    .iter()
                    .any(|i| l.starts_with(&format!("{}=", i.name())))
            })
            .collect();
        format!("the client declares {}", lines.join(", "))
    }

    /// Why one stream's frame-by-frame order is not the client's.
    pub fn declined_application(&self) -> String {
        self.declined(Item::Application)
    }

    /// Why traffic one way is not served.
    pub fn declined_direction(&self) -> String {
        self.declined(Item::Direction)
    }

    /// Why a scenario that needs `capability` (a tag) is not served: the
    /// client declares it does without transaction numbers or time stamps.
    pub fn declined_capability(&self, capability: &str) -> Option<String> {
        match capability {
            "transaction_number" if self.transaction_numbers == Some(false) => {
                Some(self.declined(Item::TransactionNumbers))
            }
            "timestamp" if self.time_stamps == Some(false) => Some(self.declined(Item::TimeStamps)),
            _ => None,
        }
    }
}

fn yes_no_name(v: &bool) -> String {
    match v {
        true => "yes".into(),
        false => "no".into(),
    }
}

mod slots;
pub use slots::{SlotRange, MAX_SLOTS};

impl Declaration for ClientDeclaration {
    /// Takes one `name=value` line; the same value twice is no conflict.
    fn declare(&mut self, line: &str) -> Result<(), DeclarationError> {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            return Ok(());
        }
        let Some((name, value)) = line.split_once('=') else {
            return Err(DeclarationError::Malformed { line: line.into() });
        };
        let (name, value) = (name.trim(), value.trim());
        let item = Item::ALL
            .into_iter()
            .find(|i| i.name() == name)
            .ok_or_else(|| DeclarationError::UnknownName {
                name: name.into(),
                what: "client declaration",
                known: Item::ALL.map(Item::name).to_vec(),
            })?;
        let bad = || bad_value(item, value);
        let line = format!("{name}={value}");
        match item {
            Item::Formats => {
                let formats = [
                    FrameFormat::Base11,
                    FrameFormat::Extended29,
                    FrameFormat::Fd,
                ];
                listed(
                    &mut self.formats,
                    value,
                    item,
                    &line,
                    (&formats, format_name),
                )
            }
            Item::Queues => {
                let queues = [QueueMode::Standard, QueueMode::Optimized, QueueMode::Fast];
                listed(&mut self.queues, value, item, &line, (&queues, queue_name))
            }
            Item::TransactionNumbers => {
                yes_or_no(&mut self.transaction_numbers, value, item, &line)
            }
            Item::TimeStamps => yes_or_no(&mut self.time_stamps, value, item, &line),
            Item::TellsSent => yes_or_no(&mut self.tells_sent, value, item, &line),
            // `slots` is both directions at once: it conflicts with a
            // `tx-slots` or `rx-slots` that says otherwise.
            Item::Slots | Item::TxSlots | Item::RxSlots => {
                let range = SlotRange::parse(value).ok_or_else(bad)?;
                if item != Item::RxSlots {
                    set(&mut self.tx_slots, range, item, &line, SlotRange::to_string)?;
                }
                if item != Item::TxSlots {
                    set(&mut self.rx_slots, range, item, &line, SlotRange::to_string)?;
                }
                Ok(())
            }
            Item::Direction => named(&mut self.direction, value, item, &line),
            Item::Application => named(&mut self.application, value, item, &line),
            Item::Restart => named(&mut self.restart, value, item, &line),
        }
    }

    /// The declaration as `name=value` lines, in a fixed order.
    fn lines(&self) -> Vec<String> {
        let mut lines = Vec::new();
        let mut line = |item: Item, value: Option<String>| {
            if let Some(value) = value {
                lines.push(format!("{}={value}", item.name()));
            }
        };
        line(
            Item::Formats,
            self.formats.as_deref().map(|f| joined(f, format_name)),
        );
        line(
            Item::Queues,
            self.queues.as_deref().map(|q| joined(q, queue_name)),
        );
        line(
            Item::TransactionNumbers,
            self.transaction_numbers.as_ref().map(yes_no_name),
        );
        line(Item::TimeStamps, self.time_stamps.as_ref().map(yes_no_name));
        match (self.tx_slots, self.rx_slots) {
            (Some(tx), Some(rx)) if tx == rx => line(Item::Slots, Some(tx.to_string())),
            (tx, rx) => {
                line(Item::TxSlots, tx.map(|s| s.to_string()));
                line(Item::RxSlots, rx.map(|s| s.to_string()));
            }
        }
        line(Item::Direction, self.direction.map(|d| d.name().into()));
        line(Item::Application, self.application.map(|a| a.name().into()));
        line(Item::Restart, self.restart.map(|c| c.name().into()));
        line(Item::TellsSent, self.tells_sent.as_ref().map(yes_no_name));
        lines
    }
}

#[cfg(test)]
mod tests;
