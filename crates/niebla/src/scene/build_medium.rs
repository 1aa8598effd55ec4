//! From a medium description to the runtime [`Medium`]: homogeneous
//! coefficients, or a grid medium's voxel data loaded from its source
//! (inline, `.npy`, `.vol`, OpenVDB, procedural), checked, placed in the
//! world and given its majorant grid.
//!
//! Spaces: a dense source's values fill a box in its
//! own *local* space, which the medium's `to_world` places in the world, so
//! `world_to_grid = inverse(to_world)`. A VDB grid keeps its own
//! index-to-world map, after which `to_world` applies, so `world_to_grid =
//! inverse(to_world * index_to_world)`; that product is formed and inverted
//! in double precision, since VDB index spaces reach thousands of voxels.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::{Affine3A, Vec3A};
use niebla_volume::{
    procedural_density, read_npy, read_vol, Affine, DenseGrid, DenseVolume, GridStorage, Leaf, MajorantGrid,
    ProceduralParams, ProceduralShape, SparseGrid, VdbFile, VolumeError,
};

use super::build_transform;
use super::desc::*;
use super::SceneError;
use crate::color::{BlackbodyTable, Rgb};
use crate::limits::{format_bytes, MemoryBudget};
use crate::medium::{
    AlbedoField, AlbedoGrid, DensityGrid, GridEmission, GridField, GridMedium, GridMotion, HomogeneousMedium,
    LazyMinorant, Medium, MinorantRecipe,
};
use crate::phase::PhaseFunction;

mod pyro;

/// Majorant cells per axis of a dense grid when the file gives none (at most
/// one cell per voxel).
pub const DEFAULT_DENSE_MAJORANT_RESOLUTION: usize = 16;

/// Build the runtime medium of one scene medium description.
///
/// `path` is the medium's JSON path (`media.smoke`), `source` the scene file
/// named in errors, `base_dir` the folder relative file names resolve
/// against, and `phase` the medium's phase function, already built by the
/// caller. Errors name the JSON path of the source at fault (`.file` for
/// unreadable files and bad values in them, `.grid` for a VDB grid that is
/// not in its file) and, through the volume crate's message, the file.
/// Grids, majorant grids and files read are charged to `budget` before they
/// are allocated; what does not fit is an error at the field that asked
/// for it.
pub(crate) fn build_medium(
    desc: &MediumDesc,
    path: &str,
    source: &str,
    base_dir: &Path,
    phase: PhaseFunction,
    budget: &mut MemoryBudget,
) -> Result<Medium, SceneError> {
    match desc {
        MediumDesc::Homogeneous(h) => {
            let (sigma_a, sigma_s) = h.sigma_a_sigma_s();
            let l_ve = h.emission.map_or(Rgb::ZERO, |e| e.l_ve.to_rgb());
            Ok(Medium::Homogeneous(HomogeneousMedium { sigma_a, sigma_s, l_ve, phase }))
        }
        MediumDesc::Grid(g) => {
            let mut loader = Loader { source, base_dir, vdb_files: Vec::new(), vdb_file_bytes: 0, budget };
            let medium = build_grid_medium(g, path, &mut loader, phase).map(Medium::Grid);
            // The files are dropped here; their bytes no longer count.
            loader.budget.used = loader.budget.used.saturating_sub(loader.vdb_file_bytes);
            medium
        }
        MediumDesc::Pyro(p) => {
            let mut loader = Loader { source, base_dir, vdb_files: Vec::new(), vdb_file_bytes: 0, budget };
            let medium = pyro::build_pyro_medium(p, path, &mut loader, phase).map(Medium::Grid);
            loader.budget.used = loader.budget.used.saturating_sub(loader.vdb_file_bytes);
            medium
        }
    }
}

