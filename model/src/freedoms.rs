//! What the documents leave to the implementer, each as a choice a device
//! declares: the model takes the declared one, and by default the one the
//! reference device takes.
//!
//! Source: ruling G3 (NoOfTxMessages beyond the slots, a length field out of
//! range: implementation-defined within bounds), 000 §5.1.1 and HS-RX-008 (Rx
//! slots past NoOfRxMessages carry no meaning), HS-RX-009 (NoOfRxMessages once
//! the PLC has acknowledged and nothing new arrived).

/// A choice's values by name, as a device declares them
/// (`--declare NAME=VALUE`).
pub trait Named: Sized + Copy + 'static {
    /// Every value, the reference device's first.
    const ALL: &'static [Self];
    /// Their names, in the same order.
    const NAMES: &'static [&'static str];

    fn name(self) -> &'static str;

    fn from_name(name: &str) -> Option<Self> {
        Self::ALL.iter().copied().find(|v| v.name() == name)
    }
}

macro_rules! named {
    ($(#[$meta:meta])* $choice:ident { $($(#[$vmeta:meta])* $value:ident = $name:literal,)+ }) => {
        $(#[$meta])*
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
        pub enum $choice { $($(#[$vmeta])* $value,)+ }

        impl Named for $choice {
            const ALL: &'static [Self] = &[$($choice::$value,)+];
            const NAMES: &'static [&'static str] = &[$($name,)+];

            fn name(self) -> &'static str {
                match self { $($choice::$value => $name,)+ }
            }
        }
    };
}

named! {
    /// A batch whose NoOfTxMessages exceeds the Tx slots (G3, HS-TX-010).
    OversizeBatch {
        /// The reference device: it sends the slots it has.
        #[default]
        SendsTheSlots = "sends-the-slots",
        /// It acknowledges the batch and sends none of it.
        DropsTheBatch = "drops-the-batch",
    }
}

named! {
    /// A Tx message whose length field is out of range: classic above 8, FD
    /// above 64 (G3, LAY-GEN-008).
    BadTxLength {
        /// The reference device: the length is clamped to 8 or 64.
        #[default]
        Clamps = "clamps",
        /// The message is not sent; the rest of its batch is.
        DropsTheMessage = "drops-the-message",
    }
}

named! {
    /// Inputs.NoOfRxMessages in a cycle that enters nothing once the PLC has
    /// acknowledged (Buffered and Optimized modes; HS-RX-009).
    RxIdleCount {
        /// The reference device: the count of the last delivery stays.
        #[default]
        KeepsTheLast = "keeps-the-last",
        /// It writes 0.
        WritesZero = "writes-zero",
    }
}

named! {
    /// What a delivery leaves in the Rx slots past its NoOfRxMessages
    /// (Buffered and Optimized modes; HS-RX-008).
    StaleRxSlots {
        /// The reference device: zeros.
        #[default]
        Zeroed = "zeroed",
        /// What they held before.
        Kept = "kept",
    }
}

/// The device's choice for each freedom.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Freedoms {
    pub oversize_batch: OversizeBatch,
    pub bad_tx_length: BadTxLength,
    pub rx_idle_count: RxIdleCount,
    pub stale_rx_slots: StaleRxSlots,
}

impl OversizeBatch {
    /// How many messages of a batch asking for `asked` go out of `slots`.
    ///
    /// Requirements: HS-TX-010.
    pub fn sends(self, asked: usize, slots: usize) -> usize {
        match self {
            _ if asked <= slots => asked,
            OversizeBatch::SendsTheSlots => slots,
            OversizeBatch::DropsTheBatch => 0,
        }
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// Every value of `T` reads back by its name, and the reference comes first.
    pub(crate) fn round_trip<T: Named + PartialEq + Default + std::fmt::Debug>() {
        assert_eq!(T::ALL[0], T::default());
        for (v, name) in T::ALL.iter().zip(T::NAMES) {
            assert_eq!(v.name(), *name);
            assert_eq!(T::from_name(name), Some(*v));
        }
        assert_eq!(T::ALL.len(), T::NAMES.len());
        assert_eq!(T::from_name("no-such-value"), None);
    }

    #[test]
    fn every_value_reads_back_by_its_name_and_the_reference_comes_first() {
        round_trip::<OversizeBatch>();
        round_trip::<BadTxLength>();
        round_trip::<RxIdleCount>();
        round_trip::<StaleRxSlots>();
    }

    #[test]
    fn an_oversize_batch_sends_the_slots_or_nothing_and_a_fitting_one_everything() {
        assert_eq!(OversizeBatch::SendsTheSlots.sends(9, 8), 8);
        assert_eq!(OversizeBatch::DropsTheBatch.sends(9, 8), 0);
        for choice in OversizeBatch::ALL {
            assert_eq!(choice.sends(8, 8), 8);
            assert_eq!(choice.sends(0, 8), 0);
        }
    }
}
