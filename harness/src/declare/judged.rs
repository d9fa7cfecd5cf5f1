//! The choices a run's verdicts rest on, as its report lists them: declared
//! (on the command line, by the implementation) or shown by a scenario.

use serde::{Deserialize, Serialize};

/// One choice the run judged the device by.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct ChoiceEntry {
    /// `NAME=VALUE`, as `--declare` takes it.
    pub choice: String,
    /// How canif knows it.
    pub how: ChoiceSource,
}

/// Where a choice came from.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ChoiceSource {
    /// The device (or the command line for it) declared it, for every profile.
    Declared,
    /// The IUT declared it itself, in its `configured` answer.
    DeclaredByIut,
    /// Undeclared: on this profile, this scenario passed only under it (or
    /// passed under it, being the first to tell the choices apart).
    Observed { profile: String, scenario: String },
}

impl std::fmt::Display for ChoiceEntry {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match &self.how {
            ChoiceSource::Declared => write!(f, "{} (declared)", self.choice),
            ChoiceSource::DeclaredByIut => write!(f, "{} (declared by the IUT)", self.choice),
            ChoiceSource::Observed { profile, scenario } => write!(
                f,
                "{} on {profile} (undeclared; shown by `{scenario}`)",
                self.choice
            ),
        }
    }
}

impl ChoiceEntry {
    /// Every choice `declaration` makes, each as declared: what either
    /// side's report says its verdicts rest on.
    pub fn declared(declaration: &impl super::Declaration) -> Vec<ChoiceEntry> {
        declaration
            .lines()
            .into_iter()
            .map(|choice| ChoiceEntry {
                choice,
                how: ChoiceSource::Declared,
            })
            .collect()
    }
}
