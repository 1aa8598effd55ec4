//! Media, density sources and phase functions of the scene description.

use super::*;

// ---------------------------------------------------------------------------
// Media
// ---------------------------------------------------------------------------

/// A participating medium, tagged by `type` in the file; `type` may be left
/// out and defaults to `grid` when the medium has a `density`, else to
/// `homogeneous`.
// A handful of descriptions per scene, read once: boxing the large variant
// would only make matching on it clumsier.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Debug, PartialEq)]
pub enum MediumDesc {
    /// `"type": "homogeneous"`: constant coefficients.
    Homogeneous(HomogeneousMediumDesc),
    /// `"type": "grid"`: coefficients per unit density times a voxel density.
    Grid(GridMediumDesc),
    /// `"type": "pyro"`: fire and smoke from the grids of one VDB file, with
    /// Blender's Principled Volume parameters.
    Pyro(PyroMediumDesc),
}

impl MediumDesc {
    /// The `type` names, in the order of the variants.
    pub const TYPES: &'static [&'static str] = &["homogeneous", "grid", "pyro"];

    /// The phase function, whatever the type.
    pub fn phase(&self) -> &PhaseDesc {
        match self {
            MediumDesc::Homogeneous(m) => &m.phase,
            MediumDesc::Grid(m) => &m.phase,
            MediumDesc::Pyro(m) => &m.phase,
        }
    }
}

/// A medium with the same coefficients everywhere.
#[derive(Clone, Debug, PartialEq)]
pub struct HomogeneousMediumDesc {
    /// Absorption and scattering, in one of the two forms of the file.
    pub coefficients: CoefficientsDesc,
    /// Multiplies the coefficients (not the albedo); > 0, default 1.
    pub scale: f32,
    /// Phase function; default isotropic.
    pub phase: PhaseDesc,
    /// Emitted radiance, if the medium glows.
    pub emission: Option<EmissionDesc>,
}

impl HomogeneousMediumDesc {
    /// `(sigma_a, sigma_s)` per scene unit, with `scale` applied, whichever
    /// form the file used.
    pub fn sigma_a_sigma_s(&self) -> (Rgb, Rgb) {
        let (sigma_a, sigma_s) = self.coefficients.sigma_a_sigma_s();
        (sigma_a * self.scale, sigma_s * self.scale)
    }
}

/// The optical coefficients of a medium, per scene unit (before `scale`). A
/// file gives exactly one of the two forms.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum CoefficientsDesc {
    /// `sigma_a` and `sigma_s`: absorption and scattering coefficients, each
    /// finite and >= 0.
    AbsorptionScattering {
        /// Absorption coefficient sigma_a, >= 0.
        sigma_a: ColorDesc,
        /// Scattering coefficient sigma_s, >= 0.
        sigma_s: ColorDesc,
    },
    /// `sigma_t` and `albedo`: extinction coefficient (>= 0) and single
    /// scattering albedo `sigma_s / sigma_t` in [0, 1].
    ExtinctionAlbedo {
        /// Extinction coefficient sigma_t = sigma_a + sigma_s, >= 0.
        sigma_t: ColorDesc,
        /// Single-scattering albedo in [0, 1].
        albedo: ColorDesc,
    },
}

impl CoefficientsDesc {
    /// `(sigma_a, sigma_s)` per scene unit, converting from `sigma_t` and
    /// `albedo` if needed (`sigma_s = albedo sigma_t`, `sigma_a = sigma_t -
    /// sigma_s`).
    pub fn sigma_a_sigma_s(&self) -> (Rgb, Rgb) {
        match self {
            CoefficientsDesc::AbsorptionScattering { sigma_a, sigma_s } => (sigma_a.to_rgb(), sigma_s.to_rgb()),
            CoefficientsDesc::ExtinctionAlbedo { sigma_t, albedo } => {
                let sigma_t = sigma_t.to_rgb();
                let sigma_s = sigma_t * albedo.to_rgb();
                (sigma_t - sigma_s, sigma_s)
            }
        }
    }
}

/// Light emitted by a medium.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EmissionDesc {
    /// `L_ve`: emitted radiance per unit length, W/(sr m^2) per scene unit;
    /// finite and >= 0. Not multiplied by `scale` or by sigma_a.
    #[serde(rename = "L_ve")]
    pub l_ve: ColorDesc,
}

