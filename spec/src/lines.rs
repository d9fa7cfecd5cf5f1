//! Finding a catalogue entry's line in its YAML text, for errors that name
//! file and line.

/// The 1-based line of the first line containing `needle` at or after `from`.
pub(crate) fn line_of(text: &str, needle: &str, from: usize) -> Option<usize> {
    LineIndex::new(text).find(needle, from)
}

/// Where each line of a text starts, so that a search from line N starts at
/// its byte offset: looking up every requirement of a file stays linear.
pub(crate) struct LineIndex<'a> {
    text: &'a str,
    starts: Vec<usize>,
}

impl<'a> LineIndex<'a> {
    pub(crate) fn new(text: &'a str) -> Self {
        let starts = std::iter::once(0)
            .chain(text.match_indices('\n').map(|(at, _)| at + 1))
            .collect();
        LineIndex { text, starts }
    }

    /// The 1-based line of the first occurrence of `needle` at or after line `from`.
    pub(crate) fn find(&self, needle: &str, from: usize) -> Option<usize> {
        let start = *self.starts.get(from.saturating_sub(1))?;
        let at = start + self.text[start..].find(needle)?;
        Some(self.starts.partition_point(|&s| s <= at))
    }
}
