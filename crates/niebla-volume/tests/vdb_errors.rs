//! Damaged, foreign and unsupported input gives a `VolumeError` naming the
//! file and the problem, never a panic or an unbounded allocation.

mod common;

use std::path::Path;

use common::Rng;
use niebla_volume::{VdbFile, VolumeError};

fn bytes(name: &str) -> Vec<u8> {
    std::fs::read(common::vdb_dir().join(name)).unwrap()
}

/// Reads every grid of a file held in memory; `Ok` only if all succeed.
fn read_all(data: Vec<u8>) -> Result<usize, VolumeError> {
    let file = VdbFile::from_bytes(data, "damaged.vdb")?;
    let names: Vec<String> = file.grids().iter().map(|g| g.unique_name.clone()).collect();
    let mut n = 0;
    for name in names {
        match file.read_float_grid(&name) {
            Ok(g) => n += g.leaf_count(),
            Err(VolumeError::UnsupportedGridType { .. }) => {}
            Err(e) => return Err(e),
        }
    }
    Ok(n)
}

#[test]
fn missing_grid_name_lists_the_available_grids() {
    let path = common::vdb_dir().join("multi_density_temperature.vdb");
    let file = VdbFile::open(&path).unwrap();
    let err = file.read_float_grid("flame").unwrap_err();
    let message = err.to_string();
    match err {
        VolumeError::GridNotFound { name, available, path: p } => {
            assert_eq!(name, "flame");
            assert_eq!(available, ["density", "temperature"]);
            assert_eq!(p, path);
        }
        e => panic!("expected GridNotFound, got {e:?}"),
    }
    assert!(message.contains("flame") && message.contains("temperature"), "{message}");
    // Both real grids read.
    assert_eq!(file.read_float_grid("temperature").unwrap().active_voxel_count(), 4);
}

#[test]
fn vector_and_bool_grids_are_type_errors_naming_grid_and_type() {
    for (file, grid, ty) in [
        ("vel_vec3f.vdb", "vel", "Tree_vec3s_5_4_3"),
        ("vel_vec3f_half.vdb", "vel", "Tree_vec3s_5_4_3_HalfFloat"),
        ("smoke_density_vel_zip.vdb", "vel", "Tree_vec3s_5_4_3"),
        ("density_and_boolmask.vdb", "mask", "Tree_bool_5_4_3"),
    ] {
        let f = VdbFile::open(common::vdb_dir().join(file)).unwrap();
        let err = f.read_float_grid(grid).unwrap_err();
        let message = err.to_string();
        assert!(matches!(err, VolumeError::UnsupportedGridType { .. }), "{file}: {err:?}");
        assert!(message.contains(grid) && message.contains(ty) && message.contains(file), "{message}");
    }
}

#[test]
fn non_vdb_and_missing_files_are_errors() {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"));
    let text = dir.join("not_a_vdb.vdb");
    std::fs::write(&text, "this is a text file, not a volume\n").unwrap();
    assert!(matches!(VdbFile::open(&text), Err(VolumeError::WrongFormat { .. })));
    assert!(matches!(VdbFile::from_bytes(Vec::new(), "empty.vdb"), Err(VolumeError::WrongFormat { .. })));
    let err = VdbFile::open(dir.join("no_such_file.vdb")).unwrap_err();
    assert!(matches!(err, VolumeError::Io { .. }));
    assert!(err.to_string().contains("no_such_file.vdb"));
}

#[test]
fn truncated_files_are_errors_at_every_offset() {
    for name in ["density_blosc.vdb", "multi_density_temperature.vdb", "density_half_zip.vdb", "tiles_root.vdb"] {
        let data = bytes(name);
        let mut offsets: Vec<usize> = (0..data.len().min(1500)).collect();
        offsets.extend((1500..data.len()).step_by(97));
        offsets.extend(data.len().saturating_sub(64)..data.len());
        for n in offsets {
            let result = read_all(data[..n].to_vec());
            assert!(result.is_err(), "{name} cut at {n} of {} read fine", data.len());
        }
    }
}

/// Replaces the last grid's end offset in the descriptor (the i64 equal to
/// the file length), so that a cut file fails inside the tree reader rather
/// than at the descriptor check.
fn cut_inside_last_grid(data: &[u8], n: usize) -> Vec<u8> {
    let needle = (data.len() as i64).to_le_bytes();
    let at = data.windows(8).rposition(|w| w == needle).expect("end offset in the header");
    let mut out = data[..n].to_vec();
    if at + 8 <= n {
        out[at..at + 8].copy_from_slice(&(n as i64).to_le_bytes());
    }
    out
}

#[test]
fn grids_cut_short_are_errors_inside_the_tree_reader() {
    for name in [
        "density_blosc.vdb",
        "density_zip.vdb",
        "density_none.vdb",
        "density_half_active.vdb",
        "tiles_internal.vdb",
        "inactive_values.vdb",
        "levelset_sphere.vdb",
        "xform_affine_rotated.vdb",
    ] {
        let data = bytes(name);
        let step = (data.len() / 3000).max(1);
        let mut tested = 0;
        for n in (200..data.len()).step_by(step).chain(data.len() - 40..data.len()) {
            let cut = cut_inside_last_grid(&data, n);
            if let Ok(leaves) = read_all(cut) {
                panic!("{name} cut at {n} of {} read {leaves} leaves without error", data.len());
            }
            tested += 1;
        }
        assert!(tested > 100, "{name}: {tested} cuts");
    }
}

#[test]
fn corrupted_bytes_never_panic() {
    let mut rng = Rng::new(7);
    for name in ["density_blosc.vdb", "density_zip.vdb", "density_half_none.vdb", "tiles_internal.vdb"] {
        let data = bytes(name);
        let (mut ok, mut err) = (0, 0);
        for _ in 0..600 {
            let mut d = data.clone();
            for _ in 0..1 + rng.below(4) {
                let at = rng.below(d.len());
                d[at] = rng.next_u64() as u8;
            }
            match read_all(d) {
                Ok(_) => ok += 1,
                Err(e) => {
                    assert!(e.to_string().contains("damaged.vdb"), "{e}");
                    err += 1;
                }
            }
        }
        assert_eq!(ok + err, 600, "{name}");
    }
}

#[test]
fn huge_sizes_in_the_file_are_rejected_before_allocating() {
    // A file metadata entry whose name claims 4 GiB.
    let mut data = bytes("density_blosc.vdb");
    let header_end = 8 + 4 + 8 + 1 + 36;
    data.truncate(header_end);
    data.extend(1u32.to_le_bytes());
    data.extend(u32::MAX.to_le_bytes());
    data.extend([b'x'; 64]);
    let err = VdbFile::from_bytes(data, "huge.vdb").unwrap_err();
    assert!(matches!(err, VolumeError::Truncated { .. }), "{err:?}");
}