/// A heterogeneous medium: `sigma_x(p) = density(p) * scale * sigma_x`.
///
/// In a file:
/// ```json
/// {"type": "grid", "density": {"type": "vdb", "file": "plume.vdb"},
///  "sigma_t": 30, "albedo": 0.8, "phase": {"type": "hg", "g": 0.3},
///  "to_world": {"scale": 2}, "majorant_resolution": 16,
///  "emission": {"temperature": {"type": "vdb", "file": "plume.vdb", "grid": "temperature"}}}
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct GridMediumDesc {
    /// Absorption and scattering per unit density, in one of the two forms.
    pub coefficients: CoefficientsDesc,
    /// Multiplies the coefficients (not the albedo); > 0, default 1.
    pub scale: f32,
    /// Phase function; default isotropic.
    pub phase: PhaseDesc,
    /// The density (dimensionless multiplier of the coefficients; finite and
    /// >= 0 everywhere).
    pub density: DensitySourceDesc,
    /// Places the density source's space in the world: a dense source's box,
    /// or a VDB grid's own world space (after its index-to-world map).
    /// Default identity.
    pub to_world: TransformDesc,
    /// Emitted radiance, if the medium glows.
    pub emission: Option<GridEmissionDesc>,
    /// Resolution of the majorant grid; `None` is the default (16^3 cells,
    /// at most one per voxel, for dense sources; for VDB grids, cubic cells
    /// of two leaves (16 voxels,
    /// [`MajorantGrid::DEFAULT_SPARSE_MIN_CELL`](niebla_volume::MajorantGrid::DEFAULT_SPARSE_MIN_CELL))
    /// within [`MajorantGrid::DEFAULT_MAX_CELLS`](niebla_volume::MajorantGrid::DEFAULT_MAX_CELLS)
    /// cells). For a VDB grid a given resolution is a cell budget, spent on
    /// cells as small as one leaf.
    pub majorant_resolution: Option<ResolutionDesc>,
    /// Precision of dense voxel storage: `"f32"` (default) or `"f16"` (half
    /// the memory, about 3 significant digits; sparse VDB grids keep f32).
    pub storage: GridStorageDesc,
    /// Name of a Vec3 velocity grid in the density's VDB file, for Eulerian
    /// motion blur (the density at `x` and time `t` is the density at
    /// `x - v(x) t`); `None`: the medium does not move.
    pub velocity: Option<String>,
    /// Units of the velocity grid's values; default
    /// [`VelocityUnitsDesc::WorldPerSecond`].
    pub velocity_units: VelocityUnitsDesc,
    /// A spatially varying single-scattering albedo (`"albedo_grid"`): a
    /// dense source (`constant`, `grid`, `npy`, `vol`, `procedural`) of one
    /// channel (grey) or three (RGB: a 3-channel `.vol` or an `(nz, ny, nx,
    /// 3)` `.npy`), values in [0, 1], multiplied by the medium's `albedo`
    /// (then optional, default 1; the file gives `sigma_t`, not `sigma_a` and
    /// `sigma_s`). It is looked up trilinearly at cell centers in its own box,
    /// placed by `albedo_to_world`; outside its box the nearest point of the
    /// box is used (clamped, like Mitsuba's `gridvolume`), so its resolution
    /// and box need not match the density's (nothing is resampled). `None`:
    /// the albedo is constant.
    pub albedo_grid: Option<DensitySourceDesc>,
    /// Places the albedo grid's box in the world; `None`: the medium's
    /// `to_world` (as the density).
    pub albedo_to_world: Option<TransformDesc>,
}

/// Units of a velocity grid (`"velocity_units"`). "world" is the VDB file's
/// world space (after the grid's index-to-world map), which the medium's
/// `to_world` places in the scene like the density; "voxel" is the velocity
/// grid's own voxels. Per-second values are turned into per-frame ones by
/// the camera's `fps`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum VelocityUnitsDesc {
    /// World units per second: what Houdini, Blender (Cycles' default
    /// velocity unit, "Second") and OpenVDB's tools write.
    #[default]
    WorldPerSecond,
    /// World units per frame.
    WorldPerFrame,
    /// Voxels of the velocity grid per second.
    VoxelPerSecond,
    /// Voxels of the velocity grid per frame.
    VoxelPerFrame,
}

