//! OpenVDB's node value encoding (`io::readCompressedValues` and
//! `io::readData` in `openvdb/io/Compression.h`): a per-node metadata byte
//! that says how inactive values were dropped ("mask compression"), then the
//! remaining values, raw, zip-compressed or blosc-compressed, optionally as
//! half floats.

use half::f16;

use crate::io::blosc;
use crate::io::bytes::ByteReader;
use crate::VolumeError;

/// Per-grid compression flags (`io::COMPRESS_*`).
pub(crate) const COMPRESS_ZIP: u32 = 0x1;
pub(crate) const COMPRESS_ACTIVE_MASK: u32 = 0x2;
pub(crate) const COMPRESS_BLOSC: u32 = 0x4;

/// Metadata byte values (how inactive values were encoded).
const NO_MASK_OR_INACTIVE_VALS: u8 = 0;
const NO_MASK_AND_ONE_INACTIVE_VAL: u8 = 2;
const MASK_AND_NO_INACTIVE_VALS: u8 = 3;
const MASK_AND_ONE_INACTIVE_VAL: u8 = 4;
const MASK_AND_TWO_INACTIVE_VALS: u8 = 5;
const NO_MASK_AND_ALL_VALS: u8 = 6;

/// The scalar type a grid stores.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum ScalarKind {
    Float,
    Double,
}

impl ScalarKind {
    /// Bytes of one full-precision value.
    pub(crate) fn size(self) -> usize {
        match self {
            ScalarKind::Float => 4,
            ScalarKind::Double => 8,
        }
    }
}

/// A grid value: one component for scalar grids, three for Vec3 grids
/// (unused components are zero).
pub(crate) type Value = [f32; 3];

/// How a grid's node values are stored.
#[derive(Clone, Copy, Debug)]
pub(crate) struct ValueCodec {
    pub kind: ScalarKind,
    /// Components per value: 1 (scalar grids) or 3 (Vec3 grids, stored
    /// x, y, z consecutively).
    pub arity: usize,
    /// Node buffers hold 16-bit halves (`_HalfFloat` grids); backgrounds,
    /// tiles of the root and inactive values stay full precision.
    pub half: bool,
    pub compression: u32,
    pub background: Value,
}

/// Reads one full-precision value of `arity` components.
pub(crate) fn read_value(r: &mut ByteReader, kind: ScalarKind, arity: usize, what: &str) -> Result<Value, VolumeError> {
    let mut v = [0.0; 3];
    for c in v.iter_mut().take(arity) {
        *c = match kind {
            ScalarKind::Float => r.f32(what)?,
            ScalarKind::Double => r.f64(what)? as f32,
        };
    }
    Ok(v)
}

/// Reads a node bit mask of `bits` bits as little-endian 64-bit words.
pub(crate) fn read_mask(r: &mut ByteReader, bits: usize, what: &str) -> Result<Vec<u64>, VolumeError> {
    let b = r.bytes(bits / 8, what)?;
    Ok(b.chunks_exact(8).map(|c| u64::from_le_bytes([c[0], c[1], c[2], c[3], c[4], c[5], c[6], c[7]])).collect())
}

/// Whether bit `n` of `mask` is set.
#[inline]
pub(crate) fn bit(mask: &[u64], n: usize) -> bool {
    mask[n / 64] >> (n % 64) & 1 == 1
}

/// Indices of the set bits of `mask`, ascending.
pub(crate) fn ones(mask: &[u64]) -> impl Iterator<Item = usize> + '_ {
    mask.iter().enumerate().flat_map(|(w, &word)| {
        let mut word = word;
        std::iter::from_fn(move || {
            (word != 0).then(|| {
                let b = word.trailing_zeros() as usize;
                word &= word - 1;
                w * 64 + b
            })
        })
    })
}

