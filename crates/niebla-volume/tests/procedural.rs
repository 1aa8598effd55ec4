//! Procedural densities are deterministic in their seed, lie in [0, 1],
//! vanish on the voxels next to the box's faces, have the shape they are
//! named after, and reject out-of-range parameters by name.

use niebla_volume::{procedural_density, DenseGrid, MajorantGrid, ProceduralParams, ProceduralShape, VolumeError};

fn params(shape: ProceduralShape, seed: u64, n: usize) -> ProceduralParams {
    ProceduralParams { shape, seed, resolution: [n; 3], ..ProceduralParams::default() }
}

fn values(g: &DenseGrid) -> Vec<f32> {
    (0..g.storage().len()).map(|i| g.storage().get(i)).collect()
}

fn mean(g: &DenseGrid) -> f64 {
    values(g).iter().map(|&v| v as f64).sum::<f64>() / g.storage().len() as f64
}

/// Inclusive index range of the non-zero voxels along each axis.
fn nonzero_extent(g: &DenseGrid) -> [(usize, usize); 3] {
    let [nx, ny, nz] = g.dims();
    let mut ext = [(usize::MAX, 0); 3];
    for z in 0..nz {
        for y in 0..ny {
            for x in 0..nx {
                if g.voxel(x, y, z) > 0.0 {
                    for (a, c) in [x, y, z].into_iter().enumerate() {
                        ext[a] = (ext[a].0.min(c), ext[a].1.max(c));
                    }
                }
            }
        }
    }
    ext
}

const SHAPES: [ProceduralShape; 2] = [ProceduralShape::Cloud, ProceduralShape::Plume];

#[test]
fn same_seed_gives_identical_grids_and_different_seeds_differ() {
    for shape in SHAPES {
        let a = procedural_density(&params(shape, 17, 48)).unwrap();
        let b = procedural_density(&params(shape, 17, 48)).unwrap();
        assert_eq!(a, b, "{shape:?}");
        let c = procedural_density(&params(shape, 18, 48)).unwrap();
        let differing = values(&a).iter().zip(values(&c)).filter(|(x, y)| **x != *y).count();
        assert!(differing > 1000, "{shape:?}: {differing} voxels differ");
    }
}

#[test]
fn values_lie_in_unit_interval_and_vanish_on_face_voxels() {
    let variants = [
        ProceduralParams::default(),
        ProceduralParams {
            resolution: [40, 24, 33],
            coverage: 1.0,
            sharpness: 1000.0,
            frequency: 50.0,
            ..ProceduralParams::default()
        },
        ProceduralParams {
            resolution: [3, 70, 5],
            octaves: 12,
            lacunarity: 3.0,
            gain: 1.0,
            coverage: 0.9,
            ..ProceduralParams::default()
        },
        ProceduralParams { resolution: [1, 2, 1], ..ProceduralParams::default() },
    ];
    for base in variants {
        for shape in SHAPES {
            let p = ProceduralParams { shape, seed: 99, ..base.clone() };
            let g = procedural_density(&p).unwrap();
            assert_eq!(g.dims(), p.resolution);
            assert_eq!(g.bounds(), ([0.0; 3], [1.0; 3]));
            let [nx, ny, nz] = g.dims();
            for z in 0..nz {
                for y in 0..ny {
                    for x in 0..nx {
                        let v = g.voxel(x, y, z);
                        assert!((0.0..=1.0).contains(&v), "{v} at ({x}, {y}, {z})");
                        let face = [(x, nx), (y, ny), (z, nz)].iter().any(|&(i, n)| i == 0 || i + 1 == n);
                        if face {
                            assert_eq!(v, 0.0, "{p:?}: face voxel ({x}, {y}, {z})");
                        }
                    }
                }
            }
        }
    }
}

#[test]
fn default_densities_are_non_trivial_and_leave_empty_space() {
    for seed in 0..4 {
        let cloud = procedural_density(&params(ProceduralShape::Cloud, seed, 64)).unwrap();
        let plume = procedural_density(&params(ProceduralShape::Plume, seed, 64)).unwrap();
        let (mc, mp) = (mean(&cloud), mean(&plume));
        assert!((0.02..0.5).contains(&mc), "cloud seed {seed}: mean {mc}");
        assert!((0.005..0.5).contains(&mp), "plume seed {seed}: mean {mp}");
        assert!(cloud.max_value() >= 0.99, "cloud max {}", cloud.max_value());
        assert!(plume.max_value() >= 0.9, "plume max {}", plume.max_value());
        // The majorant grid can skip a good part of the box.
        for g in [&cloud, &plume] {
            let m = MajorantGrid::from_dense(g, MajorantGrid::DEFAULT_RESOLUTION);
            let empty = m.values().iter().filter(|&&v| v == 0.0).count();
            assert!(empty * 4 > m.values().len(), "{empty} empty cells");
        }
    }
}

