//! Advisories: what the documents allow but the author of a client wants to
//! know (issue 27) — batches of nothing (HS-TX-009 allows them, each costs a
//! handshake of latency), handshakes used per frame, the latency from the
//! application's request to its frame's end on the bus. Counted per run and
//! shown beside the verdicts, never changing one.

use serde::{Deserialize, Serialize};

/// One run's advisories (all zero where nothing was counted: the device side).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Advisories {
    /// Handshakes the client used: new values of Outputs.TxCounter.
    pub batches: u64,
    /// Of those, batches of nothing (NoOfTxMessages = 0).
    pub empty_batches: u64,
    /// Frames of the application's requests that reached the bus.
    pub frames_sent: u64,
    /// From a request to the end of its frame on the bus: the longest, ns.
    pub latency_max_ns: u64,
    /// The sum over `frames_sent`, ns (the mean is the sum over the count).
    pub latency_sum_ns: u64,
}

impl Advisories {
    pub fn is_empty(&self) -> bool {
        *self == Advisories::default()
    }

    /// Both runs' counts together.
    pub fn add(&mut self, other: &Advisories) {
        self.batches += other.batches;
        self.empty_batches += other.empty_batches;
        self.frames_sent += other.frames_sent;
        self.latency_max_ns = self.latency_max_ns.max(other.latency_max_ns);
        self.latency_sum_ns += other.latency_sum_ns;
    }

    /// A frame requested at `requested` ended on the bus at `end`.
    pub fn frame_sent(&mut self, requested: u64, end: u64) {
        let latency = end.saturating_sub(requested);
        self.frames_sent += 1;
        self.latency_max_ns = self.latency_max_ns.max(latency);
        self.latency_sum_ns += latency;
    }

    /// The counts in one line, for the summary and the HTML.
    pub fn line(&self) -> String {
        let per_frame = match self.frames_sent {
            0 => "no frame sent".to_string(),
            n => format!("{:.2} handshakes per frame", self.batches as f64 / n as f64),
        };
        let mean = self.latency_sum_ns / self.frames_sent.max(1);
        format!(
            "{} batches ({} of nothing), {per_frame}, request to bus {:.0} µs mean, {:.0} µs at most",
            self.batches,
            self.empty_batches,
            mean as f64 / 1e3,
            self.latency_max_ns as f64 / 1e3
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_add_up_and_the_line_says_them() {
        let mut a = Advisories {
            batches: 4,
            empty_batches: 1,
            ..Advisories::default()
        };
        a.frame_sent(1_000, 301_000);
        a.frame_sent(2_000, 102_000);
        let mut total = Advisories::default();
        total.add(&a);
        total.add(&a);
        assert_eq!(
            (total.batches, total.empty_batches, total.frames_sent),
            (8, 2, 4)
        );
        assert_eq!(total.latency_max_ns, 300_000);
        assert_eq!(
            total.line(),
            "8 batches (2 of nothing), 2.00 handshakes per frame, request to bus 200 µs mean, 300 µs at most"
        );
        assert!(Advisories::default().is_empty());
    }
}
