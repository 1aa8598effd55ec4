//! Grid media from scene files: each density source parses, builds and puts
//! its voxels where the grid convention says (Mitsuba 3's: values at cell
//! centers of the box, clamped within half a cell of a face, zero outside, `to_world` placing the source's space in the world,
//! VDB index-to-world composed before `to_world`); bad data in files is an
//! error naming the JSON path, the file and the voxel.

use std::path::{Path, PathBuf};

use niebla::color::{BlackbodyTable, Rgb};
use niebla::integrator::IntegratorSettings;
use niebla::math::Vec3;
use niebla::medium::{DensityGrid, GridEmission, GridMedium, Medium};
use niebla::scene::{build_scene, load_scene, parse_scene_str, BuiltScene, SceneError};
use niebla::tracking::TransmittanceMethod;

const FILE: &str = "grid_test.json";

/// A scene whose `media` object is `media` (JSON text), with a box that
/// holds the medium `smoke`.
fn scene_text(media: &str) -> String {
    format!(
        r#"{{"version": 1,
            "camera": {{"type": "perspective", "position": [0, 0, 8], "target": [0, 0, 0],
                        "width": 16, "height": 16}},
            "media": {media},
            "shapes": [{{"type": "box", "min": [-4, -4, -4], "max": [4, 4, 4], "interior": "smoke"}}]}}"#
    )
}

