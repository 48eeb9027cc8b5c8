//! The tagged-value cursor over a Spark-DSG binary buffer.
//!
//! Invariants: every read checks the tag byte and that the value's bytes lie inside
//! the buffer before touching them; a failed read leaves the error's offset at the
//! tag (or length) that was wrong. [`Cursor::array_len`] checks a length against the
//! bytes left (times the smallest encoding of one element) before a caller may
//! allocate for it, so a corrupt length can never reserve more memory than the
//! input could fill. Every successful read consumes at least one byte, so a loop
//! that reads until the end of a dynamic array always terminates.

use std::borrow::Cow;
use std::fmt;

/// A tag byte of Spark-DSG's binary encoding (`PackType` in `binary_serialization.h`;
/// UINT16, INT8 and INT16 are not used by any layout).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u8)]
pub(super) enum Tag {
    Nil = 0xc0,
    False = 0xc2,
    True = 0xc3,
    F32 = 0xca,
    F64 = 0xcb,
    U8 = 0xcc,
    U32 = 0xce,
    U64 = 0xcf,
    I32 = 0xd2,
    I64 = 0xd3,
    Str32 = 0xdb,
    Arr32 = 0xdd,
    /// Start of a dynamic array.
    ArrStart = 0x00,
    /// End of a dynamic array.
    ArrEnd = 0x01,
}

impl Tag {
    /// The name Spark-DSG's error messages use.
    fn name(self) -> &'static str {
        match self {
            Tag::Nil => "NIL",
            Tag::False => "FALSE",
            Tag::True => "TRUE",
            Tag::F32 => "FLOAT32",
            Tag::F64 => "FLOAT64",
            Tag::U8 => "UINT8",
            Tag::U32 => "UINT32",
            Tag::U64 => "UINT64",
            Tag::I32 => "INT32",
            Tag::I64 => "INT64",
            Tag::Str32 => "STR32",
            Tag::Arr32 => "ARR32",
            Tag::ArrStart => "ARRXX (array start)",
            Tag::ArrEnd => "ARRYY (array end)",
        }
    }
}

impl fmt::Display for Tag {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} ({:#04x})", self.name(), *self as u8)
    }
}

/// A scalar type of the encoding: its tag and payload size.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Scalar {
    U8,
    U32,
    U64,
    F32,
    F64,
}

impl Scalar {
    pub(super) fn tag(self) -> Tag {
        match self {
            Scalar::U8 => Tag::U8,
            Scalar::U32 => Tag::U32,
            Scalar::U64 => Tag::U64,
            Scalar::F32 => Tag::F32,
            Scalar::F64 => Tag::F64,
        }
    }

    /// Payload bytes after the tag.
    pub(super) fn size(self) -> usize {
        match self {
            Scalar::U8 => 1,
            Scalar::U32 | Scalar::F32 => 4,
            Scalar::U64 | Scalar::F64 => 8,
        }
    }

    /// Encoded size: tag plus payload.
    pub(super) fn encoded(self) -> usize {
        1 + self.size()
    }
}

/// A decoding failure: where, in which field, and what was wrong.
#[derive(Debug)]
pub(super) struct DecodeError {
    /// Byte offset in the buffer handed to the decoder.
    pub offset: usize,
    /// The node being decoded, if any.
    pub node: Option<u64>,
    /// Field path, e.g. `attributes.bounding_box` or `mesh.faces[7]`.
    pub field: String,
    /// What was wrong.
    pub message: String,
}

impl DecodeError {
    pub(super) fn new(offset: usize, field: &str, message: impl Into<String>) -> Self {
        Self {
            offset,
            node: None,
            field: field.to_owned(),
            message: message.into(),
        }
    }

    /// Puts the field path inside `outer` (`outer` + `[i]` / `.name` of the inner path).
    pub(super) fn within(mut self, outer: impl fmt::Display) -> Self {
        self.field = if self.field.is_empty() {
            outer.to_string()
        } else if self.field.starts_with('[') {
            format!("{outer}{}", self.field)
        } else {
            format!("{outer}.{}", self.field)
        };
        self
    }

