//! Settings of the `photon`, `ppm` and `ppb` integrators (`"type": "photon"`,
//! `"type": "ppm"`, `"type": "ppb"`): their fields in a scene file, their defaults and
//! checks, and their stable keys.

use serde::Deserialize;

use super::{PhotonGather, PhotonSettings, PpbSettings, PpmSettings, VolumeQuery};
use crate::integrator::common_settings::{at_least_one, march_key, march_step, positive, sampling_key, SamplingField};
use crate::params::{rest, Located, Object};

/// `query`: how camera rays query the volume photon map.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
enum QueryField {
    /// Point queries at ray-marched points (default).
    March,
    /// One beam query per medium segment.
    Beam,
}

/// The fields of a `photon` or `ppm` object; every one is optional.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct PhotonFields {
    /// Photons emitted (>= 1; per pass for `ppm`).
    #[serde(default)]
    photons: Option<u32>,
    /// Neighbours of a k-nearest estimate (>= 1; `photon` only). With
    /// `radius` and no `k`, `photon` gathers within the fixed radius.
    #[serde(default)]
    k: Option<u32>,
    /// Volume gather radius in scene units (> 0).
    #[serde(default)]
    radius: Option<f32>,
    /// Surface gather radius in scene units (> 0).
    #[serde(default)]
    surface_radius: Option<f32>,
    /// Ray-march step length of point queries (> 0).
    #[serde(default)]
    step: Option<f32>,
    /// Ray-march steps per segment of point queries (>= 1).
    #[serde(default)]
    steps: Option<u32>,
    /// `"march"` (default) or `"beam"`.
    #[serde(default)]
    query: Option<QueryField>,
    /// Single-scattering sampling along camera rays (default `mis`).
    #[serde(default)]
    sampling: Option<SamplingField>,
    /// Largest number of scattering events on a photon path (>= 1).
    #[serde(default)]
    max_depth: Option<u32>,
    /// `ppm`'s radius reduction in (0, 1) (default 2/3).
    #[serde(default)]
    alpha: Option<f32>,
}

/// The pass settings and (for `ppm`) `alpha` from a `photon` (`ppm =
/// false`) or `ppm` object (the `type` taken out), defaults filled in.
/// `photon` gathers the `k` nearest unless the object gives a `radius` and
/// no `k`.
fn parse(object: Object, ppm: bool) -> Result<(PhotonSettings, f32), Located> {
    let f: PhotonFields = rest(object)?;
    let step = march_step(f.step, f.steps)?;
    at_least_one("photons", f.photons)?;
    at_least_one("k", f.k)?;
    at_least_one("max_depth", f.max_depth)?;
    if ppm && f.k.is_some() {
        return Err(Located::new("k", "ppm gathers within a shrinking radius: give `radius`, not `k`"));
    }
    if !ppm && f.alpha.is_some() {
        return Err(Located::new("alpha", "only ppm shrinks its radius: `alpha` applies to ppm"));
    }
    for (path, value) in [("radius", f.radius), ("surface_radius", f.surface_radius)] {
        if let Some(r) = value {
            positive(path, r)?;
        }
    }
    if let Some(alpha) = f.alpha {
        if !(alpha > 0.0 && alpha < 1.0) {
            return Err(Located::new("alpha", format!("must be in (0, 1), got {alpha}")));
        }
    }
    let defaults = if ppm { PhotonSettings::ppm() } else { PhotonSettings::photon() };
    let gather = match (ppm, f.k, f.radius) {
        (true, _, _) => PhotonGather::Radius,
        (false, Some(k), _) => PhotonGather::Nearest(k),
        (false, None, Some(_)) => PhotonGather::Radius,
        (false, None, None) => defaults.gather,
    };
    let settings = PhotonSettings {
        photons: f.photons.unwrap_or(defaults.photons),
        gather,
        radius: f.radius,
        surface_radius: f.surface_radius,
        step,
        query: if f.query == Some(QueryField::Beam) { VolumeQuery::Beam } else { VolumeQuery::March },
        sampling: f.sampling.unwrap_or(SamplingField::Mis).sampling(),
        max_depth: f.max_depth.unwrap_or(defaults.max_depth),
        store_direct: false,
    };
    Ok((settings, f.alpha.unwrap_or(PpmSettings::DEFAULT_ALPHA)))
}

/// `photon`'s settings from its object (the `type` taken out).
pub(crate) fn parse_photon(object: Object) -> Result<PhotonSettings, Located> {
    parse(object, false).map(|(settings, _)| settings)
}

