//! CDR, the byte layout ROS 2 serialises messages in (OMG CDR version 1, as rmw writes it): a
//! 4-byte encapsulation header (`00 01 00 00` little-endian, `00 00 00 00` big-endian), then
//! the fields in order, each primitive aligned to its own size counted from the end of the
//! header; a string is a `u32` length that counts its terminating NUL, the bytes and the NUL; a
//! sequence is a `u32` element count and the elements.
//!
//! The reader trusts nothing: every length and count read from a message is checked against the
//! bytes that remain before anything is allocated, so a corrupt message is an error, never a
//! panic or a huge allocation.

use std::fmt;

/// The encapsulation header this writer emits: CDR, little-endian.
const CDR_LE: [u8; 4] = [0x00, 0x01, 0x00, 0x00];

/// What is wrong with a message's bytes, and where (the offset counts from the start of the
/// message, header included).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CdrError {
    /// Byte offset in the message where reading failed.
    pub offset: usize,
    /// What was expected there.
    pub reason: String,
}

impl fmt::Display for CdrError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "at byte {}: {}", self.offset, self.reason)
    }
}

impl std::error::Error for CdrError {}

/// Serialises fields into a CDR message (little-endian).
#[derive(Debug)]
pub struct CdrWriter {
    buf: Vec<u8>,
}

impl Default for CdrWriter {
    fn default() -> Self {
        Self::new()
    }
}

impl CdrWriter {
    /// An empty message: the encapsulation header only.
    pub fn new() -> Self {
        let mut buf = Vec::with_capacity(128);
        buf.extend_from_slice(&CDR_LE);
        CdrWriter { buf }
    }

    fn align(&mut self, size: usize) {
        while !(self.buf.len() - CDR_LE.len()).is_multiple_of(size) {
            self.buf.push(0);
        }
    }

    /// A `uint32`.
    pub fn u32(&mut self, value: u32) {
        self.align(4);
        self.buf.extend_from_slice(&value.to_le_bytes());
    }

    /// An `int32`.
    pub fn i32(&mut self, value: i32) {
        self.align(4);
        self.buf.extend_from_slice(&value.to_le_bytes());
    }

    /// A `float64`.
    pub fn f64(&mut self, value: f64) {
        self.align(8);
        self.buf.extend_from_slice(&value.to_le_bytes());
    }

    /// A `float32`.
    pub fn f32(&mut self, value: f32) {
        self.align(4);
        self.buf.extend_from_slice(&value.to_le_bytes());
    }

    /// A `bool`: one byte, 0 or 1.
    pub fn bool(&mut self, value: bool) {
        self.buf.push(u8::from(value));
    }

    /// A `uint8[]`.
    pub fn bytes(&mut self, values: &[u8]) {
        self.count(values.len());
        self.buf.extend_from_slice(values);
    }

    /// A `string` (length with the NUL, bytes, NUL). Interior NULs are dropped: CDR cannot carry them.
    pub fn string(&mut self, value: &str) {
        let bytes: Vec<u8> = value.bytes().filter(|b| *b != 0).collect();
        self.u32(u32::try_from(bytes.len() + 1).unwrap_or(u32::MAX));
        self.buf.extend_from_slice(&bytes);
        self.buf.push(0);
    }

    /// A sequence's element count (the `uint32` before its elements; a count past `u32::MAX`,
    /// which no message can hold, is written as `u32::MAX`).
    pub fn count(&mut self, len: usize) {
        self.u32(u32::try_from(len).unwrap_or(u32::MAX));
    }

    /// A `float64[]`.
    pub fn f64_seq(&mut self, values: &[f64]) {
        self.count(values.len());
        for value in values {
            self.f64(*value);
        }
    }

    /// A `string[]`.
    pub fn string_seq(&mut self, values: &[String]) {
        self.count(values.len());
        for value in values {
            self.string(value);
        }
    }

    /// The message's bytes.
    pub fn finish(self) -> Vec<u8> {
        self.buf
    }
}

/// Reads fields out of a CDR message, checking every length against the bytes left.
#[derive(Debug)]
pub struct CdrReader<'a> {
    data: &'a [u8],
    pos: usize,
    little_endian: bool,
}

