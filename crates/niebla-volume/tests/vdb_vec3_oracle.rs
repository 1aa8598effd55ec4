//! Vec3 grids and a Mantaflow-style multi-grid file written by the reference
//! library (`tests/oracle/make_vec3_vdbs.py`: blosc, zip and uncompressed,
//! full and half precision, tiles at two tree levels, an inactive tile with a
//! non-background value, root-node borders, empty grids) read back with the
//! values the library itself reports: backgrounds, active voxel counts,
//! per-component sums of the active values, leaf and tile counts, active
//! bounds, and probe values (value and active state, exactly).

mod common;

use niebla_volume::{SparseVec3Grid, VdbFile, VdbValueKind, VolumeError};
use serde_json::Value;

/// Files the generator writes when vdb_tool is installed.
const EXPECTED_FILES: usize = 6;

fn f32s(v: &Value) -> Vec<f32> {
    v.as_array().expect("array").iter().map(|x| x.as_f64().expect("number") as f32).collect()
}

fn i32x3(v: &Value) -> [i32; 3] {
    let a: Vec<i32> = v.as_array().expect("array").iter().map(|x| x.as_i64().unwrap() as i32).collect();
    [a[0], a[1], a[2]]
}

/// Statistics shared by scalar and vector grids, compared with `exp`.
struct Stats {
    background: Vec<f32>,
    count: u64,
    sums: Vec<f64>,
    leaves: usize,
    tiles: [usize; 3],
    bbox: Option<([i32; 3], [i32; 3])>,
}

fn compare(file: &str, exp: &Value, got: &Stats, probe: &dyn Fn([i32; 3]) -> (Vec<f32>, bool)) -> Vec<String> {
    let mut errors = Vec::new();
    let name = exp["name"].as_str().unwrap();
    let mut check = |ok: bool, what: String| {
        if !ok {
            errors.push(format!("{file} / {name}: {what}"));
        }
    };
    let bg = f32s(&exp["background"]);
    check(got.background == bg, format!("background {:?} vs {bg:?}", got.background));
    let count = exp["active_voxel_count"].as_u64().unwrap();
    check(got.count == count, format!("active count {} vs {count}", got.count));
    for (c, want) in exp["active_value_sums"].as_array().unwrap().iter().enumerate() {
        let want = want.as_f64().unwrap();
        let s = got.sums[c];
        check((s - want).abs() <= 1e-9 * want.abs().max(1.0), format!("sum of component {c}: {s} vs {want}"));
    }
    let leaves = exp["leaf_count"].as_u64().unwrap() as usize;
    check(got.leaves == leaves, format!("leaf count {} vs {leaves}", got.leaves));
    for (depth, &n) in got.tiles.iter().enumerate() {
        let want = exp["active_tiles"].get(depth.to_string()).and_then(Value::as_u64).unwrap_or(0);
        check(n as u64 == want, format!("active tiles at depth {depth}: {n} vs {want}"));
    }
    match &exp["active_bbox"] {
        Value::Null => check(got.bbox.is_none(), format!("bbox {:?} vs none", got.bbox)),
        b => {
            let want = (i32x3(&b[0]), i32x3(&b[1]));
            check(got.bbox == Some(want), format!("bbox {:?} vs {want:?}", got.bbox));
        }
    }
    for p in exp["probes"].as_array().unwrap() {
        let ijk = i32x3(&p["ijk"]);
        let want = (f32s(&p["value"]), p["active"].as_bool().unwrap());
        let have = probe(ijk);
        check(have == want, format!("probe {ijk:?}: {have:?} vs {want:?}"));
    }
    errors
}

fn vec3_stats(g: &SparseVec3Grid) -> Stats {
    Stats {
        background: g.background().to_vec(),
        count: g.active_voxel_count(),
        sums: (0..3).map(|c| g.component(c).active_value_sum()).collect(),
        leaves: g.leaf_count(),
        tiles: g.active_tile_counts(),
        bbox: g.active_bounds_index(),
    }
}

