//! A bounds-checked little-endian cursor over a file, held in memory or
//! streamed from disk through a small window.
//!
//! Every read checks the remaining length first and reports a
//! [`VolumeError::Truncated`] naming what was being read, so that parsers
//! never index out of range and never allocate from an unchecked size.
//! A streamed cursor keeps only the bytes not yet consumed of its current
//! window (about [`STREAM_WINDOW`] bytes, or one read's size when larger),
//! so reading a large file does not hold the file in memory next to what is
//! decoded from it.

use std::fs::File;
use std::io::{Read, Seek, SeekFrom};
use std::path::Path;

use crate::VolumeError;

/// Bytes a streamed cursor reads from disk at a time.
pub(crate) const STREAM_WINDOW: usize = 1 << 20;

/// The open file and window of a streamed cursor.
struct Stream {
    file: File,
    /// Bytes `window_start..window_start + window.len()` of the file.
    window: Vec<u8>,
    window_start: usize,
}

/// Cursor over `data` (or a streamed file), reporting errors against `path`.
pub(crate) struct ByteReader<'a> {
    data: &'a [u8],
    stream: Option<Stream>,
    pos: usize,
    /// End of the readable bytes (`data.len()` in memory).
    end: usize,
    path: &'a Path,
}

impl<'a> ByteReader<'a> {
    /// A cursor at byte `pos` of `data` (which may be shorter than the file
    /// when a parser wants to stop at a known end).
    pub(crate) fn new(data: &'a [u8], pos: usize, path: &'a Path) -> Self {
        Self { data, stream: None, pos, end: data.len(), path }
    }

    /// A cursor streaming the file at `path` from byte `pos`, readable up
    /// to byte `end` or the end of the file, whichever comes first.
    pub(crate) fn open_stream(path: &'a Path, pos: usize, end: usize) -> Result<Self, VolumeError> {
        let io = |source| VolumeError::Io { path: path.to_path_buf(), source };
        let file = File::open(path).map_err(io)?;
        let len = file.metadata().map_err(io)?.len();
        let end = end.min(usize::try_from(len).unwrap_or(usize::MAX));
        let stream = Stream { file, window: Vec::new(), window_start: 0 };
        Ok(Self { data: &[], stream: Some(stream), pos, end, path })
    }

    /// Moves the cursor to byte `pos`.
    pub(crate) fn seek(&mut self, pos: usize) {
        self.pos = pos;
    }

    /// End of the readable bytes (the file length unless a parser set an
    /// earlier end).
    pub(crate) fn len(&self) -> usize {
        self.end
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
        self.end.saturating_sub(self.pos)
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
    pub(crate) fn bytes(&mut self, n: usize, what: &str) -> Result<&[u8], VolumeError> {
        if n > self.remaining() {
            return Err(self.truncated(what));
        }
        let pos = self.pos;
        self.pos += n;
        match &mut self.stream {
            None => Ok(&self.data[pos..pos + n]),
            Some(s) => {
                s.fill(pos, n, self.end).map_err(|source| VolumeError::Io { path: self.path.to_path_buf(), source })?;
                let at = pos - s.window_start;
                Ok(&s.window[at..at + n])
            }
        }
    }

    /// Skips `n` bytes (without reading them from a streamed file).
    pub(crate) fn skip(&mut self, n: usize, what: &str) -> Result<(), VolumeError> {
        if n > self.remaining() {
            return Err(self.truncated(what));
        }
        self.pos += n;
        Ok(())
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

impl Stream {
    /// Makes the window hold bytes `pos..pos + n` (`pos + n <= end`),
    /// dropping the bytes before `pos` and reading at least
    /// [`STREAM_WINDOW`] bytes ahead when it has to read.
    fn fill(&mut self, pos: usize, n: usize, end: usize) -> std::io::Result<()> {
        let window_end = self.window_start + self.window.len();
        if pos >= self.window_start && pos + n <= window_end {
            return Ok(());
        }
        if pos >= self.window_start && pos <= window_end {
            // Keep the unread tail, read on from where the file is.
            self.window.drain(..pos - self.window_start);
        } else {
            self.window.clear();
            self.file.seek(SeekFrom::Start(pos as u64))?;
        }
        self.window_start = pos;
        let have = self.window.len();
        let want = n.max(STREAM_WINDOW).min(end - pos).max(have);
        self.window.resize(want, 0);
        self.file.read_exact(&mut self.window[have..])
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
    fn streamed_reads_equal_in_memory_reads_across_windows() {
        let data: Vec<u8> = (0..3 * STREAM_WINDOW + 17).map(|i| (i * 7 % 251) as u8).collect();
        let path = std::env::temp_dir().join(format!("niebla_bytes_stream_{}.bin", std::process::id()));
        std::fs::write(&path, &data).unwrap();
        let mut m = ByteReader::new(&data, 3, &path);
        let mut s = ByteReader::open_stream(&path, 3, usize::MAX).unwrap();
        assert_eq!(s.len(), data.len());
        // Small reads, a read larger than the window, a skip past the
        // window, a seek back, and a read that runs off the end.
        for (n, skip) in [(5, 0), (STREAM_WINDOW - 3, 0), (2 * STREAM_WINDOW / 3, 11), (STREAM_WINDOW + 5, 0), (9, 0)] {
            assert_eq!(m.bytes(n, "x").unwrap(), s.bytes(n, "x").unwrap());
            m.skip(skip, "x").unwrap();
            s.skip(skip, "x").unwrap();
        }
        m.seek(100);
        s.seek(100);
        assert_eq!(m.u32("x").unwrap(), s.u32("x").unwrap());
        m.seek(data.len() - 2);
        s.seek(data.len() - 2);
        assert!(matches!(s.u32("x"), Err(VolumeError::Truncated { .. })));
        assert!(matches!(m.u32("x"), Err(VolumeError::Truncated { .. })));
        std::fs::remove_file(&path).unwrap();
    }

    #[test]
    fn string_length_is_checked_before_allocating() {
        let data = [0xff, 0xff, 0xff, 0x7f, b'a'];
        let mut r = ByteReader::new(&data, 0, Path::new("x"));
        assert!(matches!(r.string("name"), Err(VolumeError::Truncated { offset: 0, .. })));
    }
}
