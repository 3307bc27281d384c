//! The one error type of the MERL crate.

use std::path::PathBuf;

/// Everything that can go wrong reading or writing a MERL table.
///
/// Every variant names the file, and its message says what was expected,
/// so a command-line tool can print it as its one line of diagnosis.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum MerlError {
    /// The operating system refused to open, map, read or write the file.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// What the OS said.
        source: std::io::Error,
    },
    /// A material the NBRDF database does not have ([`crate::nbrdf`]).
    #[error(
        "{name:?} is not one of the 100 NBRDF materials (`brdf-atlas nbrdf --list` names them)"
    )]
    UnknownMaterial {
        /// The name asked for.
        name: String,
    },
    /// The file is a Git LFS pointer, not the table it stands for.
    #[error("{}: is a Git LFS pointer file, not MERL data (run `git lfs pull` to fetch the real table)", path.display())]
    LfsPointer {
        /// The file.
        path: PathBuf,
    },
    /// The file is something else: text, an image, an archive. Said first
    /// when a header's dims are absurd (or missing) and the first bytes
    /// look like that thing; what the header check found follows.
    #[error("{}: not a MERL file (it looks like {looks_like}); {detail}", path.display())]
    NotMerl {
        /// The file.
        path: PathBuf,
        /// What it looks like: "text", "a PNG image", ...
        looks_like: &'static str,
        /// What the header check found, without the path: "header says
        /// AxBxC, expected ...", "N bytes is too short ...".
        detail: String,
    },
    /// The file is too short to hold even the 12-byte header.
    #[error("{}: {len} bytes is too short for a MERL file (needs a 12-byte header of three int32 dims)", path.display())]
    TooShort {
        /// The file.
        path: PathBuf,
        /// Its length in bytes.
        len: u64,
    },
    /// The header's dimensions are zero, negative or absurdly large.
    #[error("{}: header says {a}x{b}x{c}, expected three positive dims of at most {max} (MERL uses 90x90x180)", path.display())]
    BadDims {
        /// The file.
        path: PathBuf,
        /// n_theta_h as read.
        a: i32,
        /// n_theta_d as read.
        b: i32,
        /// n_phi_d as read.
        c: i32,
        /// The largest dimension accepted.
        max: i32,
    },
    /// The file length disagrees with the dims in its header.
    #[error("{}: header says {dims} (needs {expected} bytes) but the file has {actual} bytes", path.display())]
    SizeMismatch {
        /// The file.
        path: PathBuf,
        /// The dims, formatted `AxBxC`.
        dims: String,
        /// 12 + 3 * 8 * bins.
        expected: u64,
        /// The real length.
        actual: u64,
    },
    /// A value is NaN or infinite.
    #[error("{}: value {index} ({channel} channel, bin {bin}) is {value}, expected a finite number", path.display())]
    NonFinite {
        /// The file.
        path: PathBuf,
        /// Flat index of the value (channel-major).
        index: usize,
        /// "red", "green" or "blue".
        channel: &'static str,
        /// Bin inside the channel block.
        bin: usize,
        /// The offending value.
        value: f64,
    },
    /// A value is finite but beyond any physical reflectance
    /// ([`crate::table::MAX_REFLECTANCE`]).
    #[error("{}: value {index} ({channel} channel, bin theta_h {} theta_d {} phi_d {}) is a reflectance of {reflectance:.3e} per steradian, beyond any physical one; expected at most 1e8 (or a negative value for an unmeasured bin)", path.display(), bin[0], bin[1], bin[2])]
    Absurd {
        /// The file.
        path: PathBuf,
        /// Flat index of the value (channel-major).
        index: usize,
        /// "red", "green" or "blue".
        channel: &'static str,
        /// The bin's (theta_h, theta_d, phi_d) indices.
        bin: [usize; 3],
        /// The value as a reflectance (1/sr).
        reflectance: f64,
    },
    /// The file was truncated or rewritten by another program while it was
    /// mapped: what was read from it cannot be trusted.
    #[error("{}: changed while being read (truncated or rewritten by another program); nothing read from it was used", path.display())]
    Changed {
        /// The file.
        path: PathBuf,
    },
    /// A table was built from a buffer whose length disagrees with its dims.
    #[error("{what}: {actual} values given, {dims} needs {expected}")]
    BufferLength {
        /// What was being built.
        what: String,
        /// The dims, formatted `AxBxC`.
        dims: String,
        /// 3 * bins.
        expected: usize,
        /// The buffer's length.
        actual: usize,
    },
    /// Dims given by a caller (not read from a file) are unusable.
    #[error("dims {a}x{b}x{c}: {why}")]
    InvalidDims {
        /// n_theta_h.
        a: usize,
        /// n_theta_d.
        b: usize,
        /// n_phi_d.
        c: usize,
        /// What is wrong.
        why: &'static str,
    },
}

impl MerlError {
    pub(crate) fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        MerlError::Io {
            path: path.into(),
            source,
        }
    }
}

/// Result with [`MerlError`].
pub type Result<T, E = MerlError> = std::result::Result<T, E>;
