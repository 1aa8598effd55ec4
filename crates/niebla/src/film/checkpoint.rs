//! Checkpoints: the EXR a progressive render rewrites after every pass,
//! carrying in its header what is needed to continue it exactly, and in
//! extra channels the exact sums that let sample ranges be added up.
//!
//! Header attributes (EXR text attributes of the layer):
//! - `nieblaCheckpoint`: the format version, `2` (`1`: written before the
//!   sums and sample ranges were stored; still read);
//! - `nieblaSpp`: samples per pixel accumulated in the pixels;
//! - `nieblaSampleRanges`: the sample indices accumulated, as half-open
//!   ranges in increasing order, `first..end` separated by commas (e.g.
//!   `0..64` or `0..16,32..48`); absent in version 1 (`0..spp`);
//! - `nieblaSeed`: the sampler seed (decimal, all 64 bits);
//! - `nieblaSceneHash`: [`scene_hash`] of the scene file's text;
//! - `nieblaIntegrator`: the integrator settings (their stable key).
//!
//! Channels: `R`, `G`, `B` hold the f32 mean of those samples (what any EXR
//! viewer shows); version 2 adds, per color `C`, the exact fixed-point sums
//! (`SampleSums`) as four `u32` channels `niebla.sum.C.0` .. `niebla.sum.C.3`
//! (the two's complement `i128`, least significant word first). The
//! progressive accumulator works on these sums, so continuing from a
//! checkpoint, or adding checkpoints of disjoint sample ranges
//! (`niebla merge`), gives the image of one render of all their samples,
//! bit for bit.

use std::path::{Path, PathBuf};

use super::{write_atomically, Image, OutputError, SampleSums};

const VERSION: &str = "2";

/// Version 1 checkpoints (the mean alone) are still read.
const VERSION_MEAN_ONLY: &str = "1";

/// How a checkpoint image was rendered.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct CheckpointInfo {
    /// Samples per pixel accumulated (the next pass starts at this sample
    /// index).
    pub spp: u64,
    /// Sampler seed.
    pub seed: u64,
    /// [`scene_hash`] of the scene text.
    pub scene_hash: String,
    /// The integrator settings (`IntegratorSettings::key`).
    pub integrator: String,
    /// The sample indices accumulated: half-open ranges `(first, end)`,
    /// increasing and disjoint, whose lengths add up to `spp`.
    pub ranges: Vec<(u64, u64)>,
}

impl CheckpointInfo {
    /// The `nieblaSampleRanges` text of `ranges`: `first..end` joined by commas.
    ///
    /// ```
    /// use niebla::film::CheckpointInfo;
    /// assert_eq!(CheckpointInfo::ranges_text(&[(0, 8), (16, 20)]), "0..8,16..20");
    /// ```
    pub fn ranges_text(ranges: &[(u64, u64)]) -> String {
        ranges.iter().map(|(a, b)| format!("{a}..{b}")).collect::<Vec<_>>().join(",")
    }

    /// Reads a `nieblaSampleRanges` text; `None` if malformed, empty,
    /// unordered, overlapping or with an empty range.
    ///
    /// ```
    /// use niebla::film::CheckpointInfo;
    /// assert_eq!(CheckpointInfo::parse_ranges("0..8,16..20"), Some(vec![(0, 8), (16, 20)]));
    /// assert_eq!(CheckpointInfo::parse_ranges("0..8,4..20"), None);
    /// ```
    pub fn parse_ranges(text: &str) -> Option<Vec<(u64, u64)>> {
        let mut ranges = Vec::new();
        for part in text.split(',') {
            let (a, b) = part.trim().split_once("..")?;
            let (a, b): (u64, u64) = (a.parse().ok()?, b.parse().ok()?);
            if a >= b || ranges.last().is_some_and(|&(_, end)| end > a) {
                return None;
            }
            ranges.push((a, b));
        }
        Some(ranges)
    }
}

/// A checkpoint as read: its mean image, how it was rendered, and its exact
/// sums (`None` for version 1 files, which stored only the mean).
#[derive(Clone, Debug, PartialEq)]
pub struct Checkpoint {
    /// The f32 mean image (the R, G, B channels).
    pub image: Image,
    /// The header.
    pub info: CheckpointInfo,
    /// The exact per-pixel sums.
    pub sums: Option<SampleSums>,
}

/// Why a checkpoint cannot be read.
#[derive(Debug, thiserror::Error)]
pub enum CheckpointError {
    /// The file is missing, not an EXR, or has no RGB layer.
    #[error("{path}: cannot read the checkpoint: {message}")]
    Read {
        /// The file.
        path: PathBuf,
        /// The decoder's message.
        message: String,
    },
    /// The EXR lacks an attribute or has a malformed one.
    #[error("{path}: not a niebla checkpoint: {message}")]
    NotCheckpoint {
        /// The file.
        path: PathBuf,
        /// What is missing or wrong.
        message: String,
    },
}