/// `ppm`'s settings from its object (the `type` taken out).
pub(crate) fn parse_ppm(object: Object) -> Result<PpmSettings, Located> {
    parse(object, true).map(|(photon, alpha)| PpmSettings { photon, alpha })
}

/// The stable key of one photon pass's settings (without the name).
fn pass_key(s: &PhotonSettings) -> String {
    let gather = match s.gather {
        PhotonGather::Nearest(k) => format!("k={k}"),
        PhotonGather::Radius => "radius".to_string(),
    };
    let radius = |r: Option<f32>| r.map_or("auto".to_string(), |r| format!("{r:?}"));
    format!(
        "photons={}, gather={gather}, radius={}, surface_radius={}, {}, query={}, sampling={}, max_depth={}, \
         store_direct={}",
        s.photons,
        radius(s.radius),
        radius(s.surface_radius),
        march_key(s.step),
        match s.query {
            VolumeQuery::March => "march",
            VolumeQuery::Beam => "beam",
        },
        sampling_key(s.sampling),
        s.max_depth,
        s.store_direct
    )
}

/// The stable key of `photon`'s settings.
pub(crate) fn photon_key(s: &PhotonSettings) -> String {
    format!("photon({})", pass_key(s))
}

/// The stable key of `ppm`'s settings.
pub(crate) fn ppm_key(s: &PpmSettings) -> String {
    format!("ppm({}, alpha={:?})", pass_key(&s.photon), s.alpha)
}

/// The fields of a `ppb` object; every one is optional.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct PpbFields {
    /// Photons emitted per pass (>= 1).
    #[serde(default)]
    photons: Option<u32>,
    /// Initial beam radius in scene units (> 0).
    #[serde(default)]
    radius: Option<f32>,
    /// Initial surface gather radius in scene units (> 0).
    #[serde(default)]
    surface_radius: Option<f32>,
    /// Radius reduction in (0, 1) (default 2/3).
    #[serde(default)]
    alpha: Option<f32>,
    /// Largest number of scattering events on a photon path (>= 1).
    #[serde(default)]
    max_depth: Option<u32>,
    /// Single-scattering sampling along camera rays (default `mis`).
    #[serde(default)]
    sampling: Option<SamplingField>,
    /// `sin theta` below which a beam crossing uses the 2D (tube) estimate, in [0, 1].
    #[serde(default)]
    tube_sin: Option<f32>,
}

/// `ppb`'s settings from its object (the `type` taken out).
pub(crate) fn parse_ppb(object: Object) -> Result<PpbSettings, Located> {
    let f: PpbFields = rest(object)?;
    at_least_one("photons", f.photons)?;
    at_least_one("max_depth", f.max_depth)?;
    for (path, value) in [("radius", f.radius), ("surface_radius", f.surface_radius)] {
        if let Some(r) = value {
            positive(path, r)?;
        }
    }
    if let Some(alpha) = f.alpha {
        if !(alpha > 0.0 && alpha < 1.0) {
            return Err(Located::new("alpha", format!("must be in (0, 1), got {alpha}")));
        }
    }
    if let Some(x) = f.tube_sin {
        if !(0.0..=1.0).contains(&x) {
            return Err(Located::new("tube_sin", format!("must be in [0, 1], got {x}")));
        }
    }
    let d = PpbSettings::default();
    Ok(PpbSettings {
        tube_sin: f.tube_sin.unwrap_or(d.tube_sin),
        photons: f.photons.unwrap_or(d.photons),
        radius: f.radius,
        surface_radius: f.surface_radius,
        alpha: f.alpha.unwrap_or(d.alpha),
        max_depth: f.max_depth.unwrap_or(d.max_depth),
        sampling: f.sampling.unwrap_or(SamplingField::Mis).sampling(),
        store_direct: false,
    })
}

/// The stable key of `ppb`'s settings.
pub(crate) fn ppb_key(s: &PpbSettings) -> String {
    let radius = |r: Option<f32>| r.map_or("auto".to_string(), |r| format!("{r:?}"));
    format!(
        "ppb(photons={}, radius={}, surface_radius={}, alpha={:?}, sampling={}, max_depth={}, store_direct={}, \
         tube_sin={:?})",
        s.photons,
        radius(s.radius),
        radius(s.surface_radius),
        s.alpha,
        sampling_key(s.sampling),
        s.max_depth,
        s.store_direct,
        s.tube_sin
    )
}
