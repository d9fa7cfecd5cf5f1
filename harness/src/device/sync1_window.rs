//! Where the first Tx message of a batch held for SYNC1 may start: 003
//! "Synchronization with SYNC0/SYNC1" and ruling R10. The start lies in
//! [SYNC1 + delay, SYNC1 + delay + jitter]; the delay is the device's declared
//! one, or one no document gives, measured: then every start the controller
//! was free for lies within the jitter of every other. The jitter is 003's
//! 500 ns, or less where the device declares less.

use canif_model::exchange::SYNC1_TX_JITTER;
use canif_model::Nanos;

use crate::device::blame;
use crate::device::diff::Difference;

/// One scenario's window around SYNC1.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Sync1Window {
    /// The declared output delay; `None`: measured.
    pub delay: Option<Nanos>,
    pub jitter: Nanos,
    /// The earliest and latest delay measured so far (undeclared).
    band: Option<(Nanos, Nanos)>,
}

impl Default for Sync1Window {
    fn default() -> Self {
        Sync1Window {
            delay: None,
            jitter: SYNC1_TX_JITTER,
            band: None,
        }
    }
}

/// What to do with the model's held batch at this moment.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Held {
    /// Keep holding it: the IUT may still start within the window.
    Wait,
    /// Hand it to the controller; `exact`: the IUT started where the delay
    /// alone says, nothing was tolerated.
    Release { exact: bool },
}

/// The moment of a decision: `now` against the batch's SYNC1 `due`.
#[derive(Debug, Clone, Copy)]
pub struct Moment {
    pub now: Nanos,
    pub due: Nanos,
    /// Whether the IUT has handed its first frame to the controller.
    pub sent: bool,
    /// Whether the IUT's own due time says it still holds the batch.
    pub iut_holds: bool,
    /// Whether the IUT's controller was idle at SYNC1 (a busy one starts
    /// later, which says nothing of the delay).
    pub controller_was_free: bool,
}

impl Sync1Window {
    pub fn new(delay: Option<Nanos>, jitter: Option<Nanos>) -> Self {
        Sync1Window {
            delay,
            jitter: jitter.unwrap_or(SYNC1_TX_JITTER),
            band: None,
        }
    }

    /// The output delay judged by: declared, or the earliest measured.
    pub fn output_delay(&self) -> Option<Nanos> {
        self.delay.or(self.band.map(|(lo, _)| lo))
    }

    /// The latest a batch due at `due` may start.
    pub fn deadline(&self, due: Nanos) -> Nanos {
        due + self.delay.unwrap_or(0) + self.jitter
    }

    /// Whether the model releases its batch now; an error when the IUT's
    /// start breaks the one delay the batches before showed. A start too
    /// early or too late is blamed by the caller when the frames differ.
    pub fn decide(&mut self, m: Moment) -> Result<Held, Difference> {
        let (now, due, jitter) = (m.now, m.due, self.jitter);
        match (m.sent, self.delay) {
            (false, Some(_)) if now < self.deadline(due) => Ok(Held::Wait),
            (false, None) if now < due + jitter || m.iut_holds => Ok(Held::Wait),
            (false, _) => Ok(Held::Release { exact: true }),
            (true, _) if now < due => Ok(Held::Wait),
            (true, Some(delay)) if now < due + delay => Ok(Held::Wait),
            (true, Some(delay)) => Ok(Held::Release {
                exact: now == due + delay,
            }),
            (true, None) if !m.controller_was_free => Ok(Held::Release { exact: true }),
            (true, None) => {
                let offset = now - due;
                let (lo, hi) = self.band.map_or((offset, offset), |(lo, hi)| {
                    (lo.min(offset), hi.max(offset))
                });
                if hi - lo > jitter {
                    let (lo, hi) = self.band.unwrap_or((offset, offset));
                    return Err(Difference {
                        frames: None,
                        candidates: blame::SYNC1_LATE,
                        what: format!(
                            "output delay of the batch's first frame (one delay, {jitter} ns jitter: R10)"
                        ),
                        expected: format!(
                            "{}..={} ns after SYNC1, as the batches before",
                            hi.saturating_sub(jitter),
                            lo + jitter
                        ),
                        actual: format!("{offset} ns after SYNC1"),
                    });
                }
                self.band = Some((lo, hi));
                Ok(Held::Release { exact: hi == lo })
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn started(window: &mut Sync1Window, due: Nanos, after: Nanos) -> Result<Held, Difference> {
        window.decide(Moment {
            now: due + after,
            due,
            sent: true,
            iut_holds: false,
            controller_was_free: true,
        })
    }

    #[test]
    fn an_undeclared_delay_is_measured_and_every_start_lies_within_the_jitter_of_the_others() {
        let mut window = Sync1Window::default();
        assert_eq!(
            started(&mut window, 1_000, 2_000),
            Ok(Held::Release { exact: true })
        );
        assert_eq!(
            started(&mut window, 2_000, 2_400),
            Ok(Held::Release { exact: false })
        );
        assert_eq!(window.output_delay(), Some(2_000));
        let wide = started(&mut window, 3_000, 1_800).unwrap_err();
        assert_eq!(wide.candidates, blame::SYNC1_LATE);
        assert!(wide.expected.contains("1900..=2500"), "{}", wide.expected);
    }

    #[test]
    fn a_declared_jitter_narrows_the_window_and_a_declared_delay_is_waited_for() {
        let mut window = Sync1Window::new(None, Some(100));
        assert!(started(&mut window, 1_000, 0).is_ok());
        assert!(started(&mut window, 2_000, 150).is_err());
        let mut window = Sync1Window::new(Some(10_000), Some(100));
        assert_eq!(window.deadline(1_000), 11_100);
        assert_eq!(started(&mut window, 1_000, 5_000), Ok(Held::Wait));
        assert_eq!(
            started(&mut window, 1_000, 10_000),
            Ok(Held::Release { exact: true })
        );
        let silent = Moment {
            now: 11_000,
            due: 1_000,
            sent: false,
            iut_holds: false,
            controller_was_free: true,
        };
        assert_eq!(window.decide(silent), Ok(Held::Wait));
        let late = Moment {
            now: 11_100,
            ..silent
        };
        assert_eq!(window.decide(late), Ok(Held::Release { exact: true }));
    }
}
