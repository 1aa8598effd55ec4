//! Building the textures of a scene's surfaces: image files read once per
//! (file, raw, wrap) within the memory budget, checkerboards from their
//! colors.

use std::collections::{HashMap, HashSet};
use std::path::{Path, PathBuf};
use std::sync::Arc;

use super::desc::TextureDesc;
use super::SceneError;
use crate::limits::MemoryBudget;
use crate::math::Vec2;
use crate::texture::{Bitmap, Texture, UvMap, WrapMode};

/// What makes two image textures share their image.
type ImageKey = (PathBuf, bool, WrapMode);

/// The image textures of the scene builds sharing a [`super::SceneCache`],
/// shared by file and options (within a build, and across builds while the
/// next build still uses them).
#[derive(Default)]
pub(super) struct TextureLoader {
    images: HashMap<ImageKey, Arc<Bitmap>>,
    /// Keys used (and charged to the budget) by the build in progress.
    used: HashSet<ImageKey>,
}

impl TextureLoader {
    /// Number of files held.
    pub(super) fn len(&self) -> usize {
        self.images.len()
    }

    /// Ends a build: files it did not use are dropped.
    pub(super) fn finish_build(&mut self) {
        let used = std::mem::take(&mut self.used);
        self.images.retain(|key, _| used.contains(key));
    }

    /// The texture of `desc`, found at JSON path `path` (errors name
    /// `path.file` for image files).
    pub(super) fn texture(
        &mut self,
        desc: &TextureDesc,
        path: &str,
        source: &str,
        base_dir: &Path,
        budget: &mut MemoryBudget,
    ) -> Result<Texture, SceneError> {
        Ok(match desc {
            TextureDesc::Checkerboard { color0, color1, scale, to_uv } => {
                Texture::Checkerboard { color0: color0.to_rgb(), color1: color1.to_rgb(), uv_map: uv_map(scale, to_uv) }
            }
            TextureDesc::Bitmap { file, wrap, raw, scale, filter, to_uv } => {
                let full = base_dir.join(file);
                let key = (full.clone(), *raw, *wrap);
                let field = format!("{path}.file");
                let image = match self.images.get(&key) {
                    Some(image) => {
                        if self.used.insert(key) {
                            budget
                                .charge(image.memory_bytes() as u64)
                                .map_err(|why| SceneError::new(source, &field, format!("texture {file:?} {why}")))?;
                        }
                        image.clone()
                    }
                    None => {
                        let image = Bitmap::read(&full, *raw, *wrap, budget.left())
                            .map_err(|e| SceneError::new(source, &field, e.to_string()))?;
                        budget
                            .charge(image.memory_bytes() as u64)
                            .map_err(|why| SceneError::new(source, &field, format!("texture {file:?} {why}")))?;
                        let image = Arc::new(image);
                        self.used.insert(key.clone());
                        self.images.insert(key, image.clone());
                        image
                    }
                };
                Texture::Bitmap { image, uv_map: uv_map(scale, to_uv), filter: *filter }
            }
        })
    }
}

/// The uv map of a texture description: `scale` after `to_uv`.
fn uv_map(scale: &[f32; 2], to_uv: &Option<[[f32; 3]; 2]>) -> UvMap {
    let scale = UvMap::scale(Vec2::from(*scale));
    match to_uv {
        Some(m) => scale.after(&UvMap::from_rows(*m)),
        None => scale,
    }
}
