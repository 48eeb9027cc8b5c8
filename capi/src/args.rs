//! Reading arguments that C passes as pointers: strings, points, point arrays and
//! output slots. Each checks for null and reports the argument by name.

use crate::errors::{FfiError, FfiResult};
use std::ffi::{CStr, c_char};
use ygg_store::Point;

/// A NUL-terminated UTF-8 string argument.
///
/// # Safety
/// `ptr` is null or points to a NUL-terminated string that stays unchanged during the
/// call (the C API's contract for every `const char*` argument).
pub(crate) unsafe fn str_arg<'a>(ptr: *const c_char, argument: &str) -> FfiResult<&'a str> {
    if ptr.is_null() {
        return Err(FfiError::null(argument));
    }
    // SAFETY: non-null, and NUL-terminated by the caller's contract.
    let bytes = unsafe { CStr::from_ptr(ptr) };
    bytes
        .to_str()
        .map_err(|e| FfiError::invalid(format!("`{argument}` is not UTF-8: {e}")))
}

/// A point argument: three floats.
///
/// # Safety
/// `ptr` is null or points to three readable `float`s.
pub(crate) unsafe fn point_arg(ptr: *const f32, argument: &str) -> FfiResult<Point> {
    if ptr.is_null() {
        return Err(FfiError::null(argument));
    }
    // SAFETY: non-null, and three readable floats by the caller's contract; `f32` has
    // no invalid bit patterns and `read_unaligned` needs no alignment.
    Ok(unsafe { ptr.cast::<Point>().read_unaligned() })
}

/// An array argument of `count` points (`3 * count` floats, x y z each); null is
/// accepted for `count == 0`.
///
/// # Safety
/// `xyz` is null or points to `3 * count` readable, `float`-aligned floats that stay
/// unchanged during the call.
pub(crate) unsafe fn points_arg<'a>(
    xyz: *const f32,
    count: usize,
    argument: &str,
) -> FfiResult<&'a [Point]> {
    if count == 0 {
        return Ok(&[]);
    }
    if xyz.is_null() {
        return Err(FfiError::null(argument));
    }
    if !xyz.cast::<Point>().is_aligned() {
        return Err(FfiError::invalid(format!(
            "`{argument}` is not aligned for float"
        )));
    }
    // SAFETY: non-null and aligned (checked); `[f32; 3]` has the layout of three
    // consecutive floats, and the caller guarantees `3 * count` readable floats that no
    // one writes during the call.
    Ok(unsafe { std::slice::from_raw_parts(xyz.cast::<Point>(), count) })
}

/// An array argument of `count` node ids; null is accepted for `count == 0`.
///
/// # Safety
/// `ids` is null or points to `count` readable, aligned `uint64_t` that stay unchanged
/// during the call.
pub(crate) unsafe fn ids_arg<'a>(
    ids: *const u64,
    count: usize,
    argument: &str,
) -> FfiResult<&'a [u64]> {
    if count == 0 {
        return Ok(&[]);
    }
    if ids.is_null() {
        return Err(FfiError::null(argument));
    }
    if !ids.is_aligned() {
        return Err(FfiError::invalid(format!(
            "`{argument}` is not aligned for uint64_t"
        )));
    }
    // SAFETY: non-null and aligned (checked); the caller guarantees `count` readable ids
    // that no one writes during the call.
    Ok(unsafe { std::slice::from_raw_parts(ids, count) })
}

/// An array argument of `count` C strings; null is accepted for `count == 0`.
///
/// # Safety
/// `items` is null or points to `count` readable pointers, each null or a
/// NUL-terminated string, all unchanged during the call.
pub(crate) unsafe fn str_array_arg<'a>(
    items: *const *const c_char,
    count: usize,
    argument: &str,
) -> FfiResult<Vec<&'a str>> {
    if count == 0 {
        return Ok(Vec::new());
    }
    if items.is_null() {
        return Err(FfiError::null(argument));
    }
    // SAFETY: non-null, `count` readable pointers by the caller's contract.
    let pointers = unsafe { std::slice::from_raw_parts(items, count) };
    pointers
        .iter()
        .enumerate()
        // SAFETY: each is null or NUL-terminated by the caller's contract.
        .map(|(i, &p)| unsafe { str_arg(p, &format!("{argument}[{i}]")) })
        .collect()
}

/// An output slot: a checked, non-null pointer the call writes its result to.
pub(crate) struct Out<T>(std::ptr::NonNull<T>);

impl<T> Out<T> {
    /// Checks an output argument.
    ///
    /// # Safety
    /// `ptr` is null or points to memory writable for one `T` (initialised or not) that
    /// no one else reads or writes during the call.
    pub(crate) unsafe fn new(ptr: *mut T, argument: &str) -> FfiResult<Self> {
        let Some(ptr) = std::ptr::NonNull::new(ptr) else {
            return Err(FfiError::null(argument));
        };
        if !ptr.is_aligned() {
            return Err(FfiError::invalid(format!("`{argument}` is misaligned")));
        }
        Ok(Out(ptr))
    }

    /// Writes the result (without reading or dropping what was there).
    pub(crate) fn write(self, value: T) {
        // SAFETY: `Out::new` checked non-null and aligned, and its caller guaranteed the
        // memory writable and unaliased for the call; `write` never reads the old value.
        unsafe { self.0.as_ptr().write(value) }
    }
}
