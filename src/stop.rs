//! Why a command ends without doing its job: the one error every command
//! returns, said once by `main` with exit status 2 (ripgrep's shape: `main →
//! run → Result<ExitCode, Stop>`). A verdict is never a `Stop`: a run that
//! judged ends with its own exit status, however it judged.

use std::fmt;

/// A command that could not do its job.
#[derive(Debug)]
pub(crate) enum Stop {
    /// The catalogue (embedded, or `--spec DIR`) does not load.
    Catalogue(canif_spec::SpecErrors),
    /// Arguments clap itself refuses together (it prints them its own way).
    Arguments(clap::Error),
    /// What was asked cannot be done: the words name the argument, the
    /// file or the resource and the cause.
    Said(String),
}

/// A [`Stop::Said`] from `format!` arguments.
macro_rules! stop {
    ($($arg:tt)*) => {
        $crate::stop::Stop::Said(format!($($arg)*))
    };
}
pub(crate) use stop;

impl fmt::Display for Stop {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Stop::Catalogue(errors) => write!(f, "{errors}"),
            Stop::Arguments(error) => write!(f, "{error}"),
            Stop::Said(words) => f.write_str(words),
        }
    }
}

impl From<canif_spec::SpecErrors> for Stop {
    fn from(errors: canif_spec::SpecErrors) -> Self {
        Stop::Catalogue(errors)
    }
}

impl From<clap::Error> for Stop {
    fn from(error: clap::Error) -> Self {
        Stop::Arguments(error)
    }
}

impl Stop {
    /// Says it on stderr: clap's errors as clap prints them, the rest as one line each.
    pub(crate) fn say(&self) {
        match self {
            Stop::Arguments(error) => {
                let _ = error.print();
            }
            other => errln!("{other}"),
        }
    }
}

impl From<canif_runner::PlanError> for Stop {
    fn from(error: canif_runner::PlanError) -> Self {
        Stop::Said(error.to_string())
    }
}