    /// Names the node the error belongs to (keeps an inner one).
    pub(super) fn at_node(mut self, id: u64) -> Self {
        self.node.get_or_insert(id);
        self
    }
}

/// Result of a decoding step.
pub(super) type Decoded<T> = Result<T, DecodeError>;

/// A read position in a binary buffer.
pub(super) struct Cursor<'a> {
    buf: &'a [u8],
    pos: usize,
    /// Added to `pos` in error offsets (the header length, for a file body).
    base: usize,
}

impl<'a> Cursor<'a> {
    /// A cursor at the start of `buf`; error offsets are reported as `base + pos`.
    pub(super) fn new(buf: &'a [u8], base: usize) -> Self {
        Self { buf, pos: 0, base }
    }

    /// Current offset, as reported in errors.
    pub(super) fn offset(&self) -> usize {
        self.base + self.pos
    }

    /// Position in the buffer (from its start, without `base`).
    pub(super) fn position(&self) -> usize {
        self.pos
    }

    /// `base` plus the buffer's length: the offset of its end, as errors report it.
    pub(super) fn total_len(&self) -> usize {
        self.base + self.buf.len()
    }

    /// Bytes not read yet.
    pub(super) fn remaining(&self) -> usize {
        self.buf.len() - self.pos
    }

    /// Whether every byte was read.
    pub(super) fn at_end(&self) -> bool {
        self.pos == self.buf.len()
    }

    /// An error at the current offset.
    pub(super) fn error(&self, field: &str, message: impl Into<String>) -> DecodeError {
        DecodeError::new(self.offset(), field, message)
    }

    /// The next byte, not consumed.
    pub(super) fn peek(&self) -> Option<u8> {
        self.buf.get(self.pos).copied()
    }

