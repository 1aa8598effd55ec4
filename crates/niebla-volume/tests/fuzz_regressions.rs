//! Inputs the fuzz targets (`fuzz/`, cargo-fuzz) found or that guard what
//! they check, kept as regression tests on the stable toolchain: every file
//! in `tests/fuzz_regressions/{vdb,vol,npy}/` is read without a panic, a
//! hang or an unbounded allocation (an `Ok` or a `VolumeError` are both
//! fine). Add a crashing input by copying it there from
//! `fuzz/artifacts/<target>/`.

mod common;

use std::path::{Path, PathBuf};

use niebla_volume::{parse_npy, parse_vol, VdbFile, VolumeError};

/// The memory a fuzzed VDB tree may take (as in `fuzz/fuzz_targets/vdb.rs`).
const MAX_GRID_BYTES: u64 = 256 << 20;

fn inputs(kind: &str) -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fuzz_regressions").join(kind);
    if !dir.exists() {
        // git keeps no empty folder: no regression input of this kind yet.
        return Vec::new();
    }
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.unwrap().path())
        .filter(|p| p.is_file() && p.file_name().is_some_and(|n| n != "README.md"))
        .collect();
    files.sort();
    files
}

/// What the fuzz target does: open, then decode every grid.
fn read_every_grid(data: Vec<u8>, name: &Path) -> Result<usize, VolumeError> {
    let file = VdbFile::from_bytes(data, name)?;
    let names: Vec<String> = file.grids().iter().map(|g| g.unique_name.clone()).collect();
    let mut leaves = 0;
    for grid in names {
        match file.read_float_grid_limited(&grid, MAX_GRID_BYTES) {
            Ok(g) => leaves += g.leaf_count(),
            Err(VolumeError::Io { .. }) => panic!("in-memory read gave an I/O error"),
            Err(_) => {}
        }
        match file.read_vec3_grid_limited(&grid, MAX_GRID_BYTES) {
            Ok(g) => leaves += g.leaf_count(),
            Err(VolumeError::Io { .. }) => panic!("in-memory read gave an I/O error"),
            Err(_) => {}
        }
        let _ = file.grid_string_metadata(&grid, "class");
    }
    Ok(leaves)
}

#[test]
fn corrupted_vec3_files_give_errors_not_panics() {
    // Byte flips and truncations of a reference-library Vec3 file (blosc
    // and zip), each read in full: any Ok or VolumeError is fine.
    let dir = common::vec3_vdb_dir();
    let mut rng = common::Rng::new(17);
    for name in ["vec3_blosc.vdb", "vec3_half_zip.vdb", "mantaflow_fire.vdb"] {
        let original = std::fs::read(dir.join(name)).unwrap();
        for i in 0..150 {
            let mut data = original.clone();
            if i % 3 == 0 {
                data.truncate(rng.below(original.len()));
            } else {
                let at = rng.below(original.len());
                data[at] ^= 1 << rng.below(8);
            }
            let _ = read_every_grid(data, Path::new(name));
        }
    }
}

#[test]
fn fuzzed_vdb_inputs_give_errors_not_panics() {
    for path in inputs("vdb") {
        let _ = read_every_grid(std::fs::read(&path).unwrap(), &path);
    }
}

#[test]
fn fuzzed_vol_inputs_give_errors_not_panics() {
    for path in inputs("vol") {
        let _ = parse_vol(&std::fs::read(&path).unwrap(), &path);
    }
}

#[test]
fn fuzzed_npy_inputs_give_errors_not_panics() {
    for path in inputs("npy") {
        let _ = parse_npy(&std::fs::read(&path).unwrap(), &path);
    }
}

#[test]
fn vdb_whose_declared_grid_end_exceeds_the_file_is_refused() {
    let mut data = std::fs::read(common::vdb_dir().join("density_none.vdb")).unwrap();
    let len = data.len() as u64;
    // The descriptor's end offset of the (only) grid is the file length.
    let at = data.windows(8).rposition(|w| w == len.to_le_bytes()).expect("end offset in the header");
    data[at..at + 8].copy_from_slice(&(len + 4096).to_le_bytes());
    let err = VdbFile::from_bytes(data, "long.vdb").unwrap_err();
    assert!(matches!(err, VolumeError::Truncated { .. }), "{err:?}");
    assert!(err.to_string().contains(&format!("should end at byte {}", len + 4096)), "{err}");
}