/// Parses and builds a scene with one grid medium `smoke` given as JSON
/// text; relative files resolve against `dir`.
fn build_in(dir: &Path, medium: &str) -> Result<BuiltScene, SceneError> {
    let text = scene_text(&format!(r#"{{"smoke": {medium}}}"#));
    let desc = parse_scene_str(&text, FILE)?;
    build_scene(&desc, FILE, dir)
}

fn build(medium: &str) -> BuiltScene {
    build_in(Path::new("."), medium).unwrap_or_else(|e| panic!("{e}"))
}

fn grid(built: &BuiltScene) -> &GridMedium {
    match &built.scene.media[0] {
        Medium::Grid(g) => g,
        other => panic!("not a grid medium: {other:?}"),
    }
}

/// Density at world point `p` through the runtime medium (`sigma_t` is 1
/// per unit density in these scenes).
fn density(built: &BuiltScene, p: [f32; 3]) -> f32 {
    built.scene.media[0].at(Vec3::from(p)).sigma_t().r()
}

#[track_caller]
fn assert_close(actual: f32, expected: f32, tolerance: f32) {
    assert!((actual - expected).abs() <= tolerance, "got {actual}, expected {expected} (tolerance {tolerance})");
}

/// A fresh folder under cargo's temporary directory for integration tests.
fn temp_dir(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("scene_grid_media_{name}"));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Flat index of voxel `(x, y, z)` in a `[z][y][x]` array of `dims`.
fn flat(dims: [usize; 3], x: usize, y: usize, z: usize) -> usize {
    (z * dims[1] + y) * dims[0] + x
}

/// Writes a little-endian float32 `.npy` file (format version 1.0) of the
/// given shape, C order.
fn write_npy(path: &Path, shape: &[usize], data: &[f32]) {
    assert_eq!(shape.iter().product::<usize>(), data.len());
    let dims: Vec<String> = shape.iter().map(|n| n.to_string()).collect();
    let shape = if dims.len() == 1 { format!("({},)", dims[0]) } else { format!("({})", dims.join(", ")) };
    let mut header = format!("{{'descr': '<f4', 'fortran_order': False, 'shape': {shape}, }}");
    // Magic (6) + version (2) + length (2) + header + '\n' is a multiple of 64.
    while (10 + header.len() + 1) % 64 != 0 {
        header.push(' ');
    }
    header.push('\n');
    let mut bytes = b"\x93NUMPY\x01\x00".to_vec();
    bytes.extend_from_slice(&(header.len() as u16).to_le_bytes());
    bytes.extend_from_slice(header.as_bytes());
    for v in data {
        bytes.extend_from_slice(&v.to_le_bytes());
    }
    std::fs::write(path, bytes).unwrap();
}

/// A 4^3 grid over [-1, 1]^3 (cells 0.5 wide), zero but for voxel
/// [z = 2][y = 1][x = 3] = 5, whose center is (0.75, -0.25, 0.25).
const ONE_BRIGHT_VOXEL: &str = r#"{"type": "grid", "dims": [4, 4, 4],
    "bounds": {"min": [-1, -1, -1], "max": [1, 1, 1]},
    "data": [0,0,0,0, 0,0,0,0, 0,0,0,0, 0,0,0,0,
             0,0,0,0, 0,0,0,0, 0,0,0,0, 0,0,0,0,
             0,0,0,0, 0,0,0,5, 0,0,0,0, 0,0,0,0,
             0,0,0,0, 0,0,0,0, 0,0,0,0, 0,0,0,0]}"#;

const VOXEL_CENTER: [f32; 3] = [0.75, -0.25, 0.25];

// ---------------------------------------------------------------------------
// Inline grids, constants and to_world
// ---------------------------------------------------------------------------

#[test]
fn inline_grid_voxel_lands_at_its_world_position() {
    let built = build(&format!(r#"{{"type": "grid", "sigma_t": 1, "albedo": 0.5, "density": {ONE_BRIGHT_VOXEL}}}"#));
    assert_eq!(density(&built, VOXEL_CENTER), 5.0);
    // Halfway to the next cell center along x (inside the clamp band near
    // the face at x = 1 the value stays 5); halfway toward y's neighbor.
    assert_close(density(&built, [0.9, -0.25, 0.25]), 5.0, 1e-5);
    assert_close(density(&built, [0.75, 0.0, 0.25]), 2.5, 1e-5);
    // Neighbouring cell centers are zero, and so is everything outside the box.
    assert_eq!(density(&built, [0.25, -0.25, 0.25]), 0.0);
    assert_eq!(density(&built, [1.01, -0.25, 0.25]), 0.0);
    assert_eq!(density(&built, [0.75, -0.25, -1.5]), 0.0);
    // Coefficients are per unit density: sigma_s = albedo sigma_t.
    let point = built.scene.media[0].at(Vec3::from(VOXEL_CENTER));
    assert_close(point.sigma_s.g(), 2.5, 1e-6);
    let m = grid(&built);
    assert_eq!(m.world_bounds, (Vec3::splat(-1.0), Vec3::splat(1.0)));
}

#[test]
fn to_world_scale_translate_and_rotation_move_the_density() {
    let medium = |to_world: &str| {
        build(&format!(
            r#"{{"type": "grid", "sigma_t": 1, "albedo": 0.5, "density": {ONE_BRIGHT_VOXEL},
                 "to_world": {to_world}}}"#
        ))
    };
    // Scale 2 then translate (1, 2, 3): the center goes to 2 c + t.
    let built = medium(r#"{"scale": 2, "translate": [1, 2, 3]}"#);
    assert_close(density(&built, [2.5, 1.5, 3.5]), 5.0, 1e-5);
    assert_eq!(density(&built, VOXEL_CENTER), 0.0);
    let m = grid(&built);
    assert_eq!(m.world_bounds, (Vec3::new(-1.0, 0.0, 1.0), Vec3::new(3.0, 4.0, 5.0)));
    // A cell is 1 unit wide now: half a cell along -x is half the value.
    assert_close(density(&built, [2.0, 1.5, 3.5]), 2.5, 1e-5);

    // Rotation by 90 degrees about z: (x, y, z) -> (-y, x, z).
    let built = medium(r#"{"rotate_z": 90}"#);
    assert_close(density(&built, [0.25, 0.75, 0.25]), 5.0, 1e-4);
    assert_eq!(density(&built, VOXEL_CENTER), 0.0);

    // A full matrix: the same as scale 2 and translate (1, 2, 3).
    let built = medium(r#"{"matrix": [[2, 0, 0, 1], [0, 2, 0, 2], [0, 0, 2, 3], [0, 0, 0, 1]]}"#);
    assert_close(density(&built, [2.5, 1.5, 3.5]), 5.0, 1e-5);
}

#[test]
fn constant_density_fills_its_bounds() {
    let built = build(
        r#"{"type": "grid", "sigma_t": 1, "albedo": 1,
            "density": {"type": "constant", "value": 0.5,
                        "bounds": {"min": [0, 0, 0], "max": [2, 1, 3]}},
            "to_world": {"translate": [-1, 0, 0]}}"#,
    );
    for p in [[-0.99, 0.01, 0.01], [0.0, 0.5, 1.5], [0.99, 0.99, 2.99]] {
        assert_eq!(density(&built, p), 0.5, "{p:?}");
    }
    for p in [[1.01, 0.5, 1.0], [0.0, -0.01, 1.0], [0.0, 0.5, 3.01]] {
        assert_eq!(density(&built, p), 0.0, "{p:?}");
    }
    // One voxel: one majorant cell, equal to the minorant.
    let m = grid(&built);
    assert_eq!(m.majorant.res(), [1, 1, 1]);
    assert_eq!(m.majorant.values(), &[0.5]);
    assert_eq!(m.minorant().map(|g| g.values().to_vec()), Some(vec![0.5]));
    // Default type, a unit box and value 1.
    let built = build(r#"{"type": "grid", "sigma_t": 1, "albedo": 1, "density": {"type": "constant"}}"#);
    assert_eq!(density(&built, [0.5, 0.5, 0.5]), 1.0);
    assert_eq!(density(&built, [-0.5, 0.5, 0.5]), 0.0);
}

#[test]
fn majorants_and_minorants_bound_the_density() {
    let built = build(&format!(
        r#"{{"type": "grid", "sigma_t": 1, "albedo": 0.5, "density": {ONE_BRIGHT_VOXEL},
             "majorant_resolution": [2, 2, 1]}}"#
    ));
    let m = grid(&built);
    assert_eq!(m.majorant.res(), [2, 2, 1]);
    assert_eq!(m.majorant.max_value(), 5.0);
    let minorant = m.minorant().expect("a minorant grid");
    assert!(minorant.same_layout(&m.majorant));
    assert!(minorant.values().iter().all(|v| *v == 0.0));
    // Without a resolution, a 4^3 grid gets 4^3 cells (at most one per voxel).
    let built = build(&format!(r#"{{"type": "grid", "sigma_t": 1, "albedo": 0.5, "density": {ONE_BRIGHT_VOXEL}}}"#));
    assert_eq!(grid(&built).majorant.res(), [4, 4, 4]);
}

// ---------------------------------------------------------------------------
// Emission
// ---------------------------------------------------------------------------

#[test]
fn emission_forms_give_the_documented_radiance() {
    // Proportional to the density.
    let built = build(&format!(
        r#"{{"type": "grid", "sigma_t": 1, "albedo": 0.5, "density": {ONE_BRIGHT_VOXEL},
             "emission": {{"L_ve": [1, 2, 3]}}}}"#
    ));
    let l_ve = built.scene.media[0].at(Vec3::from(VOXEL_CENTER)).l_ve;
    assert_eq!(l_ve, Rgb([5.0, 10.0, 15.0]));
    assert!(built.scene.media[0].is_emissive());

    // An emission grid with a color and a scale, placed by to_world.
    let built = build(&format!(
        r#"{{"type": "grid", "sigma_t": 1, "albedo": 0.5, "density": {{"type": "constant"}},
             "to_world": {{"scale": 2}},
             "emission": {{"grid": {ONE_BRIGHT_VOXEL}, "color": [1, 0.5, 0.25],
                           "emission_scale": 2}}}}"#
    ));
    let l_ve = built.scene.media[0].at(Vec3::new(1.5, -0.5, 0.5)).l_ve;
    assert_eq!(l_ve, Rgb([10.0, 5.0, 2.5]));
    assert!(matches!(grid(&built).emission, GridEmission::Field { .. }));

    // A temperature: unit-luminance blackbody color times the scale.
    let built = build(
        r#"{"type": "grid", "sigma_t": 1, "albedo": 0.5, "density": {"type": "constant"},
            "emission": {"temperature": {"type": "constant", "value": 1500},
                         "emission_scale": 3}}"#,
    );
    let l_ve = built.scene.media[0].at(Vec3::splat(0.5)).l_ve;
    let expected = BlackbodyTable::new().rgb(1500.0) * 3.0;
    for c in 0..3 {
        assert_close(l_ve.0[c], expected.0[c], 1e-5 * expected.0[c].max(1.0));
    }
    assert!(l_ve.0[0] > l_ve.0[2], "1500 K is red: {l_ve:?}");
}