#[test]
fn vec3_and_multigrid_files_match_the_reference_library() {
    let dir = common::vec3_vdb_dir();
    let text = std::fs::read_to_string(dir.join("expected.json")).unwrap();
    let expected: Value = serde_json::from_str(&text).unwrap();
    let files = expected["files"].as_object().unwrap();
    assert_eq!(files.len(), EXPECTED_FILES, "is vdb_tool (libopenvdb-tools) installed?");
    let mut errors = Vec::new();
    let mut vectors = 0;
    for (fname, grids) in files {
        let file = VdbFile::open(dir.join(fname)).unwrap();
        for exp in grids.as_array().unwrap() {
            let name = exp["name"].as_str().unwrap();
            let info = file.grid(name).unwrap();
            if info.half != exp["half"].as_bool().unwrap() {
                errors.push(format!("{fname}/{name}: half flag {}", info.half));
            }
            let class = file.grid_string_metadata(name, "class").unwrap();
            // OpenVDB writes no `class` entry for class "unknown".
            if Some(class.as_deref().unwrap_or("unknown")) != exp["class"].as_str() {
                errors.push(format!("{fname}/{name}: class {class:?} vs {}", exp["class"]));
            }
            if exp["vector"].as_bool().unwrap() {
                assert_eq!(info.value_kind(), VdbValueKind::Vec3Float, "{fname}/{name}");
                let g = file.read_vec3_grid(name).unwrap();
                assert_eq!(g.name(), name);
                let probe = |ijk| {
                    let (v, a) = g.probe(ijk);
                    (v.to_vec(), a)
                };
                errors.extend(compare(fname, exp, &vec3_stats(&g), &probe));
                // At voxel centers, world-space interpolation returns the voxel.
                for p in exp["probes"].as_array().unwrap() {
                    let w = f32s(&p["world"]);
                    let (v, _) = g.probe(i32x3(&p["ijk"]));
                    let l = g.lookup_world([w[0], w[1], w[2]]);
                    let close = (0..3).all(|c| (l[c] - v[c]).abs() <= 1e-3 * v[c].abs().max(1.0));
                    if !close {
                        errors.push(format!("{fname}/{name}: lookup_world {w:?} = {l:?}, voxel {v:?}"));
                    }
                }
                vectors += 1;
            } else {
                let g = file.read_float_grid(name).unwrap();
                let stats = Stats {
                    background: vec![g.background()],
                    count: g.active_voxel_count(),
                    sums: vec![g.active_value_sum()],
                    leaves: g.leaf_count(),
                    tiles: g.active_tile_counts(),
                    bbox: g.active_bounds_index(),
                };
                let probe = |ijk| {
                    let (v, a) = g.probe(ijk);
                    (vec![v], a)
                };
                errors.extend(compare(fname, exp, &stats, &probe));
            }
        }
    }
    assert!(errors.is_empty(), "{} mismatches:\n{}", errors.len(), errors.join("\n"));
    assert_eq!(vectors, 5 + 3, "five single-grid files and three vector grids in the Mantaflow file");
    let fog = VdbFile::open(dir.join("mantaflow_fire.vdb")).unwrap().grid_string_metadata("density", "class").unwrap();
    assert_eq!(fog.as_deref(), Some("fog volume"));
}

#[test]
fn codecs_of_one_vec3_grid_decode_to_identical_leaves() {
    let dir = common::vec3_vdb_dir();
    let read = |f: &str| VdbFile::open(dir.join(f)).unwrap().read_vec3_grid("vel").unwrap();
    for family in [
        ["vec3_blosc.vdb", "vec3_zip.vdb", "vec3_none.vdb"],
        ["vec3_half_blosc.vdb", "vec3_half_zip.vdb", "vec3_half_zip.vdb"],
    ] {
        let reference = read(family[0]);
        for other in &family[1..] {
            let g = read(other);
            for c in 0..3 {
                let (a, b) = (g.component(c), reference.component(c));
                assert_eq!(a.leaf_count(), b.leaf_count(), "{other}");
                for (la, lb) in a.leaves().iter().zip(b.leaves()) {
                    assert_eq!(la.active, lb.active, "{other}");
                    for n in (0..512).filter(|&n| la.is_active(n)) {
                        assert_eq!(la.values[n].to_bits(), lb.values[n].to_bits(), "{other} {:?} {n}", la.origin);
                    }
                }
            }
        }
    }
    // Half storage rounds each component to the nearest half float.
    let full = read("vec3_blosc.vdb");
    let half = read("vec3_half_blosc.vdb");
    let v = full.value([-300, 200, -4100]);
    assert_eq!(half.value([-300, 200, -4100]), v.map(|c| half::f16::from_f32(c).to_f32()));
    assert_ne!(half.value([-300, 200, -4100])[0], 0.1f32);
}

#[test]
fn asking_for_the_wrong_value_type_names_file_grid_and_type() {
    let path = common::vec3_vdb_dir().join("mantaflow_fire.vdb");
    let file = VdbFile::open(&path).unwrap();
    let err = file.read_float_grid("vel").unwrap_err();
    let text = err.to_string();
    assert!(matches!(err, VolumeError::UnsupportedGridType { .. }), "{err:?}");
    assert!(
        text.contains("mantaflow_fire.vdb") && text.contains("\"vel\"") && text.contains("Tree_vec3s_5_4_3"),
        "{text}"
    );
    assert!(text.contains("expected a scalar"), "{text}");
    let err = file.read_vec3_grid("temperature").unwrap_err().to_string();
    assert!(
        err.contains("\"temperature\"") && err.contains("Tree_float_5_4_3") && err.contains("expected a Vec3"),
        "{err}"
    );
    let err = file.read_vec3_grid("Cd").unwrap_err().to_string();
    assert!(err.contains("no grid named \"Cd\"") && err.contains("velocity_guide"), "{err}");
}

#[test]
fn vec3_memory_limit_counts_all_three_components() {
    let file = VdbFile::open(common::vec3_vdb_dir().join("vec3_blosc.vdb")).unwrap();
    let g = file.read_vec3_grid("vel").unwrap();
    // One component's leaves alone take leaf_count * 2 KiB + 64 B masks.
    let one_component = g.leaf_count() as u64 * 2112;
    let err = file.read_vec3_grid_limited("vel", 2 * one_component).unwrap_err();
    assert!(matches!(err, VolumeError::TooLarge { .. }), "{err:?}");
}