#[test]
fn vdb_tree_over_the_memory_limit_is_refused_before_allocating_it() {
    let file = VdbFile::open(common::vdb_dir().join("density_none.vdb")).unwrap();
    let whole = file.read_float_grid("density").unwrap();
    assert!(whole.leaf_count() > 4);
    let err = file.read_float_grid_limited("density", 64 << 10).unwrap_err();
    let VolumeError::TooLarge { what, bytes, limit, .. } = &err else { panic!("{err:?}") };
    assert_eq!(*limit, 64 << 10);
    assert!(*bytes > *limit && *bytes < *limit + (160 << 10), "{bytes}");
    assert!(what.starts_with("grid \"density\""), "{what}");
    assert!(err.to_string().ends_with("over the memory limit of 64 KiB"), "{err}");
    // Enough memory: the same grid.
    let limited = file.read_float_grid_limited("density", 1 << 30).unwrap();
    assert_eq!(limited.leaf_count(), whole.leaf_count());
}

#[test]
fn dense_files_declaring_more_values_than_they_hold_are_refused() {
    // A .vol header claiming 2^31-1 cubed voxels, and a .npy claiming a
    // 2^20 x 2^20 x 2^20 float64 array, each followed by 8 bytes.
    let mut vol = b"VOL\x03".to_vec();
    for v in [1i32, i32::MAX, i32::MAX, i32::MAX, 1] {
        vol.extend(v.to_le_bytes());
    }
    vol.extend([0u8; 24 + 8]);
    let err = parse_vol(&vol, Path::new("huge.vol")).unwrap_err();
    assert!(matches!(err, VolumeError::Truncated { .. }), "{err:?}");

    let header = b"{'descr': '<f8', 'fortran_order': False, 'shape': (1048576, 1048576, 1048576), }\n";
    let mut npy = b"\x93NUMPY\x01\x00".to_vec();
    npy.extend((header.len() as u16).to_le_bytes());
    npy.extend(header);
    npy.extend([0u8; 8]);
    let err = parse_npy(&npy, Path::new("huge.npy")).unwrap_err();
    assert!(matches!(err, VolumeError::Truncated { .. }), "{err:?}");
    // A shape whose byte count overflows u64.
    let header = b"{'descr': '<f8', 'fortran_order': False, 'shape': (4294967296, 4294967296, 4294967296), }\n";
    let mut npy = b"\x93NUMPY\x01\x00".to_vec();
    npy.extend((header.len() as u16).to_le_bytes());
    npy.extend(header);
    assert!(parse_npy(&npy, Path::new("overflow.npy")).is_err());
}

/// Not a regression test: sorts a fuzz corpus of VDB, .vol or .npy inputs
/// by the reader's verdict (for the fuzzing report). Run with
/// `NIEBLA_FUZZ_CORPUS=fuzz/corpus/vdb cargo test -p niebla-volume --test fuzz_regressions -- --ignored --nocapture`
/// (the folder's last name picks the reader).
#[test]
#[ignore]
fn classify_corpus() {
    let Ok(dir) = std::env::var("NIEBLA_FUZZ_CORPUS") else { return };
    let kind = Path::new(&dir).file_name().unwrap().to_string_lossy().into_owned();
    let mut counts = std::collections::BTreeMap::<String, usize>::new();
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        let data = std::fs::read(&path).unwrap();
        let verdict = match kind.as_str() {
            "vdb" => VdbFile::from_bytes(data, &path).and_then(|file| {
                let names: Vec<String> = file.grids().iter().map(|g| g.unique_name.clone()).collect();
                names.iter().try_for_each(|n| file.read_float_grid_limited(n, MAX_GRID_BYTES).map(|_| ()))
            }),
            "vol" => parse_vol(&data, &path).map(|_| ()),
            _ => parse_npy(&data, &path).map(|_| ()),
        };
        let class = match verdict {
            Ok(()) => "read (Ok)".to_string(),
            Err(e) => format!("{:?}", e).split([' ', '{', '(']).next().unwrap().to_string(),
        };
        *counts.entry(class).or_default() += 1;
    }
    println!("{dir}: {counts:#?}");
}