impl VelocityUnitsDesc {
    /// Whether the values are per second (else per frame).
    pub fn per_second(self) -> bool {
        matches!(self, VelocityUnitsDesc::WorldPerSecond | VelocityUnitsDesc::VoxelPerSecond)
    }

    /// Whether the values are in voxels of the velocity grid (else world units).
    pub fn in_voxels(self) -> bool {
        matches!(self, VelocityUnitsDesc::VoxelPerSecond | VelocityUnitsDesc::VoxelPerFrame)
    }
}

/// Precision in which a dense density grid is stored (`storage` in the file).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum GridStorageDesc {
    /// 32-bit floats.
    #[default]
    F32,
    /// 16-bit floats (IEEE half).
    F16,
}

impl GridMediumDesc {
    /// `(sigma_a, sigma_s)` per scene unit per unit density, with `scale`
    /// applied, whichever form the file used.
    pub fn sigma_a_sigma_s(&self) -> (Rgb, Rgb) {
        let (sigma_a, sigma_s) = self.coefficients.sigma_a_sigma_s();
        (sigma_a * self.scale, sigma_s * self.scale)
    }

    /// What multiplies the `albedo_grid`'s values: the `albedo` color of the
    /// `sigma_t` form (1 with the other form, which an albedo grid excludes).
    pub fn albedo_grid_scale(&self) -> Rgb {
        match &self.coefficients {
            CoefficientsDesc::ExtinctionAlbedo { albedo, .. } => albedo.to_rgb(),
            CoefficientsDesc::AbsorptionScattering { .. } => Rgb::ONE,
        }
    }
}

/// Largest majorant grid resolution per axis a file may ask for.
pub const MAX_MAJORANT_RESOLUTION: u32 = 256;
/// Largest number of voxels of an inline or procedural grid (2^28).
pub const MAX_GRID_VOXELS: u64 = 1 << 28;

/// A resolution: one number for all three axes, or `[nx, ny, nz]`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ResolutionDesc {
    /// The same count on every axis.
    Uniform(u32),
    /// Per axis, `[nx, ny, nz]`.
    PerAxis([u32; 3]),
}

impl ResolutionDesc {
    /// `[nx, ny, nz]`.
    pub fn dims(&self) -> [u32; 3] {
        match *self {
            ResolutionDesc::Uniform(n) => [n; 3],
            ResolutionDesc::PerAxis(d) => d,
        }
    }
}

/// An axis-aligned box `{"min": [x, y, z], "max": [x, y, z]}`; `max` exceeds
/// `min` on every axis. The default is the unit box `[0, 1]^3`.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BoundsDesc {
    /// Lowest corner.
    #[serde(deserialize_with = "vec3")]
    pub min: [f32; 3],
    /// Highest corner.
    #[serde(deserialize_with = "vec3")]
    pub max: [f32; 3],
}

impl BoundsDesc {
    /// The unit box `[0, 1]^3`.
    pub const UNIT: BoundsDesc = BoundsDesc { min: [0.0; 3], max: [1.0; 3] };
}

impl Default for BoundsDesc {
    fn default() -> BoundsDesc {
        BoundsDesc::UNIT
    }
}

/// Where a scalar field (a density, an emission grid, a temperature) comes
/// from, tagged by `type` in the file. Dense sources (`constant`, `grid`,
/// `npy`, `vol`, `procedural`) fill a box with `nx * ny * nz` values at cell
/// centers, indexed `[z][y][x]` with x fastest; `vdb` keeps the file's
/// sparse grid and its index-to-world map. File names are relative to the
/// scene file's folder.
#[derive(Clone, Debug, PartialEq)]
pub enum DensitySourceDesc {
    /// `"constant"`: one value filling `bounds`.
    Constant {
        /// The value, finite and >= 0; default 1.
        value: f32,
        /// The box it fills; default the unit box.
        bounds: BoundsDesc,
    },
    /// `"grid"`: a small grid written in the scene file.
    Grid(InlineGridDesc),
    /// `"npy"`: a NumPy `.npy` array of shape `(nz, ny, nx)`, float32 or
    /// float64, filling `bounds`.
    Npy {
        /// The file.
        file: String,
        /// The box it fills; default the unit box.
        bounds: BoundsDesc,
    },
    /// `"vol"`: a Mitsuba 3 binary `.vol` grid; its box is stored in the file.
    Vol {
        /// The file.
        file: String,
    },
    /// `"vdb"`: one float grid of an OpenVDB file.
    Vdb {
        /// The file.
        file: String,
        /// The grid's name; default `"density"`.
        grid: String,
    },
    /// `"procedural"`: seeded fractal noise over the unit box `[0, 1]^3`.
    Procedural(ProceduralDesc),
}