#[test]
fn plume_has_more_mass_in_its_lower_half() {
    for seed in 0..6 {
        let g = procedural_density(&params(ProceduralShape::Plume, seed, 48)).unwrap();
        let [nx, ny, nz] = g.dims();
        let (mut lower, mut upper) = (0.0f64, 0.0f64);
        for z in 0..nz {
            for y in 0..ny {
                for x in 0..nx {
                    let v = g.voxel(x, y, z) as f64;
                    if y < ny / 2 {
                        lower += v;
                    } else {
                        upper += v;
                    }
                }
            }
        }
        assert!(lower > 1.5 * upper, "seed {seed}: lower {lower}, upper {upper}");
        // It rises from near the bottom face.
        let ext = nonzero_extent(&g);
        assert!(ext[1].0 <= ny / 8, "seed {seed}: starts at y voxel {}", ext[1].0);
    }
}

#[test]
fn cloud_is_wider_than_tall() {
    for seed in 0..6 {
        let g = procedural_density(&params(ProceduralShape::Cloud, seed, 48)).unwrap();
        let ext = nonzero_extent(&g);
        let size = ext.map(|(lo, hi)| hi + 1 - lo);
        assert!(size[0] > size[1] && size[2] > size[1], "seed {seed}: non-zero extent {size:?} (x, y, z)");
    }
}

#[test]
fn density_grows_with_coverage_from_empty() {
    for shape in SHAPES {
        let at = |coverage: f32| procedural_density(&ProceduralParams { coverage, ..params(shape, 5, 40) }).unwrap();
        assert_eq!(at(0.0).max_value(), 0.0, "{shape:?} at coverage 0");
        let grids: Vec<Vec<f32>> = [0.2, 0.5, 0.8, 1.0].map(|c| values(&at(c))).into();
        for pair in grids.windows(2) {
            assert!(pair[0].iter().zip(&pair[1]).all(|(a, b)| a <= b), "{shape:?}");
            let (s0, s1) = (pair[0].iter().sum::<f32>(), pair[1].iter().sum::<f32>());
            assert!(s1 > s0, "{shape:?}: mass {s0} -> {s1}");
        }
    }
}

#[test]
fn invalid_parameters_are_errors_naming_the_field() {
    let d = ProceduralParams::default;
    let cases: Vec<(&str, ProceduralParams)> = vec![
        ("resolution", ProceduralParams { resolution: [0, 8, 8], ..d() }),
        ("resolution", ProceduralParams { resolution: [8, 1025, 8], ..d() }),
        ("resolution", ProceduralParams { resolution: [1024, 1024, 257], ..d() }),
        ("octaves", ProceduralParams { octaves: 0, ..d() }),
        ("octaves", ProceduralParams { octaves: 13, ..d() }),
        ("frequency", ProceduralParams { frequency: 0.0, ..d() }),
        ("frequency", ProceduralParams { frequency: f32::NAN, ..d() }),
        ("frequency", ProceduralParams { frequency: f32::INFINITY, ..d() }),
        ("lacunarity", ProceduralParams { lacunarity: 0.5, ..d() }),
        ("gain", ProceduralParams { gain: -0.1, ..d() }),
        ("gain", ProceduralParams { gain: 1.5, ..d() }),
        ("coverage", ProceduralParams { coverage: 1.01, ..d() }),
        ("coverage", ProceduralParams { coverage: f32::NAN, ..d() }),
        ("sharpness", ProceduralParams { sharpness: 0.0, ..d() }),
        ("sharpness", ProceduralParams { sharpness: -3.0, ..d() }),
    ];
    for (field, p) in cases {
        let err = procedural_density(&p).unwrap_err();
        let message = err.to_string();
        assert!(
            matches!(err, VolumeError::InvalidParameter { parameter, .. } if parameter == field),
            "{field}: {message}"
        );
        assert!(message.contains(field), "{message}");
        assert!(message.contains("expected"), "{message}");
    }
    // The limits themselves are accepted.
    let edge = ProceduralParams {
        resolution: [4, 4, 4],
        octaves: 12,
        frequency: 1000.0,
        lacunarity: 8.0,
        gain: 0.0,
        coverage: 0.0,
        sharpness: 1000.0,
        ..d()
    };
    assert!(procedural_density(&edge).is_ok());
}