/// A 64-bit FNV-1a hash of the scene file's bytes as 16 hex digits: the
/// checkpoint's proof that `--resume` renders the same scene. (Files the
/// scene refers to, such as grids, are not hashed.)
///
/// ```
/// assert_eq!(niebla::film::scene_hash(b""), "cbf29ce484222325");
/// assert_ne!(niebla::film::scene_hash(b"{}"), niebla::film::scene_hash(b"{ }"));
/// ```
pub fn scene_hash(text: &[u8]) -> String {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for &b in text {
        h ^= u64::from(b);
        h = h.wrapping_mul(0x0000_0100_0000_01b3);
    }
    format!("{h:016x}")
}

/// Name of the channel holding 32-bit word `word` (0 = least significant)
/// of the sums of color channel `color` (0, 1, 2 = R, G, B).
fn sum_channel_name(color: usize, word: usize) -> String {
    format!("niebla.sum.{}.{word}", ["R", "G", "B"][color])
}

/// Writes the mean of `sums` (over `info.spp` samples per pixel) and the
/// sums themselves to the EXR `path` with `info` in its header, through a
/// temporary file and a rename.
pub fn write_checkpoint(sums: &SampleSums, info: &CheckpointInfo, path: &Path) -> Result<(), OutputError> {
    write_checkpoint_with(sums, info, path, Vec::new(), &[])
}

/// [`write_checkpoint`] with `extra` channels (the layers of `crate::aov`
/// and their sums) and extra text attributes.
pub(crate) fn write_checkpoint_with(
    sums: &SampleSums,
    info: &CheckpointInfo,
    path: &Path,
    extra: Vec<exr::prelude::AnyChannel<exr::prelude::FlatSamples>>,
    extra_attributes: &[(&str, String)],
) -> Result<(), OutputError> {
    use exr::prelude::*;
    let encode = |message: String| OutputError::Encode { path: path.to_path_buf(), message };
    let attributes = [
        ("nieblaCheckpoint", VERSION.to_string()),
        ("nieblaSpp", info.spp.to_string()),
        ("nieblaSampleRanges", CheckpointInfo::ranges_text(&info.ranges)),
        ("nieblaSeed", info.seed.to_string()),
        ("nieblaSceneHash", info.scene_hash.clone()),
        ("nieblaIntegrator", info.integrator.clone()),
    ];
    let mean = sums.mean(info.spp);
    let mut list: SmallVec<[AnyChannel<FlatSamples>; 4]> = SmallVec::new();
    for (color, name) in ["R", "G", "B"].iter().enumerate() {
        let values = mean.pixels.iter().map(|p| p[color]).collect();
        list.push(AnyChannel::new(*name, FlatSamples::F32(values)));
        for word in 0..4 {
            let values = sums.sums.iter().map(|s| (s[color] as u128 >> (32 * word)) as u32).collect();
            list.push(AnyChannel::new(sum_channel_name(color, word).as_str(), FlatSamples::U32(values)));
        }
    }
    list.extend(extra);
    let mut layer_attributes = LayerAttributes::default();
    for (name, value) in attributes.into_iter().chain(extra_attributes.iter().map(|(n, v)| (*n, v.clone()))) {
        let value =
            Text::new_or_none(&value).ok_or_else(|| encode(format!("attribute value {value:?} is not ASCII")))?;
        layer_attributes.other.insert(Text::from(name), AttributeValue::Text(value));
    }
    let size = (sums.width as usize, sums.height as usize);
    let layer = Layer::new(size, layer_attributes, Encoding::SMALL_LOSSLESS, AnyChannels::sort(list));
    let mut bytes = Vec::new();
    exr::image::Image::from_layer(layer)
        .write()
        .non_parallel()
        .to_buffered(std::io::Cursor::new(&mut bytes))
        .map_err(|e| encode(e.to_string()))?;
    write_atomically(path, &bytes)
}

