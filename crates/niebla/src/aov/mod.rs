//! Render layers beside the beauty image (arbitrary output variables): the
//! alpha channel, the beauty split by path class (`direct`, `indirect`,
//! `emission`, `surface`), denoiser features (`albedo`, `normal`, `depth`)
//! and the per-pixel variance.
//!
//! Definitions (all per pixel, means over the pixel's camera samples):
//! - **alpha** `A = 1 - mean_c T_c`, one minus the camera ray's
//!   transmittance to the background averaged over the three channels
//!   (exact for homogeneous media, ratio tracking in grids: unbiased).
//!   Every surface that is not an index-matched boundary (`null`) is opaque
//!   (`T = 0`), lamps and glass included. `RGB + (1 - A) * background`
//!   recomposites a `transparent` render over any background (exactly for
//!   grey media; chromatic media would need one alpha per channel).
//! - **direct**: light scattered once in a medium before reaching the
//!   camera (the first vertex of the path is a medium collision and the
//!   path has one scattering event), emission of media lit included;
//!   **indirect**: paths whose first vertex is a medium collision and that
//!   scatter more than once; **surface**: paths whose first vertex is a
//!   surface (diffuse, glass or metal); **emission**: what reaches the camera
//!   without scattering (media's emission, lamps and the environment seen
//!   directly). The four add up to the beauty (float rounding apart). Only
//!   `volpath` splits its paths ([`LayerSplit`]).
//! - **albedo**, **normal**, **depth** ([`features`]): the value at the
//!   camera ray's first real collision or opaque surface. The collision is
//!   drawn by free-flight sampling with the extinction of one channel
//!   chosen uniformly, so a pixel's mean weights a medium's points by the
//!   channel average of `sigma_t T` and a surface behind it by the average
//!   of `T`. In a medium, albedo is the single-scattering albedo
//!   `sigma_s / sigma_t` per channel and the normal is zero (a medium has no
//!   orientation); on a surface, the diffuse reflectance (1 for glass and
//!   metal) and the shading normal facing the camera (world space). Rays
//!   that escape count as albedo 0, normal 0. `depth` is the mean distance
//!   from the camera to that first collision or surface over the samples
//!   that have one (0 where none has).
//! - **variance**: the estimated variance of the pixel's mean per channel,
//!   `(sum x^2 - n mean^2) / (n (n - 1))` (0 for one sample), the square of
//!   its standard error.

mod exr;
pub mod features;
mod render;
mod split;
mod sums;

pub use exr::{read_aov_exr, read_aov_sums, write_aov_checkpoint, write_aov_outputs, write_rgba_png};
pub use render::{
    render_aov_sums_masked_with, render_aov_sums_with, render_range_sums_with, render_segment_sums_with,
    segment_channels,
};
pub use split::{FirstVertex, LayerSplit, PathClass, RadianceSum};
pub use sums::{variance_of_mean, AovChannel, AovImage, AovLayer, AovSample, AovSums};

/// One layer a render can write beside the beauty.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Aov {
    /// The alpha channel `A`.
    Alpha,
    /// Single scattering in media.
    Direct,
    /// Multiple scattering in media.
    Indirect,
    /// Emission seen without scattering (media, lamps, environment).
    Emission,
    /// Paths whose first vertex is a surface.
    Surface,
    /// First-hit albedo.
    Albedo,
    /// First-hit shading normal.
    Normal,
    /// Mean distance to the first collision or surface.
    Depth,
    /// Variance of the pixel mean.
    Variance,
}

impl Aov {
    /// Every layer, in the order they are written.
    pub const ALL: [Aov; 9] = [
        Aov::Alpha,
        Aov::Direct,
        Aov::Indirect,
        Aov::Emission,
        Aov::Surface,
        Aov::Albedo,
        Aov::Normal,
        Aov::Depth,
        Aov::Variance,
    ];

    /// The layer's name (`--aovs`, the scene's `film.aovs`, EXR layer
    /// prefixes and Python dict keys).
    pub fn name(self) -> &'static str {
        match self {
            Aov::Alpha => "alpha",
            Aov::Direct => "direct",
            Aov::Indirect => "indirect",
            Aov::Emission => "emission",
            Aov::Surface => "surface",
            Aov::Albedo => "albedo",
            Aov::Normal => "normal",
            Aov::Depth => "depth",
            Aov::Variance => "variance",
        }
    }

    /// Whether the layer splits the beauty by path class (needs an
    /// integrator that classifies paths: `volpath`).
    pub fn is_split(self) -> bool {
        matches!(self, Aov::Direct | Aov::Indirect | Aov::Emission | Aov::Surface)
    }

    fn bit(self) -> u16 {
        1 << Aov::ALL.iter().position(|&a| a == self).expect("every layer is in ALL")
    }
}