impl DensitySourceDesc {
    /// The `type` names, in the order of the variants.
    pub const TYPES: &'static [&'static str] = &["constant", "grid", "npy", "vol", "vdb", "procedural"];

    /// The file the source reads, if any (relative to the scene's folder).
    pub fn file(&self) -> Option<&str> {
        match self {
            DensitySourceDesc::Npy { file, .. }
            | DensitySourceDesc::Vol { file }
            | DensitySourceDesc::Vdb { file, .. } => Some(file),
            _ => None,
        }
    }
}

/// A grid written inline: `{"type": "grid", "data": [...], "dims": [nx, ny,
/// nz], "bounds": {...}}`.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InlineGridDesc {
    /// `nx * ny * nz` values, `[z][y][x]` with x fastest, each finite and
    /// >= 0.
    pub data: Vec<f32>,
    /// `[nx, ny, nz]`, each >= 1, product at most 2^28.
    pub dims: [u32; 3],
    /// The box the grid fills; default the unit box.
    #[serde(default)]
    pub bounds: BoundsDesc,
}

/// Seeded fractal noise (`"type": "procedural"`) over the unit box `[0,
/// 1]^3`, y up, baked by [`niebla_volume::procedural_density`]; values in
/// [0, 1].
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ProceduralDesc {
    /// `"cloud"` (default) or `"plume"`.
    #[serde(default)]
    pub shape: ProceduralShapeDesc,
    /// Seed of the noise; default 0.
    #[serde(default)]
    pub seed: u64,
    /// Voxels per axis, a number or `[nx, ny, nz]`, each from 1 to 1024, at
    /// most 2^28 in all; default 64. The voxels next to each face are zero.
    #[serde(default = "default_procedural_resolution")]
    pub resolution: ResolutionDesc,
    /// Noise octaves, 1 to 12; default 5.
    #[serde(default = "default_octaves")]
    pub octaves: u32,
    /// Base frequency in cycles per unit box, in (0, 1000]; default 3.
    #[serde(default = "default_frequency")]
    pub frequency: f32,
    /// Frequency ratio between octaves, in [1, 8]; default 2.
    #[serde(default = "default_lacunarity")]
    pub lacunarity: f32,
    /// Amplitude ratio between octaves, in [0, 1] (higher is rougher);
    /// default 0.5.
    #[serde(default = "default_gain")]
    pub gain: f32,
    /// Fraction of the box the medium covers, in [0, 1]; default 0.5.
    #[serde(default = "default_coverage")]
    pub coverage: f32,
    /// Edge sharpness, in (0, 1000]: the density rises from 0 to 1 over a
    /// band `1 / sharpness` wide (1 soft, 50 nearly hard); default 4.
    #[serde(default = "default_sharpness")]
    pub sharpness: f32,
}

fn default_procedural_resolution() -> ResolutionDesc {
    ResolutionDesc::Uniform(64)
}
fn default_octaves() -> u32 {
    5
}
fn default_frequency() -> f32 {
    3.0
}
fn default_lacunarity() -> f32 {
    2.0
}
fn default_gain() -> f32 {
    0.5
}
fn default_coverage() -> f32 {
    0.5
}
fn default_sharpness() -> f32 {
    4.0
}

/// The kind of procedural field.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ProceduralShapeDesc {
    /// `"cloud"`: a puffy blob.
    #[default]
    Cloud,
    /// `"plume"`: a rising column that spreads with height.
    Plume,
}