fn build_grid_medium(
    desc: &GridMediumDesc,
    path: &str,
    loader: &mut Loader,
    phase: PhaseFunction,
) -> Result<GridMedium, SceneError> {
    let to_world = build_transform(&desc.to_world)
        .ok_or_else(|| loader.error(&format!("{path}.to_world"), "transform is singular (zero scale?)".into()))?;
    let to_world = to_world.to_world;

    // Density, placed in the world.
    let density_path = format!("{path}.density");
    let density = loader.load(&density_path, &desc.density, FieldKind::Density)?;
    let density = match (density, desc.storage) {
        (DensityGrid::Dense(g), GridStorageDesc::F16) => DensityGrid::Dense(std::sync::Arc::new(g.to_f16())),
        (other, _) => other,
    };
    let world_to_grid = loader.world_to_grid(&density_path, &density, &to_world)?;

    // Majorant and minorant grids (the same cells), in the density grid's
    // space; the minorant is residual ratio tracking's control density,
    // built on first use (its memory is charged here all the same).
    let majorant_path = format!("{path}.majorant_resolution");
    let charge_cells = |loader: &mut Loader, cells: usize| {
        // Two grids (majorant and minorant) of one f32 per cell.
        let bytes = (cells as u64).saturating_mul(2 * 4);
        loader.charge(&majorant_path, bytes, &format!("the majorant and minorant grids of {cells} cells"))
    };
    let (majorant, minorant) = match &density {
        DensityGrid::Dense(g) => {
            let res = match desc.majorant_resolution {
                Some(r) => r.dims().map(|n| n as usize),
                // More cells than voxels bound nothing tighter.
                None => g.dims().map(|n| n.min(DEFAULT_DENSE_MAJORANT_RESOLUTION)),
            };
            charge_cells(loader, res.iter().product())?;
            (MajorantGrid::from_dense(g, res), MinorantRecipe::Dense(res))
        }
        DensityGrid::Sparse(g) => {
            // A given resolution is a cell budget; the cells stay cubic and
            // aligned to the VDB leaves, one per leaf where the budget
            // allows. By default, cells of two leaves (fewer DDA steps).
            let (max_cells, min_cell) = match desc.majorant_resolution {
                Some(r) => (r.dims().iter().map(|&n| n as usize).product(), niebla_volume::LEAF_DIM as usize),
                None => (MajorantGrid::DEFAULT_MAX_CELLS, MajorantGrid::DEFAULT_SPARSE_MIN_CELL),
            };
            charge_cells(loader, max_cells)?;
            let majorant = MajorantGrid::from_sparse_with_min_cell(g, max_cells, min_cell);
            (majorant, MinorantRecipe::Sparse { max_cells, min_cell })
        }
    };

    // Emission.
    let emission = match &desc.emission {
        None => GridEmission::None,
        Some(GridEmissionDesc::ProportionalToDensity { l_ve }) => GridEmission::ProportionalToDensity(l_ve.to_rgb()),
        Some(GridEmissionDesc::Field { grid, color, emission_scale }) => {
            let field_path = format!("{path}.emission.grid");
            let field = loader.field(&field_path, grid, FieldKind::Emission, &to_world)?;
            GridEmission::Field { field, scale: color.to_rgb() * *emission_scale }
        }
        Some(GridEmissionDesc::Temperature { temperature, emission_scale }) => {
            let field_path = format!("{path}.emission.temperature");
            let field = loader.field(&field_path, temperature, FieldKind::Temperature, &to_world)?;
            GridEmission::Temperature { field, scale: *emission_scale, table: Arc::new(BlackbodyTable::new()) }
        }
    };

    let motion = match &desc.velocity {
        None => None,
        Some(name) => Some(build_motion(desc, path, name, loader, &density, &to_world, &world_to_grid)?),
    };

    // Albedo field, placed by its own transform (default: the density's).
    let albedo = match &desc.albedo_grid {
        None => None,
        Some(source) => {
            let at = format!("{path}.albedo_grid");
            let place = match &desc.albedo_to_world {
                None => to_world,
                Some(t) => {
                    build_transform(t)
                        .ok_or_else(|| {
                            loader
                                .error(&format!("{path}.albedo_to_world"), "transform is singular (zero scale?)".into())
                        })?
                        .to_world
                }
            };
            Some(loader.albedo_field(&at, source, &place, desc.albedo_grid_scale())?)
        }
    };

    let (sigma_a, sigma_s) = desc.sigma_a_sigma_s();
    let mut medium = GridMedium::new(sigma_a, sigma_s, density, world_to_grid, majorant, None, emission, phase);
    medium.minorant = LazyMinorant::on_demand(minorant);
    medium.albedo = albedo;
    // Until the shutter is set, the moving medium is bounded by the static
    // majorant (valid at time 0).
    medium.motion = motion.map(|m| GridMotion { majorant: medium.majorant.clone(), ..m });
    Ok(medium)
}

