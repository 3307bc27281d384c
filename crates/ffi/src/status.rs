//! Statuses, the thread's last error message, and the guard every entry
//! point runs its body in.

use std::cell::RefCell;
use std::ffi::{CString, c_char, c_int};
use std::panic::{AssertUnwindSafe, catch_unwind};

use brdf_atlas_analytic::AnalyticError;
use brdf_atlas_core::CoreError;
use brdf_merl::MerlError;

/// What a call did. Every fallible function returns one; the numbers are
/// fixed and will not change. `brdf_atlas_status_message` names a status,
/// `brdf_atlas_last_error_message` gives the full message of the last failed
/// call on this thread.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BrdfAtlasStatus {
    /// Success; outputs are written.
    Ok = 0,
    /// A required pointer argument (handle, buffer, out-parameter, path) is NULL.
    NullArgument = 1,
    /// An argument has an unusable value: a NaN or infinite coordinate, an
    /// index out of range, an empty or non-finite view window, a zero map
    /// size, a path that is not UTF-8, a misaligned buffer, a MERL file whose
    /// dims differ from the model's.
    InvalidArgument = 2,
    /// A caller buffer is shorter than the output; nothing was written. The
    /// matching size query says how much is needed.
    BufferTooSmall = 3,
    /// The model cannot answer this query: a 2-D call (x, y) or a map on a
    /// model whose latent space is not 2-D.
    Unsupported = 4,
    /// The operating system refused a file operation (missing file,
    /// permission, disk full).
    Io = 5,
    /// A model or store file is malformed, of another version, or changed
    /// since the fit; or a store or MERL file changed on disk while the
    /// library had it open (the handle then refuses every call until
    /// reopened).
    BadFile = 6,
    /// A MERL file is malformed (header, size, non-finite values).
    BadMerl = 7,
    /// The model's kernel matrix is not positive definite.
    NotPositiveDefinite = 8,
    /// A bug in brdf-atlas was caught before it could reach the caller (a
    /// Rust panic). The handle is still usable; please report the message.
    Panic = 9,
    /// Another failure; the message says what.
    Other = 10,
    /// The caller cancelled the call through its cancel flag; nothing was
    /// written.
    Cancelled = 11,
}

/// Every status, in number order.
const ALL: [BrdfAtlasStatus; 12] = [
    BrdfAtlasStatus::Ok,
    BrdfAtlasStatus::NullArgument,
    BrdfAtlasStatus::InvalidArgument,
    BrdfAtlasStatus::BufferTooSmall,
    BrdfAtlasStatus::Unsupported,
    BrdfAtlasStatus::Io,
    BrdfAtlasStatus::BadFile,
    BrdfAtlasStatus::BadMerl,
    BrdfAtlasStatus::NotPositiveDefinite,
    BrdfAtlasStatus::Panic,
    BrdfAtlasStatus::Other,
    BrdfAtlasStatus::Cancelled,
];

impl BrdfAtlasStatus {
    /// The status with this number, if any.
    pub fn from_number(n: c_int) -> Option<BrdfAtlasStatus> {
        usize::try_from(n).ok().and_then(|i| ALL.get(i).copied())
    }

    /// A short static description, NUL-terminated.
    pub fn message(self) -> &'static std::ffi::CStr {
        match self {
            BrdfAtlasStatus::Ok => c"ok",
            BrdfAtlasStatus::NullArgument => c"a required pointer argument is NULL",
            BrdfAtlasStatus::InvalidArgument => c"invalid argument",
            BrdfAtlasStatus::BufferTooSmall => c"buffer too small",
            BrdfAtlasStatus::Unsupported => c"the model cannot answer this query",
            BrdfAtlasStatus::Io => c"file operation failed",
            BrdfAtlasStatus::BadFile => c"malformed or changed model file",
            BrdfAtlasStatus::BadMerl => c"malformed MERL file",
            BrdfAtlasStatus::NotPositiveDefinite => c"kernel matrix not positive definite",
            BrdfAtlasStatus::Panic => c"internal error (a bug in brdf-atlas)",
            BrdfAtlasStatus::Other => c"error",
            BrdfAtlasStatus::Cancelled => c"cancelled by the caller",
        }
    }
}

