//! OpenVDB grid transforms (`math::Transform::read` and the `read` of each
//! linear map in `openvdb/math/Maps.h`).

use crate::io::bytes::ByteReader;
use crate::{Affine, VolumeError};

/// Reads a transform: the map's type name, then the map's own fields.
/// Returns the map type and the index-to-world [`Affine`].
///
/// Layouts (all f64): scale maps store five `Vec3d` (scale, voxel size,
/// inverse scale, inverse squared scale, inverse twice scale);
/// scale-translate maps store the translation first, then those five;
/// the translation map stores one `Vec3d`; affine and unitary maps store a
/// row-major 4x4 matrix in the row-vector convention.
pub(crate) fn read_transform(r: &mut ByteReader) -> Result<(String, Affine), VolumeError> {
    let start = r.pos();
    let map = r.string("transform map type")?;
    let affine = match map.as_str() {
        "UniformScaleMap" | "ScaleMap" => {
            let scale = r.vec3d("scale map")?;
            r.skip(4 * 24, "scale map")?;
            Affine::scale_translate(scale, [0.0; 3])
        }
        "UniformScaleTranslateMap" | "ScaleTranslateMap" => {
            let translation = r.vec3d("scale-translate map")?;
            let scale = r.vec3d("scale-translate map")?;
            r.skip(4 * 24, "scale-translate map")?;
            Affine::scale_translate(scale, translation)
        }
        "TranslationMap" => {
            let translation = r.vec3d("translation map")?;
            Affine::scale_translate([1.0; 3], translation)
        }
        "AffineMap" | "UnitaryMap" => {
            let mut m = [[0.0; 4]; 4];
            for row in m.iter_mut() {
                for v in row.iter_mut() {
                    *v = r.f64("affine map matrix")?;
                }
            }
            if m[0][3] != 0.0 || m[1][3] != 0.0 || m[2][3] != 0.0 || m[3][3] != 1.0 {
                return Err(r.corrupt_at(start, format!("{map} matrix is not affine: {m:?}")));
            }
            Affine::from_row_vector_mat4(m)
        }
        "NonlinearFrustumMap" => {
            return Err(r.unsupported("frustum transforms (NonlinearFrustumMap)"));
        }
        other => {
            return Err(r.corrupt_at(start, format!("unknown transform map type {other:?}")));
        }
    };
    if affine.inverse().is_none() {
        return Err(r.corrupt_at(start, format!("{map} is singular or not finite: {affine:?}")));
    }
    Ok((map, affine))
}
