//! Mitsuba `.vol` and NumPy `.npy` files, written here by small writers,
//! read back with the documented axis order (a single bright voxel lands
//! where expected), and damaged files give errors.

use std::path::{Path, PathBuf};

use niebla_volume::{read_npy, read_vol, DenseVolume, VolumeError};

fn tmp(name: &str) -> PathBuf {
    Path::new(env!("CARGO_TARGET_TMPDIR")).join(name)
}

/// A Mitsuba VOL v3 float32 file; `values` indexed `((z*ny + y)*nx + x)*c + ch`.
fn vol_bytes(dims: [usize; 3], channels: usize, bbox: [f32; 6], values: &[f32]) -> Vec<u8> {
    let mut out = b"VOL\x03".to_vec();
    out.extend(1i32.to_le_bytes());
    for n in dims {
        out.extend((n as i32).to_le_bytes());
    }
    out.extend((channels as i32).to_le_bytes());
    for v in bbox {
        out.extend(v.to_le_bytes());
    }
    for v in values {
        out.extend(v.to_le_bytes());
    }
    out
}

/// A version 1 `.npy` file of the given dtype and shape.
fn npy_bytes(descr: &str, shape: &[usize], fortran: bool, data: &[u8]) -> Vec<u8> {
    let shape_text = shape.iter().map(|n| format!("{n}, ")).collect::<String>();
    let shape_text = if shape.len() == 1 { shape_text } else { shape_text.trim_end_matches(", ").to_string() };
    let mut header = format!(
        "{{'descr': '{descr}', 'fortran_order': {}, 'shape': ({shape_text}), }}",
        if fortran { "True" } else { "False" }
    );
    while (10 + header.len() + 1) % 64 != 0 {
        header.push(' ');
    }
    header.push('\n');
    let mut out = b"\x93NUMPY\x01\x00".to_vec();
    out.extend((header.len() as u16).to_le_bytes());
    out.extend(header.as_bytes());
    out.extend(data);
    out
}

fn f32_bytes(v: &[f32]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_le_bytes()).collect()
}

const DIMS: [usize; 3] = [5, 4, 3]; // nx, ny, nz
const BRIGHT: [usize; 3] = [3, 1, 2]; // x, y, z

fn bright_values(channels: usize) -> Vec<f32> {
    let mut v = vec![0.0; DIMS[0] * DIMS[1] * DIMS[2] * channels];
    let i = (BRIGHT[2] * DIMS[1] + BRIGHT[1]) * DIMS[0] + BRIGHT[0];
    for c in 0..channels {
        v[i * channels + c] = 10.0 + c as f32;
    }
    v
}

/// Local-space center of voxel `BRIGHT` in the box `lo..hi`.
fn bright_center(lo: [f32; 3], hi: [f32; 3]) -> [f32; 3] {
    std::array::from_fn(|a| lo[a] + (BRIGHT[a] as f32 + 0.5) * (hi[a] - lo[a]) / DIMS[a] as f32)
}

#[test]
fn vol_scalar_bright_voxel_lands_at_x_y_z() {
    let path = tmp("bright.vol");
    let bbox = [-1.0, 0.0, 2.0, 4.0, 8.0, 5.0];
    std::fs::write(&path, vol_bytes(DIMS, 1, bbox, &bright_values(1))).unwrap();
    let g = read_vol(&path).unwrap().into_scalar().unwrap();
    assert_eq!(g.dims(), DIMS);
    assert_eq!(g.bounds(), ([-1.0, 0.0, 2.0], [4.0, 8.0, 5.0]));
    assert_eq!(g.voxel(BRIGHT[0], BRIGHT[1], BRIGHT[2]), 10.0);
    assert_eq!(g.lookup(bright_center([-1.0, 0.0, 2.0], [4.0, 8.0, 5.0])), 10.0);
    assert_eq!(g.max_value(), 10.0);
    // The transposed position holds nothing.
    assert_eq!(g.voxel(2, 1, 0), 0.0);
}

#[test]
fn vol_rgb_channels_are_interleaved_per_voxel() {
    let path = tmp("bright_rgb.vol");
    std::fs::write(&path, vol_bytes(DIMS, 3, [0.0, 0.0, 0.0, 1.0, 1.0, 1.0], &bright_values(3))).unwrap();
    let DenseVolume::Rgb(g) = read_vol(&path).unwrap() else { panic!("expected RGB") };
    assert_eq!(g.voxel(BRIGHT[0], BRIGHT[1], BRIGHT[2]), [10.0, 11.0, 12.0]);
    assert_eq!(g.lookup(bright_center([0.0; 3], [1.0; 3])), [10.0, 11.0, 12.0]);
    assert_eq!(g.max_value(), [10.0, 11.0, 12.0]);
}

