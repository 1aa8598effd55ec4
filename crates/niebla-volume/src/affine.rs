//! Affine maps between a sparse grid's index space and world space.

/// An affine map `y = A x + b` in double precision, stored as 3 rows
/// `[a_r0, a_r1, a_r2, b_r]`.
///
/// For a VDB grid, [`Affine`] maps *index space* (voxel `(i, j, k)` has its
/// value at the point `(i, j, k)`) to the grid's *world space* (the space of
/// the file, before the medium's own `to_world`).
///
/// ```
/// use niebla_volume::Affine;
/// let m = Affine::scale_translate([0.5, 0.5, 2.0], [1.0, 0.0, 0.0]);
/// assert_eq!(m.transform_point([2.0, 4.0, 1.0]), [2.0, 2.0, 2.0]);
/// assert_eq!(m.inverse().unwrap().transform_point([2.0, 2.0, 2.0]), [2.0, 4.0, 1.0]);
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Affine {
    /// Row `r` is `[A[r][0], A[r][1], A[r][2], b[r]]`.
    pub rows: [[f64; 4]; 3],
}

impl Affine {
    /// The identity map.
    pub const IDENTITY: Affine = Affine { rows: [[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0]] };

    /// `y = scale * x + translation`, per axis.
    pub fn scale_translate(scale: [f64; 3], translation: [f64; 3]) -> Affine {
        let mut rows = [[0.0; 4]; 3];
        for r in 0..3 {
            rows[r][r] = scale[r];
            rows[r][3] = translation[r];
        }
        Affine { rows }
    }

    /// From a 4x4 matrix in OpenVDB's row-vector convention
    /// (`y = [x 1] * M`, translation in the last row).
    pub fn from_row_vector_mat4(m: [[f64; 4]; 4]) -> Affine {
        let mut rows = [[0.0; 4]; 3];
        for (r, row) in rows.iter_mut().enumerate() {
            for (c, value) in row.iter_mut().enumerate() {
                *value = m[c][r];
            }
        }
        Affine { rows }
    }

    /// `A x + b`.
    #[inline]
    pub fn transform_point(&self, x: [f64; 3]) -> [f64; 3] {
        std::array::from_fn(|r| {
            let m = &self.rows[r];
            m[0] * x[0] + m[1] * x[1] + m[2] * x[2] + m[3]
        })
    }

    /// `A x` (a direction or offset; no translation).
    #[inline]
    pub fn transform_vector(&self, x: [f64; 3]) -> [f64; 3] {
        std::array::from_fn(|r| {
            let m = &self.rows[r];
            m[0] * x[0] + m[1] * x[1] + m[2] * x[2]
        })
    }

    /// Single-precision [`Affine::transform_point`] (computed in f64).
    #[inline]
    pub fn transform_point_f32(&self, x: [f32; 3]) -> [f32; 3] {
        let y = self.transform_point(x.map(f64::from));
        y.map(|v| v as f32)
    }

    /// Single-precision [`Affine::transform_vector`] (computed in f64).
    #[inline]
    pub fn transform_vector_f32(&self, x: [f32; 3]) -> [f32; 3] {
        let y = self.transform_vector(x.map(f64::from));
        y.map(|v| v as f32)
    }

    /// The translation `b` (the image of the origin).
    pub fn translation(&self) -> [f64; 3] {
        [self.rows[0][3], self.rows[1][3], self.rows[2][3]]
    }

    /// Column `c` of `A`: the image of the unit vector along axis `c`.
    pub fn axis(&self, c: usize) -> [f64; 3] {
        [self.rows[0][c], self.rows[1][c], self.rows[2][c]]
    }

    /// Determinant of `A`.
    pub fn determinant(&self) -> f64 {
        let m = &self.rows;
        m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
    }

    /// The inverse map, or `None` if `A` is singular or not finite.
    pub fn inverse(&self) -> Option<Affine> {
        let m = &self.rows;
        let det = self.determinant();
        if !det.is_finite() || det == 0.0 || m.iter().flatten().any(|v| !v.is_finite()) {
            return None;
        }
        let inv_det = 1.0 / det;
        let mut a = [[0.0; 3]; 3];
        for (r, row) in a.iter_mut().enumerate() {
            for (c, value) in row.iter_mut().enumerate() {
                // Cofactor of A[c][r] (transposed adjugate).
                let (r0, r1) = ((c + 1) % 3, (c + 2) % 3);
                let (c0, c1) = ((r + 1) % 3, (r + 2) % 3);
                *value = (m[r0][c0] * m[r1][c1] - m[r0][c1] * m[r1][c0]) * inv_det;
            }
        }
        let b = [m[0][3], m[1][3], m[2][3]];
        let mut rows = [[0.0; 4]; 3];
        for r in 0..3 {
            rows[r][..3].copy_from_slice(&a[r]);
            rows[r][3] = -(a[r][0] * b[0] + a[r][1] * b[1] + a[r][2] * b[2]);
        }
        Some(Affine { rows })
    }

    /// The map `self` after `first`: `x -> self(first(x))`.
    pub fn compose(&self, first: &Affine) -> Affine {
        let mut rows = [[0.0; 4]; 3];
        for (r, row) in rows.iter_mut().enumerate() {
            for (c, value) in row.iter_mut().enumerate() {
                let mut s = if c == 3 { self.rows[r][3] } else { 0.0 };
                for k in 0..3 {
                    s += self.rows[r][k] * first.rows[k][c];
                }
                *value = s;
            }
        }
        Affine { rows }
    }
}

impl Default for Affine {
    fn default() -> Self {
        Affine::IDENTITY
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inverse_composes_to_identity() {
        let (s, c) = (0.3f64.sin(), 0.3f64.cos());
        let m =
            Affine { rows: [[0.05 * c, -0.05 * s, 0.0, 1.0], [0.05 * s, 0.05 * c, 0.0, 2.0], [0.1, 0.0, 0.2, 3.0]] };
        let id = m.inverse().unwrap().compose(&m);
        for r in 0..3 {
            for c in 0..4 {
                assert!((id.rows[r][c] - Affine::IDENTITY.rows[r][c]).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn row_vector_matrix_puts_translation_in_last_row() {
        let m = Affine::from_row_vector_mat4([
            [2.0, 0.0, 0.0, 0.0],
            [0.0, 3.0, 0.0, 0.0],
            [1.0, 0.0, 4.0, 0.0],
            [5.0, 6.0, 7.0, 1.0],
        ]);
        // [x y z 1] * M
        assert_eq!(m.transform_point([1.0, 1.0, 1.0]), [8.0, 9.0, 11.0]);
    }

    #[test]
    fn singular_maps_have_no_inverse() {
        assert!(Affine::scale_translate([1.0, 0.0, 1.0], [0.0; 3]).inverse().is_none());
    }
}