// ---------------------------------------------------------------------------
// Files: .npy
// ---------------------------------------------------------------------------

#[test]
fn npy_density_is_read_relative_to_the_scene_file() {
    let dir = temp_dir("npy");
    // nx = 4, ny = 3, nz = 2 over [0, 4] x [0, 3] x [0, 2]: unit cells.
    let mut data = vec![0.0f32; 24];
    data[flat([4, 3, 2], 1, 2, 1)] = 7.0;
    write_npy(&dir.join("density.npy"), &[2, 3, 4], &data);
    let scene = dir.join("scene.json");
    std::fs::write(
        &scene,
        scene_text(
            r#"{"smoke": {"type": "grid", "sigma_t": 1, "albedo": 0.5,
                 "density": {"type": "npy", "file": "density.npy",
                             "bounds": {"min": [0, 0, 0], "max": [4, 3, 2]}}}}"#,
        ),
    )
    .unwrap();
    let built = load_scene(&scene).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(density(&built, [1.5, 2.5, 1.5]), 7.0);
    assert_eq!(density(&built, [2.5, 2.5, 1.5]), 0.0);
    assert_eq!(density(&built, [1.5, 3.5, 1.5]), 0.0);
    match &grid(&built).density {
        DensityGrid::Dense(g) => assert_eq!(g.dims(), [4, 3, 2]),
        other => panic!("expected a dense grid, got {other:?}"),
    }
}

#[test]
fn npy_rgb_density_is_rejected_for_having_three_channels() {
    let dir = temp_dir("npy_rgb");
    write_npy(&dir.join("rgb.npy"), &[2, 2, 2, 3], &[0.5; 24]);
    let err =
        build_in(&dir, r#"{"type": "grid", "sigma_t": 1, "albedo": 1, "density": {"type": "npy", "file": "rgb.npy"}}"#)
            .unwrap_err();
    assert_eq!(err.path, "media.smoke.density.file", "{err}");
    assert!(err.message.contains("rgb.npy"), "{err}");
    assert!(err.message.contains("a density must have one channel"), "{err}");
    // An RGB emission grid is not supported yet, and says so.
    let err = build_in(
        &dir,
        r#"{"type": "grid", "sigma_t": 1, "albedo": 1, "density": {"type": "constant"},
            "emission": {"grid": {"type": "npy", "file": "rgb.npy"}}}"#,
    )
    .unwrap_err();
    assert_eq!(err.path, "media.smoke.emission.grid.file", "{err}");
    assert!(err.message.contains("RGB emission grids are not supported"), "{err}");
}