    fn take(&mut self, n: usize, field: &str, what: &str) -> Decoded<&'a [u8]> {
        match self.buf.get(self.pos..).and_then(|rest| rest.get(..n)) {
            Some(b) => {
                self.pos += n;
                Ok(b)
            }
            None => Err(self.error(
                field,
                format!(
                    "{what} needs {n} bytes but the buffer ends after {}",
                    self.remaining()
                ),
            )),
        }
    }

    fn array<const N: usize>(&mut self, field: &str, what: &str) -> Decoded<[u8; N]> {
        let b = self.take(N, field, what)?;
        // `take` returned exactly N bytes.
        Ok(<[u8; N]>::try_from(b).unwrap_or([0; N]))
    }

    /// Consumes the tag byte if it is `tag`.
    pub(super) fn tag(&mut self, tag: Tag, field: &str) -> Decoded<()> {
        match self.peek() {
            Some(b) if b == tag as u8 => {
                self.pos += 1;
                Ok(())
            }
            Some(b) => Err(self.error(field, format!("expected {tag}, found byte {b:#04x}"))),
            None => Err(self.error(field, format!("expected {tag}, but the buffer ends"))),
        }
    }

    pub(super) fn u8(&mut self, field: &str) -> Decoded<u8> {
        self.tag(Tag::U8, field)?;
        Ok(self.array::<1>(field, "UINT8")?[0])
    }

    pub(super) fn u32(&mut self, field: &str) -> Decoded<u32> {
        self.tag(Tag::U32, field)?;
        Ok(u32::from_le_bytes(self.array(field, "UINT32")?))
    }

    pub(super) fn u64(&mut self, field: &str) -> Decoded<u64> {
        self.tag(Tag::U64, field)?;
        Ok(u64::from_le_bytes(self.array(field, "UINT64")?))
    }

    pub(super) fn i32(&mut self, field: &str) -> Decoded<i32> {
        self.tag(Tag::I32, field)?;
        Ok(i32::from_le_bytes(self.array(field, "INT32")?))
    }

    pub(super) fn i64(&mut self, field: &str) -> Decoded<i64> {
        self.tag(Tag::I64, field)?;
        Ok(i64::from_le_bytes(self.array(field, "INT64")?))
    }

    pub(super) fn f32(&mut self, field: &str) -> Decoded<f32> {
        self.tag(Tag::F32, field)?;
        Ok(f32::from_le_bytes(self.array(field, "FLOAT32")?))
    }

    pub(super) fn f64(&mut self, field: &str) -> Decoded<f64> {
        self.tag(Tag::F64, field)?;
        Ok(f64::from_le_bytes(self.array(field, "FLOAT64")?))
    }

    /// A scalar of any type, skipped.
    pub(super) fn skip_scalar(&mut self, s: Scalar, field: &str) -> Decoded<()> {
        self.tag(s.tag(), field)?;
        self.take(s.size(), field, s.tag().name()).map(drop)
    }

    pub(super) fn bool(&mut self, field: &str) -> Decoded<bool> {
        match self.peek() {
            Some(b) if b == Tag::True as u8 => {
                self.pos += 1;
                Ok(true)
            }
            Some(b) if b == Tag::False as u8 => {
                self.pos += 1;
                Ok(false)
            }
            Some(b) => Err(self.error(field, format!("expected a bool, found byte {b:#04x}"))),
            None => Err(self.error(field, "expected a bool, but the buffer ends")),
        }
    }

    /// `std::optional<u32>`: NIL or a UINT32.
    pub(super) fn opt_u32(&mut self, field: &str) -> Decoded<Option<u32>> {
        if self.peek() == Some(Tag::Nil as u8) {
            self.pos += 1;
            return Ok(None);
        }
        self.u32(field).map(Some)
    }

    /// `std::optional<std::chrono::nanoseconds>`: NIL or an INT64.
    pub(super) fn opt_i64(&mut self, field: &str) -> Decoded<Option<i64>> {
        if self.peek() == Some(Tag::Nil as u8) {
            self.pos += 1;
            return Ok(None);
        }
        self.i64(field).map(Some)
    }

    /// The length of an `ARR32` (or `STR32`) value, checked against the bytes left:
    /// `len * min_element` must fit in what remains.
    pub(super) fn array_len(&mut self, min_element: usize, field: &str) -> Decoded<usize> {
        let at = self.offset();
        match self.peek() {
            Some(b) if b == Tag::Arr32 as u8 || b == Tag::Str32 as u8 => self.pos += 1,
            Some(b) => {
                return Err(self.error(
                    field,
                    format!("expected {}, found byte {b:#04x}", Tag::Arr32),
                ));
            }
            None => {
                return Err(self.error(
                    field,
                    format!("expected {}, but the buffer ends", Tag::Arr32),
                ));
            }
        }
        let len = u32::from_le_bytes(self.array(field, "an array length")?) as usize;
        let need = len.saturating_mul(min_element.max(1));
        if need > self.remaining() {
            return Err(DecodeError::new(
                at,
                field,
                format!(
                    "array of {len} elements needs at least {need} bytes but only {} are left",
                    self.remaining()
                ),
            ));
        }
        Ok(len)
    }

    /// An `ARR32` header of exactly `n` elements.
    pub(super) fn fixed(&mut self, n: usize, field: &str) -> Decoded<()> {
        let at = self.offset();
        let len = self.array_len(1, field)?;
        if len != n {
            return Err(DecodeError::new(
                at,
                field,
                format!("expected an array of {n} elements, found {len}"),
            ));
        }
        Ok(())
    }

    /// A string (`ARR32`/`STR32` length, then the bytes), as raw bytes.
    pub(super) fn bytes(&mut self, field: &str) -> Decoded<&'a [u8]> {
        let len = self.array_len(1, field)?;
        self.take(len, field, "string")
    }

    /// A string; bytes that are not UTF-8 are replaced (Spark-DSG strings are bytes).
    pub(super) fn string(&mut self, field: &str) -> Decoded<Cow<'a, str>> {
        self.bytes(field).map(String::from_utf8_lossy)
    }

    /// Consumes the start of a dynamic array.
    pub(super) fn dyn_start(&mut self, field: &str) -> Decoded<()> {
        self.tag(Tag::ArrStart, field)
    }

    /// Consumes the end of a dynamic array if it is next.
    pub(super) fn dyn_end(&mut self, field: &str) -> Decoded<bool> {
        match self.peek() {
            Some(b) if b == Tag::ArrEnd as u8 => {
                self.pos += 1;
                Ok(true)
            }
            Some(_) => Ok(false),
            None => Err(self.error(field, "the buffer ends inside a dynamic array")),
        }
    }

    /// Decodes the next `n` records of `N` bytes each with `record`, which returns
    /// `None` for a record that is not well-formed; all or nothing: on success the
    /// values are appended to `out` and the bytes consumed, otherwise neither happens
    /// and the caller reads value by value to find the error. (A fast path for long
    /// homogeneous arrays.)
    pub(super) fn records<T, const N: usize>(
        &mut self,
        n: usize,
        out: &mut Vec<T>,
        record: impl Fn(&[u8; N]) -> Option<T>,
    ) -> bool {
        let Some(block) = n
            .checked_mul(N)
            .and_then(|len| self.buf.get(self.pos..)?.get(..len))
        else {
            return false;
        };
        let start = out.len();
        for r in block.chunks_exact(N) {
            match <&[u8; N]>::try_from(r).ok().and_then(&record) {
                Some(v) => out.push(v),
                None => {
                    out.truncate(start);
                    return false;
                }
            }
        }
        self.pos += block.len();
        true
    }

    /// `Eigen::Vector3d`: three FLOAT64, no container.
    pub(super) fn vec3_f64(&mut self, field: &str) -> Decoded<[f64; 3]> {
        let at = |k: usize| move |e: DecodeError| e.within(format!("[{k}]"));
        Ok([
            self.f64(field).map_err(at(0))?,
            self.f64(field).map_err(at(1))?,
            self.f64(field).map_err(at(2))?,
        ])
    }

    /// `Eigen::Vector3f`: three FLOAT32, no container.
    pub(super) fn vec3_f32(&mut self, field: &str) -> Decoded<[f32; 3]> {
        Ok([self.f32(field)?, self.f32(field)?, self.f32(field)?])
    }
}