/// The Eulerian motion of a grid medium from the Vec3 grid `name` of its
/// density's VDB file (errors at `{path}.velocity`); its majorant is the
/// static one until the scene's shutter is known
/// ([`GridMedium::set_shutter`]).
fn build_motion(
    desc: &GridMediumDesc,
    path: &str,
    name: &str,
    loader: &mut Loader,
    density: &DensityGrid,
    to_world: &Affine3A,
    world_to_grid: &Affine3A,
) -> Result<GridMotion, SceneError> {
    let at = format!("{path}.velocity");
    let (DensitySourceDesc::Vdb { file, .. }, DensityGrid::Sparse(_)) = (&desc.density, density) else {
        return Err(loader.error(
            &at,
            "a velocity grid is read from the density's OpenVDB file: it needs a density of \
             \"type\": \"vdb\""
                .into(),
        ));
    };
    let full = loader.base_dir.join(file);
    let kinds = loader.vdb_grid_kinds(&at, &full)?;
    match kinds.iter().find(|(n, _)| n == name) {
        None => {
            let names: Vec<&str> = kinds.iter().map(|(n, _)| n.as_str()).collect();
            return Err(loader.error(
                &at,
                format!("{}: no grid named {name:?} (the file holds: {})", full.display(), names.join(", ")),
            ));
        }
        Some((_, kind)) if !kind.is_vec3() => {
            return Err(loader.error(
                &at,
                format!(
                    "{}: grid {name:?} is not a Vec3 grid ({}); a velocity grid must be a Vec3 grid",
                    full.display(),
                    if kind.is_scalar() { "it holds scalars" } else { "its values are of another type" }
                ),
            ));
        }
        Some(_) => {}
    }
    let index = loader.open_vdb(&at, &full)?;
    let left = loader.budget.left();
    let velocity = loader.vdb_files[index]
        .1
        .read_vec3_grid_limited(name, left)
        .map_err(|e| loader.error(&at, format!("{}: grid {name:?}: {e}", full.display())))?;
    let bytes = 3 * (velocity.leaf_count() as u64 * std::mem::size_of::<Leaf>() as u64);
    loader.charge(&at, bytes, &format!("velocity grid {name:?}"))?;

    // Largest |component| over everything interpolation reads; NaN or
    // infinite velocities are errors.
    let mut max_abs = [0.0f32; 3];
    for (c, m) in max_abs.iter_mut().enumerate() {
        let g = velocity.component(c);
        let values = std::iter::once(g.background())
            .chain(g.tiles().iter().map(|t| t.value))
            .chain(g.leaves().iter().flat_map(|l| l.values.iter().copied()));
        for v in values {
            if !v.is_finite() {
                return Err(loader.error(
                    &at,
                    format!("{}: grid {name:?} holds the value {v}; velocities must be finite", full.display()),
                ));
            }
            *m = m.max(v.abs());
        }
    }

    // Spaces: density grid (index) -> scene world -> velocity index.
    let to_world_f64 = affine_f64(to_world);
    let velocity_to_world = to_world_f64.compose(velocity.transform());
    let world_to_velocity = velocity_to_world.inverse().ok_or_else(|| {
        loader.error(&at, "the velocity grid's index-to-world transform followed by `to_world` is singular".into())
    })?;
    let grid_to_velocity = affine_f32(&world_to_velocity) * world_to_grid.inverse();
    // A stored vector to a scene-world displacement per unit of time.
    let units = desc.velocity_units;
    let stored_to_world = if units.in_voxels() { affine_f32(&velocity_to_world).matrix3 } else { to_world.matrix3 };
    let stored_to_world = glam::Mat3::from(stored_to_world);
    let to_grid = glam::Mat3::from(world_to_grid.matrix3) * stored_to_world;
    Ok(GridMotion {
        velocity: Arc::new(velocity),
        grid_to_velocity,
        to_grid_per_frame: to_grid,
        to_world_per_frame: stored_to_world,
        max_abs_velocity: max_abs,
        per_second: units.per_second(),
        majorant: MajorantGrid::new([1, 1, 1], [0.0; 3], [1.0; 3], vec![0.0]).expect("a 1-cell grid"),
    })
}

/// What a field means, for messages.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum FieldKind {
    Density,
    Emission,
    Temperature,
    Albedo,
}

impl FieldKind {
    fn noun(self) -> &'static str {
        match self {
            FieldKind::Density => "density",
            FieldKind::Emission => "emission",
            FieldKind::Temperature => "temperature",
            FieldKind::Albedo => "albedo",
        }
    }
}

