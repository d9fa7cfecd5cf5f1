//! `canif spec …`: the catalogue, read.

use std::path::PathBuf;

use clap::Subcommand;

#[derive(Subcommand)]
pub(crate) enum SpecCommand {
    /// Every requirement, one line each.
    List {
        /// Only ids starting with this prefix (e.g. HS-TX).
        #[arg(long)]
        area: Option<String>,
    },
    /// One requirement in full.
    Show { id: String },
    /// Counts by area and status, and the assumptions.
    Summary,
    /// Validates the catalogue (the embedded one, or --spec DIR).
    Check,
    /// The test specification: every requirement with its source, rulings,
    /// profiles, the cases that check it and the faults that fail it; every
    /// case with its steps; a traceability matrix. Markdown and HTML.
    Plan {
        /// Where to write test-plan.md and test-plan.html.
        #[arg(long, default_value = "reports/plan")]
        out: PathBuf,
    },
    /// Which tests name which requirement; exit 1 if a normative or derived one has none.
    Coverage {
        /// The workspace whose tests to read.
        #[arg(long, default_value = ".")]
        root: PathBuf,
        /// List every requirement with the tests, properties and scenarios that cover it.
        #[arg(long)]
        each: bool,
    },
}
