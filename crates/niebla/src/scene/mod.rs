//! Scenes: the JSON description (serde), its validation, and the build into
//! the render-ready [`Scene`].
//!
//! Describe, then build: a file is parsed into plain description types
//! (`SceneDesc`, every value checked, errors with JSON paths), then built
//! into the render-ready scene, which holds no strings on the per-sample path:
//! ```
//! use niebla::scene::{build_scene, parse_scene_str, DEFAULT_SCENE};
//! let desc = parse_scene_str(DEFAULT_SCENE, "<default>").unwrap();
//! let built = build_scene(&desc, "<default>", std::path::Path::new(".")).unwrap();
//! assert!(built.scene.camera_medium.is_some());
//! ```

mod build;
mod build_medium;
mod build_mesh;
mod build_surfaces;
mod build_texture;
pub mod desc;
mod error;
pub mod frames;
pub mod mitsuba;
mod parse;
mod parse_surfaces;
mod rebuild;
mod source;
mod validate;

pub use crate::world::{
    offset_origin, surface_epsilon, walk_shadow_ray, Hit, PaneCrossing, PathRay, Scene, SceneObject, ShadowSegment,
    MAX_BOUNDARY_CROSSINGS, MAX_PATH_BOUNDARY_CROSSINGS,
};
pub use build::{
    build_scene, build_scene_cached, build_scene_with_options, build_transform, integrator_settings,
    unused_media_warnings, BuildOptions, BuiltScene, SceneCache,
};
pub use desc::*;
pub use error::SceneError;
pub use parse::{load_scene_file, parse_scene_frame, parse_scene_str};
pub use rebuild::{rebuild_scene, SceneEdit};
pub use source::{read_scene_source, read_scene_source_frame, SceneSource};

use crate::integrator::IntegratorSettings;

/// The built-in default scene (scenes/default.json): a hazy room lit by a spot
/// light whose cone and shadows show in the haze.
pub const DEFAULT_SCENE: &str = include_str!("../../../../scenes/default.json");

/// What a scene file asks of a render.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RenderSettings {
    /// Integrator and its parameters.
    pub integrator: IntegratorSettings,
    /// Samples per pixel.
    pub spp: u32,
    /// Sampler seed.
    pub seed: u64,
    /// The numbers of the camera samples.
    pub sampler: crate::sampling::SamplerKind,
    /// PNG exposure in stops (the PNG is the EXR times 2^exposure).
    pub exposure: f32,
    /// The film's layers and transparency.
    pub film: FilmSettings,
}

/// Load, validate and build a scene file (niebla JSON, or Mitsuba 3 XML for
/// `.xml`) in one call; relative paths resolve against the file's folder.
pub fn load_scene(path: &std::path::Path) -> Result<BuiltScene, SceneError> {
    let desc = read_scene_source(path, &[])?.desc;
    let base = path.parent().unwrap_or(std::path::Path::new("."));
    build_scene(&desc, &path.display().to_string(), base)
}