/// Light emitted by a grid medium: the file gives exactly one of `L_ve`,
/// `grid` and `temperature`.
#[derive(Clone, Debug, PartialEq)]
pub enum GridEmissionDesc {
    /// `{"L_ve": color}`: `L_ve(x) = L_ve * density(x)`.
    ProportionalToDensity {
        /// Emitted radiance per unit length at unit density, finite and >= 0.
        l_ve: ColorDesc,
    },
    /// `{"grid": source, "color": c, "emission_scale": s}`:
    /// `L_ve(x) = s * c * value(x)`.
    Field {
        /// The emission field (one channel, finite and >= 0), placed by the
        /// medium's `to_world` like the density.
        grid: DensitySourceDesc,
        /// Color, finite and >= 0; default 1.
        color: ColorDesc,
        /// Scale, finite and >= 0; default 1.
        emission_scale: f32,
    },
    /// `{"temperature": source, "emission_scale": s}`: `L_ve(x) = s *
    /// blackbody(T(x))`, the blackbody color of unit luminance at `T(x)`
    /// Kelvin (black below 400 K).
    Temperature {
        /// Temperature in Kelvin (finite and >= 0), placed by the medium's
        /// `to_world` like the density.
        temperature: DensitySourceDesc,
        /// Scale, finite and >= 0; default 1.
        emission_scale: f32,
    },
}

/// A phase function, tagged by `type` in the file; default isotropic.
///
/// Convention: `p(wo, wi)` with both directions pointing away from the
/// scattering point, normalized over the sphere; `g > 0` scatters forward.
#[derive(Clone, Debug, Default, PartialEq)]
pub enum PhaseDesc {
    /// `"isotropic"`: `1 / (4 pi)`.
    #[default]
    Isotropic,
    /// `"hg"`: Henyey-Greenstein (1941); pbrt-v4 section 11.3.1.
    HenyeyGreenstein {
        /// Asymmetry g in (-1, 1); g > 0 scatters forward.
        g: f32,
    },
    /// `"double_hg"`: `w HG(g1) + (1 - w) HG(g2)`.
    DoubleHenyeyGreenstein {
        /// Weight of the first lobe, in [0, 1].
        w: f32,
        /// Asymmetry of the first lobe, in (-1, 1).
        g1: f32,
        /// Asymmetry of the second lobe, in (-1, 1).
        g2: f32,
    },
    /// `"schlick"`: Blasi, Le Saec and Schlick (1993) approximation of HG.
    Schlick(SchlickDesc),
    /// `"rayleigh"`: `3 / (16 pi) (1 + cos^2 theta)`.
    Rayleigh,
    /// `"cornette_shanks"`: Cornette and Shanks (1992), HG with a Rayleigh-like
    /// `(1 + cos^2 theta)` factor.
    CornetteShanks {
        /// Asymmetry parameter g in (-1, 1).
        g: f32,
    },
    /// `"tabulated"`: a phase function read from a table file.
    Tabulated {
        /// Table file, relative to the scene file's folder.
        file: String,
        /// Name of the column holding the phase values; default
        /// `"p_mie_poly"`.
        column: String,
    },
    /// `"tabulated"` with the table written in the scene: `mu`, cosines of
    /// the scattering angle strictly increasing from -1 (backward) to 1
    /// (forward), and `p` (1/sr, any scale: renormalized), interpolated
    /// linearly in `mu` (Mitsuba 3's `tabphase`).
    TabulatedInline {
        /// Node cosines, ascending from -1 to 1.
        mu: Vec<f64>,
        /// Phase values at the nodes, 1/sr (any scale).
        p: Vec<f64>,
    },
    /// `"fog"`: two-lobe HG fit of the Mie phase function of fog droplets.
    Fog,
    /// `"mie_fog"`: the built-in Mie table of fog droplets.
    MieFog,
}

impl PhaseDesc {
    /// The `type` names, in the order of the variants.
    pub const TYPES: &'static [&'static str] =
        &["isotropic", "hg", "double_hg", "schlick", "rayleigh", "cornette_shanks", "tabulated", "fog", "mie_fog"];
}

/// The parameter of a Schlick phase function: the file gives exactly one of
/// `k` and `g`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SchlickDesc {
    /// `k`: Schlick's own parameter, in (-1, 1).
    K(f32),
    /// `g`: the asymmetry of the HG lobe to approximate, in (-1, 1); the
    /// renderer converts it to `k` (`k = 1.55 g - 0.55 g^3`).
    G(f32),
}
