//! Decompression of blosc1 frames, as OpenVDB writes them for
//! `COMPRESS_BLOSC` (pure Rust; codecs lz4/lz4hc and zlib).
//!
//! A frame is a 16-byte header (version, codec version, flags, type size,
//! uncompressed size, block size, compressed size), then, unless the frame
//! is a plain copy, one i32 start offset per block, and per block one or
//! `typesize` "splits" of `i32 size + codec stream` (a split whose size
//! equals its uncompressed size is stored raw). Flags: bit 0 byte shuffle,
//! bit 1 plain copy, bit 2 bit shuffle, bit 4 "do not split", bits 5-7 the
//! codec (0 blosclz, 1 lz4, 2 snappy, 3 zlib, 4 zstd). Reference: the
//! c-blosc 1.x `README_HEADER.rst` and `blosc_d`; OpenVDB 10 writes lz4
//! with byte shuffle, type size 4 and one block per buffer.

/// Header size of a blosc1 frame.
pub(crate) const HEADER_SIZE: usize = 16;

const FLAG_SHUFFLE: u8 = 0x1;
const FLAG_MEMCPYED: u8 = 0x2;
const FLAG_BITSHUFFLE: u8 = 0x4;
const FLAG_DONT_SPLIT: u8 = 0x10;
const MAX_SPLITS: usize = 16;
const MIN_BUFFERSIZE: usize = 128;

fn u32_at(b: &[u8], at: usize) -> Result<u32, String> {
    b.get(at..at + 4)
        .map(|s| u32::from_le_bytes([s[0], s[1], s[2], s[3]]))
        .ok_or_else(|| format!("blosc frame ends at byte {} inside a size field", b.len()))
}

/// Decompresses the blosc1 frame `src` into `dest`, whose length must be
/// the frame's uncompressed size. Errors are messages for the caller to
/// wrap with the file and offset.
pub(crate) fn decompress(src: &[u8], dest: &mut [u8]) -> Result<(), String> {
    if src.len() < HEADER_SIZE {
        return Err(format!("blosc frame of {} bytes is shorter than its header", src.len()));
    }
    let (version, flags, typesize) = (src[0], src[2], src[3] as usize);
    let nbytes = u32_at(src, 4)? as usize;
    let blocksize = u32_at(src, 8)? as usize;
    let cbytes = u32_at(src, 12)? as usize;
    if version == 0 || version > 3 {
        return Err(format!("blosc format version {version} (expected 1 to 3)"));
    }
    if nbytes != dest.len() {
        return Err(format!("blosc frame holds {nbytes} bytes, expected {}", dest.len()));
    }
    if cbytes > src.len() || cbytes < HEADER_SIZE {
        return Err(format!("blosc frame claims {cbytes} bytes, {} available", src.len()));
    }
    let src = &src[..cbytes];
    if nbytes == 0 {
        return Ok(());
    }
    if flags & FLAG_MEMCPYED != 0 {
        let body = src
            .get(HEADER_SIZE..HEADER_SIZE + nbytes)
            .ok_or_else(|| format!("uncompressed blosc frame shorter than {nbytes} bytes"))?;
        dest.copy_from_slice(body);
        return Ok(());
    }
    if flags & FLAG_BITSHUFFLE != 0 {
        return Err("blosc bit shuffle is not supported".to_string());
    }
    if blocksize == 0 || typesize == 0 {
        return Err(format!("blosc block size {blocksize}, type size {typesize}"));
    }
    let nblocks = nbytes.div_ceil(blocksize);
    if HEADER_SIZE + 4 * nblocks > src.len() {
        return Err(format!("blosc frame too short for {nblocks} block offsets"));
    }
    let codec = flags >> 5;
    let shuffle = flags & FLAG_SHUFFLE != 0 && typesize > 1;
    let mut tmp = if shuffle { vec![0u8; blocksize] } else { Vec::new() };
    for j in 0..nblocks {
        let start = u32_at(src, HEADER_SIZE + 4 * j)? as usize;
        let block_start = j * blocksize;
        let bsize = blocksize.min(nbytes - block_start);
        let leftover = bsize < blocksize;
        let out = &mut dest[block_start..block_start + bsize];
        let target: &mut [u8] = if shuffle { &mut tmp[..bsize] } else { out };
        let splits = if flags & FLAG_DONT_SPLIT == 0
            && typesize <= MAX_SPLITS
            && bsize / typesize >= MIN_BUFFERSIZE
            && !leftover
        {
            typesize
        } else {
            1
        };
        decode_block(src, start, target, splits, codec)?;
        if shuffle {
            unshuffle(typesize, &tmp[..bsize], &mut dest[block_start..block_start + bsize]);
        }
    }
    Ok(())
}

