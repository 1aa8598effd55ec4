//! Fog presets from the reference Mie computation (reference/README.md
//! section 5): water droplets in air at 550 nm, m = 1.333 - 1.96e-9 i,
//! gamma size distribution r_eff = 8 um, v_eff = 0.1 (Hansen and Travis 1974),
//! miepython 3.3.0.

use super::double_hg::DoubleHg;
use super::tabulated::Tabulated;
use std::sync::{Arc, OnceLock};

/// Weight of the forward lobe of the two-lobe HG fit of the poly fog
/// (reference/mie_fog_fit.json, `cases.poly.two_lobe_hg_fit.w`).
pub const FOG_W: f64 = 0.9704604249825882;
/// Asymmetry of the forward lobe (`cases.poly.two_lobe_hg_fit.g1`).
pub const FOG_G1: f64 = 0.9044783543024993;
/// Asymmetry of the backward lobe (`cases.poly.two_lobe_hg_fit.g2`).
pub const FOG_G2: f64 = -0.6010696321391038;
/// Mie mean cosine of the poly fog, kept exactly by the fit
/// (`cases.poly.g`; good to about 1e-5 per the reference's size-integration error).
pub const FOG_MEAN_COSINE: f64 = 0.8600051066146943;

/// The Mie phase function table shipped with the renderer (copy of
/// reference/mie_fog_phase.csv: 243 angles, 0.05 deg steps below 2 deg,
/// 0.25 deg to 10 deg, 1 deg after; p in 1/sr).
pub const MIE_FOG_CSV: &str = include_str!("../../data/mie_fog_phase.csv");
/// The column of [`MIE_FOG_CSV`] used by `PhaseFunction::mie_fog`: the
/// polydisperse ("typical fog") Mie curve.
pub const MIE_FOG_COLUMN: &str = "p_mie_poly";
/// The two-lobe HG fit of the poly fog.
pub(crate) fn fog_double_hg() -> DoubleHg {
    DoubleHg::new(FOG_W as f32, FOG_G1 as f32, FOG_G2 as f32).expect("fog fit parameters are valid")
}

/// The shipped Mie fog table, parsed on first use and shared.
pub(crate) fn mie_fog_table() -> Arc<Tabulated> {
    static TABLE: OnceLock<Arc<Tabulated>> = OnceLock::new();
    TABLE
        .get_or_init(|| {
            Arc::new(
                Tabulated::from_csv_str(MIE_FOG_CSV, MIE_FOG_COLUMN, "data/mie_fog_phase.csv")
                    .expect("the shipped Mie fog table is valid"),
            )
        })
        .clone()
}