/// Loads field sources of one medium; an OpenVDB file read for the density
/// is reused for the emission.
struct Loader<'a> {
    source: &'a str,
    base_dir: &'a Path,
    vdb_files: Vec<(PathBuf, VdbFile)>,
    /// Bytes of the files in `vdb_files`, charged while they are held.
    vdb_file_bytes: u64,
    budget: &'a mut MemoryBudget,
}

impl Loader<'_> {
    fn error(&self, path: &str, message: String) -> SceneError {
        SceneError::new(self.source, path, message)
    }

    /// Charges `bytes` for `what` to the budget, or an error at `path`.
    fn charge(&mut self, path: &str, bytes: u64, what: &str) -> Result<(), SceneError> {
        self.budget.charge(bytes).map_err(|why| self.error(path, format!("{what} {why}")))
    }

    /// Checks that `file` is a regular file whose bytes, read into memory
    /// and decoded into at most as many bytes of values, fit in what is left
    /// of the budget; returns its length. (Devices and pipes are refused:
    /// `/dev/zero` would never end.)
    fn check_file(&self, at: &str, file: &Path, copies: u64) -> Result<u64, SceneError> {
        let meta =
            std::fs::metadata(file).map_err(|e| self.error(at, format!("{}: cannot read: {e}", file.display())))?;
        if !meta.is_file() {
            return Err(self.error(at, format!("{}: not a regular file", file.display())));
        }
        let bytes = meta.len().saturating_mul(copies);
        if bytes > self.budget.left() {
            let mut probe = *self.budget;
            let why = probe.charge(bytes).unwrap_err();
            return Err(
                self.error(at, format!("{}: reading the {} file {why}", file.display(), format_bytes(meta.len())))
            );
        }
        Ok(meta.len())
    }

    /// A volume crate error at `{field}.file` (its message names the file).
    fn file_error(&self, field: &str, e: VolumeError) -> SceneError {
        let at = match e {
            VolumeError::GridNotFound { .. } | VolumeError::UnsupportedGridType { .. } => {
                format!("{field}.grid")
            }
            _ => format!("{field}.file"),
        };
        self.error(&at, e.to_string())
    }

    /// A field source placed in the world by `to_world`.
    fn field(
        &mut self,
        field: &str,
        desc: &DensitySourceDesc,
        kind: FieldKind,
        to_world: &Affine3A,
    ) -> Result<GridField, SceneError> {
        let grid = self.load(field, desc, kind)?;
        let world_to_grid = self.world_to_grid(field, &grid, to_world)?;
        Ok(GridField { grid, world_to_grid })
    }

    /// An albedo field (one channel or RGB) placed in the world by
    /// `to_world`, its values times `scale`; values outside [0, 1] are errors
    /// at `{field}.file` (or `field` for sources in the scene file).
    fn albedo_field(
        &mut self,
        field: &str,
        desc: &DensitySourceDesc,
        to_world: &Affine3A,
        scale: Rgb,
    ) -> Result<AlbedoField, SceneError> {
        let file_path = format!("{field}.file");
        let volume = match desc {
            DensitySourceDesc::Npy { file, bounds } => {
                let full = self.base_dir.join(file);
                self.check_file(&file_path, &full, 2)?;
                Some(
                    read_npy(&full)
                        .and_then(|v| v.with_bounds(bounds.min, bounds.max))
                        .map_err(|e| self.file_error(field, e))?,
                )
            }
            DensitySourceDesc::Vol { file } => {
                let full = self.base_dir.join(file);
                self.check_file(&file_path, &full, 2)?;
                Some(read_vol(&full).map_err(|e| self.file_error(field, e))?)
            }
            DensitySourceDesc::Vdb { .. } => {
                return Err(self.error(
                    &format!("{field}.type"),
                    "an albedo grid must be a dense source (constant, grid, npy, vol or procedural), not vdb".into(),
                ))
            }
            _ => None,
        };
        let (grid, label, at) = match volume {
            None => match self.load(field, desc, FieldKind::Albedo)? {
                DensityGrid::Dense(g) => (AlbedoGrid::Grey(g), "albedo source".to_string(), field.to_string()),
                DensityGrid::Sparse(_) => unreachable!("sparse sources were refused above"),
            },
            Some(volume) => {
                let [nx, ny, nz] = volume.dims();
                let label = self.base_dir.join(desc.file().unwrap_or_default()).display().to_string();
                let grid = match volume {
                    DenseVolume::Scalar(g) => {
                        self.charge(
                            &file_path,
                            g.storage().len() as u64 * 4,
                            &format!("the {nx} x {ny} x {nz} albedo grid"),
                        )?;
                        AlbedoGrid::Grey(Arc::new(g))
                    }
                    DenseVolume::Rgb(g) => {
                        self.charge(
                            &file_path,
                            g.values().len() as u64 * 12,
                            &format!("the {nx} x {ny} x {nz} RGB albedo grid"),
                        )?;
                        AlbedoGrid::Rgb(Arc::new(g))
                    }
                };
                (grid, label, file_path)
            }
        };
        // Finite, in [0, 1] (a grey grid from a source in the scene file was
        // checked >= 0 by `load`; the upper bound is checked here).
        let bad = match &grid {
            AlbedoGrid::Grey(g) => {
                let s = g.storage();
                (0..s.len()).find(|&i| !(0.0..=1.0).contains(&s.get(i))).map(|i| (i, format!("{}", s.get(i)), g.dims()))
            }
            AlbedoGrid::Rgb(g) => g
                .values()
                .iter()
                .position(|v| !v.iter().all(|c| (0.0..=1.0).contains(c)))
                .map(|i| (i, format!("{:?}", g.values()[i]), g.dims())),
        };
        if let Some((i, value, [nx, ny, _])) = bad {
            let (x, y, z) = (i % nx, i / nx % ny, i / (nx * ny));
            return Err(self.error(
                &at,
                format!(
                    "{label}: voxel (x, y, z) = ({x}, {y}, {z}) has value {value}; albedo values must be in [0, 1]"
                ),
            ));
        }
        Ok(AlbedoField::new(grid, to_world.inverse(), scale))
    }

    /// World to the grid's own space (dense: local box; sparse: index).
    fn world_to_grid(&self, field: &str, grid: &DensityGrid, to_world: &Affine3A) -> Result<Affine3A, SceneError> {
        match grid {
            DensityGrid::Dense(_) => Ok(to_world.inverse()),
            DensityGrid::Sparse(g) => {
                let index_to_world = affine_f64(to_world).compose(g.transform());
                let world_to_index = index_to_world.inverse().ok_or_else(|| {
                    self.error(
                        field,
                        "the VDB grid's index-to-world transform followed by the medium's \
                         `to_world` is singular"
                            .into(),
                    )
                })?;
                Ok(affine_f32(&world_to_index))
            }
        }
    }

    /// Loads and checks one field source.
    fn load(&mut self, field: &str, desc: &DensitySourceDesc, kind: FieldKind) -> Result<DensityGrid, SceneError> {
        let file_path = format!("{field}.file");
        let noun = kind.noun();
        let grid = match desc {
            DensitySourceDesc::Constant { value, bounds } => {
                DenseGrid::new([1, 1, 1], vec![*value], bounds.min, bounds.max)
                    .map_err(|e| self.error(field, e.to_string()))?
            }
            DensitySourceDesc::Grid(g) => {
                let voxels = g.dims.iter().fold(1u64, |a, &n| a.saturating_mul(u64::from(n)));
                let [nx, ny, nz] = g.dims;
                self.charge(
                    &format!("{field}.dims"),
                    voxels.saturating_mul(4),
                    &format!("the {nx} x {ny} x {nz} {noun} grid"),
                )?;
                DenseGrid::new(g.dims.map(|n| n as usize), g.data.clone(), g.bounds.min, g.bounds.max)
                    .map_err(|e| self.error(field, e.to_string()))?
            }
            DensitySourceDesc::Npy { file, bounds } => {
                let full = self.base_dir.join(file);
                self.check_file(&file_path, &full, 2)?;
                let volume = read_npy(&full)
                    .and_then(|v| v.with_bounds(bounds.min, bounds.max))
                    .map_err(|e| self.file_error(field, e))?;
                self.scalar(&file_path, &full, volume, kind)?
            }
            DensitySourceDesc::Vol { file } => {
                let full = self.base_dir.join(file);
                self.check_file(&file_path, &full, 2)?;
                let volume = read_vol(&full).map_err(|e| self.file_error(field, e))?;
                self.scalar(&file_path, &full, volume, kind)?
            }
            DensitySourceDesc::Vdb { file, grid } => {
                let full = self.base_dir.join(file);
                let sparse = self.read_vdb(field, &full, grid)?;
                check_sparse(&sparse, kind)
                    .map_err(|what| self.error(&file_path, format!("{}: grid {grid:?}: {what}", full.display())))?;
                return Ok(DensityGrid::Sparse(Arc::new(sparse)));
            }
            DensitySourceDesc::Procedural(p) => {
                let [nx, ny, nz] = p.resolution.dims();
                let voxels = [nx, ny, nz].iter().fold(1u64, |a, &n| a.saturating_mul(u64::from(n)));
                let what = format!("the procedural {noun} of {nx} x {ny} x {nz} voxels");
                self.charge(&format!("{field}.resolution"), voxels.saturating_mul(4), &what)?;
                build_procedural(p).map_err(|e| self.error(field, format!("procedural {noun}: {e}")))?
            }
        };
        if desc.file().is_some() {
            let [nx, ny, nz] = grid.dims();
            self.charge(&file_path, grid.storage().len() as u64 * 4, &format!("the {nx} x {ny} x {nz} {noun} grid"))?;
        }
        check_dense(&grid, kind).map_err(|what| {
            let at = desc.file().map_or(field, |_| file_path.as_str());
            let label = desc
                .file()
                .map_or_else(|| format!("{} source", kind.noun()), |f| self.base_dir.join(f).display().to_string());
            self.error(at, format!("{label}: {what}"))
        })?;
        Ok(DensityGrid::Dense(Arc::new(grid)))
    }

    /// The one channel of a dense file volume; RGB volumes are rejected.
    fn scalar(&self, at: &str, file: &Path, volume: DenseVolume, kind: FieldKind) -> Result<DenseGrid, SceneError> {
        match volume {
            DenseVolume::Scalar(g) => Ok(g),
            DenseVolume::Rgb(_) => {
                let hint = match kind {
                    FieldKind::Density => "a density must have one channel",
                    FieldKind::Emission => {
                        "RGB emission grids are not supported yet: give a one-channel grid \
                         and its `color`"
                    }
                    FieldKind::Temperature => "a temperature must have one channel",
                    FieldKind::Albedo => "an albedo grid of 3 channels is read by `albedo_grid` only",
                };
                Err(self.error(at, format!("{}: has 3 channels (RGB); {hint}", file.display())))
            }
        }
    }

    /// The names and value types of the grids of an OpenVDB file (read
    /// once per medium, like [`Loader::read_vdb`]).
    fn vdb_grid_kinds(
        &mut self,
        field: &str,
        file: &Path,
    ) -> Result<Vec<(String, niebla_volume::VdbValueKind)>, SceneError> {
        let index = self.open_vdb(field, file)?;
        Ok(self.vdb_files[index].1.grids().iter().map(|g| (g.unique_name.clone(), g.value_kind())).collect())
    }

    /// The index in `vdb_files` of `file`, opening it (within the budget)
    /// on first use.
    fn open_vdb(&mut self, field: &str, file: &Path) -> Result<usize, SceneError> {
        if let Some(i) = self.vdb_files.iter().position(|(p, _)| p == file) {
            return Ok(i);
        }
        let at = if field.ends_with(".file") { field.to_string() } else { format!("{field}.file") };
        let len = self.check_file(&at, file, 1)?;
        self.charge(&at, len, &format!("{}: reading the file", file.display()))?;
        self.vdb_file_bytes += len;
        let opened = VdbFile::open(file).map_err(|e| self.error(&at, e.to_string()))?;
        self.vdb_files.push((file.to_path_buf(), opened));
        Ok(self.vdb_files.len() - 1)
    }

    /// One float grid of an OpenVDB file; each file is read once per medium.
    fn read_vdb(&mut self, field: &str, file: &Path, grid: &str) -> Result<SparseGrid, SceneError> {
        let index = match self.vdb_files.iter().position(|(p, _)| p == file) {
            Some(i) => i,
            None => {
                let at = format!("{field}.file");
                let len = self.check_file(&at, file, 1)?;
                self.charge(&at, len, &format!("{}: reading the file", file.display()))?;
                self.vdb_file_bytes += len;
                let opened = VdbFile::open(file).map_err(|e| self.file_error(field, e))?;
                self.vdb_files.push((file.to_path_buf(), opened));
                self.vdb_files.len() - 1
            }
        };
        let left = self.budget.left();
        let sparse =
            self.vdb_files[index].1.read_float_grid_limited(grid, left).map_err(|e| self.file_error(field, e))?;
        let bytes = sparse.leaf_count() as u64 * std::mem::size_of::<Leaf>() as u64
            + sparse.tiles().len() as u64 * std::mem::size_of::<niebla_volume::Tile>() as u64;
        self.charge(&format!("{field}.file"), bytes, &format!("grid {grid:?}"))?;
        Ok(sparse)
    }
}

