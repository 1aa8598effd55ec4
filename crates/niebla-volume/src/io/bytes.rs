//! A bounds-checked little-endian cursor over an in-memory file.
//!
//! Every read checks the remaining length first and reports a
//! [`VolumeError::Truncated`] naming what was being read, so that parsers
//! never index out of range and never allocate from an unchecked size.

use std::path::Path;

use crate::VolumeError;

/// Cursor over `data`, reporting errors against `path`.
pub(crate) struct ByteReader<'a> {
    data: &'a [u8],
    pos: usize,
    path: &'a Path,
}

impl<'a> ByteReader<'a> {
    /// A cursor at byte `pos` of `data` (which may be shorter than the file
    /// when a parser wants to stop at a known end).
    pub(crate) fn new(data: &'a [u8], pos: usize, path: &'a Path) -> Self {
        Self { data, pos, path }
    }

    /// Current byte offset.
    pub(crate) fn pos(&self) -> usize {
        self.pos
    }

    /// The file named in errors.
    pub(crate) fn path(&self) -> &'a Path {
        self.path
    }

    /// Bytes left before the end of the readable data.
    pub(crate) fn remaining(&self) -> usize {
        self.data.len().saturating_sub(self.pos)
    }

    /// A [`VolumeError::Truncated`] at the current offset.
    pub(crate) fn truncated(&self, what: &str) -> VolumeError {
        VolumeError::Truncated { path: self.path.to_path_buf(), offset: self.pos as u64, what: what.to_string() }
    }

    /// A [`VolumeError::Corrupt`] at byte `offset`.
    pub(crate) fn corrupt_at(&self, offset: usize, what: impl Into<String>) -> VolumeError {
        VolumeError::Corrupt { path: self.path.to_path_buf(), offset: offset as u64, what: what.into() }
    }

    /// A [`VolumeError::Unsupported`] for this file.
    pub(crate) fn unsupported(&self, what: impl Into<String>) -> VolumeError {
        VolumeError::Unsupported { path: self.path.to_path_buf(), what: what.into() }
    }

    /// The next `n` bytes.
    pub(crate) fn bytes(&mut self, n: usize, what: &str) -> Result<&'a [u8], VolumeError> {
        if n > self.remaining() {
            return Err(self.truncated(what));
        }
        let out = &self.data[self.pos..self.pos + n];
        self.pos += n;
        Ok(out)
    }

    /// Skips `n` bytes.
    pub(crate) fn skip(&mut self, n: usize, what: &str) -> Result<(), VolumeError> {
        self.bytes(n, what).map(|_| ())
    }

    fn array<const N: usize>(&mut self, what: &str) -> Result<[u8; N], VolumeError> {
        let b = self.bytes(N, what)?;
        let mut out = [0u8; N];
        out.copy_from_slice(b);
        Ok(out)
    }

    pub(crate) fn u8(&mut self, what: &str) -> Result<u8, VolumeError> {
        Ok(self.array::<1>(what)?[0])
    }

    pub(crate) fn u16(&mut self, what: &str) -> Result<u16, VolumeError> {
        Ok(u16::from_le_bytes(self.array(what)?))
    }

    pub(crate) fn u32(&mut self, what: &str) -> Result<u32, VolumeError> {
        Ok(u32::from_le_bytes(self.array(what)?))
    }

    pub(crate) fn i32(&mut self, what: &str) -> Result<i32, VolumeError> {
        Ok(i32::from_le_bytes(self.array(what)?))
    }

    pub(crate) fn i64(&mut self, what: &str) -> Result<i64, VolumeError> {
        Ok(i64::from_le_bytes(self.array(what)?))
    }

    pub(crate) fn f32(&mut self, what: &str) -> Result<f32, VolumeError> {
        Ok(f32::from_le_bytes(self.array(what)?))
    }

    pub(crate) fn f64(&mut self, what: &str) -> Result<f64, VolumeError> {
        Ok(f64::from_le_bytes(self.array(what)?))
    }

    /// Three little-endian f64 values (an OpenVDB `Vec3d`).
    pub(crate) fn vec3d(&mut self, what: &str) -> Result<[f64; 3], VolumeError> {
        Ok([self.f64(what)?, self.f64(what)?, self.f64(what)?])
    }

    /// A string stored as a u32 byte count and its bytes (Latin-1 is mapped
    /// byte for byte, so any content is accepted).
    pub(crate) fn string(&mut self, what: &str) -> Result<String, VolumeError> {
        let start = self.pos;
        let n = self.u32(what)? as usize;
        if n > self.remaining() {
            self.pos = start;
            return Err(self.truncated(what));
        }
        let b = self.bytes(n, what)?;
        Ok(b.iter().map(|&c| c as char).collect())
    }
}

/// Reads a whole file, mapping the I/O error to [`VolumeError::Io`].
pub(crate) fn read_file(path: &Path) -> Result<Vec<u8>, VolumeError> {
    std::fs::read(path).map_err(|source| VolumeError::Io { path: path.to_path_buf(), source })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_past_end_are_truncation_errors() {
        let data = [1u8, 0, 0, 0, 5, 0];
        let mut r = ByteReader::new(&data, 0, Path::new("x"));
        assert_eq!(r.u32("a").unwrap(), 1);
        assert!(matches!(r.u32("b"), Err(VolumeError::Truncated { offset: 4, .. })));
        assert_eq!(r.u16("c").unwrap(), 5);
        assert_eq!(r.remaining(), 0);
    }

    #[test]
    fn string_length_is_checked_before_allocating() {
        let data = [0xff, 0xff, 0xff, 0x7f, b'a'];
        let mut r = ByteReader::new(&data, 0, Path::new("x"));
        assert!(matches!(r.string("name"), Err(VolumeError::Truncated { offset: 0, .. })));
    }
}
