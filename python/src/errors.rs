//! Every failure of the library as a Python exception of
//! `brdf_atlas.errors`, carrying the one-line message the command-line tool
//! prints (the file, then what was expected).

use brdf_atlas_core::CoreError;
use brdf_merl::MerlError;
use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;

/// Which class of `brdf_atlas.errors` a failure raises.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// An argument the library cannot use (`InputError`, a `ValueError`).
    Input,
    /// The operating system refused a file operation (`FileError`, an `OSError`).
    File,
    /// A file that is not what was expected (`FormatError`, a `ValueError`).
    Format,
    /// A numerical failure (`NumericalError`, an `ArithmeticError`).
    Numerical,
    /// Anything else (`Error`).
    Other,
}

impl Kind {
    fn class(self) -> &'static str {
        match self {
            Kind::Input => "InputError",
            Kind::File => "FileError",
            Kind::Format => "FormatError",
            Kind::Numerical => "NumericalError",
            Kind::Other => "Error",
        }
    }
}

/// A failure on its way to Python: its class and its message.
#[derive(Debug)]
pub struct Failure {
    /// The exception class.
    pub kind: Kind,
    /// The one-line message.
    pub message: String,
}

/// Result with [`Failure`].
pub type Result<T, E = Failure> = std::result::Result<T, E>;

impl Failure {
    /// An argument that cannot be used: `message` says which and what was expected.
    pub fn input(message: impl Into<String>) -> Failure {
        Failure {
            kind: Kind::Input,
            message: message.into(),
        }
    }
}

fn merl_kind(e: &MerlError) -> Kind {
    match e {
        MerlError::Io { .. } => Kind::File,
        MerlError::BufferLength { .. } | MerlError::InvalidDims { .. } => Kind::Input,
        _ => Kind::Format,
    }
}

impl From<MerlError> for Failure {
    fn from(e: MerlError) -> Failure {
        Failure {
            kind: merl_kind(&e),
            message: e.to_string(),
        }
    }
}

impl From<CoreError> for Failure {
    fn from(e: CoreError) -> Failure {
        let kind = match &e {
            CoreError::Merl(m) => merl_kind(m),
            CoreError::Io { .. } | CoreError::Write { .. } => Kind::File,
            CoreError::EmptyDataset { .. }
            | CoreError::DimsDiffer { .. }
            | CoreError::BadFile { .. } => Kind::Format,
            CoreError::InvalidParams(_) | CoreError::BadQuery(_) => Kind::Input,
            CoreError::NotPositiveDefinite { .. } | CoreError::Eigen(_) => Kind::Numerical,
            _ => Kind::Other,
        };
        Failure {
            kind,
            message: e.to_string(),
        }
    }
}

impl From<Failure> for PyErr {
    fn from(f: Failure) -> PyErr {
        Python::attach(|py| {
            let raised = py
                .import("brdf_atlas.errors")
                .and_then(|m| m.getattr(f.kind.class()))
                .and_then(|class| class.call1((f.message.as_str(),)));
            match raised {
                Ok(exception) => PyErr::from_value(exception),
                // The package is broken (errors.py missing): still say what failed.
                Err(_) => PyRuntimeError::new_err(f.message),
            }
        })
    }
}
