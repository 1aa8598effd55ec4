//! Every VDB file written by the reference library (`make_test_vdbs.py`)
//! reads back with the values the library itself reports in
//! `expected.json`: grid list, backgrounds, transforms, active voxel counts
//! and sums, leaf and tile counts, active bounding boxes, and probe values
//! (value and active state) at their index and world positions.

mod common;

use niebla_volume::{SparseGrid, VdbFile, VolumeError};
use serde_json::Value;

/// Number of files the generator writes (with `vdb_tool` and big files).
const EXPECTED_FILES: usize = 29;

fn f64s(v: &Value) -> Vec<f64> {
    v.as_array().expect("array").iter().map(|x| x.as_f64().expect("number")).collect()
}

fn i32x3(v: &Value) -> [i32; 3] {
    let a: Vec<i32> = v.as_array().expect("array").iter().map(|x| x.as_i64().unwrap() as i32).collect();
    [a[0], a[1], a[2]]
}

/// Compares one scalar grid with its reference; returns the mismatches.
fn check_scalar_grid(file: &str, grid: &SparseGrid, exp: &Value) -> Vec<String> {
    let mut errors = Vec::new();
    let mut check = |ok: bool, what: String| {
        if !ok {
            errors.push(format!("{file} / {}: {what}", exp["name_in_file"]));
        }
    };
    let bg = exp["background"].as_f64().unwrap();
    check(grid.background() as f64 == bg, format!("background {} vs {bg}", grid.background()));

    let count = exp["active_voxel_count"].as_u64().unwrap();
    check(grid.active_voxel_count() == count, format!("active count {} vs {count}", grid.active_voxel_count()));
    let sum = exp["active_value_sum"].as_f64().unwrap();
    let got = grid.active_value_sum();
    check((got - sum).abs() <= 1e-9 * sum.abs().max(1.0), format!("active sum {got} vs {sum}"));
    let leaves = exp["leaf_count"].as_u64().unwrap() as usize;
    check(grid.leaf_count() == leaves, format!("leaf count {} vs {leaves}", grid.leaf_count()));

    let tiles = grid.active_tile_counts();
    for (depth, &count) in tiles.iter().enumerate() {
        let want = exp["active_tiles"].get(format!("depth{depth}")).and_then(Value::as_u64).unwrap_or(0);
        check(count as u64 == want, format!("active tiles at depth {depth}: {count} vs {want}"));
    }

    let bbox = grid.active_bounds_index();
    match &exp["active_bbox"] {
        Value::Null => check(bbox.is_none(), format!("active bbox {bbox:?} vs none")),
        b => {
            let want = (i32x3(&b[0]), i32x3(&b[1]));
            check(bbox == Some(want), format!("active bbox {bbox:?} vs {want:?}"));
        }
    }

    // Transform: map type, origin and the images of the index axes.
    let t = &exp["transform"];
    check(grid.map_type() == t["map"].as_str().unwrap(), format!("map {} vs {}", grid.map_type(), t["map"]));
    let m = grid.transform();
    let origin = f64s(&t["translation"]);
    for a in 0..3 {
        check(
            (m.translation()[a] - origin[a]).abs() < 1e-12,
            format!("translation {:?} vs {origin:?}", m.translation()),
        );
        let axis = f64s(&t["index_axes_in_world"][a]);
        for c in 0..3 {
            check((m.axis(a)[c] - axis[c]).abs() < 1e-12, format!("axis {a}: {:?} vs {axis:?}", m.axis(a)));
        }
    }

    // Probes: stored value and active state, then the world position maps
    // back to the voxel and interpolation there returns its value.
    for p in exp["probes"].as_array().unwrap() {
        let ijk = i32x3(&p["ijk"]);
        let want = p["value"].as_f64().unwrap() as f32;
        let active = p["active"].as_bool().unwrap();
        let (value, on) = grid.probe(ijk);
        check(value == want && on == active, format!("probe {ijk:?}: ({value}, {on}) vs ({want}, {active})"));
        check(grid.value(ijk) == want, format!("value {ijk:?}: {} vs {want}", grid.value(ijk)));

        let world: Vec<f64> = f64s(&p["world"]);
        let index = grid.inverse_transform().transform_point([world[0], world[1], world[2]]);
        let back = index.map(|v| v.round());
        let exact = (0..3).all(|a| (index[a] - back[a]).abs() < 1e-6 && back[a] as i32 == ijk[a]);
        check(exact, format!("world {world:?} maps to index {index:?}, not {ijk:?}"));
        let at_center = grid.lookup_index(back.map(|v| v as f32));
        check(at_center == want, format!("lookup_index at {ijk:?}: {at_center} vs {want}"));
        // From f32 world coordinates the index lands within ~1e-3 voxel.
        let w32 = [world[0] as f32, world[1] as f32, world[2] as f32];
        let looked = grid.lookup_world(w32);
        check((looked - want).abs() <= 1e-2, format!("lookup_world {w32:?}: {looked} vs {want}"));
    }
    errors
}