/// The sums stored in the EXR bytes of a version 2 checkpoint of
/// `width` x `height` pixels.
fn read_sums(bytes: &[u8], width: u32, height: u32) -> Result<SampleSums, String> {
    use exr::prelude::*;
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .from_buffered(std::io::Cursor::new(bytes))
        .map_err(|e| e.to_string())?;
    let mut sums = SampleSums::new(width, height);
    for color in 0..3 {
        for word in 0..4 {
            let name = sum_channel_name(color, word);
            let channel = image.layer_data.channel_data.list.iter().find(|c| c.name.eq(name.as_str()));
            let Some(FlatSamples::U32(values)) = channel.map(|c| &c.sample_data) else {
                return Err(format!("the u32 channel {name} of the exact sums is missing"));
            };
            if values.len() != sums.sums.len() {
                return Err(format!("channel {name} has {} values for {} pixels", values.len(), sums.sums.len()));
            }
            for (s, &v) in sums.sums.iter_mut().zip(values) {
                s[color] = (s[color] as u128 | (v as u128) << (32 * word)) as i128;
            }
        }
    }
    Ok(sums)
}

/// Reads a checkpoint written by [`write_checkpoint`]: its mean image and
/// how it was rendered (see [`read_checkpoint_full`] for the sums).
pub fn read_checkpoint(path: &Path) -> Result<(Image, CheckpointInfo), CheckpointError> {
    let Checkpoint { image, info, .. } = read_checkpoint_full(path)?;
    Ok((image, info))
}

/// Reads a checkpoint: its mean image, header and exact sums (none in a
/// version 1 checkpoint).
///
/// ```
/// use niebla::film::{quantize_sample, read_checkpoint_full, write_checkpoint, CheckpointInfo, SampleSums};
/// let path = std::env::temp_dir().join(format!("niebla_doc_checkpoint_{}.exr", std::process::id()));
/// let mut sums = SampleSums::new(3, 2);
/// sums.sums[4] = [quantize_sample(0.1), -1, i128::MAX >> 3];
/// let info = CheckpointInfo {
///     spp: 8,
///     seed: u64::MAX,
///     scene_hash: "00ff".into(),
///     integrator: "volpath".into(),
///     ranges: vec![(0, 4), (12, 16)],
/// };
/// write_checkpoint(&sums, &info, &path)?;
/// let read = read_checkpoint_full(&path)?;
/// assert_eq!((read.image, read.info, read.sums), (sums.mean(8), info, Some(sums)));
/// # std::fs::remove_file(&path).unwrap();
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn read_checkpoint_full(path: &Path) -> Result<Checkpoint, CheckpointError> {
    let read =
        super::read_exr(path).map_err(|e| CheckpointError::Read { path: path.to_path_buf(), message: e.reason() })?;
    let text = |name: &str| -> std::result::Result<String, CheckpointError> {
        read.text_attributes.get(name).cloned().ok_or_else(|| CheckpointError::NotCheckpoint {
            path: path.to_path_buf(),
            message: format!("the header has no text attribute {name} (was it written by `niebla render`?)"),
        })
    };
    let number = |name: &str| -> std::result::Result<u64, CheckpointError> {
        let t = text(name)?;
        t.parse().map_err(|_| CheckpointError::NotCheckpoint {
            path: path.to_path_buf(),
            message: format!("attribute {name} = {t:?} is not a whole number"),
        })
    };
    let version = text("nieblaCheckpoint")?;
    if version != VERSION && version != VERSION_MEAN_ONLY {
        return Err(CheckpointError::NotCheckpoint {
            path: path.to_path_buf(),
            message: format!(
                "checkpoint format version {version:?} (this niebla reads {VERSION_MEAN_ONLY} and {VERSION})"
            ),
        });
    }
    let not_checkpoint = |message: String| CheckpointError::NotCheckpoint { path: path.to_path_buf(), message };
    let spp = number("nieblaSpp")?;
    let ranges = if version == VERSION_MEAN_ONLY {
        vec![(0, spp)]
    } else {
        let t = text("nieblaSampleRanges")?;
        let ranges = CheckpointInfo::parse_ranges(&t).ok_or_else(|| {
            not_checkpoint(format!("attribute nieblaSampleRanges = {t:?} is not increasing disjoint ranges a..b"))
        })?;
        let count: u64 = ranges.iter().map(|(a, b)| b - a).sum();
        if count != spp {
            return Err(not_checkpoint(format!("nieblaSampleRanges {t} hold {count} samples, nieblaSpp says {spp}")));
        }
        ranges
    };
    let info = CheckpointInfo {
        spp,
        seed: number("nieblaSeed")?,
        scene_hash: text("nieblaSceneHash")?,
        integrator: text("nieblaIntegrator")?,
        ranges,
    };
    let sums = if version == VERSION_MEAN_ONLY {
        None
    } else {
        let bytes = std::fs::read(path)
            .map_err(|e| CheckpointError::Read { path: path.to_path_buf(), message: e.to_string() })?;
        Some(read_sums(&bytes, read.image.width, read.image.height).map_err(not_checkpoint)?)
    };
    Ok(Checkpoint { image: read.image, info, sums })
}
