//! The command-line tool's error type: every failure is one line naming
//! what failed (a file, a directory) and what was expected.

use std::path::PathBuf;

use brdf_atlas_analytic::AnalyticError;
use brdf_atlas_core::CoreError;
use brdf_merl::MerlError;

/// Everything a command can fail with.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// Reading, validating or writing a MERL file failed.
    #[error(transparent)]
    Merl(#[from] MerlError),
    /// Building, fitting, opening or querying a model failed.
    #[error(transparent)]
    Core(#[from] CoreError),
    /// Input the command cannot use: the message names the file or option
    /// and what was expected.
    #[error("{0}")]
    Input(String),
    /// Reading an input file other than a MERL table failed.
    #[error("{}: {source}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// What the OS said.
        source: std::io::Error,
    },
    /// A path given as a MERL file is a directory.
    #[error("{}: is a directory, expected a MERL .binary file", path.display())]
    IsDirectory {
        /// The directory.
        path: PathBuf,
    },
    /// Writing an output file (or directory), or putting it in place,
    /// failed. Output failures are this, never [`Error::Input`].
    #[error("{}: {source}", path.display())]
    Write {
        /// The file.
        path: PathBuf,
        /// What the OS said.
        source: std::io::Error,
    },
    /// Creating an output directory failed.
    #[error("{}: cannot create directory: {source}", path.display())]
    CreateDir {
        /// The directory.
        path: PathBuf,
        /// What the OS said.
        source: std::io::Error,
    },
    /// Writing the report to stdout failed.
    #[error("cannot write to stdout: {0}")]
    Stdout(#[from] std::io::Error),
}

impl From<(PathBuf, std::io::Error)> for Error {
    fn from((path, source): (PathBuf, std::io::Error)) -> Self {
        Error::Write { path, source }
    }
}

impl From<AnalyticError> for Error {
    /// A file the export could not write is [`Error::Write`]; anything
    /// else the analytic crate refuses is input the command cannot use.
    fn from(e: AnalyticError) -> Self {
        match e {
            AnalyticError::Write { path, source } => Error::Write { path, source },
            e => Error::Input(e.to_string()),
        }
    }
}

impl Error {
    /// True when stdout was closed by its reader (`brdf-atlas info ... | head`),
    /// which is not worth a message.
    pub fn is_broken_pipe(&self) -> bool {
        matches!(self, Error::Stdout(e) if e.kind() == std::io::ErrorKind::BrokenPipe)
    }
}