impl<'a> CdrReader<'a> {
    /// Starts reading `data`, checking its encapsulation header (plain CDR, either byte order).
    pub fn new(data: &'a [u8]) -> Result<Self, CdrError> {
        let Some(header) = data.get(..4) else {
            return Err(CdrError {
                offset: 0,
                reason: format!("{} byte(s) cannot hold the 4-byte encapsulation header", data.len()),
            });
        };
        let little_endian = match (header[0], header[1]) {
            (0x00, 0x01) => true,
            (0x00, 0x00) => false,
            (a, b) => {
                return Err(CdrError {
                    offset: 0,
                    reason: format!(
                        "encapsulation `{a:02x} {b:02x}` is not plain CDR (`00 01` little-endian or `00 00` big-endian); XCDR2 and parameter lists are not read"
                    ),
                })
            }
        };
        Ok(CdrReader {
            data,
            pos: 4,
            little_endian,
        })
    }

    fn fail(&self, reason: String) -> CdrError {
        CdrError {
            offset: self.pos,
            reason,
        }
    }

    /// Where the next field is read, counted from the start of the message.
    pub fn offset(&self) -> usize {
        self.pos
    }

    /// Bytes left after the current position.
    pub fn remaining(&self) -> usize {
        self.data.len().saturating_sub(self.pos)
    }

    fn align(&mut self, size: usize) {
        let misalignment = (self.pos - 4) % size;
        if misalignment != 0 {
            self.pos += size - misalignment;
        }
    }

    fn take<const N: usize>(&mut self, what: &str) -> Result<[u8; N], CdrError> {
        self.align(N);
        let bytes = self
            .data
            .get(self.pos..self.pos + N)
            .ok_or_else(|| self.fail(format!("the message ends before its {what}")))?;
        let mut out = [0u8; N];
        out.copy_from_slice(bytes);
        self.pos += N;
        Ok(out)
    }

    /// A number of `N` bytes in the message's byte order, decoded by `le` or `be`.
    fn number<const N: usize, T>(
        &mut self,
        what: &str,
        le: fn([u8; N]) -> T,
        be: fn([u8; N]) -> T,
    ) -> Result<T, CdrError> {
        let bytes = self.take::<N>(what)?;
        Ok(if self.little_endian { le(bytes) } else { be(bytes) })
    }

    /// A `uint32`; `what` names the field in an error.
    pub fn u32(&mut self, what: &str) -> Result<u32, CdrError> {
        self.number(what, u32::from_le_bytes, u32::from_be_bytes)
    }

    /// An `int32`.
    pub fn i32(&mut self, what: &str) -> Result<i32, CdrError> {
        self.number(what, i32::from_le_bytes, i32::from_be_bytes)
    }

    /// A `float64`.
    pub fn f64(&mut self, what: &str) -> Result<f64, CdrError> {
        self.number(what, f64::from_le_bytes, f64::from_be_bytes)
    }

    /// A `float32`.
    pub fn f32(&mut self, what: &str) -> Result<f32, CdrError> {
        self.number(what, f32::from_le_bytes, f32::from_be_bytes)
    }

    /// A `bool`: a byte that must be 0 or 1.
    pub fn bool(&mut self, what: &str) -> Result<bool, CdrError> {
        let start = self.pos;
        match self.take::<1>(what)? {
            [0] => Ok(false),
            [1] => Ok(true),
            [other] => Err(CdrError {
                offset: start,
                reason: format!("{what} is a bool, 0 or 1, not {other}: the message is not of this type or is corrupt"),
            }),
        }
    }

    /// A `uint8[]`.
    pub fn bytes(&mut self, what: &str) -> Result<Vec<u8>, CdrError> {
        let count = self.count(what, 1)?;
        let out = self.data[self.pos..self.pos + count].to_vec();
        self.pos += count;
        Ok(out)
    }