/// Reads the `out.len() / codec.arity` values of a node whose value mask is
/// `value_mask` into `out`, components of one value consecutive (OpenVDB's
/// `readCompressedValues`).
pub(crate) fn read_compressed_values(
    r: &mut ByteReader,
    codec: &ValueCodec,
    value_mask: &[u64],
    out: &mut [f32],
) -> Result<(), VolumeError> {
    let arity = codec.arity;
    let count = out.len() / arity;
    let meta_pos = r.pos();
    let metadata = r.u8("node value metadata")?;
    if metadata > NO_MASK_AND_ALL_VALS {
        return Err(r.corrupt_at(meta_pos, format!("node value metadata {metadata} (expected 0 to 6)")));
    }
    let bg = codec.background;
    let mut inactive0 = if metadata == NO_MASK_OR_INACTIVE_VALS { bg } else { bg.map(|v| -v) };
    let mut inactive1 = bg;
    if matches!(metadata, NO_MASK_AND_ONE_INACTIVE_VAL | MASK_AND_ONE_INACTIVE_VAL | MASK_AND_TWO_INACTIVE_VALS) {
        inactive0 = read_value(r, codec.kind, arity, "inactive value")?;
        if metadata == MASK_AND_TWO_INACTIVE_VALS {
            inactive1 = read_value(r, codec.kind, arity, "second inactive value")?;
        }
    }
    let selection =
        if matches!(metadata, MASK_AND_NO_INACTIVE_VALS | MASK_AND_ONE_INACTIVE_VAL | MASK_AND_TWO_INACTIVE_VALS) {
            Some(read_mask(r, count, "inactive value selection mask")?)
        } else {
            None
        };

    let mask_compressed = codec.compression & COMPRESS_ACTIVE_MASK != 0;
    let stored = if mask_compressed && metadata != NO_MASK_AND_ALL_VALS {
        value_mask.iter().map(|w| w.count_ones() as usize).sum()
    } else {
        count
    };
    let values = read_data(r, codec, stored * arity)?;
    if stored == count {
        out.copy_from_slice(&values);
        return Ok(());
    }
    // Put the stored (active) values back in place and rebuild the inactive
    // ones from the background, the inactive values and the selection mask.
    let mut next = values.chunks_exact(arity);
    for (n, slot) in out.chunks_exact_mut(arity).enumerate() {
        if bit(value_mask, n) {
            slot.copy_from_slice(next.next().expect("one stored value per active bit"));
        } else if selection.as_deref().is_some_and(|s| bit(s, n)) {
            slot.copy_from_slice(&inactive1[..arity]);
        } else {
            slot.copy_from_slice(&inactive0[..arity]);
        }
    }
    Ok(())
}

/// Reads `count` scalars (value components) stored with the grid's compression
/// (`io::readData` / `HalfReader::read`).
fn read_data(r: &mut ByteReader, codec: &ValueCodec, count: usize) -> Result<Vec<f32>, VolumeError> {
    if codec.half && count == 0 {
        // HalfReader::read writes nothing at all for zero values.
        return Ok(Vec::new());
    }
    let elem = if codec.half { 2 } else { codec.kind.size() };
    let nbytes = count * elem;
    let bytes = if codec.compression & (COMPRESS_BLOSC | COMPRESS_ZIP) != 0 {
        let size_pos = r.pos();
        let size = r.i64("compressed chunk size")?;
        if size <= 0 {
            let raw = size.unsigned_abs() as usize;
            if raw != nbytes {
                return Err(r.corrupt_at(size_pos, format!("uncompressed chunk of {raw} bytes, expected {nbytes}")));
            }
            r.bytes(nbytes, "uncompressed node values")?.to_vec()
        } else {
            let size = size as u64;
            if size > r.remaining() as u64 {
                return Err(r.truncated(&format!("compressed node values ({size} bytes)")));
            }
            let data_pos = r.pos();
            let input = r.bytes(size as usize, "compressed node values")?;
            let mut out = vec![0u8; nbytes];
            if codec.compression & COMPRESS_BLOSC != 0 {
                blosc::decompress(input, &mut out).map_err(|e| r.corrupt_at(data_pos, e))?;
            } else {
                out = inflate_zlib(input, nbytes).map_err(|e| r.corrupt_at(data_pos, e))?;
            }
            out
        }
    } else {
        r.bytes(nbytes, "node values")?.to_vec()
    };
    Ok(decode(&bytes, codec, elem))
}

fn inflate_zlib(input: &[u8], nbytes: usize) -> Result<Vec<u8>, String> {
    let out = miniz_oxide::inflate::decompress_to_vec_zlib_with_limit(input, nbytes)
        .map_err(|e| format!("zip data does not inflate to {nbytes} bytes: {:?}", e.status))?;
    if out.len() != nbytes {
        return Err(format!("zip data inflates to {} bytes, expected {nbytes}", out.len()));
    }
    Ok(out)
}

