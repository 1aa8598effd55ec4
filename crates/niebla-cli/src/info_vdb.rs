//! `niebla info FILE.vdb`: every grid of an OpenVDB file, one a line, with
//! its value type, class, active voxel count, bounds and value range.

use std::path::Path;

use niebla_volume::{Leaf, SparseGrid, Tile, VdbFile, VdbValueKind};

use crate::error::CliError;

/// Whether `path` names an OpenVDB file (by its extension).
pub fn is_vdb(path: &Path) -> bool {
    path.extension().is_some_and(|e| e.eq_ignore_ascii_case("vdb"))
}

/// Prints the file's grids (each decoded within the default memory limit).
pub fn run(path: &Path) -> Result<(), CliError> {
    if !path.exists() {
        return Err(CliError::SceneNotFound(path.to_path_buf()));
    }
    let file = VdbFile::open(path)?;
    let (major, minor) = file.library_version();
    println!(
        "file: {} (OpenVDB format {}, written by library {major}.{minor}), {} grids",
        path.display(),
        file.file_version(),
        file.grids().len()
    );
    let limit = niebla::limits::default_memory_limit();
    for info in file.grids() {
        let name = &info.unique_name;
        let class = file.grid_string_metadata(name, "class")?.unwrap_or_else(|| "unknown".into());
        let precision = if info.half { ", stored as half" } else { "" };
        let kind = info.value_kind();
        let type_name = match kind {
            VdbValueKind::Float => "float",
            VdbValueKind::Double => "double",
            VdbValueKind::Vec3Float => "vec3s",
            VdbValueKind::Vec3Double => "vec3d",
            VdbValueKind::Other => info.grid_type.as_str(),
        };
        let shown = name.replace('\u{1e}', "#");
        let stats = if kind.is_scalar() {
            let g = file.read_float_grid_limited(name, limit)?;
            let range = scalar_range(&g).map(|(lo, hi)| format!("values {lo}..{hi}"));
            describe(&g, g.active_voxel_count(), range)
        } else if kind.is_vec3() {
            let g = file.read_vec3_grid_limited(name, limit)?;
            let range = g.active_length_range().map(|(lo, hi)| format!("vector lengths {lo}..{hi}"));
            describe(g.component(0), g.active_voxel_count(), range)
        } else {
            "not read by niebla".to_string()
        };
        println!("  {shown}: {type_name}{precision}, class {class}, {stats}");
    }
    Ok(())
}

/// Active voxel count, index and world bounds of the active voxels, and the
/// value range, as one phrase.
fn describe(g: &SparseGrid, active: u64, range: Option<String>) -> String {
    let Some((lo, hi)) = g.active_bounds_index() else {
        return format!("empty (0 active voxels), background {}", g.background());
    };
    let mut wlo = [f64::INFINITY; 3];
    let mut whi = [f64::NEG_INFINITY; 3];
    for c in 0..8 {
        let p = std::array::from_fn(|a| if c >> a & 1 == 0 { lo[a] as f64 } else { hi[a] as f64 });
        let w = g.transform().transform_point(p);
        for a in 0..3 {
            wlo[a] = wlo[a].min(w[a]);
            whi[a] = whi[a].max(w[a]);
        }
    }
    format!(
        "{active} active voxels, {} leaves, index bounds {lo:?}..{hi:?}, world bounds {:?}..{:?} (voxel centers), {}",
        g.leaf_count(),
        wlo.map(|v| v as f32),
        whi.map(|v| v as f32),
        range.unwrap_or_default()
    )
}

/// Smallest and largest active value (voxels and active tiles).
fn scalar_range(g: &SparseGrid) -> Option<(f32, f32)> {
    let leaf_values = g
        .leaves()
        .iter()
        .flat_map(|l: &Leaf| (0..l.values.len()).filter(|&n| l.is_active(n)).map(move |n| l.values[n]));
    let tile_values = g.tiles().iter().filter(|t: &&Tile| t.active).map(|t| t.value);
    leaf_values.chain(tile_values).fold(None, |acc, v| match acc {
        None => Some((v, v)),
        Some((lo, hi)) => Some((lo.min(v), hi.max(v))),
    })
}
