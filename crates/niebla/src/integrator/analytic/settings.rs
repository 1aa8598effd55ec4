//! Settings of the `analytic` integrator (`"type": "analytic"`): it has no
//! fields besides `type`.

use serde::Deserialize;

use crate::params::{rest, Located, Object};

/// An `analytic` object has no fields besides `type`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct AnalyticFields {}

/// Checks that `object` (the `type` taken out) is empty.
pub(crate) fn parse(object: Object) -> Result<(), Located> {
    let _: AnalyticFields = rest(object)?;
    Ok(())
}