#[test]
fn npy_shape_nz_ny_nx_is_indexed_z_y_x() {
    let path = tmp("bright.npy");
    let shape = [DIMS[2], DIMS[1], DIMS[0]];
    std::fs::write(&path, npy_bytes("<f4", &shape, false, &f32_bytes(&bright_values(1)))).unwrap();
    let g = read_npy(&path).unwrap().into_scalar().unwrap();
    assert_eq!(g.dims(), DIMS);
    assert_eq!(g.bounds(), ([0.0; 3], [1.0; 3]));
    assert_eq!(g.voxel(BRIGHT[0], BRIGHT[1], BRIGHT[2]), 10.0);
    let g = g.with_bounds([0.0; 3], [5.0, 4.0, 3.0]).unwrap();
    assert_eq!(g.lookup([3.5, 1.5, 2.5]), 10.0);
    assert_eq!(g.lookup([3.5, 2.5, 1.5]), 0.0);
}

#[test]
fn npy_float64_and_rgb_arrays() {
    let path = tmp("bright64.npy");
    let values: Vec<u8> = bright_values(1).iter().flat_map(|&v| (v as f64).to_le_bytes()).collect();
    std::fs::write(&path, npy_bytes("<f8", &[DIMS[2], DIMS[1], DIMS[0]], false, &values)).unwrap();
    let g = read_npy(&path).unwrap().into_scalar().unwrap();
    assert_eq!(g.voxel(BRIGHT[0], BRIGHT[1], BRIGHT[2]), 10.0);

    let path = tmp("bright_rgb.npy");
    std::fs::write(&path, npy_bytes("<f4", &[DIMS[2], DIMS[1], DIMS[0], 3], false, &f32_bytes(&bright_values(3))))
        .unwrap();
    let DenseVolume::Rgb(g) = read_npy(&path).unwrap() else { panic!("expected RGB") };
    assert_eq!(g.voxel(BRIGHT[0], BRIGHT[1], BRIGHT[2]), [10.0, 11.0, 12.0]);
}

#[test]
fn truncated_and_garbage_dense_files_are_errors() {
    let vol = vol_bytes(DIMS, 1, [0.0, 0.0, 0.0, 1.0, 1.0, 1.0], &bright_values(1));
    let npy = npy_bytes("<f4", &[DIMS[2], DIMS[1], DIMS[0]], false, &f32_bytes(&bright_values(1)));
    for n in 0..vol.len() {
        let path = tmp("cut.vol");
        std::fs::write(&path, &vol[..n]).unwrap();
        let err = read_vol(&path).unwrap_err();
        assert!(err.to_string().contains("cut.vol"), "{err}");
    }
    for n in 0..npy.len() {
        let path = tmp("cut.npy");
        std::fs::write(&path, &npy[..n]).unwrap();
        assert!(read_npy(&path).is_err(), "npy cut at {n}");
    }
    let garbage = tmp("garbage.bin");
    std::fs::write(&garbage, b"\x00\x01garbage that is no volume at all").unwrap();
    assert!(matches!(read_vol(&garbage), Err(VolumeError::WrongFormat { .. })));
    assert!(matches!(read_npy(&garbage), Err(VolumeError::WrongFormat { .. })));
    // A VOL header claiming 2^31-1 voxels per axis is a truncation error, not an allocation.
    let mut huge = vol.clone();
    huge[8..12].copy_from_slice(&i32::MAX.to_le_bytes());
    std::fs::write(&garbage, &huge).unwrap();
    assert!(matches!(read_vol(&garbage), Err(VolumeError::Truncated { .. })));
}

#[test]
fn unsupported_dense_layouts_are_errors() {
    let values = f32_bytes(&bright_values(1));
    let cases = [
        ("fortran.npy", npy_bytes("<f4", &[3, 4, 5], true, &values)),
        ("int.npy", npy_bytes("<i4", &[3, 4, 5], false, &values)),
        ("bigendian.npy", npy_bytes(">f4", &[3, 4, 5], false, &values)),
        ("2d.npy", npy_bytes("<f4", &[12, 5], false, &values)),
        ("rgba.npy", npy_bytes("<f4", &[1, 3, 5, 4], false, &values)),
    ];
    for (name, bytes) in cases {
        let path = tmp(name);
        std::fs::write(&path, bytes).unwrap();
        let err = read_npy(&path).unwrap_err();
        assert!(matches!(err, VolumeError::Unsupported { .. }), "{name}: {err:?}");
    }
    let mut two_channels = vol_bytes(DIMS, 2, [0.0, 0.0, 0.0, 1.0, 1.0, 1.0], &bright_values(2));
    let path = tmp("two_channels.vol");
    std::fs::write(&path, &two_channels).unwrap();
    assert!(matches!(read_vol(&path), Err(VolumeError::Unsupported { .. })));
    two_channels[3] = 2; // version 2
    std::fs::write(&path, &two_channels).unwrap();
    assert!(matches!(read_vol(&path), Err(VolumeError::Unsupported { .. })));
}
