//! Shapes, surfaces and transforms of the scene description.

use super::*;

// ---------------------------------------------------------------------------
// Shapes
// ---------------------------------------------------------------------------

/// A shape: its geometry (tagged by `type` in the file), the media on either
/// side and its surface.
#[derive(Clone, Debug, PartialEq)]
pub struct ShapeDesc {
    /// Geometry; `type` names it.
    pub geometry: GeometryDesc,
    /// Name of the medium inside (behind the surface normal), a key of
    /// `media`; `None` means vacuum, or for open shapes nothing.
    pub interior: Option<String>,
    /// Name of the medium outside (on the normal's side), a key of `media`;
    /// `None` means the surrounding medium.
    pub exterior: Option<String>,
    /// Surface scattering; default `null` (an index-matched medium boundary).
    pub bsdf: BsdfDesc,
    /// The shape's pose one frame later (time 1), for motion blur; default:
    /// the shape does not move. Boxed, as few shapes move.
    pub motion: Option<Box<ShapeMotionDesc>>,
    /// `"tangent_frame"`: how anisotropic roughness (`alpha_u` != `alpha_v`)
    /// is oriented on this shape; default `"normal"`.
    pub tangent_frame: TangentFrameDesc,
}

/// `"tangent_frame"` of a shape: the direction of a microfacet
/// distribution's `alpha_u` axis (it matters for anisotropic roughness
/// only).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum TangentFrameDesc {
    /// `"normal"` (the default, niebla's frame before 2026-12): the x axis
    /// of a basis built from the shading normal alone (Duff et al. 2017),
    /// which turns with the normal but follows no parameterization.
    #[default]
    Normal,
    /// `"dpdu"`: the shape's `dp/du` made orthogonal to the shading normal,
    /// Mitsuba 3's frame (sphere: along the azimuth; rectangle: its local
    /// x; disk: radial; box: the face's u axis; mesh: from its uvs, else
    /// its barycentric uv, i.e. the triangle's edge `p1 - p0`).
    Dpdu,
}

/// `"motion"` of a shape: its pose one frame after the rendered frame (time
/// 1, in frames; the shape's own fields are its pose at time 0), with the
/// names of the shape's own fields: `center` and `radius` for a sphere,
/// `min` and `max` for a box, `to_world` for a rectangle, disk or mesh.
/// Fields left out keep the shape's own value. The pose at a camera
/// sample's time is interpolated linearly (sphere and box) or by
/// translation, rotation (slerp) and scale (transforms); see
/// `geometry::MovingShape`.
#[derive(Clone, Debug, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ShapeMotionDesc {
    /// A sphere's center at time 1.
    #[serde(default, deserialize_with = "optional_vec3")]
    pub center: Option<[f32; 3]>,
    /// A sphere's radius at time 1.
    #[serde(default)]
    pub radius: Option<f32>,
    /// A box's minimum corner at time 1.
    #[serde(default, deserialize_with = "optional_vec3")]
    pub min: Option<[f32; 3]>,
    /// A box's maximum corner at time 1.
    #[serde(default, deserialize_with = "optional_vec3")]
    pub max: Option<[f32; 3]>,
    /// A rectangle's, disk's or mesh's object-to-world transform at time 1.
    #[serde(default)]
    pub to_world: Option<TransformDesc>,
}

/// The geometry of a shape.
#[derive(Clone, Debug, PartialEq)]
pub enum GeometryDesc {
    /// `"type": "sphere"`.
    Sphere(SphereDesc),
    /// `"type": "box"`: an axis-aligned box.
    Box(BoxDesc),
    /// `"type": "rectangle"`.
    Rectangle(RectangleDesc),
    /// `"type": "disk"`.
    Disk(DiskDesc),
    /// `"type": "mesh"`: a triangle mesh from a file or inline arrays.
    Mesh(Box<MeshDesc>),
}

impl GeometryDesc {
    /// The `type` names, in the order of the variants.
    pub const TYPES: &'static [&'static str] = &["sphere", "box", "rectangle", "disk", "mesh"];
}