/// The procedural field over the unit box.
fn build_procedural(desc: &ProceduralDesc) -> Result<DenseGrid, VolumeError> {
    let params = ProceduralParams {
        shape: match desc.shape {
            ProceduralShapeDesc::Cloud => ProceduralShape::Cloud,
            ProceduralShapeDesc::Plume => ProceduralShape::Plume,
        },
        seed: desc.seed,
        resolution: desc.resolution.dims().map(|n| n as usize),
        octaves: desc.octaves,
        frequency: desc.frequency,
        lacunarity: desc.lacunarity,
        gain: desc.gain,
        coverage: desc.coverage,
        sharpness: desc.sharpness,
    };
    procedural_density(&params)
}

/// First voxel of a dense grid that is NaN, infinite or negative, as a
/// message.
fn check_dense(grid: &DenseGrid, kind: FieldKind) -> Result<(), String> {
    let storage = grid.storage();
    let bad = match storage {
        GridStorage::F32(v) => v.iter().position(|x| !valid(*x)),
        GridStorage::F16(_) => (0..storage.len()).find(|&i| !valid(storage.get(i))),
    };
    let Some(i) = bad else { return Ok(()) };
    let [nx, ny, _] = grid.dims();
    let (x, y, z) = (i % nx, i / nx % ny, i / (nx * ny));
    Err(format!(
        "voxel (x, y, z) = ({x}, {y}, {z}) has value {}; {} values must be finite and >= 0",
        storage.get(i),
        kind.noun()
    ))
}