#[test]
fn every_generated_vdb_matches_the_reference_library() {
    let dir = common::vdb_dir();
    let expected = common::expected();
    let files = expected["files"].as_object().expect("files");
    assert_eq!(
        files.len(),
        EXPECTED_FILES,
        "the generator wrote {} files; is vdb_tool (libopenvdb-tools) installed?",
        files.len()
    );
    let mut errors = Vec::new();
    let mut grids_read = 0;
    let mut files_ok = 0;
    for (name, fexp) in files {
        let file = match VdbFile::open(dir.join(name)) {
            Ok(f) => f,
            Err(e) => {
                errors.push(format!("{name}: open failed: {e}"));
                continue;
            }
        };
        let before = errors.len();
        if file.file_version() as u64 != fexp["file_version"].as_u64().unwrap() {
            errors.push(format!("{name}: version {}", file.file_version()));
        }
        let exp_grids = fexp["grids"].as_array().unwrap();
        // expected.json lists grids sorted by name; the file keeps its order.
        let mut names: Vec<String> = file.grids().iter().map(|g| g.unique_name.clone()).collect();
        let mut want: Vec<String> = exp_grids.iter().map(|g| g["name_in_file"].as_str().unwrap().to_string()).collect();
        names.sort();
        want.sort();
        if names != want {
            errors.push(format!("{name}: grids {names:?} vs {want:?}"));
        }
        for g in exp_grids {
            let unique = g["name_in_file"].as_str().unwrap();
            let info = file.grid(unique).expect("grid listed");
            let type_name = g["file_type_name"].as_str().unwrap();
            if info.file_type_name() != type_name || info.half != g["half"].as_bool().unwrap() {
                errors.push(format!("{name}/{unique}: type {} vs {type_name}", info.file_type_name()));
            }
            match g["value_type"].as_str().unwrap() {
                "float" | "double" => match file.read_float_grid(unique) {
                    Ok(grid) => {
                        errors.extend(check_scalar_grid(name, &grid, g));
                        grids_read += 1;
                    }
                    Err(e) => errors.push(format!("{name}/{unique}: {e}")),
                },
                other => match file.read_float_grid(unique) {
                    Err(VolumeError::UnsupportedGridType { grid, grid_type, .. }) => {
                        let message = file.read_float_grid(unique).unwrap_err().to_string();
                        if grid != unique || grid_type != type_name || !message.contains(type_name) {
                            errors.push(format!("{name}/{unique}: error names {grid:?} {grid_type:?}"));
                        }
                    }
                    r => errors.push(format!("{name}/{unique} ({other}): expected a type error, got {r:?}")),
                },
            }
        }
        if errors.len() == before {
            files_ok += 1;
        }
    }
    println!("{files_ok} of {} files and {grids_read} scalar grids match the reference", files.len());
    assert!(errors.is_empty(), "{} mismatches:\n{}", errors.len(), errors.join("\n"));
    assert_eq!(files_ok, EXPECTED_FILES);
}

#[test]
fn half_float_grids_hold_the_rounded_values() {
    let dir = common::vdb_dir();
    let full = VdbFile::open(dir.join("density_blosc.vdb")).unwrap().read_float_grid("density").unwrap();
    let half = VdbFile::open(dir.join("density_half_blosc.vdb")).unwrap().read_float_grid("density").unwrap();
    for ijk in [[0, 0, 0], [1000, 2000, 3000], [-300, 200, -4100], [40, 40, 40], [45, 38, 40]] {
        let rounded = half::f16::from_f32(full.value(ijk)).to_f32();
        assert_eq!(half.value(ijk), rounded, "at {ijk:?}");
    }
    assert_ne!(half.value([1000, 2000, 3000]), 0.3f32, "0.3 is not a half float");
}

#[test]
fn duplicate_names_pick_the_first_grid_unless_the_unique_name_is_given() {
    let file = VdbFile::open(common::vdb_dir().join("duplicate_names.vdb")).unwrap();
    let first = file.read_float_grid("density").unwrap();
    let second = file.read_float_grid("density\u{1e}1").unwrap();
    assert_eq!(first.active_voxel_count(), 25351);
    assert_eq!(second.active_voxel_count(), 10);
    assert_eq!(second.name(), "density");
}

#[test]
fn codec_variants_decode_to_identical_grids() {
    let dir = common::vdb_dir();
    let read = |f: &str| VdbFile::open(dir.join(f)).unwrap().read_float_grid("density").unwrap();
    for family in [
        ["density_blosc.vdb", "density_zip.vdb", "density_none.vdb", "density_active.vdb"],
        ["big_ball_blosc.vdb", "big_ball_zip.vdb", "big_ball_none.vdb", "big_ball_blosc.vdb"],
    ] {
        let reference = read(family[0]);
        for other in &family[1..] {
            let g = read(other);
            assert_eq!(g.leaf_count(), reference.leaf_count(), "{other}");
            for (a, b) in g.leaves().iter().zip(reference.leaves()) {
                assert_eq!(a.origin, b.origin, "{other}");
                assert_eq!(a.active, b.active, "{other}");
                // Inactive voxels are not stored by mask compression; active
                // ones must agree bit for bit.
                for n in 0..512 {
                    if a.is_active(n) {
                        assert_eq!(a.values[n].to_bits(), b.values[n].to_bits(), "{other} {:?} {n}", a.origin);
                    }
                }
            }
        }
    }
}