#[test]
fn negative_or_nan_values_in_files_name_the_file_and_voxel() {
    let dir = temp_dir("npy_bad");
    let mut data = vec![0.25f32; 24];
    data[flat([4, 3, 2], 2, 0, 1)] = -1.0;
    write_npy(&dir.join("negative.npy"), &[2, 3, 4], &data);
    data[flat([4, 3, 2], 2, 0, 1)] = 0.0;
    data[flat([4, 3, 2], 1, 1, 0)] = f32::NAN;
    write_npy(&dir.join("nan.npy"), &[2, 3, 4], &data);
    let medium = |file: &str| {
        format!(r#"{{"type": "grid", "sigma_t": 1, "albedo": 1, "density": {{"type": "npy", "file": "{file}"}}}}"#)
    };
    let err = build_in(&dir, &medium("negative.npy")).unwrap_err();
    assert_eq!(err.path, "media.smoke.density.file", "{err}");
    assert!(err.message.contains("negative.npy"), "{err}");
    assert!(err.message.contains("voxel (x, y, z) = (2, 0, 1) has value -1"), "{err}");
    assert!(err.message.contains("density values must be finite and >= 0"), "{err}");
    let err = build_in(&dir, &medium("nan.npy")).unwrap_err();
    assert!(err.message.contains("voxel (x, y, z) = (1, 1, 0) has value NaN"), "{err}");
}

#[test]
fn unreadable_files_are_reported_at_their_path() {
    let dir = temp_dir("missing");
    let err = build_in(
        &dir,
        r#"{"type": "grid", "sigma_t": 1, "albedo": 1, "density": {"type": "vol", "file": "nope.vol"}}"#,
    )
    .unwrap_err();
    assert_eq!(err.path, "media.smoke.density.file", "{err}");
    assert!(err.message.contains("nope.vol") && err.message.contains("cannot read"), "{err}");
    assert_eq!(err.file, FILE);
    // Not a VDB file.
    std::fs::write(dir.join("fake.vdb"), b"definitely not a vdb").unwrap();
    let err = build_in(
        &dir,
        r#"{"type": "grid", "sigma_t": 1, "albedo": 1, "density": {"type": "constant"},
            "emission": {"temperature": {"type": "vdb", "file": "fake.vdb"}}}"#,
    )
    .unwrap_err();
    assert_eq!(err.path, "media.smoke.emission.temperature.file", "{err}");
    assert!(err.message.contains("fake.vdb"), "{err}");
}

// ---------------------------------------------------------------------------
// Procedural
// ---------------------------------------------------------------------------

#[test]
fn procedural_density_is_deterministic_bounded_and_placed_by_to_world() {
    let medium = r#"{"type": "grid", "sigma_t": 1, "albedo": 1,
        "density": {"type": "procedural", "shape": "plume", "seed": 3, "resolution": 24},
        "to_world": {"scale": 4, "translate": [-2, -2, -2]}}"#;
    let a = build(medium);
    let b = build(medium);
    let m = grid(&a);
    let DensityGrid::Dense(g) = &m.density else { panic!("procedural densities are dense") };
    assert_eq!(g.dims(), [24, 24, 24]);
    assert_eq!(g.bounds(), ([0.0; 3], [1.0; 3]));
    assert!(g.max_value() > 0.0 && g.max_value() <= 1.0);
    assert_eq!(m.majorant.res(), [16, 16, 16]);
    assert_eq!(m.world_bounds, (Vec3::splat(-2.0), Vec3::splat(2.0)));
    // Each voxel's value sits at its center, mapped by to_world (scale 4,
    // translate -2): the two builds agree bit for bit.
    let mut nonzero = 0;
    for z in 0..24 {
        for y in 0..24 {
            for x in 0..24 {
                let center = [x, y, z].map(|i| 4.0 * (i as f32 + 0.5) / 24.0 - 2.0);
                let d = density(&a, center);
                assert_close(d, g.voxel(x, y, z), 1e-5);
                assert_eq!(d.to_bits(), density(&b, center).to_bits());
                assert!((0.0..=1.0).contains(&d), "{d} at {center:?}");
                nonzero += usize::from(d > 0.0);
            }
        }
    }
    assert!(nonzero > 100, "the plume is nearly empty: {nonzero} voxels");
    // Zero on the faces of the box.
    assert_eq!(density(&a, [-1.99, 0.0, 0.0]), 0.0);
}

// ---------------------------------------------------------------------------
// OpenVDB (files from /work/shared/vdb/make_test_vdbs.py, when present)
// ---------------------------------------------------------------------------