/// A triangle mesh: read from `file` (Wavefront OBJ or PLY, ASCII or
/// binary; polygons are triangulated) or given inline by `positions` and
/// `indices` (with optional `normals` and `uvs`, one per vertex), placed by
/// `to_world`. Triangles wind counter-clockwise seen from outside (the
/// right-hand rule gives the outward normal). A mesh that bounds a medium
/// (`interior` or `exterior`) must be closed unless `allow_open` is set.
#[derive(Clone, Debug, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MeshDesc {
    /// Mesh file, relative to the scene file's folder (`.obj` or `.ply`).
    #[serde(default)]
    pub file: Option<String>,
    /// OBJ only: the object or group to read (default: all of them).
    #[serde(default)]
    pub object: Option<String>,
    /// Inline vertex positions `[[x, y, z], ...]`, in scene units (object space).
    #[serde(default)]
    pub positions: Option<Vec<[f32; 3]>>,
    /// Inline triangles `[[i, j, k], ...]`: 0-based indices into `positions`.
    #[serde(default)]
    pub indices: Option<Vec<[u32; 3]>>,
    /// Inline vertex normals (smooth shading), one per position.
    #[serde(default)]
    pub normals: Option<Vec<[f32; 3]>>,
    /// Inline vertex uv coordinates, one per position.
    #[serde(default)]
    pub uvs: Option<Vec<[f32; 2]>>,
    /// Object-to-world transform; default identity.
    #[serde(default)]
    pub to_world: TransformDesc,
    /// Turn the mesh inside out: reverse every triangle's winding and negate
    /// the vertex normals (Mitsuba 3's `flip_normals`; the uv and dp/du of a
    /// mesh without uvs keep the file's corner order, as Mitsuba's). Default
    /// false.
    #[serde(default)]
    pub flip_normals: bool,
    /// Shade with the flat triangle normals even where the mesh has vertex
    /// normals (Mitsuba 3's `face_normals`). Default false.
    #[serde(default)]
    pub face_normals: bool,
    /// Give a mesh without vertex normals (and without `face_normals`)
    /// smooth ones: at each vertex the unit normals of the triangles
    /// around it weighted by their angles there (Thuermer and Wuethrich
    /// 1998, "Computing vertex normals from polygonal facets"), computed in
    /// object space from the file's winding before `flip_normals`, as Mitsuba
    /// 3 does for OBJ and PLY files without normals. Default false.
    #[serde(default)]
    pub compute_normals: bool,
    /// Replace every vertex uv `(u, v)` by `(u, 1 - v)` (Mitsuba 3's
    /// `flip_tex_coords`; meshes without uvs are unaffected). Default false.
    #[serde(default)]
    pub flip_tex_coords: bool,
    /// Let an open mesh (boundary edges, inconsistent winding) bound a
    /// medium: it then acts like a rectangle, with the `interior` medium
    /// behind its normals. Default false (such a mesh is an error).
    #[serde(default)]
    pub allow_open: bool,
    /// `"shading_normal_backside"`: what the surface does where the
    /// direction toward the viewer lies behind the interpolated vertex
    /// normal but in front of the triangle; default `"geometric"`.
    #[serde(default)]
    pub shading_normal_backside: ShadingBacksideDesc,
}

/// `"shading_normal_backside"` of a mesh with vertex normals: the rule for a
/// hit whose `wo` (toward the viewer) lies on the other side of the shading
/// normal than of the geometric normal.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ShadingBacksideDesc {
    /// `"geometric"` (the default, niebla's rule before 2026-12): the BSDF
    /// is evaluated about the geometric normal there.
    #[default]
    Geometric,
    /// `"mitsuba"`: Mitsuba 3's rule: the BSDF is evaluated about the
    /// shading normal with `wo` behind it, so one-sided BSDFs (diffuse,
    /// conductors, plastics) give zero, `twosided` shows its back side and
    /// dielectrics treat `wo` as coming from inside. Paths go on along every
    /// direction the BSDF samples about the shading normal (also across the
    /// triangle's plane; the medium is the one on the direction's
    /// geometric side), light sampling reaches the same directions, and
    /// vertex normals that point against the winding are kept as written.
    Mitsuba,
}

/// A sphere; its normal points outward.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SphereDesc {
    /// Center, in scene units.
    #[serde(deserialize_with = "vec3")]
    pub center: [f32; 3],
    /// Radius in scene units, > 0.
    pub radius: f32,
    /// `"rotation"` (optional): turns the sphere's uv parameterization, and
    /// so its `dp/du` (textures, `"tangent_frame": "dpdu"`), but not its
    /// surface; as the rotation of a Mitsuba 3 sphere's `to_world`. Default:
    /// none (the uv pole along world `+z`, the seam `u = 0` toward `+x`).
    #[serde(default)]
    pub rotation: Option<RotationDesc>,
}

