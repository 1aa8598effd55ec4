//! Settings of the `single` integrator (`"type": "single"`): its fields in
//! a scene file, their defaults and checks, and their stable key.

use serde::Deserialize;

use super::SingleSampling;
use crate::integrator::common_settings::{
    march_key, march_step, sampling_key, transmittance_key, SamplingField, TransmittanceField,
};
use crate::params::{rest, Located, Object};
use crate::tracking::{MarchStep, TransmittanceMethod};

/// The fields of a `single` object; every one is optional.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SingleFields {
    /// Ray-march step length in scene units (> 0).
    #[serde(default)]
    step: Option<f32>,
    /// Ray-march steps per medium segment (>= 1).
    #[serde(default)]
    steps: Option<u32>,
    /// Scattering points along camera rays (default `march`).
    #[serde(default)]
    sampling: SamplingField,
    /// Transmittance estimator of shadow rays (default `analytic`).
    #[serde(default)]
    transmittance: TransmittanceField,
    /// Emissive media as lights for single scattering and surfaces
    /// (default false: old scenes keep their images).
    #[serde(default)]
    volume_lights: bool,
}

/// `single`'s settings, `(step, sampling, transmittance, volume_lights)`,
/// from its object (the `type` taken out).
pub(crate) fn parse(object: Object) -> Result<(Option<MarchStep>, SingleSampling, TransmittanceMethod, bool), Located> {
    let fields: SingleFields = rest(object)?;
    let step = march_step(fields.step, fields.steps)?;
    Ok((step, fields.sampling.sampling(), fields.transmittance.method(step), fields.volume_lights))
}

/// The stable key of `single`'s settings, e.g.
/// `single(step=auto, sampling=mis, transmittance=analytic)`; with volume
/// lights on, `, volume_lights=true` is appended (keys of old scenes are
/// unchanged).
pub(crate) fn key(
    step: Option<MarchStep>,
    sampling: SingleSampling,
    transmittance: TransmittanceMethod,
    volume_lights: bool,
) -> String {
    format!(
        "single({}, sampling={}, transmittance={}{})",
        march_key(step),
        sampling_key(sampling),
        transmittance_key(transmittance),
        if volume_lights { ", volume_lights=true" } else { "" }
    )
}