/// The folder of reference VDB files, if some earlier run generated it.
fn test_vdbs() -> Option<PathBuf> {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("niebla_test_vdbs");
    if dir.join("multi_density_temperature.vdb").is_file() {
        Some(dir)
    } else {
        eprintln!(
            "skipped: no VDB test files in {} (run /usr/bin/python3 \
             /work/shared/vdb/make_test_vdbs.py {} --no-big)",
            dir.display(),
            dir.display()
        );
        None
    }
}

#[test]
fn vdb_density_composes_index_to_world_with_to_world() {
    let Some(dir) = test_vdbs() else { return };
    // Written probe voxels (ijk -> value); neighbours of these are unset.
    let probes = [([0, 0, 0], 0.25), ([1, 2, 3], 0.5), ([7, 7, 7], 0.75)];
    let file = dir.join("xform_affine_rotated.vdb");
    let sparse = niebla_volume::VdbFile::open(&file).unwrap().read_float_grid("density").unwrap();
    let medium = |to_world: &str| {
        let text = format!(
            r#"{{"type": "grid", "sigma_t": 1, "albedo": 1,
                 "density": {{"type": "vdb", "file": "xform_affine_rotated.vdb"}},
                 "to_world": {to_world}}}"#
        );
        build_in(&dir, &text).unwrap_or_else(|e| panic!("{e}"))
    };
    let identity = medium("{}");
    let moved = medium(r#"{"scale": 2, "translate": [1, 0, -1]}"#);
    assert!(matches!(grid(&identity).density, DensityGrid::Sparse(_)));
    assert!(!grid(&identity).minorant.is_built(), "built before first use");
    assert!(grid(&identity).minorant().is_some());
    for (ijk, value) in probes {
        let world = sparse.index_to_world(ijk.map(|v| v as f32));
        assert_close(density(&identity, world), value, 1e-3);
        let moved_world = [2.0 * world[0] + 1.0, 2.0 * world[1], 2.0 * world[2] - 1.0];
        assert_close(density(&moved, moved_world), value, 1e-3);
        // The old place is empty in the moved medium (0 between voxels).
        assert!(density(&moved, world) < value, "{ijk:?}");
    }
}

#[test]
fn vdb_temperature_emission_and_default_grid_name() {
    let Some(dir) = test_vdbs() else { return };
    let built = build_in(
        &dir,
        r#"{"type": "grid", "sigma_t": 1, "albedo": 1,
            "density": {"type": "vdb", "file": "multi_density_temperature.vdb"},
            "emission": {"temperature": {"type": "vdb", "file": "multi_density_temperature.vdb",
                                         "grid": "temperature"},
                         "emission_scale": 2},
            "majorant_resolution": 64}"#,
    )
    .unwrap_or_else(|e| panic!("{e}"));
    // Density 0.5 and temperature 1500 K at voxel (1, 2, 3), identity transforms.
    let p = [1.0, 2.0, 3.0];
    assert_close(density(&built, p), 0.5, 1e-6);
    let l_ve = built.scene.media[0].at(Vec3::from(p)).l_ve;
    let expected = BlackbodyTable::new().rgb(1500.0) * 2.0;
    for c in 0..3 {
        assert_close(l_ve.0[c], expected.0[c], 1e-4 * expected.0[c].max(1.0));
    }
    // A resolution is a cell budget for sparse grids.
    let res = grid(&built).majorant.res();
    assert!(res.iter().product::<usize>() <= 64 * 64 * 64, "{res:?}");
    assert!(matches!(grid(&built).emission, GridEmission::Temperature { .. }));
}

#[test]
fn vdb_errors_name_the_grid_or_the_bad_voxel() {
    let Some(dir) = test_vdbs() else { return };
    let err = build_in(
        &dir,
        r#"{"type": "grid", "sigma_t": 1, "albedo": 1,
            "density": {"type": "vdb", "file": "multi_density_temperature.vdb", "grid": "smoke"}}"#,
    )
    .unwrap_err();
    assert_eq!(err.path, "media.smoke.density.grid", "{err}");
    assert!(err.message.contains("no grid named \"smoke\"") && err.message.contains("temperature"), "{err}");
    if !dir.join("levelset_sphere.vdb").is_file() {
        return;
    }
    // A level set stores negative distances inside: not a density.
    let err = build_in(
        &dir,
        r#"{"type": "grid", "sigma_t": 1, "albedo": 1,
            "density": {"type": "vdb", "file": "levelset_sphere.vdb", "grid": "surface"}}"#,
    )
    .unwrap_err();
    assert_eq!(err.path, "media.smoke.density.file", "{err}");
    assert!(err.message.contains("levelset_sphere.vdb: grid \"surface\""), "{err}");
    assert!(err.message.contains("density values must be finite and >= 0"), "{err}");
}

// ---------------------------------------------------------------------------
// Integrator settings
// ---------------------------------------------------------------------------

