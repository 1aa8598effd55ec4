//! Settings of the `volpath` integrator (`"type": "volpath"`): its fields
//! in a scene file, their defaults and checks, and their stable key.

use serde::Deserialize;

use crate::params::{rest, Located, Object};

/// Default path depth of `volpath`: deep enough for dense albedo-0.99 media.
pub const DEFAULT_MAX_DEPTH: u32 = 1024;

/// The fields of a `volpath` object.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct VolPathFields {
    /// Largest number of scattering events on a path (>= 1; default 1024).
    #[serde(default)]
    max_depth: Option<u32>,
    /// Whether emissive media are sampled as lights (default true).
    #[serde(default)]
    volume_light_sampling: Option<bool>,
    /// Whether surface vertices mix BSDF sampling, and medium vertices
    /// phase sampling, with directions toward the emitting region, when
    /// emissive media are sampled as lights (default true).
    #[serde(default)]
    emitter_guiding: Option<bool>,
}

/// The parsed fields of a `volpath` object.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Parsed {
    /// Largest number of scattering events on a path.
    pub(crate) max_depth: u32,
    /// Whether emissive media are sampled as lights.
    pub(crate) volume_light_sampling: bool,
    /// Whether surface and medium vertices guide directions toward emissive media.
    pub(crate) emitter_guiding: bool,
}

/// `volpath`'s `max_depth`, `volume_light_sampling` and `emitter_guiding`
/// from its object (the `type` taken out).
pub(crate) fn parse(object: Object) -> Result<Parsed, Located> {
    let fields: VolPathFields = rest(object)?;
    let volume_light_sampling = fields.volume_light_sampling.unwrap_or(true);
    let emitter_guiding = fields.emitter_guiding.unwrap_or(true);
    match fields.max_depth {
        Some(0) => Err(Located::new("max_depth", "must be at least 1, got 0")),
        depth => Ok(Parsed { max_depth: depth.unwrap_or(DEFAULT_MAX_DEPTH), volume_light_sampling, emitter_guiding }),
    }
}

/// The stable key of `volpath`'s settings, e.g. `volpath(max_depth=1024)`;
/// `, volume_light_sampling=false` and `, emitter_guiding=false` are added
/// only when off, so the default's key is the one it had before the
/// settings existed (the expected image is the same either way).
pub(crate) fn key(max_depth: u32, volume_light_sampling: bool, emitter_guiding: bool) -> String {
    let mut key = format!("volpath(max_depth={max_depth}");
    if !volume_light_sampling {
        key.push_str(", volume_light_sampling=false");
    }
    if !emitter_guiding {
        key.push_str(", emitter_guiding=false");
    }
    key.push(')');
    key
}