/// Decodes the `splits` codec streams of one block starting at `start`.
fn decode_block(src: &[u8], start: usize, out: &mut [u8], splits: usize, codec: u8) -> Result<(), String> {
    let neblock = out.len() / splits;
    if neblock * splits != out.len() {
        return Err(format!("blosc block of {} bytes cannot split in {splits}", out.len()));
    }
    let mut pos = start;
    for part in out.chunks_mut(neblock) {
        let csize = u32_at(src, pos)? as i32;
        pos += 4;
        if csize < 0 {
            return Err(format!("negative blosc split size {csize}"));
        }
        let csize = csize as usize;
        let input =
            src.get(pos..pos + csize).ok_or_else(|| format!("blosc split of {csize} bytes runs past the frame"))?;
        pos += csize;
        if csize == neblock {
            part.copy_from_slice(input);
            continue;
        }
        let written = match codec {
            1 => lz4_flex::block::decompress_into(input, part).map_err(|e| format!("lz4: {e}"))?,
            3 => {
                let v = miniz_oxide::inflate::decompress_to_vec_zlib_with_limit(input, neblock)
                    .map_err(|e| format!("blosc zlib: {e:?}"))?;
                let n = v.len().min(part.len());
                part[..n].copy_from_slice(&v[..n]);
                v.len()
            }
            0 => return Err("blosc codec blosclz is not supported (only lz4 and zlib)".into()),
            2 => return Err("blosc codec snappy is not supported (only lz4 and zlib)".into()),
            4 => return Err("blosc codec zstd is not supported (only lz4 and zlib)".into()),
            c => return Err(format!("unknown blosc codec {c}")),
        };
        if written != neblock {
            return Err(format!("blosc split decoded to {written} bytes, expected {neblock}"));
        }
    }
    Ok(())
}

/// Undoes blosc's byte shuffle: byte `j` of element `i` was stored at
/// `j * count + i`; trailing bytes beyond whole elements are stored as is.
fn unshuffle(typesize: usize, src: &[u8], dest: &mut [u8]) {
    let count = src.len() / typesize;
    for i in 0..count {
        for j in 0..typesize {
            dest[i * typesize + j] = src[j * count + i];
        }
    }
    let tail = count * typesize;
    dest[tail..].copy_from_slice(&src[tail..]);
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A frame with one lz4 block, byte-shuffled, as OpenVDB writes it.
    fn frame(values: &[f32]) -> Vec<u8> {
        let raw: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
        let n = raw.len() / 4;
        let mut shuffled = vec![0u8; raw.len()];
        for i in 0..n {
            for j in 0..4 {
                shuffled[j * n + i] = raw[i * 4 + j];
            }
        }
        let compressed = lz4_flex::block::compress(&shuffled);
        let mut out = vec![2, 1, FLAG_SHUFFLE | FLAG_DONT_SPLIT | (1 << 5), 4];
        out.extend((raw.len() as u32).to_le_bytes());
        out.extend((raw.len() as u32).to_le_bytes());
        let total = HEADER_SIZE + 4 + 4 + compressed.len();
        out.extend((total as u32).to_le_bytes());
        out.extend(((HEADER_SIZE + 4) as u32).to_le_bytes());
        out.extend((compressed.len() as u32).to_le_bytes());
        out.extend(compressed);
        out
    }

    #[test]
    fn lz4_shuffled_frame_round_trips() {
        let values: Vec<f32> = (0..512).map(|i| (i % 37) as f32 * 0.25).collect();
        let f = frame(&values);
        let mut out = vec![0u8; 2048];
        decompress(&f, &mut out).unwrap();
        let back: Vec<f32> = out.chunks(4).map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]])).collect();
        assert_eq!(back, values);
    }

    /// A frame of two blocks (the second a leftover), each split per byte
    /// plane, compressed with zlib: the paths OpenVDB 10 does not use.
    #[test]
    fn split_zlib_frames_with_leftover_blocks_decode() {
        let raw: Vec<u8> = (0..3000u32).flat_map(|i| ((i % 50) as f32).to_le_bytes()).collect();
        let (typesize, blocksize) = (4usize, 8192usize);
        let mut blocks = Vec::new();
        for (j, block) in raw.chunks(blocksize).enumerate() {
            let count = block.len() / typesize;
            let mut shuffled = vec![0u8; block.len()];
            for i in 0..count {
                for b in 0..typesize {
                    shuffled[b * count + i] = block[i * typesize + b];
                }
            }
            let leftover = block.len() < blocksize;
            let splits = if leftover { 1 } else { typesize };
            let mut encoded = Vec::new();
            for part in shuffled.chunks(block.len() / splits) {
                let z = miniz_oxide::deflate::compress_to_vec_zlib(part, 6);
                encoded.extend((z.len() as u32).to_le_bytes());
                encoded.extend(z);
            }
            assert_eq!(leftover, j == 1);
            blocks.push(encoded);
        }
        let mut out = vec![2, 1, FLAG_SHUFFLE | (3 << 5), typesize as u8];
        out.extend((raw.len() as u32).to_le_bytes());
        out.extend((blocksize as u32).to_le_bytes());
        let total = HEADER_SIZE + 8 + blocks.iter().map(Vec::len).sum::<usize>();
        out.extend((total as u32).to_le_bytes());
        out.extend(((HEADER_SIZE + 8) as u32).to_le_bytes());
        out.extend(((HEADER_SIZE + 8 + blocks[0].len()) as u32).to_le_bytes());
        for b in blocks {
            out.extend(b);
        }
        let mut back = vec![0u8; raw.len()];
        decompress(&out, &mut back).unwrap();
        assert_eq!(back, raw);
    }

    #[test]
    fn damaged_frames_are_errors() {
        let values: Vec<f32> = (0..512).map(|i| i as f32).collect();
        let f = frame(&values);
        let mut out = vec![0u8; 2048];
        for cut in [0, 10, 16, 20, 24, f.len() - 1] {
            assert!(decompress(&f[..cut], &mut out).is_err(), "cut at {cut}");
        }
        let mut wrong_size = vec![0u8; 2044];
        assert!(decompress(&f, &mut wrong_size).is_err());
        let mut garbage = f.clone();
        for b in garbage[24..].iter_mut() {
            *b = 0xff;
        }
        assert!(decompress(&garbage, &mut out).is_err());
    }
}
