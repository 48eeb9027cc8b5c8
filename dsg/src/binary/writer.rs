//! The tagged-value writer: the inverse of [`Cursor`](super::reader::Cursor).
//!
//! Values are written little-endian (Spark-DSG writes host order; every supported
//! target is little-endian). Arrays and strings carry a u32 length: a longer one
//! cannot be written, so the writer records the first such length and
//! [`Writer::finish`] reports it instead of writing a wrong length.

use super::reader::Tag;

/// A growing buffer of tagged values.
pub(super) struct Writer {
    buf: Vec<u8>,
    /// The first array length that did not fit u32.
    too_long: Option<usize>,
}

impl Writer {
    pub(super) fn with_capacity(n: usize) -> Self {
        Self {
            buf: Vec::with_capacity(n),
            too_long: None,
        }
    }

    /// The bytes, or the first length that does not fit the format.
    pub(super) fn finish(self) -> Result<Vec<u8>, usize> {
        match self.too_long {
            Some(n) => Err(n),
            None => Ok(self.buf),
        }
    }

    fn tag(&mut self, t: Tag) {
        self.buf.push(t as u8);
    }

    pub(super) fn u8(&mut self, v: u8) {
        self.tag(Tag::U8);
        self.buf.push(v);
    }

    pub(super) fn u32(&mut self, v: u32) {
        self.tag(Tag::U32);
        self.buf.extend_from_slice(&v.to_le_bytes());
    }

    pub(super) fn u64(&mut self, v: u64) {
        self.tag(Tag::U64);
        self.buf.extend_from_slice(&v.to_le_bytes());
    }

    pub(super) fn i32(&mut self, v: i32) {
        self.tag(Tag::I32);
        self.buf.extend_from_slice(&v.to_le_bytes());
    }

    pub(super) fn i64(&mut self, v: i64) {
        self.tag(Tag::I64);
        self.buf.extend_from_slice(&v.to_le_bytes());
    }

    pub(super) fn f32(&mut self, v: f32) {
        self.tag(Tag::F32);
        self.buf.extend_from_slice(&v.to_le_bytes());
    }

    pub(super) fn f64(&mut self, v: f64) {
        self.tag(Tag::F64);
        self.buf.extend_from_slice(&v.to_le_bytes());
    }

    pub(super) fn bool(&mut self, v: bool) {
        self.tag(if v { Tag::True } else { Tag::False });
    }

    /// An `ARR32` header of `n` elements.
    pub(super) fn array(&mut self, n: usize) {
        let len = u32::try_from(n).unwrap_or_else(|_| {
            self.too_long.get_or_insert(n);
            u32::MAX
        });
        self.tag(Tag::Arr32);
        self.buf.extend_from_slice(&len.to_le_bytes());
    }

    /// A string, as spark_dsg writes it (`ARR32` length, then the bytes).
    pub(super) fn str(&mut self, s: &str) {
        self.array(s.len());
        self.buf.extend_from_slice(s.as_bytes());
    }

    /// NIL (an empty `std::optional`).
    #[cfg(test)]
    pub(super) fn nil(&mut self) {
        self.tag(Tag::Nil);
    }

    pub(super) fn dyn_start(&mut self) {
        self.tag(Tag::ArrStart);
    }

    pub(super) fn dyn_end(&mut self) {
        self.tag(Tag::ArrEnd);
    }

    pub(super) fn vec3_f64(&mut self, v: [f64; 3]) {
        v.into_iter().for_each(|x| self.f64(x));
    }

    pub(super) fn vec3_f32(&mut self, v: [f32; 3]) {
        v.into_iter().for_each(|x| self.f32(x));
    }

    /// `Eigen::Quaterniond` as `[w, x, y, z]`.
    pub(super) fn quaternion(&mut self, q: [f64; 4]) {
        self.array(4);
        q.into_iter().for_each(|x| self.f64(x));
    }

    /// The header of an Eigen matrix; the caller writes `rows * cols` values.
    pub(super) fn matrix_header(&mut self, rows: i64, cols: i64) {
        let n = usize::try_from(rows * cols).unwrap_or(0);
        self.array(n + 2);
        self.i64(rows);
        self.i64(cols);
    }
}
