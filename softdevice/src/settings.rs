//! What the device is set up as, and what it refuses (000/001 §2, §3, §5.1.2; 003).

use crate::Fault;

/// The message format chosen in TwinCAT.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    Std11,
    Ext29,
    Fd,
}

/// Rx path.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Queue {
    Buffered,
    Optimized,
    Fast,
}

/// What this device (firmware) offers.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Offer {
    pub std11: bool,
    pub ext29: bool,
    pub fd: bool,
    pub fast: bool,
    pub optimized: bool,
    pub transaction_number: bool,
    pub transaction_number_29bit_only: bool,
    pub time_stamp: bool,
    pub filters: bool,
    pub info_data: bool,
    pub distributed_clocks: bool,
    pub max_slots: u8,
}

/// One row of the filter table: `accept` or reject identifiers in `[low, high]`
/// or those equal to `code` in the bits of `mask`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FilterRule {
    Range { accept: bool, low: u32, high: u32 },
    Mask { accept: bool, code: u32, mask: u32 },
}

impl FilterRule {
    fn hit(&self, id: u32, end_excluded: bool) -> Option<bool> {
        match *self {
            FilterRule::Range { accept, low, high } => {
                ((low..=high).contains(&id) && !(end_excluded && id == high)).then_some(accept)
            }
            FilterRule::Mask { accept, code, mask } => ((id ^ code) & mask == 0).then_some(accept),
        }
    }

    fn accepts(&self) -> bool {
        matches!(
            self,
            FilterRule::Range { accept: true, .. } | FilterRule::Mask { accept: true, .. }
        )
    }
}

pub(crate) fn filter_passes(rules: &[FilterRule], id: u32, has: impl Fn(Fault) -> bool) -> bool {
    let hit = |r: &FilterRule| r.hit(id, has(Fault::FilterRangeEndExcluded));
    let verdict = match has(Fault::FilterLastMatchWins) {
        true => rules.iter().rev().find_map(hit),
        false => rules.iter().find_map(hit),
    };
    verdict.unwrap_or_else(|| {
        has(Fault::FilterUnmatchedAccepted) || !rules.iter().any(FilterRule::accepts)
    })
}

#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Settings {
    pub offer: Offer,
    pub format: Format,
    pub queue: Queue,
    pub transaction_number: bool,
    pub time_stamp: bool,
    pub tx_slots: u8,
    pub rx_slots: u8,
    pub filters: Vec<FilterRule>,
    /// Distributed Clocks: SYNC1 comes this long after SYNC0 (the cycle start).
    pub dc_sync1_shift: Option<u64>,
    pub rx_fifo_depth: usize,
    pub tx_fifo_depth: usize,
    /// The bit timing words reported in InfoData\[1\] and \[2\].
    pub nominal_timing: u32,
    pub data_timing: u32,
}

/// A setting the device does not accept.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SettingsError(pub String);

impl std::fmt::Display for SettingsError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for SettingsError {}

impl Settings {
    /// Refuses what the device does not offer; `faults` (the self-check's)
    /// let through what one of them accepts by mistake.
    pub(crate) fn check(&self, faults: &[Fault]) -> Result<(), SettingsError> {
        let refuse = |why: &str| Err(SettingsError(why.to_string()));
        let lenient = |fault: Fault| faults.contains(&fault);
        let o = &self.offer;
        let format_ok = match self.format {
            Format::Std11 => o.std11,
            Format::Ext29 => o.ext29,
            Format::Fd => o.fd,
        };
        if !format_ok && !lenient(Fault::AcceptsEveryFormat) {
            return refuse("frame format not offered");
        }
        if self.queue != Queue::Buffered {
            let offered = if self.queue == Queue::Fast {
                o.fast
            } else {
                o.optimized
            };
            if !offered {
                return refuse("queue mode not offered");
            }
            if (self.format != Format::Std11 && !lenient(Fault::QueueTakes29Bit))
                || (self.transaction_number && !lenient(Fault::QueueTakesTransactionNumber))
                || (!self.filters.is_empty() && !lenient(Fault::QueueTakesFilters))
            {
                return refuse(
                    "fast/optimized queue: 11-bit only, no transaction number, no filters",
                );
            }
        }
        if !self.filters.is_empty() && !o.filters {
            return refuse("no filters on this device");
        }
        for rule in &self.filters {
            let bad = match *rule {
                FilterRule::Range { low, high, .. } => low > high || high > 0x1FFF_FFFF,
                FilterRule::Mask { code, mask, .. } => (code | mask) > 0x1FFF_FFFF,
            };
            if bad && !lenient(Fault::AcceptsMalformedFilter) {
                return refuse("malformed filter row");
            }
        }
        if self.transaction_number
            && ((!o.transaction_number && !lenient(Fault::TransactionNumberNotOffered))
                || (o.transaction_number_29bit_only
                    && self.format == Format::Std11
                    && !lenient(Fault::TransactionNumberOn11Bit)))
        {
            return refuse("transaction number not offered here");
        }
        if self.time_stamp
            && (!o.time_stamp
                || (self.format == Format::Std11 && !lenient(Fault::TimeStampOn11Bit))
                || !self.transaction_number)
        {
            return refuse("time stamp needs 29-bit mode with transaction number");
        }
        if self.format == Format::Fd
            && !(self.transaction_number && self.time_stamp)
            && !lenient(Fault::FdWithoutTransactionNumber)
        {
            return refuse("FD structures carry transaction number and time stamp");
        }
        let most = match (
            lenient(Fault::SlotCountUnbounded),
            lenient(Fault::RefusesThirtyTwoSlots),
        ) {
            (true, _) => o.max_slots.saturating_add(1),
            (_, true) => o.max_slots.min(31),
            _ => o.max_slots,
        };
        if !(1..=most).contains(&self.tx_slots) || !(1..=most).contains(&self.rx_slots) {
            return refuse("slot count out of range");
        }
        if self.dc_sync1_shift.is_some() && (!o.distributed_clocks || self.queue != Queue::Fast) {
            return refuse("distributed clocks only with the fast queue");
        }
        Ok(())
    }
}
