//! Meshes generated from a few parameters, for tests and benchmarks. Every
//! generator returns its vertices numbered in order of first use
//! ([`MeshData::renumbered_by_first_use`]), so a generated mesh reads back
//! identical from every file format this crate writes.

use std::collections::HashMap;

use crate::MeshData;

/// Largest subdivision level [`icosphere`] computes (20 * 4^10 = 20,971,520
/// triangles); larger requests are clamped to it.
pub const MAX_ICOSPHERE_SUBDIVISIONS: u32 = 10;

/// Largest triangle count [`random_soup`] generates (2^30, so that every
/// vertex index fits in `u32`).
pub const MAX_SOUP_TRIANGLES: u32 = 1 << 30;

/// A rounded, bumpy closed surface: the [`icosphere`] of `subdivisions`
/// with each vertex pushed along its radius by `1 + amplitude * b(p)`, where
/// `b(p) = (sin 7x + sin(9y + 1) cos 5z) / 2` (in [-1, 1]) is a smooth
/// bump field, and area-weighted vertex normals of the displaced faces.
/// Non-convex for amplitudes above a few percent; closed and welded like
/// the sphere. Used by `niebla bench geometry` and the mesh showcase scene.
pub fn blob(subdivisions: u32, amplitude: f32) -> MeshData {
    let mut mesh = icosphere(subdivisions, 1.0);
    for p in &mut mesh.positions {
        let b = 0.5 * ((7.0 * p[0]).sin() + (9.0 * p[1] + 1.0).sin() * (5.0 * p[2]).cos());
        let k = 1.0 + amplitude * b;
        *p = p.map(|c| c * k);
    }
    let mut normals = vec![[0f64; 3]; mesh.positions.len()];
    for t in &mesh.indices {
        let [a, b, c] = t.map(|i| mesh.positions[i as usize].map(f64::from));
        let e1 = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
        let e2 = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
        let n = [e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]];
        for &i in t {
            for k in 0..3 {
                normals[i as usize][k] += n[k];
            }
        }
    }
    mesh.normals = Some(
        normals
            .into_iter()
            .map(|n| {
                let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt().max(1e-300);
                [(n[0] / len) as f32, (n[1] / len) as f32, (n[2] / len) as f32]
            })
            .collect(),
    );
    mesh
}

