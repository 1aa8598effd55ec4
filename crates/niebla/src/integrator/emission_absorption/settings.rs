//! Settings of the `emission` integrator (`"type": "emission"`): its fields
//! in a scene file, their defaults and checks, and their stable key.

use serde::Deserialize;

use crate::integrator::common_settings::{march_key, march_step, transmittance_key, TransmittanceField};
use crate::params::{rest, Located, Object};
use crate::tracking::{MarchStep, TransmittanceMethod};

/// The fields of an `emission` object; every one is optional.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct EmissionFields {
    /// Ray-march step length in scene units (> 0).
    #[serde(default)]
    step: Option<f32>,
    /// Ray-march steps per medium segment (>= 1).
    #[serde(default)]
    steps: Option<u32>,
    /// Transmittance estimator (default `analytic`).
    #[serde(default)]
    transmittance: TransmittanceField,
}

/// `emission`'s settings, `(step, transmittance)`, from its object (the
/// `type` taken out).
pub(crate) fn parse(object: Object) -> Result<(Option<MarchStep>, TransmittanceMethod), Located> {
    let fields: EmissionFields = rest(object)?;
    let step = march_step(fields.step, fields.steps)?;
    Ok((step, fields.transmittance.method(step)))
}

/// The stable key of `emission`'s settings, e.g.
/// `emission(steps=32, transmittance=ratio)`.
pub(crate) fn key(step: Option<MarchStep>, transmittance: TransmittanceMethod) -> String {
    format!("emission({}, transmittance={})", march_key(step), transmittance_key(transmittance))
}