/// A rotation of a sphere's local frame into world space.
#[derive(Clone, Debug, PartialEq)]
pub enum RotationDesc {
    /// `{"rotate_x": a, "rotate_y": b, "rotate_z": c}`: degrees about world
    /// x, then y, then z (right-handed; the order of a transform's
    /// components), each default 0.
    Angles([f32; 3]),
    /// `{"matrix": [[...], [...], [...]]}`: a row-major 3x3 matrix from
    /// local to world, orthonormal with determinant +1 (to 1e-4).
    Matrix([[f32; 3]; 3]),
}

/// An axis-aligned box; its normals point outward.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BoxDesc {
    /// Minimum corner, in scene units.
    #[serde(deserialize_with = "vec3")]
    pub min: [f32; 3],
    /// Maximum corner; greater than `min` on every axis.
    #[serde(deserialize_with = "vec3")]
    pub max: [f32; 3],
}

/// A rectangle: the square [-1, 1]^2 in the xy plane with normal +z
/// (Mitsuba's convention), mapped by `to_world`.
#[derive(Clone, Debug, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RectangleDesc {
    /// Object-to-world transform; default identity.
    #[serde(default)]
    pub to_world: TransformDesc,
}

/// A disk: the unit disk `x^2 + y^2 <= 1` in the xy plane at `z = 0` with
/// normal +z (Mitsuba's convention), mapped by `to_world`.
#[derive(Clone, Debug, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DiskDesc {
    /// Object-to-world transform; default identity.
    #[serde(default)]
    pub to_world: TransformDesc,
}

/// A surface color: one color, or a texture over the surface's uv
/// coordinates (`{"type": "bitmap", ...}` or `{"type": "checkerboard", ...}`).
#[derive(Clone, Debug, PartialEq)]
pub enum ReflectanceDesc {
    /// The same color everywhere.
    Color(ColorDesc),
    /// A texture.
    Texture(TextureDesc),
}

impl ReflectanceDesc {
    /// The color, for a constant; `None` for a texture.
    pub fn color(&self) -> Option<&ColorDesc> {
        match self {
            ReflectanceDesc::Color(c) => Some(c),
            ReflectanceDesc::Texture(_) => None,
        }
    }
}

/// A texture, tagged by `type`. uv conventions are in [`crate::texture`].
#[derive(Clone, Debug, PartialEq)]
pub enum TextureDesc {
    /// `"bitmap"`: an image file (`.png`, `.jpg`, `.exr`), relative to the
    /// scene file's folder, filtered bilinearly.
    Bitmap {
        /// Image file.
        file: String,
        /// `"repeat"` (default), `"mirror"` or `"clamp"`.
        wrap: crate::texture::WrapMode,
        /// Keep 8/16-bit values as they are instead of decoding sRGB
        /// (default false; EXR is always linear).
        raw: bool,
        /// uv scale `[su, sv]` (default `[1, 1]`): repetitions of the image.
        scale: [f32; 2],
        /// `"bilinear"` (default) or `"nearest"`.
        filter: crate::texture::FilterMode,
        /// Optional affine map of uv applied before `scale`: rows
        /// `[[a, b, c], [d, e, f]]` give `(a u + b v + c, d u + e v + f)`.
        to_uv: Option<[[f32; 3]; 2]>,
    },
    /// `"checkerboard"`: two colors on a grid of `scale` cells per unit uv.
    Checkerboard {
        /// Color of the cell at uv (0, 0) and every other cell (default 0.4).
        color0: ColorDesc,
        /// Color of the other cells (default 0.2).
        color1: ColorDesc,
        /// Cells per unit of u and v (default `[2, 2]`, four cells over the
        /// unit square, as Mitsuba 3's checkerboard).
        scale: [f32; 2],
        /// Optional affine map of uv applied before `scale` (as for `bitmap`).
        to_uv: Option<[[f32; 3]; 2]>,
    },
}

impl TextureDesc {
    /// The `type` names, in the order of the variants.
    pub const TYPES: &'static [&'static str] = &["bitmap", "checkerboard"];
}

