//! A cursor over a PSD file's bytes: every read checked against the bytes that remain, so that
//! no length or count declared by the file is trusted before the bytes it speaks of are there.

use super::damaged;
use crate::parts::layers::LayersError;

/// Reads big-endian fields from a slice, refusing any read past its end.
#[derive(Clone, Copy, Debug)]
pub(super) struct Bytes<'a> {
    data: &'a [u8],
    at: usize,
}

impl<'a> Bytes<'a> {
    /// A cursor at the start of `data`.
    pub(super) fn new(data: &'a [u8]) -> Self {
        Bytes { data, at: 0 }
    }

    /// Bytes not yet read.
    pub(super) fn remaining(&self) -> usize {
        self.data.len() - self.at
    }

    /// Whether the bytes left start with `prefix`.
    pub(super) fn starts_with(&self, prefix: &[u8]) -> bool {
        self.data[self.at..].starts_with(prefix)
    }

    /// The next `n` bytes (`what` names them in the error).
    pub(super) fn take(&mut self, n: u64, what: &str) -> Result<&'a [u8], LayersError> {
        if n > self.remaining() as u64 {
            return Err(damaged(format!(
                "{what} needs {n} bytes but only {} are left",
                self.remaining()
            )));
        }
        let n = n as usize;
        let out = &self.data[self.at..self.at + n];
        self.at += n;
        Ok(out)
    }

    /// A cursor over the next `n` bytes, which this one skips.
    pub(super) fn sub(&mut self, n: u64, what: &str) -> Result<Bytes<'a>, LayersError> {
        Ok(Bytes::new(self.take(n, what)?))
    }

    /// One byte.
    pub(super) fn u8(&mut self, what: &str) -> Result<u8, LayersError> {
        Ok(self.take(1, what)?[0])
    }

    /// A big-endian `u16`.
    pub(super) fn u16(&mut self, what: &str) -> Result<u16, LayersError> {
        let b = self.take(2, what)?;
        Ok(u16::from_be_bytes([b[0], b[1]]))
    }

    /// A big-endian `u32`.
    pub(super) fn u32(&mut self, what: &str) -> Result<u32, LayersError> {
        let b = self.take(4, what)?;
        Ok(u32::from_be_bytes([b[0], b[1], b[2], b[3]]))
    }

    /// A big-endian `i32`.
    pub(super) fn i32(&mut self, what: &str) -> Result<i32, LayersError> {
        Ok(self.u32(what)? as i32)
    }

    /// A big-endian `u64`.
    pub(super) fn u64(&mut self, what: &str) -> Result<u64, LayersError> {
        let b = self.take(8, what)?;
        let mut a = [0u8; 8];
        a.copy_from_slice(b);
        Ok(u64::from_be_bytes(a))
    }

    /// A length: 4 bytes in a PSD, 8 in a PSB (`long`).
    pub(super) fn len(&mut self, long: bool, what: &str) -> Result<u64, LayersError> {
        if long {
            self.u64(what)
        } else {
            self.u32(what).map(u64::from)
        }
    }

    /// A section: its length (4 or 8 bytes) and then that many bytes.
    pub(super) fn section(&mut self, long: bool, what: &str) -> Result<Bytes<'a>, LayersError> {
        let n = self.len(long, what)?;
        self.sub(n, what)
    }
}