/// A failed call: its status and its one-line message.
#[derive(Debug)]
pub(crate) struct Failure {
    pub status: BrdfAtlasStatus,
    pub message: String,
}

impl Failure {
    pub fn new(status: BrdfAtlasStatus, message: impl Into<String>) -> Failure {
        Failure {
            status,
            message: message.into(),
        }
    }

    pub fn invalid(message: impl Into<String>) -> Failure {
        Failure::new(BrdfAtlasStatus::InvalidArgument, message)
    }
}

impl From<MerlError> for Failure {
    fn from(e: MerlError) -> Failure {
        let status = match e {
            MerlError::Io { .. } => BrdfAtlasStatus::Io,
            MerlError::Changed { .. } => BrdfAtlasStatus::BadFile,
            MerlError::BufferLength { .. } | MerlError::InvalidDims { .. } => {
                BrdfAtlasStatus::InvalidArgument
            }
            _ => BrdfAtlasStatus::BadMerl,
        };
        Failure::new(status, e.to_string())
    }
}

impl From<AnalyticError> for Failure {
    fn from(e: AnalyticError) -> Failure {
        let status = match e {
            AnalyticError::NotADirectory { .. } | AnalyticError::Write { .. } => {
                BrdfAtlasStatus::Io
            }
            _ => BrdfAtlasStatus::InvalidArgument,
        };
        Failure::new(status, e.to_string())
    }
}

impl From<CoreError> for Failure {
    fn from(e: CoreError) -> Failure {
        let status = match e {
            CoreError::Merl(e) => return e.into(),
            CoreError::Io { .. } | CoreError::Write { .. } => BrdfAtlasStatus::Io,
            CoreError::BadFile { .. } | CoreError::FileChanged { .. } => BrdfAtlasStatus::BadFile,
            CoreError::EmptyDataset { .. } | CoreError::DimsDiffer { .. } => {
                BrdfAtlasStatus::BadMerl
            }
            CoreError::InvalidParams(_) | CoreError::BadQuery(_) => {
                BrdfAtlasStatus::InvalidArgument
            }
            CoreError::NotPositiveDefinite { .. } => BrdfAtlasStatus::NotPositiveDefinite,
            CoreError::Cancelled => BrdfAtlasStatus::Cancelled,
            _ => BrdfAtlasStatus::Other,
        };
        Failure::new(status, e.to_string())
    }
}

/// Result of an entry point's body.
pub(crate) type Result<T, E = Failure> = std::result::Result<T, E>;

thread_local! {
    /// The message of the last call on this thread: empty after a success.
    static LAST_ERROR: RefCell<CString> = RefCell::new(CString::default());
}

fn set_last_error(message: CString) {
    // During thread teardown the slot may be gone: then there is nowhere to keep it.
    let _ = LAST_ERROR.try_with(|e| *e.borrow_mut() = message);
}

/// One line, no NUL bytes.
fn one_line(function: &str, message: &str) -> CString {
    let text: String = format!("{function}: {message}")
        .chars()
        .map(|c| match c {
            '\0' => '?',
            '\n' | '\r' => ' ',
            c => c,
        })
        .collect();
    CString::new(text).unwrap_or_default()
}

/// The body of entry point `function`, with panics caught and the last
/// error recorded: the only way an entry point runs its work.
pub(crate) fn run(function: &str, body: impl FnOnce() -> Result<()>) -> BrdfAtlasStatus {
    match catch_unwind(AssertUnwindSafe(body)) {
        Ok(Ok(())) => {
            set_last_error(CString::default());
            BrdfAtlasStatus::Ok
        }
        Ok(Err(f)) => {
            set_last_error(one_line(function, &f.message));
            f.status
        }
        Err(payload) => {
            let what = payload
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| payload.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "unknown panic".into());
            // Dropping the payload could itself panic; keep it out of harm's way.
            std::mem::forget(payload);
            set_last_error(one_line(
                function,
                &format!("internal error, please report it: {what}"),
            ));
            BrdfAtlasStatus::Panic
        }
    }
}

