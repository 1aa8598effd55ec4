//! Settings fields that several integrators share, as read from their
//! `render.integrator` object: the ray-march step (`step` or `steps`), the
//! transmittance estimator (`transmittance`) and the choice of scattering
//! points along camera rays (`sampling`); and the value checks whose
//! messages every integrator's settings use.

use serde::Deserialize;

use super::SingleSampling;
use crate::params::Located;
use crate::tracking::{MarchStep, TransmittanceMethod};

/// Steps of `transmittance: "ray_march"` per segment when no `step` or
/// `steps` is given.
pub const DEFAULT_TRANSMITTANCE_STEPS: u32 = 64;

/// The march step from the mutually exclusive `step` (a length in scene
/// units, > 0) and `steps` (a count per medium segment, >= 1); `None` when
/// neither is given (the integrator picks a default per medium).
pub fn march_step(step: Option<f32>, steps: Option<u32>) -> Result<Option<MarchStep>, Located> {
    match (step, steps) {
        (Some(_), Some(_)) => Err(Located::new(
            "steps",
            "`step` and `steps` are mutually exclusive: give a step length in scene units \
             (`step`) or a number of steps per medium segment (`steps`), not both",
        )),
        (Some(step), None) => {
            positive("step", step)?;
            Ok(Some(MarchStep::Length(step)))
        }
        (None, Some(0)) => Err(Located::new("steps", "must be at least 1, got 0")),
        (None, Some(n)) => Ok(Some(MarchStep::Count(n))),
        (None, None) => Ok(None),
    }
}

/// `sampling`: how single scattering chooses points along a camera ray.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SamplingField {
    /// `"march"`: stratified ray marching with the integrator's step.
    #[default]
    March,
    /// `"equiangular"`: equiangular sampling toward each point or spot light
    /// (Kulla and Fajardo 2012).
    Equiangular,
    /// `"mis"`: distance and equiangular sampling combined by multiple
    /// importance sampling.
    Mis,
}

impl SamplingField {
    /// The integrator's sampling mode.
    pub fn sampling(self) -> SingleSampling {
        match self {
            SamplingField::March => SingleSampling::March,
            SamplingField::Equiangular => SingleSampling::Equiangular,
            SamplingField::Mis => SingleSampling::Mis,
        }
    }
}

/// `transmittance`: how transmittance is estimated.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum TransmittanceField {
    /// `"analytic"`: exact Beer-Lambert `exp(-sigma_t d)` in homogeneous media.
    #[default]
    Analytic,
    /// `"ray_march"`: numerical quadrature of the optical depth with the
    /// integrator's step.
    RayMarch,
    /// `"delta"`: delta tracking (Woodcock et al. 1965).
    Delta,
    /// `"ratio"`: ratio tracking (Novak et al. 2014).
    Ratio,
    /// `"residual_ratio"`: residual ratio tracking (Novak et al. 2014).
    ResidualRatio,
}

impl TransmittanceField {
    /// The estimator; ray marching uses `step`, else
    /// [`DEFAULT_TRANSMITTANCE_STEPS`] steps per segment.
    pub fn method(self, step: Option<MarchStep>) -> TransmittanceMethod {
        match self {
            TransmittanceField::Analytic => TransmittanceMethod::Analytic,
            TransmittanceField::RayMarch => {
                TransmittanceMethod::RayMarch(step.unwrap_or(MarchStep::Count(DEFAULT_TRANSMITTANCE_STEPS)))
            }
            TransmittanceField::Delta => TransmittanceMethod::Delta,
            TransmittanceField::Ratio => TransmittanceMethod::Ratio,
            TransmittanceField::ResidualRatio => TransmittanceMethod::ResidualRatio,
        }
    }
}

/// `x` must be a finite number.
pub fn finite(path: &str, x: f32) -> Result<(), Located> {
    if x.is_finite() {
        Ok(())
    } else {
        Err(Located::new(path, format!("expected a finite number, got {x} (magnitude must be below 3.4e38)")))
    }
}

/// `x` must be finite and > 0.
pub fn positive(path: &str, x: f32) -> Result<(), Located> {
    finite(path, x)?;
    if x > 0.0 {
        Ok(())
    } else {
        Err(Located::new(path, format!("must be > 0, got {x}")))
    }
}

/// `n`, when given, must be at least 1.
pub fn at_least_one(path: &str, n: Option<u32>) -> Result<(), Located> {
    match n {
        Some(0) => Err(Located::new(path, "must be at least 1, got 0")),
        _ => Ok(()),
    }
}

/// `n` must lie in `lo..=hi`.
pub fn within(path: &str, n: u32, lo: u32, hi: u32) -> Result<(), Located> {
    if (lo..=hi).contains(&n) {
        Ok(())
    } else {
        Err(Located::new(path, format!("must be between {lo} and {hi}, got {n}")))
    }
}

/// A settings key of a march step: `step=auto`, `step=L` or `steps=N`.
pub fn march_key(step: Option<MarchStep>) -> String {
    match step {
        None => "step=auto".to_string(),
        Some(MarchStep::Length(l)) => format!("step={l:?}"),
        Some(MarchStep::Count(n)) => format!("steps={n}"),
    }
}

/// A settings key of a transmittance estimator, e.g. `ray_march(steps=64)`.
pub fn transmittance_key(method: TransmittanceMethod) -> String {
    match method {
        TransmittanceMethod::Analytic => "analytic".to_string(),
        TransmittanceMethod::RayMarch(step) => format!("ray_march({})", march_key(Some(step))),
        TransmittanceMethod::Delta => "delta".to_string(),
        TransmittanceMethod::Ratio => "ratio".to_string(),
        TransmittanceMethod::ResidualRatio => "residual_ratio".to_string(),
    }
}

/// A settings key of a sampling mode: `march`, `equiangular` or `mis`.
pub fn sampling_key(sampling: SingleSampling) -> &'static str {
    match sampling {
        SingleSampling::March => "march",
        SingleSampling::Equiangular => "equiangular",
        SingleSampling::Mis => "mis",
    }
}
