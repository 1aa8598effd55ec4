//! Closedness, degenerate triangles and array validation, with exact counts.

use niebla_mesh::{icosphere, random_soup, uv_sphere, Closedness, MeshData};

#[test]
fn icosphere_is_closed() {
    for s in 0..5 {
        let c = icosphere(s, 1.0).closedness();
        assert_eq!(c, Closedness::default(), "subdivisions {s}");
        assert!(c.is_closed());
    }
}

#[test]
fn uv_sphere_with_seams_is_closed_after_welding() {
    let m = uv_sphere(8, 16, 3.0);
    // Seam and pole vertices are split; welding leaves 7 rings of 16 and 2 poles.
    let welded: std::collections::HashSet<u32> = m.welded_ids().into_iter().collect();
    assert_eq!(welded.len(), 7 * 16 + 2);
    assert!(m.vertex_count() > welded.len());
    assert_eq!(m.closedness(), Closedness::default());
}

#[test]
fn one_removed_triangle_leaves_three_boundary_edges() {
    let mut m = icosphere(2, 1.0);
    m.indices.remove(17);
    let c = m.closedness();
    assert_eq!(c, Closedness { boundary_edges: 3, ..Closedness::default() });
    assert!(!c.is_closed());
    // Two adjacent triangles removed: a hole bounded by 4 edges.
    let mut m = icosphere(0, 1.0);
    let [a, b, _] = m.indices[0];
    let neighbour =
        (1..20).find(|&t| m.indices[t].contains(&a) && m.indices[t].contains(&b)).expect("every edge has two faces");
    m.indices.remove(neighbour);
    m.indices.remove(0);
    assert_eq!(m.closedness().boundary_edges, 4);
}

#[test]
fn one_flipped_triangle_gives_its_three_edges_as_inconsistent() {
    let mut m = icosphere(1, 1.0);
    m.indices[5].swap(1, 2);
    assert_eq!(m.closedness(), Closedness { inconsistent_edges: 3, ..Closedness::default() });
}

#[test]
fn a_fin_is_non_manifold_and_degenerates_are_ignored() {
    let mut m = icosphere(0, 1.0);
    let [a, b, _] = m.indices[0];
    // A third triangle on edge (a, b), to a new vertex at the origin.
    m.positions.push([0.0, 0.0, 0.0]);
    let o = (m.positions.len() - 1) as u32;
    m.indices.push([a, b, o]);
    let c = m.closedness();
    assert_eq!(c.non_manifold_edges, 1);
    assert_eq!(c.boundary_edges, 2); // (b, o) and (o, a)
                                     // Degenerate triangles: a repeated index, a zero-area sliver, a
                                     // triangle whose two corners are distinct vertices at the same place.
    let mut m = icosphere(0, 1.0);
    m.positions.push(m.positions[3]);
    let dup = (m.positions.len() - 1) as u32;
    m.positions.push([m.positions[1][0] * 2.0, m.positions[1][1] * 2.0, m.positions[1][2] * 2.0]);
    let far = (m.positions.len() - 1) as u32;
    m.positions.push([0.0; 3]);
    let origin = (m.positions.len() - 1) as u32;
    m.indices.extend([[0, 0, 1], [origin, 1, far], [3, dup, 4]]);
    assert_eq!(m.degenerate_triangles(), 3);
    assert_eq!(m.closedness(), Closedness { degenerate_triangles: 3, ..Closedness::default() });
    assert!(m.is_degenerate(20) && m.is_degenerate(21) && m.is_degenerate(22) && !m.is_degenerate(0));
}

#[test]
fn negative_zero_welds_with_zero() {
    let positions = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [-0.0, 0.0, -0.0]];
    let m = MeshData::from_arrays(positions, vec![[0, 1, 2], [3, 2, 1]], None, None).unwrap();
    assert_eq!(m.welded_ids(), vec![0, 1, 2, 0]);
    // After welding, the second triangle is the first one seen from behind:
    // a closed two-sided "pillow".
    assert_eq!(m.closedness(), Closedness::default());
}

#[test]
fn soup_is_all_boundary() {
    let m = random_soup(50, 1);
    assert_eq!(m.closedness(), Closedness { boundary_edges: 150, ..Closedness::default() });
}

#[test]
fn from_arrays_names_the_element() {
    let p = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
    let e = |r: Result<MeshData, niebla_mesh::MeshError>| r.unwrap_err().to_string();
    let mut indices = vec![[0, 1, 2]; 13];
    indices[12][2] = 907;
    assert_eq!(
        e(MeshData::from_arrays(p.clone(), indices, None, None)),
        "mesh arrays: indices[12][2]: vertex index 907 out of range (the mesh has 3 vertices)"
    );
    let mut bad = p.clone();
    bad[1][2] = f32::NAN;
    assert_eq!(
        e(MeshData::from_arrays(bad, vec![[0, 1, 2]], None, None)),
        "mesh arrays: positions[1][2]: NaN is not a finite number"
    );
    assert_eq!(
        e(MeshData::from_arrays(p.clone(), vec![[0, 1, 2]], Some(vec![[0.0, 0.0, 1.0]; 2]), None)),
        "mesh arrays: 2 normals for 3 vertices (need one per vertex)"
    );
    assert_eq!(
        e(MeshData::from_arrays(p.clone(), vec![[0, 1, 2]], None, Some(vec![[0.0, f32::INFINITY]; 3]))),
        "mesh arrays: uvs[0][1]: inf is not a finite number"
    );
    let err = MeshData::from_arrays(p.clone(), vec![[0, 1, 3]], None, None).unwrap_err();
    assert_eq!(
        err.with_origin("scene.json: media[0].mesh").to_string(),
        "scene.json: media[0].mesh: indices[0][2]: vertex index 3 out of range (the mesh has 3 vertices)"
    );
    let m = MeshData::from_arrays(p, vec![[0, 1, 2]], None, None).unwrap();
    assert_eq!(m.bounds(), Some(([0.0; 3], [1.0, 1.0, 0.0])));
    assert_eq!(MeshData::default().bounds(), None);
}