/// A short static description of `status`.
///
/// Ownership: the returned string is static, owned by the library, never
/// NULL and never to be freed. A number that is not a status gives
/// "unknown status".
#[unsafe(no_mangle)]
pub extern "C" fn brdf_atlas_status_message(status: c_int) -> *const c_char {
    match BrdfAtlasStatus::from_number(status) {
        Some(s) => s.message().as_ptr(),
        None => c"unknown status".as_ptr(),
    }
}

/// The full one-line message of the last call on the calling thread: empty
/// ("") if that call succeeded or no call was made yet. It names the
/// function, then the file and what was expected where there is one
/// ("brdf_atlas_model_open: m.atlas: No such file or directory (os error 2)").
///
/// Ownership: the returned string is owned by the library, never NULL and
/// never to be freed. It stays valid until the next call into brdf-atlas on
/// the same thread (this function excepted) or the thread's exit; copy it
/// to keep it. Each thread has its own.
#[unsafe(no_mangle)]
pub extern "C" fn brdf_atlas_last_error_message() -> *const c_char {
    LAST_ERROR
        .try_with(|e| e.borrow().as_ptr())
        .unwrap_or(c"".as_ptr())
}

/// The library's version, "MAJOR.MINOR.PATCH".
///
/// Ownership: static, never NULL, never to be freed.
#[unsafe(no_mangle)]
pub extern "C" fn brdf_atlas_version() -> *const c_char {
    concat!(env!("CARGO_PKG_VERSION"), "\0").as_ptr().cast()
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::ffi::CStr;

    fn last() -> String {
        unsafe { CStr::from_ptr(brdf_atlas_last_error_message()) }
            .to_str()
            .unwrap()
            .to_owned()
    }

    #[test]
    fn numbers_are_fixed_and_named() {
        for (i, s) in ALL.iter().enumerate() {
            assert_eq!(*s as usize, i);
            assert_eq!(BrdfAtlasStatus::from_number(i as c_int), Some(*s));
            let m = unsafe { CStr::from_ptr(brdf_atlas_status_message(i as c_int)) };
            assert!(!m.to_bytes().is_empty());
        }
        for bad in [-1, ALL.len() as c_int, c_int::MAX, c_int::MIN] {
            let m = unsafe { CStr::from_ptr(brdf_atlas_status_message(bad)) };
            assert_eq!(m.to_str().unwrap(), "unknown status");
        }
    }

    #[test]
    fn failures_set_and_successes_clear_the_message() {
        let s = run("f", || Err(Failure::invalid("x is NaN\nsecond line")));
        assert_eq!(s, BrdfAtlasStatus::InvalidArgument);
        assert_eq!(last(), "f: x is NaN second line");
        assert_eq!(run("g", || Ok(())), BrdfAtlasStatus::Ok);
        assert_eq!(last(), "");
        // Other threads keep their own.
        run("h", || Err(Failure::invalid("mine")));
        std::thread::spawn(|| assert_eq!(last(), ""))
            .join()
            .unwrap();
        assert_eq!(last(), "h: mine");
    }

    #[test]
    fn panics_become_a_status() {
        let s = run("p", || panic!("boom {}", 7));
        assert_eq!(s, BrdfAtlasStatus::Panic);
        assert!(last().starts_with("p: internal error"), "{}", last());
        assert!(last().ends_with("boom 7"), "{}", last());
    }

    #[test]
    fn version_matches_the_crate() {
        let v = unsafe { CStr::from_ptr(brdf_atlas_version()) };
        assert_eq!(v.to_str().unwrap(), env!("CARGO_PKG_VERSION"));
    }
}
