//! Status codes, the thread-local last error, and `guard`, the wrapper every entry
//! point runs its body in (no panic crosses the boundary).

use std::cell::RefCell;
use std::ffi::{CString, c_char};
use std::panic::{AssertUnwindSafe, catch_unwind};

/// What a call of the C API did. Every function returns one; on anything but
/// `YGG_STATUS_OK`, `ygg_last_error()` gives the message.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum YggStatus {
    /// Success.
    Ok = 0,
    /// A required pointer argument was null.
    NullArgument = 1,
    /// A handle is not live: destroyed, never created by this library, of another kind,
    /// or (for a writer's graph) its writer is gone.
    InvalidHandle = 2,
    /// An argument is malformed: a string not UTF-8, a non-finite point, a negative
    /// radius, an unknown layout name, ...
    InvalidArgument = 3,
    /// A mutation was refused (unknown node, cycle, ...); the graph is unchanged.
    GraphEdit = 4,
    /// No such node, layer, label or feature in a snapshot.
    NotFound = 5,
    /// A file could not be read, written or validated.
    Io = 6,
    /// A Spark-DSG file could not be imported or laid out.
    Import = 7,
    /// The writer could not be created (bad scene name, another live writer, ...).
    WriterCreate = 8,
    /// A publish failed; readers keep the previous snapshot.
    Publish = 9,
    /// The reader could not attach (no writer within the wait, bad scene name, ...).
    ReaderOpen = 10,
    /// Receiving a snapshot failed (transport error or bytes that fail validation).
    Receive = 11,
    /// An internal error (a bug): a panic was caught at the boundary.
    Panic = 12,
}

/// A failed call: its status and message.
#[derive(Debug)]
pub(crate) struct FfiError {
    pub(crate) status: YggStatus,
    pub(crate) message: String,
}

impl FfiError {
    /// An error with `status` and `message`.
    pub(crate) fn new(status: YggStatus, message: impl Into<String>) -> Self {
        FfiError {
            status,
            message: message.into(),
        }
    }

    /// `YGG_STATUS_NULL_ARGUMENT` naming the argument.
    pub(crate) fn null(argument: &str) -> Self {
        Self::new(
            YggStatus::NullArgument,
            format!("argument `{argument}` is null"),
        )
    }

    /// `YGG_STATUS_INVALID_ARGUMENT` with `message`.
    pub(crate) fn invalid(message: impl Into<String>) -> Self {
        Self::new(YggStatus::InvalidArgument, message)
    }

    /// Maps any error to `status`, prefixed with what was being done.
    pub(crate) fn wrap<E: std::fmt::Display>(
        status: YggStatus,
        what: &str,
    ) -> impl FnOnce(E) -> Self {
        move |e| Self::new(status, format!("{what}: {e}"))
    }
}

/// The result of an entry point's body.
pub(crate) type FfiResult<T = ()> = Result<T, FfiError>;

thread_local! {
    /// The message of the last failed call on this thread.
    static LAST_ERROR: RefCell<CString> = RefCell::new(CString::default());
}

fn set_last_error(message: &str) {
    // An interior NUL cannot be passed through a C string: show it escaped.
    let text = CString::new(message.replace('\0', "\\0")).unwrap_or_default();
    LAST_ERROR.with(|e| *e.borrow_mut() = text);
}

/// Runs an entry point's body: its error becomes the status and the thread's last
/// error, and a panic is caught and reported as `YGG_STATUS_PANIC` (never unwinding
/// into C).
pub(crate) fn guard(function: &str, body: impl FnOnce() -> FfiResult) -> YggStatus {
    match catch_unwind(AssertUnwindSafe(body)) {
        Ok(Ok(())) => YggStatus::Ok,
        Ok(Err(e)) => {
            set_last_error(&format!("{function}: {}", e.message));
            e.status
        }
        Err(panic) => {
            let what = panic
                .downcast_ref::<&str>()
                .map(|s| (*s).to_owned())
                .or_else(|| panic.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "unknown panic".to_owned());
            set_last_error(&format!("{function}: internal error (panic): {what}"));
            YggStatus::Panic
        }
    }
}

/// The message of the last call that failed on the calling thread, prefixed with the
/// function's name (`""` before any failure). Successful calls leave it unchanged.
///
/// Ownership: the string belongs to the library; it stays valid until the next failing
/// call on the same thread. Copy it to keep it. Thread-safe (one message per thread).
#[unsafe(no_mangle)]
pub extern "C" fn ygg_last_error() -> *const c_char {
    LAST_ERROR.with(|e| e.borrow().as_ptr())
}

/// The name of a status code (`"YGG_STATUS_OK"`, ...), a static string. Thread-safe.
#[unsafe(no_mangle)]
pub extern "C" fn ygg_status_name(status: YggStatus) -> *const c_char {
    let name: &'static std::ffi::CStr = match status {
        YggStatus::Ok => c"YGG_STATUS_OK",
        YggStatus::NullArgument => c"YGG_STATUS_NULL_ARGUMENT",
        YggStatus::InvalidHandle => c"YGG_STATUS_INVALID_HANDLE",
        YggStatus::InvalidArgument => c"YGG_STATUS_INVALID_ARGUMENT",
        YggStatus::GraphEdit => c"YGG_STATUS_GRAPH_EDIT",
        YggStatus::NotFound => c"YGG_STATUS_NOT_FOUND",
        YggStatus::Io => c"YGG_STATUS_IO",
        YggStatus::Import => c"YGG_STATUS_IMPORT",
        YggStatus::WriterCreate => c"YGG_STATUS_WRITER_CREATE",
        YggStatus::Publish => c"YGG_STATUS_PUBLISH",
        YggStatus::ReaderOpen => c"YGG_STATUS_READER_OPEN",
        YggStatus::Receive => c"YGG_STATUS_RECEIVE",
        YggStatus::Panic => c"YGG_STATUS_PANIC",
    };
    name.as_ptr()
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::ffi::CStr;

    fn last_error() -> String {
        // SAFETY: `ygg_last_error` returns this thread's NUL-terminated message, alive
        // until the next failing call (none happens while it is read).
        unsafe { CStr::from_ptr(ygg_last_error()) }
            .to_string_lossy()
            .into_owned()
    }

    #[test]
    fn a_panic_in_a_body_becomes_the_panic_status_with_its_message() {
        let status = guard("ygg_test", || panic!("boom {}", 7));
        assert_eq!(status, YggStatus::Panic);
        assert_eq!(last_error(), "ygg_test: internal error (panic): boom 7");
    }

    #[test]
    fn an_error_sets_the_message_and_success_leaves_it() {
        let status = guard("ygg_test", || Err(FfiError::null("graph")));
        assert_eq!(status, YggStatus::NullArgument);
        assert_eq!(guard("ygg_other", || Ok(())), YggStatus::Ok);
        assert_eq!(last_error(), "ygg_test: argument `graph` is null");
    }
}
