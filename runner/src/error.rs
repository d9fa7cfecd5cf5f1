//! Why a run cannot start: each refusal names the flag, file or profile
//! and the cause, in words the command line shows as they are.

use std::fmt;
use std::path::PathBuf;

use canif_spec::Side;

/// A plan that cannot be run.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum PlanError {
    /// The feature files (features/*.feature) do not parse.
    FeatureFiles(String),
    /// `--requirement ID` names no requirement of the catalogue.
    UnknownRequirement { id: String, near: Option<String> },
    /// `--requirement ID` binds the other side: where it is judged, and
    /// this side's own statements related to it.
    OtherSide {
        id: String,
        binds: Side,
        this: Side,
        own: Vec<String>,
    },
    /// The selection matches no check on these profiles.
    NothingSelected {
        flags: String,
        profiles: Vec<String>,
    },
    /// What is under test cannot be run on these profiles or this bus.
    Preflight(String),
    /// `--rerun-failed`: the report cannot be read, or is another run's.
    Rerun(RerunError),
}

impl fmt::Display for PlanError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            PlanError::FeatureFiles(error) => write!(f, "the feature files do not parse: {error}"),
            PlanError::UnknownRequirement { id, near } => {
                write!(f, "--requirement {id}: no such requirement")?;
                if let Some(near) = near {
                    write!(f, " (did you mean `{near}`?)")?;
                }
                write!(f, "; `canif spec list` lists them")
            }
            PlanError::OtherSide {
                id,
                binds,
                this,
                own,
            } => {
                write!(
                    f,
                    "--requirement {id} binds the {binds} side, not the {this} side: `canif run {binds} --requirement {id}` judges it"
                )?;
                if !own.is_empty() {
                    write!(f, "; this side's own statement: {}", own.join(", "))?;
                }
                Ok(())
            }
            PlanError::NothingSelected { flags, profiles } => write!(
                f,
                "{flags} matches no check on {}; `canif list scenarios` lists them",
                profiles.join(", ")
            ),
            PlanError::Preflight(words) => f.write_str(words),
            PlanError::Rerun(error) => write!(f, "{error}"),
        }
    }
}

impl std::error::Error for PlanError {}

impl PlanError {
    /// What is under test cannot start at all (its command is not found,
    /// its library is no file, it never answered within the start limit):
    /// no run of it could judge anything.
    pub fn not_started(error: canif_harness::IutError) -> Self {
        PlanError::Preflight(format!("canif: {}", error.what))
    }
}

impl From<RerunError> for PlanError {
    fn from(error: RerunError) -> Self {
        PlanError::Rerun(error)
    }
}

/// `--rerun-failed REPORT` that cannot be taken.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum RerunError {
    /// The report cannot be read or parsed.
    Unreadable { report: PathBuf, cause: String },
    /// It is a run of the other side.
    OtherSide {
        report: PathBuf,
        was: Side,
        this: Side,
    },
    /// It is a run of another implementation.
    OtherIut {
        report: PathBuf,
        was: String,
        this: String,
    },
}

impl fmt::Display for RerunError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            RerunError::Unreadable { report, cause } => {
                write!(f, "--rerun-failed {}: {cause}", report.display())
            }
            RerunError::OtherSide { report, was, this } => write!(
                f,
                "--rerun-failed {}: a {was} side run; this is the {this} side",
                report.display()
            ),
            RerunError::OtherIut { report, was, this } => write!(
                f,
                "--rerun-failed {}: that run was of `{was}`, this one of `{this}`",
                report.display()
            ),
        }
    }
}

impl std::error::Error for RerunError {}

/// The known name nearest `name`, where a typo is likely.
pub fn nearest<'a>(name: &str, known: impl IntoIterator<Item = &'a str>) -> Option<&'a str> {
    known
        .into_iter()
        .map(|k| {
            (
                strsim::jaro_winkler(&name.to_lowercase(), &k.to_lowercase()),
                k,
            )
        })
        .filter(|(likeness, _)| *likeness > 0.85)
        .max_by(|a, b| a.0.total_cmp(&b.0))
        .map(|(_, k)| k)
}
