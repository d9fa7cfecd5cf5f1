//! The fixed image headers as values: what the PLC and the device say to each
//! other in every cycle, apart from the messages.
//!
//! Source: 003 (0x700z:01..03, 0x600z:01..04), 000 §6.

use super::{InputImage, OutputImage};

/// `Outputs.TxCounter`, `Outputs.RxCounter`, `Outputs.NoOfTxMessages`.
///
/// Requirements: LAY-GEN-002.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct OutputHeader {
    pub tx_counter: u16,
    pub rx_counter: u16,
    pub no_of_tx_messages: u16,
}

impl OutputHeader {
    pub fn parse<T: AsRef<[u8]>>(image: &OutputImage<T>) -> Self {
        OutputHeader {
            tx_counter: image.tx_counter(),
            rx_counter: image.rx_counter(),
            no_of_tx_messages: image.no_of_tx_messages(),
        }
    }

    pub fn emit<T: AsRef<[u8]> + AsMut<[u8]>>(&self, image: &mut OutputImage<T>) {
        image.set_tx_counter(self.tx_counter);
        image.set_rx_counter(self.rx_counter);
        image.set_no_of_tx_messages(self.no_of_tx_messages);
    }
}

/// `Inputs.TxCounter`, `Inputs.RxCounter`, `Inputs.NoOfRxMessages` and, where
/// the interface has one, `Inputs.TransactionNumber`.
///
/// Requirements: LAY-GEN-004, TN-002.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct InputHeader {
    pub tx_counter: u16,
    pub rx_counter: u16,
    pub no_of_rx_messages: u16,
    pub transaction_number: Option<u16>,
}

impl InputHeader {
    pub fn parse<T: AsRef<[u8]>>(image: &InputImage<T>) -> Self {
        InputHeader {
            tx_counter: image.tx_counter(),
            rx_counter: image.rx_counter(),
            no_of_rx_messages: image.no_of_rx_messages(),
            transaction_number: image.transaction_number(),
        }
    }

    /// Writes every field; the transaction number only where the layout has one.
    pub fn emit<T: AsRef<[u8]> + AsMut<[u8]>>(&self, image: &mut InputImage<T>) {
        image.set_tx_counter(self.tx_counter);
        image.set_rx_counter(self.rx_counter);
        image.set_no_of_rx_messages(self.no_of_rx_messages);
        if let Some(number) = self.transaction_number {
            image.set_transaction_number(number);
        }
    }
}

impl<T: AsRef<[u8]>> OutputImage<T> {
    /// The header as a value.
    pub fn header(&self) -> OutputHeader {
        OutputHeader::parse(self)
    }
}

impl<T: AsRef<[u8]>> InputImage<T> {
    /// The header as a value.
    pub fn header(&self) -> InputHeader {
        InputHeader::parse(self)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::{FrameFormat, InterfaceConfig};
    use crate::image::ImageLayout;

    static OUTPUTS_11BIT_1_SLOT: [u8; 16] = [
        0x34, 0x12, // TxCounter
        0x02, 0x00, // RxCounter
        0x01, 0x00, // NoOfTxMessages
        0, 0, 0, 0, 0, 0, 0, 0, 0, 0,
    ];

    #[test]
    fn output_header_round_trips_through_the_image() {
        let layout = ImageLayout::new(&InterfaceConfig::new(FrameFormat::Base11, 1), false);
        let image = OutputImage::new_checked(&OUTPUTS_11BIT_1_SLOT[..], layout).unwrap();
        let header = image.header();
        assert_eq!(
            header,
            OutputHeader {
                tx_counter: 0x1234,
                rx_counter: 2,
                no_of_tx_messages: 1
            }
        );
        let mut bytes = [0u8; 16];
        header.emit(&mut OutputImage::new_checked(&mut bytes[..], layout).unwrap());
        assert_eq!(bytes, OUTPUTS_11BIT_1_SLOT);
    }

    #[test]
    fn input_header_has_a_transaction_number_only_where_the_layout_does() {
        let mut config = InterfaceConfig::new(FrameFormat::Extended29, 1);
        let plain = ImageLayout::new(&config, false);
        config.transaction_number = true;
        let numbered = ImageLayout::new(&config, false);
        let mut bytes = vec![0u8; numbered.input_size()];
        bytes[..8].copy_from_slice(&[1, 0, 2, 0, 1, 0, 0x0A, 0x00]);
        let header = InputImage::new_checked(&bytes[..], numbered)
            .unwrap()
            .header();
        assert_eq!(header.transaction_number, Some(10));
        assert_eq!(
            (
                header.tx_counter,
                header.rx_counter,
                header.no_of_rx_messages
            ),
            (1, 2, 1)
        );
        let bytes = vec![0u8; plain.input_size()];
        let header = InputImage::new_checked(&bytes[..], plain).unwrap().header();
        assert_eq!(header.transaction_number, None);
    }
}