/// The FLOAT32 value of a record whose byte `at` is its tag, if it is.
#[inline]
pub(super) fn f32_at<const N: usize>(r: &[u8; N], at: usize) -> Option<f32> {
    match r.get(at..at + 5)? {
        &[t, a, b, c, d] if t == Tag::F32 as u8 => Some(f32::from_le_bytes([a, b, c, d])),
        _ => None,
    }
}

/// The UINT32 value of a record whose byte `at` is its tag, if it is.
#[inline]
pub(super) fn u32_at<const N: usize>(r: &[u8; N], at: usize) -> Option<u32> {
    match r.get(at..at + 5)? {
        &[t, a, b, c, d] if t == Tag::U32 as u8 => Some(u32::from_le_bytes([a, b, c, d])),
        _ => None,
    }
}

/// The UINT64 value of a record whose byte `at` is its tag, if it is and fits u32.
#[inline]
pub(super) fn u64_as_u32_at<const N: usize>(r: &[u8; N], at: usize) -> Option<u32> {
    match r.get(at..at + 9)? {
        &[t, a, b, c, d, 0, 0, 0, 0] if t == Tag::U64 as u8 => {
            Some(u32::from_le_bytes([a, b, c, d]))
        }
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lengths_are_checked_before_use() {
        let buf = [0xdd, 0xff, 0xff, 0xff, 0xff, 0xcc];
        let mut c = Cursor::new(&buf, 10);
        let e = c.array_len(2, "x").unwrap_err();
        assert_eq!(e.offset, 10);
        assert!(e.message.contains("4294967295 elements"), "{}", e.message);
    }

    #[test]
    fn tags_are_checked() {
        let mut c = Cursor::new(&[0xcb, 0, 0], 0);
        assert!(c.f32("p").unwrap_err().message.contains("FLOAT32"));
        assert!(c.f64("p").unwrap_err().message.contains("needs 8 bytes"));
        let mut c = Cursor::new(&[0xdb, 2, 0, 0, 0, b'h', b'i', 0xc3, 0xc0], 0);
        assert_eq!(c.string("s").unwrap(), "hi");
        assert!(c.bool("b").unwrap());
        assert_eq!(c.opt_u32("l").unwrap(), None);
        assert!(c.at_end());
    }
}
