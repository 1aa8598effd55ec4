//! Building the textures of a scene's surfaces: image files read once per
//! (file, raw, wrap) within the memory budget, checkerboards from their
//! colors.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use super::desc::TextureDesc;
use super::SceneError;
use crate::limits::MemoryBudget;
use crate::math::Vec2;
use crate::texture::{Bitmap, Texture, WrapMode};

/// The image textures of one scene build, shared by file and options.
#[derive(Default)]
pub(super) struct TextureLoader {
    images: HashMap<(PathBuf, bool, WrapMode), Arc<Bitmap>>,
}

impl TextureLoader {
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
            TextureDesc::Checkerboard { color0, color1, scale } => {
                Texture::Checkerboard { color0: color0.to_rgb(), color1: color1.to_rgb(), scale: Vec2::from(*scale) }
            }
            TextureDesc::Bitmap { file, wrap, raw, scale } => {
                let full = base_dir.join(file);
                let key = (full.clone(), *raw, *wrap);
                let image = match self.images.get(&key) {
                    Some(image) => image.clone(),
                    None => {
                        let field = format!("{path}.file");
                        let image = Bitmap::read(&full, *raw, *wrap, budget.left())
                            .map_err(|e| SceneError::new(source, &field, e.to_string()))?;
                        budget
                            .charge(image.memory_bytes() as u64)
                            .map_err(|why| SceneError::new(source, &field, format!("texture {file:?} {why}")))?;
                        let image = Arc::new(image);
                        self.images.insert(key, image.clone());
                        image
                    }
                };
                Texture::Bitmap { image, scale: Vec2::from(*scale) }
            }
        })
    }
}