/// The first stored value of a sparse grid (background, tiles, leaves, in
/// that order) that is NaN, infinite or negative, as a message. Inactive
/// values count too: interpolation reads them.
fn check_sparse(grid: &SparseGrid, kind: FieldKind) -> Result<(), String> {
    let rule = format!("{} values must be finite and >= 0", kind.noun());
    if !valid(grid.background()) {
        return Err(format!("the background value is {}; {rule}", grid.background()));
    }
    if let Some(t) = grid.tiles().iter().find(|t| !valid(t.value)) {
        let s = t.size();
        return Err(format!(
            "the tile of {s}^3 voxels at index (i, j, k) = ({}, {}, {}) has value {}; {rule}",
            t.origin[0], t.origin[1], t.origin[2], t.value
        ));
    }
    for leaf in grid.leaves() {
        if let Some(n) = leaf.values.iter().position(|v| !valid(*v)) {
            let [i, j, k] = leaf_voxel(leaf, n);
            return Err(format!("voxel (i, j, k) = ({i}, {j}, {k}) has value {}; {rule}", leaf.values[n]));
        }
    }
    Ok(())
}

/// Index-space coordinates of value `n` of a leaf (`n = i << 6 | j << 3 | k`
/// in the leaf).
fn leaf_voxel(leaf: &Leaf, n: usize) -> [i32; 3] {
    let n = n as i32;
    [leaf.origin[0] + (n >> 6 & 7), leaf.origin[1] + (n >> 3 & 7), leaf.origin[2] + (n & 7)]
}

fn valid(x: f32) -> bool {
    x.is_finite() && x >= 0.0
}

/// An `Affine3A` in double precision.
fn affine_f64(m: &Affine3A) -> Affine {
    let cols = [m.matrix3.x_axis, m.matrix3.y_axis, m.matrix3.z_axis, m.translation];
    Affine { rows: std::array::from_fn(|r| std::array::from_fn(|c| f64::from(cols[c][r]))) }
}

/// A double-precision affine map rounded to `Affine3A`.
fn affine_f32(m: &Affine) -> Affine3A {
    let col = |c: usize| Vec3A::from(std::array::from_fn::<f32, 3, _>(|r| m.rows[r][c] as f32));
    Affine3A::from_cols(col(0), col(1), col(2), col(3))
}