fn decode(bytes: &[u8], codec: &ValueCodec, elem: usize) -> Vec<f32> {
    let chunks = bytes.chunks_exact(elem);
    if codec.half {
        chunks.map(|c| f16::from_le_bytes([c[0], c[1]]).to_f32()).collect()
    } else {
        match codec.kind {
            ScalarKind::Float => chunks.map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]])).collect(),
            ScalarKind::Double => {
                chunks.map(|c| f64::from_le_bytes([c[0], c[1], c[2], c[3], c[4], c[5], c[6], c[7]]) as f32).collect()
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    fn codec(compression: u32) -> ValueCodec {
        ValueCodec { kind: ScalarKind::Float, arity: 1, half: false, compression, background: [1.5, 0.0, 0.0] }
    }

    #[test]
    fn mask_compressed_values_rebuild_inactive_ones() {
        // 64 values, active bits 0 and 3; selection mask picks value 1 for bit 2.
        let mut file = vec![MASK_AND_ONE_INACTIVE_VAL];
        file.extend(7.0f32.to_le_bytes());
        file.extend(4u64.to_le_bytes());
        file.extend(0.25f32.to_le_bytes());
        file.extend(0.5f32.to_le_bytes());
        let mut r = ByteReader::new(&file, 0, Path::new("t"));
        let mut out = [0f32; 64];
        read_compressed_values(&mut r, &codec(COMPRESS_ACTIVE_MASK), &[0b1001], &mut out).unwrap();
        assert_eq!(&out[..5], &[0.25, 7.0, 1.5, 0.5, 7.0]);
        assert_eq!(r.remaining(), 0);
    }

    #[test]
    fn minus_background_case_uses_negated_background() {
        let mut file = vec![1u8];
        file.extend(2.0f32.to_le_bytes());
        let mut r = ByteReader::new(&file, 0, Path::new("t"));
        let mut out = [0f32; 64];
        read_compressed_values(&mut r, &codec(COMPRESS_ACTIVE_MASK), &[1], &mut out).unwrap();
        assert_eq!((out[0], out[1], out[63]), (2.0, -1.5, -1.5));
    }

    #[test]
    fn double_vec3_values_with_an_inactive_value_decode_per_component() {
        // Vec3d grid (the reference Python bindings cannot write one): 64
        // values, active bits 0 and 2, one inactive value for the rest.
        let mut file = vec![NO_MASK_AND_ONE_INACTIVE_VAL];
        for v in [9.0f64, 8.0, 7.0] {
            file.extend(v.to_le_bytes());
        }
        for v in [1.0f64, 2.0, 3.0, -4.0, 0.5, 0.25] {
            file.extend(v.to_le_bytes());
        }
        let mut r = ByteReader::new(&file, 0, Path::new("t"));
        let codec = ValueCodec {
            kind: ScalarKind::Double,
            arity: 3,
            half: false,
            compression: COMPRESS_ACTIVE_MASK,
            background: [0.0; 3],
        };
        let mut out = [0f32; 64 * 3];
        read_compressed_values(&mut r, &codec, &[0b101], &mut out).unwrap();
        assert_eq!(&out[..9], &[1.0, 2.0, 3.0, 9.0, 8.0, 7.0, -4.0, 0.5, 0.25]);
        assert_eq!(&out[189..], &[9.0, 8.0, 7.0]);
        assert_eq!(r.remaining(), 0);
    }

    #[test]
    fn bad_chunk_sizes_are_errors() {
        let mut file = vec![NO_MASK_AND_ALL_VALS];
        file.extend((-12i64).to_le_bytes());
        file.extend([0u8; 12]);
        let mut r = ByteReader::new(&file, 0, Path::new("t"));
        let mut out = [0f32; 64];
        assert!(read_compressed_values(&mut r, &codec(COMPRESS_ZIP), &[0], &mut out).is_err());
        let mut file = vec![NO_MASK_AND_ALL_VALS];
        file.extend(i64::MAX.to_le_bytes());
        let mut r = ByteReader::new(&file, 0, Path::new("t"));
        assert!(read_compressed_values(&mut r, &codec(COMPRESS_BLOSC), &[0], &mut out).is_err());
    }
}