    /// A `string`: its length (with the NUL) must fit in the bytes left, its last byte must be
    /// the terminating NUL and no other byte a NUL, and the text must be UTF-8. An empty string is
    /// length 1 and a NUL; the length 0 some writers emit for it (malformed, no bytes follow) is
    /// read as empty too. Neither moves the next field off its alignment: that is counted from
    /// the header whatever the string's length.
    pub fn string(&mut self, what: &str) -> Result<String, CdrError> {
        let start = self.pos;
        let len = self.u32(&format!("{what}'s length"))? as usize;
        if len > self.remaining() {
            return Err(CdrError {
                offset: start,
                reason: format!(
                    "{what} claims {len} byte(s), only {} remain in the message",
                    self.remaining()
                ),
            });
        }
        let bytes = &self.data[self.pos..self.pos + len];
        self.pos += len;
        let text = match bytes.split_last() {
            None => &[][..],
            Some((0, text)) => text,
            Some(_) => {
                return Err(CdrError {
                    offset: start,
                    reason: format!(
                        "{what} (length {len}) does not end in the NUL a CDR string ends in: the message is not of this type or is corrupt"
                    ),
                })
            }
        };
        if text.contains(&0) {
            return Err(CdrError {
                offset: start,
                reason: format!(
                    "{what} (length {len}) holds a NUL before its end: the message is not of this type or is corrupt"
                ),
            });
        }
        String::from_utf8(text.to_vec()).map_err(|_| CdrError {
            offset: start,
            reason: format!("{what} is not UTF-8 text"),
        })
    }

    /// Ends a message after its last field, `last`: every byte must have been read but for at
    /// most 3 bytes of padding that bring the message to a multiple of 4 bytes after the header
    /// (XCDR's end padding, which rmw may add). Anything more means the bytes are another type,
    /// or the decoder misread a length.
    pub fn finish(self, last: &str) -> Result<(), CdrError> {
        let left = self.remaining();
        let body = self.data.len().saturating_sub(CDR_LE.len());
        if left == 0 || (left < 4 && body.is_multiple_of(4)) {
            return Ok(());
        }
        Err(CdrError {
            offset: self.pos,
            reason: format!(
                "{left} byte(s) are left over after the last field (`{last}`): the message is longer than this type"
            ),
        })
    }

    /// A sequence's element count, checked against the bytes left: each element takes at least
    /// `min_size` bytes.
    pub fn count(&mut self, what: &str, min_size: usize) -> Result<usize, CdrError> {
        let start = self.pos;
        let count = self.u32(&format!("{what}'s length"))? as usize;
        if count.saturating_mul(min_size.max(1)) > self.remaining() {
            return Err(CdrError {
                offset: start,
                reason: format!(
                    "{what} claims {count} element(s), only {} byte(s) remain in the message",
                    self.remaining()
                ),
            });
        }
        Ok(count)
    }

    /// A `float64[]`.
    pub fn f64_seq(&mut self, what: &str) -> Result<Vec<f64>, CdrError> {
        let count = self.count(what, 8)?;
        (0..count).map(|_| self.f64(what)).collect()
    }

