//! Files with layers: the multilayer EXR (the checkpoint of `film` plus one
//! channel group per layer, `A` for alpha, `NAME.R/G/B`, `normal.X/Y/Z`,
//! `depth.Z`, and the layers' exact sums for resuming) and the RGBA PNG.

use std::path::Path;

use crate::color::{rgb_to_srgb8, Rgb};
use crate::film::{write_checkpoint_with, CheckpointInfo, Image, OutputError, SampleSums};

use super::{AovSet, AovSums};

/// Header attribute listing the layers whose sums a checkpoint holds.
const AOVS_ATTRIBUTE: &str = "nieblaAovs";

/// Ends [`AOVS_ATTRIBUTE`] for a render with a held-out background.
const TRANSPARENT_SUFFIX: &str = ";transparent";

/// Name of 32-bit word `word` of the sums of stored channel `name`.
fn sum_word_name(name: &str, word: usize) -> String {
    format!("niebla.aovsum.{name}.{word}")
}

/// Writes the checkpoint EXR of `sums` (as `film::write_checkpoint`) with
/// the layers of `aov` as extra channels and their exact sums, so that
/// `read_aov_sums` can continue them. The header attribute `nieblaAovs`
/// lists the layers, followed by `;transparent` for a held-out background.
pub fn write_aov_checkpoint(
    sums: &SampleSums,
    aov: &AovSums,
    info: &CheckpointInfo,
    transparent: bool,
    path: &Path,
) -> Result<(), OutputError> {
    use exr::prelude::*;
    let layers = aov.layers(sums, info.spp);
    let mut extra = Vec::new();
    for layer in &layers.layers {
        for (c, name) in layer.channel_names().iter().enumerate() {
            let values = layer.data.iter().skip(c).step_by(layer.components).copied().collect();
            extra.push(AnyChannel::new(name.as_str(), FlatSamples::F32(values)));
        }
    }
    let k = aov.channels.len();
    for (i, ch) in aov.channels.iter().enumerate() {
        for word in 0..4 {
            let values = aov.values.iter().skip(i).step_by(k).map(|&s| (s as u128 >> (32 * word)) as u32).collect();
            extra.push(AnyChannel::new(sum_word_name(&ch.name(), word).as_str(), FlatSamples::U32(values)));
        }
    }
    let names: Vec<&str> = aov.set.iter().map(|a| a.name()).collect();
    let recorded = names.join(",") + if transparent { TRANSPARENT_SUFFIX } else { "" };
    write_checkpoint_with(sums, info, path, extra, &[(AOVS_ATTRIBUTE, recorded)])
}

/// The layer sums of `set` stored in the checkpoint EXR `path` of
/// `width` x `height` pixels: `Ok(None)` if it stores no layers, an error
/// message if it stores others than `set`, was (or was not) `transparent`
/// unlike this render, or a channel is missing.
pub fn read_aov_sums(
    path: &Path,
    set: AovSet,
    transparent: bool,
    width: u32,
    height: u32,
) -> Result<Option<AovSums>, String> {
    use exr::prelude::*;
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .from_file(path)
        .map_err(|e| e.to_string())?;
    let recorded = image.layer_data.attributes.other.get(&Text::from(AOVS_ATTRIBUTE)).and_then(|v| match v {
        AttributeValue::Text(t) => Some(t.to_string()),
        _ => None,
    });
    let Some(recorded) = recorded else {
        return Ok(None);
    };
    let (list, was_transparent) = match recorded.strip_suffix(TRANSPARENT_SUFFIX) {
        Some(list) => (list, true),
        None => (recorded.as_str(), false),
    };
    if was_transparent != transparent {
        let film = |t: bool| if t { "a transparent" } else { "an opaque" };
        return Err(format!(
            "was rendered with {} background, this render has {}",
            film(was_transparent),
            film(transparent)
        ));
    }
    let recorded_set = AovSet::parse_list(list).map_err(|e| format!("attribute {AOVS_ATTRIBUTE}: {e}"))?;
    if recorded_set != set {
        return Err(format!("holds the layers {recorded:?}, not those asked for"));
    }
    let mut sums = AovSums::new(width, height, set);
    let k = sums.channels.len();
    let pixels = width as usize * height as usize;
    for (i, ch) in sums.channels.clone().iter().enumerate() {
        for word in 0..4 {
            let name = sum_word_name(&ch.name(), word);
            let channel = image.layer_data.channel_data.list.iter().find(|c| c.name.eq(name.as_str()));
            let Some(FlatSamples::U32(values)) = channel.map(|c| &c.sample_data) else {
                return Err(format!("the u32 channel {name} of the layer sums is missing"));
            };
            if values.len() != pixels {
                return Err(format!("channel {name} has {} values for {pixels} pixels", values.len()));
            }
            for (p, &v) in values.iter().enumerate() {
                let s = &mut sums.values[p * k + i];
                *s = (*s as u128 | (v as u128) << (32 * word)) as i128;
            }
        }
    }
    Ok(Some(sums))
}