/// A set of layers ([`Aov`]); empty for a plain render.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct AovSet(u16);

impl AovSet {
    /// No layers.
    pub const EMPTY: AovSet = AovSet(0);

    /// Whether no layer is asked for.
    pub fn is_empty(self) -> bool {
        self.0 == 0
    }

    /// Whether `aov` is in the set.
    pub fn contains(self, aov: Aov) -> bool {
        self.0 & aov.bit() != 0
    }

    /// The set with `aov` added.
    pub fn with(self, aov: Aov) -> AovSet {
        AovSet(self.0 | aov.bit())
    }

    /// The union of two sets.
    pub fn union(self, other: AovSet) -> AovSet {
        AovSet(self.0 | other.0)
    }

    /// The layers in the set, in [`Aov::ALL`]'s order.
    pub fn iter(self) -> impl Iterator<Item = Aov> {
        Aov::ALL.into_iter().filter(move |&a| self.contains(a))
    }

    /// Whether a layer of the set splits the beauty by path class.
    pub fn has_split(self) -> bool {
        self.iter().any(Aov::is_split)
    }

    /// Reads a list of layer names (`alpha`, `direct`, `indirect`,
    /// `emission`, `surface`, `albedo`, `normal`, `depth`, `variance`) or
    /// `all`; the error names the unknown entry and lists the valid ones.
    ///
    /// ```
    /// use niebla::aov::{Aov, AovSet};
    /// let set = AovSet::parse(["albedo", "normal"]).unwrap();
    /// assert!(set.contains(Aov::Normal) && !set.contains(Aov::Depth));
    /// assert_eq!(AovSet::parse(["all"]).unwrap().iter().count(), 9);
    /// assert!(AovSet::parse(["albedos"]).unwrap_err().contains("unknown layer \"albedos\""));
    /// ```
    pub fn parse<'a>(names: impl IntoIterator<Item = &'a str>) -> Result<AovSet, String> {
        let mut set = AovSet::EMPTY;
        for name in names {
            let name = name.trim();
            if name == "all" {
                set = Aov::ALL.into_iter().fold(set, AovSet::with);
                continue;
            }
            match Aov::ALL.into_iter().find(|a| a.name() == name) {
                Some(a) => set = set.with(a),
                None => {
                    let valid: Vec<&str> = Aov::ALL.iter().map(|a| a.name()).collect();
                    return Err(format!("unknown layer {name:?} (expected all or some of {})", valid.join(", ")));
                }
            }
        }
        Ok(set)
    }

    /// Reads a comma-separated list (`--aovs direct,albedo` or `all`).
    pub fn parse_list(list: &str) -> Result<AovSet, String> {
        AovSet::parse(list.split(',').filter(|s| !s.trim().is_empty()))
    }
}

/// Why a set of layers cannot be rendered with an integrator (`None`: it can).
/// The split layers need `volpath`; `photon`, `ppm` and `ppb` render per
/// pass with their own photon maps and write no layers.
pub fn unsupported_reason(set: AovSet, integrator: &crate::integrator::IntegratorSettings) -> Option<String> {
    use crate::integrator::IntegratorSettings as S;
    if set.is_empty() {
        return None;
    }
    match integrator {
        S::Photon(_) | S::Ppm(_) | S::Ppb(_) => {
            Some(format!("the {} integrator writes no layers (alpha or AOVs)", integrator.name()))
        }
        S::VolPath { .. } => None,
        _ if set.has_split() => {
            let split: Vec<&str> = set.iter().filter(|a| a.is_split()).map(Aov::name).collect();
            Some(format!(
                "the layers {} split paths by their scattering events, which only the volpath integrator does (not {})",
                split.join(", "),
                integrator.name()
            ))
        }
        _ => None,
    }
}

/// Bytes per pixel a render with `set` holds beside [`crate::film::render_memory`]:
/// per stored channel ([`AovSums::channels_for`]) the accumulated, pass and
/// tile sums (16 bytes each) and the EXR's float and sum words (uncompressed
/// and compressed, 40 bytes), rounded up to 96.
pub fn aov_memory(width: u32, height: u32, set: AovSet) -> u64 {
    u64::from(width) * u64::from(height) * 96 * AovSums::channels_for(set).len() as u64
}
