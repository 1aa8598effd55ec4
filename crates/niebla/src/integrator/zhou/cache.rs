//! On-disk cache of RBF fits, keyed by the sampled density and the fit
//! parameters, so a scene re-rendered with other lighting, camera, albedo or
//! phase function skips the fit (Zhou et al.'s preprocessing is per density).
//!
//! Location: `$NIEBLA_CACHE_DIR`, else `$XDG_CACHE_HOME/niebla`, else
//! `$HOME/.cache/niebla`; an empty `NIEBLA_CACHE_DIR` disables the cache.
//! Files are written to a temporary name and renamed; a file that does not
//! parse is ignored (the fit runs again and replaces it).

use std::io::Write;
use std::path::PathBuf;

use super::fit::FitSettings;
use super::rbf::Rbf;
use crate::math::Vec3;

const MAGIC: &[u8; 12] = b"NIEBLA-RBF-1";

/// The cache folder, if one is configured or derivable.
pub fn cache_dir() -> Option<PathBuf> {
    if let Some(dir) = std::env::var_os("NIEBLA_CACHE_DIR") {
        return (!dir.is_empty()).then(|| PathBuf::from(dir));
    }
    if let Some(dir) = std::env::var_os("XDG_CACHE_HOME").filter(|d| !d.is_empty()) {
        return Some(PathBuf::from(dir).join("niebla"));
    }
    std::env::var_os("HOME").filter(|d| !d.is_empty()).map(|h| PathBuf::from(h).join(".cache").join("niebla"))
}

/// FNV-1a hash of the lattice shape, the fit parameters and the density values.
pub fn fit_key(n: [usize; 3], density: &[f32], settings: &FitSettings) -> u64 {
    let mut h = 0xcbf2_9ce4_8422_2325u64;
    let mut feed = |bytes: &[u8]| {
        for b in bytes {
            h ^= *b as u64;
            h = h.wrapping_mul(0x0000_0100_0000_01b3);
        }
    };
    feed(MAGIC);
    for v in n {
        feed(&(v as u64).to_le_bytes());
    }
    for v in [settings.count, settings.iterations, settings.teleport_every] {
        feed(&(v as u64).to_le_bytes());
    }
    feed(&settings.seed.to_le_bytes());
    for v in density {
        feed(&v.to_bits().to_le_bytes());
    }
    h
}

fn path(key: u64) -> Option<PathBuf> {
    cache_dir().map(|d| d.join(format!("zhou-{key:016x}.rbf")))
}

/// RBFs (lattice units: centres in node coordinates, radii in cells) and
/// the fit's relative error stored under `key`, if present and well formed.
pub fn load(key: u64) -> Option<(Vec<Rbf>, f64)> {
    let bytes = std::fs::read(path(key)?).ok()?;
    let rest = bytes.strip_prefix(MAGIC.as_slice())?;
    let count = u64::from_le_bytes(rest.get(..8)?.try_into().ok()?) as usize;
    let error = f64::from_le_bytes(rest.get(8..16)?.try_into().ok()?);
    let body = rest.get(16..)?;
    if body.len() != count.checked_mul(20)? {
        return None;
    }
    let f = |k: usize| f32::from_le_bytes(body[4 * k..4 * k + 4].try_into().unwrap());
    let rbfs: Vec<Rbf> = (0..count)
        .map(|i| Rbf {
            center: Vec3::new(f(5 * i), f(5 * i + 1), f(5 * i + 2)),
            radius: f(5 * i + 3),
            weight: f(5 * i + 4),
        })
        .collect();
    let finite = rbfs.iter().all(|r| r.center.is_finite() && r.radius > 0.0 && r.weight.is_finite());
    (finite && error.is_finite()).then_some((rbfs, error))
}

/// Store a fit under `key`; failures are ignored (the cache is an optimization).
pub fn store(key: u64, rbfs: &[Rbf], error: f64) {
    let Some(path) = path(key) else { return };
    let Some(dir) = path.parent() else { return };
    if std::fs::create_dir_all(dir).is_err() {
        return;
    }
    let mut bytes = Vec::with_capacity(MAGIC.len() + 16 + rbfs.len() * 20);
    bytes.extend_from_slice(MAGIC);
    bytes.extend_from_slice(&(rbfs.len() as u64).to_le_bytes());
    bytes.extend_from_slice(&error.to_le_bytes());
    for r in rbfs {
        for v in [r.center.x, r.center.y, r.center.z, r.radius, r.weight] {
            bytes.extend_from_slice(&v.to_le_bytes());
        }
    }
    let tmp = path.with_extension(format!("tmp{}", std::process::id()));
    let written = std::fs::File::create(&tmp).and_then(|mut f| f.write_all(&bytes));
    if written.is_err() || std::fs::rename(&tmp, &path).is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
}