/// Writes `image` with straight (unassociated) alpha `alpha` as an 8-bit
/// sRGB RGBA PNG: the color is the premultiplied radiance divided by alpha
/// (where alpha > 0), times `2^exposure`, through the sRGB curve.
pub fn write_rgba_png(image: &Image, alpha: &[f32], path: &Path, exposure: f32) -> Result<(), OutputError> {
    let mut data = Vec::with_capacity(image.pixels.len() * 4);
    for (p, &a) in image.pixels.iter().zip(alpha) {
        let a = a.clamp(0.0, 1.0);
        let straight = if a > 0.0 { *p * (1.0 / a) } else { Rgb::ZERO };
        data.extend_from_slice(&rgb_to_srgb8(straight, exposure));
        data.push((a * 255.0).round() as u8);
    }
    crate::film::write_srgb8_png(path, image.width, image.height, png::ColorType::Rgba, &data)
}

/// Writes the final images of a render with layers: EXR outputs get the
/// checkpoint with every layer ([`write_aov_checkpoint`]); PNG outputs the
/// beauty, as RGBA when the alpha layer was rendered.
pub fn write_aov_outputs(
    sums: &SampleSums,
    aov: &AovSums,
    info: &CheckpointInfo,
    transparent: bool,
    path: &Path,
    exposure: f32,
) -> Result<(), OutputError> {
    let is_exr = path.extension().is_some_and(|e| e.eq_ignore_ascii_case("exr"));
    if is_exr {
        return write_aov_checkpoint(sums, aov, info, transparent, path);
    }
    let image = sums.mean(info.spp);
    let layers = aov.layers(sums, info.spp);
    match layers.get(super::Aov::Alpha) {
        Some(alpha) => write_rgba_png(&image, &alpha.data, path, exposure),
        None => crate::film::write_image(&image, path, exposure),
    }
}

/// The beauty and layers of an EXR written with layers (by
/// [`write_aov_checkpoint`], the `niebla render --aovs` output): the
/// layers its `nieblaAovs` attribute names, read from their float channels.
pub fn read_aov_exr(path: &Path) -> std::result::Result<(crate::film::Image, super::AovImage), String> {
    use exr::prelude::*;
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .from_file(path)
        .map_err(|e| format!("{}: {e}", path.display()))?;
    let size = image.layer_data.size;
    let (width, height) = (size.width() as u32, size.height() as u32);
    let pixels = size.width() * size.height();
    let channel = |name: &str| -> std::result::Result<&Vec<f32>, String> {
        let found = image.layer_data.channel_data.list.iter().find(|c| c.name.eq(name));
        match found.map(|c| &c.sample_data) {
            Some(FlatSamples::F32(values)) if values.len() == pixels => Ok(values),
            _ => Err(format!("{}: no float channel {name} of {pixels} values", path.display())),
        }
    };
    let (r, g, b) = (channel("R")?, channel("G")?, channel("B")?);
    let beauty =
        crate::film::Image { width, height, pixels: (0..pixels).map(|i| Rgb::new(r[i], g[i], b[i])).collect() };
    let recorded = match image.layer_data.attributes.other.get(&Text::from(AOVS_ATTRIBUTE)) {
        Some(AttributeValue::Text(t)) => t.to_string(),
        _ => return Err(format!("{}: no attribute {AOVS_ATTRIBUTE} (not written with layers)", path.display())),
    };
    let list = recorded.strip_suffix(TRANSPARENT_SUFFIX).unwrap_or(&recorded);
    let set = AovSet::parse_list(list).map_err(|e| format!("{}: {AOVS_ATTRIBUTE}: {e}", path.display()))?;
    let mut layers = Vec::new();
    for aov in set.iter() {
        let components = if matches!(aov, super::Aov::Alpha | super::Aov::Depth) { 1 } else { 3 };
        let mut layer = super::AovLayer { aov, components, data: vec![0.0; pixels * components] };
        for (c, name) in layer.channel_names().iter().enumerate() {
            for (i, v) in channel(name)?.iter().enumerate() {
                layer.data[i * components + c] = *v;
            }
        }
        layers.push(layer);
    }
    Ok((beauty, super::AovImage { width, height, layers }))
}
