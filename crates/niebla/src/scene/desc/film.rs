//! The `film` object of a scene file: layers written beside the beauty and
//! the transparent background.

use serde::Deserialize;

use crate::aov::{Aov, AovSet};

/// `"film": {"transparent": true, "aovs": ["albedo", "normal"]}`; every
/// field optional, and the whole object.
#[derive(Clone, Debug, Default, PartialEq, Eq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FilmDesc {
    /// Hold out the background: camera rays that reach the environment
    /// without scattering see black, and the alpha layer is written (the
    /// environment still lights the scene). Default false.
    #[serde(default)]
    pub transparent: bool,
    /// Layers written beside the beauty (`crate::aov::Aov` names or
    /// `"all"`). Default none.
    #[serde(default)]
    pub aovs: Vec<String>,
}

impl FilmDesc {
    /// The error message for the first unknown layer name, with its index.
    pub fn check(&self) -> Result<(), (usize, String)> {
        for (i, name) in self.aovs.iter().enumerate() {
            AovSet::parse([name.as_str()]).map_err(|e| (i, e))?;
        }
        Ok(())
    }
}

/// What the film asks of a render: its layers (alpha added when
/// transparent) and whether the background is held out.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct FilmSettings {
    /// Hold out the background.
    pub transparent: bool,
    /// The layers.
    pub aovs: AovSet,
}

impl FilmSettings {
    /// From a checked description (unknown names, refused by validation,
    /// are skipped).
    pub fn from_desc(desc: &FilmDesc) -> FilmSettings {
        let mut aovs =
            desc.aovs.iter().filter_map(|n| AovSet::parse([n.as_str()]).ok()).fold(AovSet::EMPTY, AovSet::union);
        if desc.transparent {
            aovs = aovs.with(Aov::Alpha);
        }
        FilmSettings { transparent: desc.transparent, aovs }
    }
}