    /// A `string[]`.
    pub fn string_seq(&mut self, what: &str) -> Result<Vec<String>, CdrError> {
        let count = self.count(what, 4)?;
        (0..count).map(|_| self.string(what)).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fields_are_aligned_after_the_header() {
        let mut writer = CdrWriter::new();
        writer.i32(7);
        writer.string("ab");
        writer.f64(1.5);
        let bytes = writer.finish();
        // header 4, i32 4, length 4, "ab\0" 3, padding to 16 bytes after the header 5, f64 8.
        assert_eq!(bytes.len(), 4 + 4 + 4 + 3 + 5 + 8);
        let mut reader = CdrReader::new(&bytes).expect("header");
        assert_eq!(reader.i32("a").expect("i32"), 7);
        assert_eq!(reader.string("b").expect("string"), "ab");
        assert_eq!(reader.f64("c").expect("f64"), 1.5);
        assert_eq!(reader.remaining(), 0);
    }

    #[test]
    fn lengths_beyond_the_message_are_errors() {
        let mut bytes = CDR_LE.to_vec();
        bytes.extend_from_slice(&u32::MAX.to_le_bytes());
        let err = CdrReader::new(&bytes)
            .expect("header")
            .string("frame_id")
            .expect_err("too long");
        assert!(err.reason.contains("claims 4294967295"), "{err}");
        let err = CdrReader::new(&bytes)
            .expect("header")
            .f64_seq("position")
            .expect_err("too many");
        assert!(err.reason.contains("element"), "{err}");
        assert!(CdrReader::new(&[0, 1]).is_err());
        assert!(CdrReader::new(&[0, 7, 0, 0]).is_err());
    }

    /// An `i32`, a string written as `string_bytes` (length field and bytes), then an `f64`.
    fn int_string_double(string_bytes: &[u8]) -> Vec<u8> {
        let mut bytes = CDR_LE.to_vec();
        bytes.extend_from_slice(&7i32.to_le_bytes());
        bytes.extend_from_slice(string_bytes);
        while !(bytes.len() - 4).is_multiple_of(8) {
            bytes.push(0);
        }
        bytes.extend_from_slice(&2.5f64.to_le_bytes());
        bytes
    }

    #[test]
    fn empty_strings_of_length_one_and_zero_keep_the_next_field_aligned() {
        let mut writer = CdrWriter::new();
        writer.i32(7);
        writer.string("");
        writer.f64(2.5);
        let written = writer.finish();
        assert_eq!(written, int_string_double(&[1, 0, 0, 0, 0]), "ROS 2's empty string");
        // Length 1 and a NUL, as rmw writes it; length 0 and nothing, as some writers do.
        for bytes in [written, int_string_double(&[0, 0, 0, 0])] {
            let mut reader = CdrReader::new(&bytes).expect("header");
            assert_eq!(reader.i32("a").expect("i32"), 7);
            assert_eq!(reader.string("frame_id").expect("string"), "");
            assert_eq!(reader.f64("x").expect("f64"), 2.5, "{bytes:?}");
            reader.finish("x").expect("nothing left");
        }
    }

    #[test]
    fn strings_must_end_in_their_nul_and_hold_no_other() {
        let bytes = int_string_double(&[3, 0, 0, 0, b'a', b'b', b'c']);
        let err = CdrReader::new(&bytes)
            .and_then(|mut reader| {
                reader.i32("a")?;
                reader.string("frame_id")
            })
            .expect_err("no NUL");
        assert!(
            err.reason.contains("frame_id (length 3) does not end in the NUL"),
            "{err}"
        );
        let bytes = int_string_double(&[3, 0, 0, 0, b'a', 0, 0]);
        let err = CdrReader::new(&bytes)
            .and_then(|mut reader| {
                reader.i32("a")?;
                reader.string("frame_id")
            })
            .expect_err("inner NUL");
        assert!(err.reason.contains("holds a NUL before its end"), "{err}");
    }

    #[test]
    fn a_message_must_be_read_to_its_end_but_for_end_padding() {
        let mut writer = CdrWriter::new();
        writer.string("ab");
        let exact = writer.finish();
        assert_eq!(exact.len(), 4 + 4 + 3);
        let read = |bytes: &[u8]| {
            let mut reader = CdrReader::new(bytes)?;
            reader.string("data")?;
            reader.finish("data")
        };
        read(&exact).expect("exact");
        // One byte of padding brings the body to 8 bytes: allowed.
        let mut padded = exact.clone();
        padded.push(0);
        read(&padded).expect("end padding");
        // Two more bytes pass the 4-byte boundary; four bytes are never padding.
        padded.extend_from_slice(&[0, 0]);
        let err = read(&padded).expect_err("leftover");
        assert_eq!(err.offset, 11);
        assert!(
            err.reason
                .starts_with("3 byte(s) are left over after the last field (`data`)"),
            "{err}"
        );
        let mut long = exact;
        long.extend_from_slice(&[0; 5]);
        assert!(read(&long).is_err());
    }

    #[test]
    fn big_endian_is_read() {
        let mut bytes = vec![0, 0, 0, 0];
        bytes.extend_from_slice(&5u32.to_be_bytes());
        bytes.extend_from_slice(&[0; 4]);
        bytes.extend_from_slice(&2.5f64.to_be_bytes());
        let mut reader = CdrReader::new(&bytes).expect("header");
        assert_eq!(reader.u32("n").expect("u32"), 5);
        assert_eq!(reader.f64("x").expect("f64"), 2.5);
    }
}
