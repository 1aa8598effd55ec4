//! OpenVDB reader: parse the header and descriptors, then decode every grid
//! (scalar grids into sparse grids, Vec3 grids into sparse vector grids;
//! other types must give an error), and read each grid's class metadata.
#![no_main]

use libfuzzer_sys::fuzz_target;
use niebla_volume::VdbFile;

/// Memory a fuzzed tree may take (the reader refuses more).
const MAX_GRID_BYTES: u64 = 256 << 20;

fuzz_target!(|data: &[u8]| {
    let Ok(file) = VdbFile::from_bytes(data.to_vec(), "fuzz.vdb") else { return };
    let names: Vec<String> = file.grids().iter().map(|g| g.unique_name.clone()).collect();
    for name in names {
        if let Ok(grid) = file.read_float_grid_limited(&name, MAX_GRID_BYTES) {
            // Touch what a renderer would: bounds and a lookup.
            let _ = grid.lookup_world([0.0, 0.0, 0.0]);
        }
        if let Ok(grid) = file.read_vec3_grid_limited(&name, MAX_GRID_BYTES) {
            let _ = grid.lookup_world([0.0, 0.0, 0.0]);
            let _ = grid.active_length_range();
        }
        let _ = file.grid_string_metadata(&name, "class");
    }
});