#[test]
fn tracking_transmittance_methods_reach_the_integrator_settings() {
    for (name, method) in [
        ("delta", TransmittanceMethod::Delta),
        ("ratio", TransmittanceMethod::Ratio),
        ("residual_ratio", TransmittanceMethod::ResidualRatio),
    ] {
        let text =
            scene_text(r#"{"smoke": {"type": "grid", "sigma_t": 1, "albedo": 1, "density": {"type": "constant"}}}"#)
                .replace(
                    r#""media""#,
                    &format!(
                        r#""render": {{"integrator": {{"type": "emission", "transmittance": "{name}"}}}}, "media""#
                    ),
                );
        let desc = parse_scene_str(&text, FILE).unwrap();
        let built = build_scene(&desc, FILE, Path::new(".")).unwrap();
        match built.settings.integrator {
            IntegratorSettings::Emission { transmittance, .. } => {
                assert_eq!(transmittance, method, "{name}")
            }
            other => panic!("wrong integrator {other:?}"),
        }
    }
}

#[test]
fn half_precision_storage_keeps_densities_within_half_precision() {
    let medium = r#"{"type": "grid", "sigma_t": 1, "albedo": 0.5, "storage": "f16",
                     "density": {"type": "procedural", "shape": "cloud", "seed": 3, "resolution": 24}}"#;
    let half = build(medium);
    let full = build(&medium.replace(r#""storage": "f16","#, ""));
    let DensityGrid::Dense(g) = &grid(&half).density else { panic!("expected a dense grid") };
    assert!(matches!(g.storage(), niebla_volume::GridStorage::F16(_)));
    let mut compared = 0;
    for i in 0..400 {
        let p = [(i % 7) as f32 / 7.0 + 0.03, (i % 11) as f32 / 11.0 + 0.02, (i % 13) as f32 / 13.0 + 0.01];
        let (a, b) = (density(&half, p), density(&full, p));
        // f16 has an 11-bit significand: relative rounding error below 2^-11.
        assert!((a - b).abs() <= b.abs() * 4.9e-4 + 1e-7, "at {p:?}: f16 {a} vs f32 {b}");
        compared += usize::from(b > 0.0);
    }
    assert!(compared > 20);
    let bad = medium.replace(r#""f16""#, r#""f8""#);
    let err = parse_scene_str(&scene_text(&format!(r#"{{"smoke": {bad}}}"#)), FILE).unwrap_err();
    assert_eq!(err.path, "media.smoke.storage", "{err}");
}

// ---------------------------------------------------------------------------
// Albedo grids
// ---------------------------------------------------------------------------

/// Writes a Mitsuba `.vol` file (version 3, float32) of `channels` values per
/// voxel, `[z][y][x][channel]`, filling the box `lo..hi`.
fn write_vol(path: &Path, dims: [usize; 3], channels: usize, lo: [f32; 3], hi: [f32; 3], data: &[f32]) {
    assert_eq!(dims.iter().product::<usize>() * channels, data.len());
    let mut bytes = b"VOL\x03".to_vec();
    for v in [1, dims[0] as i32, dims[1] as i32, dims[2] as i32, channels as i32] {
        bytes.extend_from_slice(&v.to_le_bytes());
    }
    for v in lo.iter().chain(&hi).chain(data) {
        bytes.extend_from_slice(&v.to_le_bytes());
    }
    std::fs::write(path, bytes).unwrap();
}

/// The RGB albedo of voxel `(x, y, z)` in the test grids: distinct values in
/// (0, 1) per voxel and channel.
fn test_albedo(x: usize, y: usize, z: usize) -> [f32; 3] {
    [0.1 + 0.2 * x as f32, 0.9 - 0.3 * y as f32 - 0.05 * z as f32, 0.2 + 0.15 * (x + y + 2 * z) as f32]
}

#[test]
fn rgb_albedo_grid_is_placed_by_its_own_transform_and_clamped_outside_its_box() {
    let dir = temp_dir("albedo_rgb");
    // 3 x 2 x 2 voxels over the file's box [0, 1]^3 (ignored placement: the
    // source fills its box, albedo_to_world maps it to [-0.5, 1] x [-1, 0] x [0, 1]).
    let dims = [3, 2, 2];
    let mut data = Vec::new();
    for z in 0..2 {
        for y in 0..2 {
            for x in 0..3 {
                data.extend(test_albedo(x, y, z));
            }
        }
    }
    write_vol(&dir.join("albedo.vol"), dims, 3, [0.0; 3], [1.0; 3], &data);
    // Density 2 everywhere in [-2, 2]^3, sigma_t 3: extinction 6; the albedo
    // color [1, 0.5, 1] multiplies the grid.
    let built = build_in(
        &dir,
        r#"{"type": "grid", "sigma_t": 3, "albedo": [1, 0.5, 1],
            "density": {"type": "constant", "value": 2, "bounds": {"min": [-2, -2, -2], "max": [2, 2, 2]}},
            "albedo_grid": {"type": "vol", "file": "albedo.vol"},
            "albedo_to_world": {"scale": [1.5, 1, 1], "translate": [-0.5, -1, 0]}}"#,
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let color = [1.0, 0.5, 1.0];
    let check = |p: [f32; 3], albedo: [f32; 3]| {
        let point = built.scene.media[0].at(Vec3::from(p));
        for c in 0..3 {
            // sigma_t is untouched by the albedo; sigma_s = sigma_t * color * grid.
            assert_close(point.sigma_t()[c], 6.0, 1e-5);
            assert_close(point.sigma_s[c], 6.0 * color[c] * albedo[c], 1e-5);
        }
    };
    // Cell centers: x = -0.5 + 1.5 (i + 0.5) / 3, y = -1 + (j + 0.5) / 2, z = (k + 0.5) / 2.
    let center = |x: usize, y: usize, z: usize| {
        [-0.5 + 0.5 * (x as f32 + 0.5), -1.0 + 0.5 * (y as f32 + 0.5), 0.5 * (z as f32 + 0.5)]
    };
    for (x, y, z) in [(0, 0, 0), (2, 1, 0), (1, 0, 1), (2, 1, 1)] {
        check(center(x, y, z), test_albedo(x, y, z));
    }
    // Halfway between two centers along x: the mean.
    let (a, b) = (test_albedo(0, 1, 1), test_albedo(1, 1, 1));
    let mid = [(center(0, 1, 1)[0] + center(1, 1, 1)[0]) / 2.0, center(0, 1, 1)[1], center(0, 1, 1)[2]];
    check(mid, std::array::from_fn(|c| (a[c] + b[c]) / 2.0));
    // Outside the albedo's box but inside the density: the nearest point of the box.
    check([1.9, 1.5, 1.7], test_albedo(2, 1, 1));
    check([-1.9, -1.9, -1.9], test_albedo(0, 0, 0));
    check([center(1, 0, 0)[0], -1.8, center(1, 0, 0)[2]], test_albedo(1, 0, 0));
    // Outside the density there is no medium.
    assert_eq!(built.scene.media[0].at(Vec3::new(2.5, 0.0, 0.0)).sigma_t(), Rgb::ZERO);
}

#[test]
fn one_channel_albedo_grid_defaults_to_the_density_placement() {
    let dir = temp_dir("albedo_grey");
    // Two voxels along x (values 0.2 and 0.8) over [0, 1]^3, placed like the
    // density by the medium's to_world (scale 2): x centers at 0.5 and 1.5.
    write_npy(&dir.join("albedo.npy"), &[1, 1, 2], &[0.2, 0.8]);
    let built = build_in(
        &dir,
        r#"{"type": "grid", "sigma_t": 1,
            "density": {"type": "constant", "value": 1},
            "albedo_grid": {"type": "npy", "file": "albedo.npy"},
            "to_world": {"scale": 2}}"#,
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let sigma_s = |x: f32| built.scene.media[0].at(Vec3::new(x, 1.0, 1.0)).sigma_s;
    assert_eq!(sigma_s(0.5), Rgb::splat(0.2));
    assert_eq!(sigma_s(1.5), Rgb::splat(0.8));
    assert_close(sigma_s(1.0).g(), 0.5, 1e-6);
    assert_close(sigma_s(0.1).b(), 0.2, 1e-6);
}

#[test]
fn albedo_grid_errors_name_the_field_and_what_was_expected() {
    let dir = temp_dir("albedo_errors");
    write_vol(&dir.join("two.vol"), [1, 1, 1], 2, [0.0; 3], [1.0; 3], &[0.5, 0.5]);
    write_vol(&dir.join("bright.vol"), [2, 1, 1], 3, [0.0; 3], [1.0; 3], &[0.5, 0.5, 0.5, 0.5, 1.2, 0.5]);
    let err = |medium: &str| build_in(&dir, medium).map(|_| ()).unwrap_err();
    let density = r#""density": {"type": "constant", "value": 1}"#;
    let e = err(&format!(
        r#"{{"type": "grid", "sigma_t": 1, {density}, "albedo_grid": {{"type": "vol", "file": "bright.vol"}}}}"#
    ));
    assert_eq!(e.path, "media.smoke.albedo_grid.file", "{e}");
    assert!(e.message.contains("voxel (x, y, z) = (1, 0, 0)") && e.message.contains("must be in [0, 1]"), "{e}");
    let e = err(&format!(
        r#"{{"type": "grid", "sigma_t": 1, {density}, "albedo_grid": {{"type": "vol", "file": "two.vol"}}}}"#
    ));
    assert_eq!(e.path, "media.smoke.albedo_grid.file", "{e}");
    assert!(e.message.contains("two.vol") && e.message.contains("channel"), "{e}");
    let e = err(&format!(
        r#"{{"type": "grid", "sigma_a": 1, "sigma_s": 1, {density}, "albedo_grid": {{"type": "constant", "value": 0.5}}}}"#
    ));
    assert_eq!(e.path, "media.smoke.sigma_a", "{e}");
    assert!(e.message.contains("cannot be combined with `albedo_grid`"), "{e}");
    let e = err(&format!(r#"{{"type": "grid", {density}, "albedo_grid": {{"type": "constant", "value": 0.5}}}}"#));
    assert_eq!(e.path, "media.smoke.sigma_t", "{e}");
    let e =
        err(&format!(r#"{{"type": "grid", "sigma_t": 1, "albedo": 1, {density}, "albedo_to_world": {{"scale": 2}}}}"#));
    assert_eq!(e.path, "media.smoke.albedo_to_world", "{e}");
    let e = err(&format!(
        r#"{{"type": "grid", "sigma_t": 1, {density}, "albedo_grid": {{"type": "constant", "value": 1.5}}}}"#
    ));
    assert_eq!(e.path, "media.smoke.albedo_grid.value", "{e}");
    let e = err(&format!(
        r#"{{"type": "grid", "sigma_t": 1, {density}, "albedo_grid": {{"type": "vdb", "file": "a.vdb"}}}}"#
    ));
    assert_eq!(e.path, "media.smoke.albedo_grid.type", "{e}");
    let e = err(&format!(
        r#"{{"type": "grid", "sigma_t": 1, {density}, "albedo_grid": {{"type": "vol", "file": "missing.vol"}}}}"#
    ));
    assert_eq!(e.path, "media.smoke.albedo_grid.file", "{e}");
    assert!(e.message.contains("missing.vol"), "{e}");
    // A homogeneous medium has no albedo grid.
    let e = err(r#"{"type": "homogeneous", "sigma_t": 1, "albedo_grid": {"type": "constant", "value": 0.5}}"#);
    assert!(e.message.contains("albedo_grid"), "{e}");
}

/// A constant albedo grid renders what the same constant albedo renders:
/// volpath in a lit medium, image means within 4 standard errors of their
/// difference (per-pixel spread over 1024 pixels, 64 spp).
#[test]
fn constant_albedo_grid_renders_as_the_constant_albedo() {
    let scene = |albedo: &str| {
        format!(
            r#"{{"version": 1,
                "camera": {{"type": "perspective", "position": [0, 0, 5], "target": [0, 0, 0], "fov_y": 40,
                            "width": 32, "height": 32}},
                "render": {{"spp": 64}},
                "media": {{"smoke": {{"type": "grid", "sigma_t": 2, {albedo},
                    "density": {{"type": "grid", "dims": [2, 2, 2], "data": [0.3, 1, 0.6, 1.4, 1.2, 0.5, 0.9, 0.2],
                                 "bounds": {{"min": [-1, -1, -1], "max": [1, 1, 1]}}}},
                    "phase": {{"type": "hg", "g": 0.4}}}}}},
                "shapes": [{{"type": "box", "min": [-1, -1, -1], "max": [1, 1, 1], "interior": "smoke"}}],
                "lights": [{{"type": "directional", "direction": [-1, -0.6, -0.3], "irradiance": [3, 2.8, 2.5]}},
                           {{"type": "constant", "radiance": [0.1, 0.12, 0.16]}}]}}"#
        )
    };
    let means = |text: &str, seed: u64| {
        let desc = parse_scene_str(text, FILE).unwrap_or_else(|e| panic!("{e}"));
        let built = build_scene(&desc, FILE, Path::new(".")).unwrap_or_else(|e| panic!("{e}"));
        let options = niebla::render::RenderOptions {
            spp: 64,
            seed,
            first_sample: 0,
            threads: None,
            sampler: niebla::sampling::SamplerKind::Independent,
        };
        let image =
            niebla::render::render(&built.scene, &built.settings.integrator, &options, &|_, _| {}, None).unwrap();
        let (w, h) = (built.scene.camera.width, built.scene.camera.height);
        let mut pixels = Vec::new();
        for y in 0..h {
            for x in 0..w {
                pixels.push(image.get(x, y).0);
            }
        }
        pixels
    };
    // Different seeds: independent estimates.
    let a = means(
        &scene(
            r#""albedo": [1, 0.5, 0.8], "albedo_grid": {"type": "constant", "value": 0.6, "bounds": {"min": [-1, -1, -1], "max": [1, 1, 1]}}"#,
        ),
        1,
    );
    let b = means(&scene(r#""albedo": [0.6, 0.3, 0.48]"#), 2);
    for c in 0..3 {
        let n = a.len() as f64;
        let d: Vec<f64> = a.iter().zip(&b).map(|(p, q)| p[c] as f64 - q[c] as f64).collect();
        let mean = d.iter().sum::<f64>() / n;
        let se = (d.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0) / n).sqrt();
        let level = b.iter().map(|p| p[c] as f64).sum::<f64>() / n;
        println!("channel {c}: mean {level:.5}, difference {mean:.6} (se {se:.6})");
        assert!(level > 0.01, "the medium is lit");
        assert!(mean.abs() < 4.0 * se, "channel {c}: difference {mean} exceeds 4 standard errors {se}");
    }
}