/// Surface scattering, tagged by `type` in the file; default `null`.
#[derive(Clone, Debug, Default, PartialEq)]
pub enum BsdfDesc {
    /// `"null"`: no surface; light passes unchanged (an index-matched
    /// boundary between media).
    #[default]
    Null,
    /// `"diffuse"`: Lambertian reflection.
    Diffuse {
        /// Reflectance (albedo), each channel in [0, 1]; default 0.5; a
        /// color or a texture.
        reflectance: ReflectanceDesc,
    },
    /// `"dielectric"`: smooth glass-like interface (Fresnel reflection and
    /// refraction; absorption belongs to the media on either side).
    Dielectric {
        /// Index of refraction inside the shape (`int_ior`, > 0; default 1.5).
        int_ior: f32,
        /// Index of refraction outside (`ext_ior`, > 0; default 1).
        ext_ior: f32,
    },
    /// `"conductor"`: smooth metal mirror, given by a named `material`
    /// ("gold", "silver", "aluminium", "copper" or their symbols), by
    /// `eta` and `k` (complex index per channel), or by a normal-incidence
    /// `reflectance`.
    Conductor(ConductorDesc),
    /// `"roughconductor"`: rough metal (see [`RoughConductorDesc`]).
    RoughConductor(RoughConductorDesc),
    /// `"roughdielectric"`: rough glass (see [`RoughDielectricDesc`]).
    RoughDielectric(RoughDielectricDesc),
    /// `"thindielectric"`: thin glass sheet (see [`ThinDielectricDesc`]).
    ThinDielectric(ThinDielectricDesc),
    /// `"plastic"`: coated diffuse (see [`PlasticDesc`]).
    Plastic(PlasticDesc),
    /// `"roughplastic"`: rough coated diffuse (see [`RoughPlasticDesc`]).
    RoughPlastic(RoughPlasticDesc),
    /// `"twosided"`: reflecting models on both sides (see [`TwoSidedDesc`]).
    TwoSided(TwoSidedDesc),
}

/// How a conductor's complex index of refraction is given.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ConductorDesc {
    /// A named preset.
    Material(&'static str),
    /// `eta` (> 0) and `k` (>= 0) per channel.
    Index {
        /// Real part.
        eta: ColorDesc,
        /// Extinction coefficient.
        k: ColorDesc,
    },
    /// Reflectance at normal incidence, in [0, 1) per channel.
    Reflectance(ColorDesc),
}

impl BsdfDesc {
    /// The `type` names, in the order of the variants.
    pub const TYPES: &'static [&'static str] = &[
        "null",
        "diffuse",
        "dielectric",
        "conductor",
        "roughconductor",
        "roughdielectric",
        "thindielectric",
        "plastic",
        "roughplastic",
        "twosided",
    ];
}

/// An object-to-world transform.
///
/// In a file: an object with any of `scale` (a number or `[x, y, z]`, each
/// non-zero), `rotate_x`, `rotate_y`, `rotate_z` (degrees, right-handed about
/// the world axes) and `translate` (`[x, y, z]`), applied in that order: scale,
/// then rotate about x, then y, then z, then translate. Or just `matrix`: a
/// row-major 4x4 array of 4 rows of 4 numbers, acting on column vectors
/// `[x, y, z, 1]` (last row `[0, 0, 0, 1]`, upper 3x3 invertible).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TransformDesc {
    /// Scale, rotations and translation.
    Components {
        /// Per-axis scale factors, each non-zero (a scalar `s` in the file
        /// gives `[s, s, s]`).
        scale: [f32; 3],
        /// Rotation about the x axis, in degrees.
        rotate_x: f32,
        /// Rotation about the y axis, in degrees.
        rotate_y: f32,
        /// Rotation about the z axis, in degrees.
        rotate_z: f32,
        /// Translation, in scene units.
        translate: [f32; 3],
    },
    /// A row-major 4x4 affine matrix.
    Matrix([[f32; 4]; 4]),
}

impl TransformDesc {
    /// The identity transform.
    pub const IDENTITY: TransformDesc =
        TransformDesc::Components { scale: [1.0; 3], rotate_x: 0.0, rotate_y: 0.0, rotate_z: 0.0, translate: [0.0; 3] };
}

impl Default for TransformDesc {
    fn default() -> TransformDesc {
        TransformDesc::IDENTITY
    }
}