/// A geodesic sphere of the given `radius` centered at the origin: the
/// regular icosahedron (20 triangles, 12 vertices) with each triangle split
/// into 4 `subdivisions` times (`20 * 4^s` triangles, `10 * 4^s + 2`
/// vertices), new vertices pushed onto the sphere. Closed, welded (each
/// position once), wound counter-clockwise seen from outside; per-vertex
/// normals are the unit radial directions, no uvs. Subdivision levels above
/// [`MAX_ICOSPHERE_SUBDIVISIONS`] are clamped to it.
pub fn icosphere(subdivisions: u32, radius: f32) -> MeshData {
    let t = (1.0 + 5f64.sqrt()) / 2.0;
    let mut dirs: Vec<[f64; 3]> = [
        [-1.0, t, 0.0],
        [1.0, t, 0.0],
        [-1.0, -t, 0.0],
        [1.0, -t, 0.0],
        [0.0, -1.0, t],
        [0.0, 1.0, t],
        [0.0, -1.0, -t],
        [0.0, 1.0, -t],
        [t, 0.0, -1.0],
        [t, 0.0, 1.0],
        [-t, 0.0, -1.0],
        [-t, 0.0, 1.0],
    ]
    .iter()
    .map(|&v| normalize(v))
    .collect();
    let mut tris: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..subdivisions.min(MAX_ICOSPHERE_SUBDIVISIONS) {
        let mut midpoint: HashMap<(u32, u32), u32> = HashMap::with_capacity(tris.len() * 3 / 2);
        let mut mid = |a: u32, b: u32, dirs: &mut Vec<[f64; 3]>| {
            *midpoint.entry((a.min(b), a.max(b))).or_insert_with(|| {
                let (pa, pb) = (dirs[a as usize], dirs[b as usize]);
                dirs.push(normalize([pa[0] + pb[0], pa[1] + pb[1], pa[2] + pb[2]]));
                (dirs.len() - 1) as u32
            })
        };
        let mut next = Vec::with_capacity(tris.len() * 4);
        for &[a, b, c] in &tris {
            let ab = mid(a, b, &mut dirs);
            let bc = mid(b, c, &mut dirs);
            let ca = mid(c, a, &mut dirs);
            next.extend_from_slice(&[[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        tris = next;
    }
    let r = f64::from(radius);
    let positions = dirs.iter().map(|d| d.map(|c| (c * r) as f32)).collect();
    let normals = dirs.iter().map(|d| d.map(|c| c as f32)).collect();
    MeshData { positions, normals: Some(normals), uvs: None, indices: tris }.renumbered_by_first_use()
}

/// A latitude-longitude sphere of the given `radius` centered at the origin,
/// poles on the z axis: `n_theta` bands from the north pole `(0, 0, r)` to
/// the south pole, `n_phi` segments around (clamped to at least 2 and 3).
/// Vertex `(i, j)` is at `r (sin t cos p, sin t sin p, cos t)` with
/// `t = pi i / n_theta`, `p = 2 pi j / n_phi`, uv `(j / n_phi, 1 - i /
/// n_theta)` (v = 1 at the north pole) and the unit radial normal.
///
/// Like meshes exported by modeling tools, it splits vertices: the seam
/// column `j = n_phi` repeats the positions of `j = 0` with `u = 1`, and
/// each pole is one position repeated per segment. It is closed only after
/// welding ([`MeshData::closedness`] reports zero open edges). The pole
/// bands have one triangle per segment, the others two; wound
/// counter-clockwise seen from outside.
pub fn uv_sphere(n_theta: u32, n_phi: u32, radius: f32) -> MeshData {
    let (nt, np) = (n_theta.max(2), n_phi.max(3));
    let r = f64::from(radius);
    let cols = np + 1;
    let mut positions = Vec::with_capacity(((nt + 1) * cols) as usize);
    let mut normals = Vec::with_capacity(positions.capacity());
    let mut uvs = Vec::with_capacity(positions.capacity());
    for i in 0..=nt {
        let theta = std::f64::consts::PI * f64::from(i) / f64::from(nt);
        for j in 0..=np {
            let phi = 2.0 * std::f64::consts::PI * f64::from(j % np) / f64::from(np);
            let d = if i == 0 {
                [0.0, 0.0, 1.0]
            } else if i == nt {
                [0.0, 0.0, -1.0]
            } else {
                [theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos()]
            };
            positions.push(d.map(|c| (c * r) as f32));
            normals.push(d.map(|c| c as f32));
            uvs.push([(f64::from(j) / f64::from(np)) as f32, (1.0 - f64::from(i) / f64::from(nt)) as f32]);
        }
    }
    let mut indices = Vec::with_capacity((2 * nt * np) as usize);
    for i in 0..nt {
        for j in 0..np {
            let v00 = i * cols + j;
            let (v01, v10, v11) = (v00 + 1, v00 + cols, v00 + cols + 1);
            if i + 1 < nt {
                indices.push([v00, v10, v11]);
            }
            if i > 0 {
                indices.push([v00, v11, v01]);
            }
        }
    }
    MeshData { positions, normals: Some(normals), uvs: Some(uvs), indices }.renumbered_by_first_use()
}

/// `triangles` independent triangles (a "soup": no shared vertices), the
/// same for the same `seed`: vertex `3t + k` is corner `k` of triangle `t`,
/// positions uniform in the unit cube `[0, 1)^3`, normals uniform unit
/// vectors (unrelated to the faces), uvs uniform in `[0, 1)^2`. For
/// benchmarks and round-trip tests, not for rendering media (it is open).
/// At most [`MAX_SOUP_TRIANGLES`]; larger counts are clamped to it.
pub fn random_soup(triangles: u32, seed: u64) -> MeshData {
    let triangles = triangles.min(MAX_SOUP_TRIANGLES);
    let mut rng = SplitMix64(seed);
    let n = triangles as usize * 3;
    let mut positions = Vec::with_capacity(n);
    let mut normals = Vec::with_capacity(n);
    let mut uvs = Vec::with_capacity(n);
    for _ in 0..n {
        positions.push([rng.unit(), rng.unit(), rng.unit()]);
        normals.push(loop {
            let v = [2.0 * rng.unit() - 1.0, 2.0 * rng.unit() - 1.0, 2.0 * rng.unit() - 1.0];
            let len2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
            if len2 > 1e-4 && len2 <= 1.0 {
                let len = len2.sqrt();
                break v.map(|c| c / len);
            }
        });
        uvs.push([rng.unit(), rng.unit()]);
    }
    let indices = (0..triangles).map(|t| [3 * t, 3 * t + 1, 3 * t + 2]).collect();
    MeshData { positions, normals: Some(normals), uvs: Some(uvs), indices }
}

fn normalize(v: [f64; 3]) -> [f64; 3] {
    let len = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    v.map(|c| c / len)
}

/// SplitMix64 (Steele, Lea and Flood, "Fast splittable pseudorandom number
/// generators", OOPSLA 2014): small, seedable, good enough for test data.
struct SplitMix64(u64);

impl SplitMix64 {
    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// Uniform in `[0, 1)` with 24 random bits.
    fn unit(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 / (1u64 << 24) as f32
    }
}
