//! Peak resident memory of reading a VDB's `density` grid, against the
//! grid's own size.
//!
//! Run: `cargo run --release -p niebla-volume --example vdb_load_memory -- FILE.vdb [GRID]`
//! (make a large file with `bench/make_big_vdb.py`). Linux only: reads
//! `VmHWM` (peak resident set) and `VmRSS` from `/proc/self/status`.

use std::time::Instant;

use niebla_volume::VdbFile;

/// A `/proc/self/status` field in bytes (`None` off Linux).
fn status_bytes(field: &str) -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with(field))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

fn mib(b: u64) -> f64 {
    b as f64 / (1u64 << 20) as f64
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let Some(path) = args.get(1) else {
        eprintln!("usage: vdb_load_memory FILE.vdb [GRID]");
        std::process::exit(2);
    };
    let name = args.get(2).map(String::as_str).unwrap_or("density");
    let file_bytes = std::fs::metadata(path).map(|m| m.len()).unwrap_or(0);
    let before = status_bytes("VmRSS:").unwrap_or(0);
    let start = Instant::now();
    let grid = match VdbFile::open(path).and_then(|f| f.read_float_grid(name)) {
        Ok(g) => g,
        Err(e) => {
            eprintln!("{e}");
            std::process::exit(1);
        }
    };
    let secs = start.elapsed().as_secs_f64();
    let peak = status_bytes("VmHWM:").unwrap_or(0);
    let after = status_bytes("VmRSS:").unwrap_or(0);
    let (memory, payload) = (grid.memory_bytes(), grid.payload_bytes());
    println!("file                 {path} ({:.1} MiB on disk)", mib(file_bytes));
    println!(
        "grid                 {:?}: {} leaves, {} tiles, read in {secs:.2} s",
        name,
        grid.leaf_count(),
        grid.tiles().len()
    );
    println!(
        "grid memory          {:.1} MiB (payload: leaves + tiles {:.1} MiB, ratio {:.3})",
        mib(memory),
        mib(payload),
        memory as f64 / payload as f64
    );
    println!("RSS before reading   {:.1} MiB", mib(before));
    println!("RSS after reading    {:.1} MiB", mib(after));
    println!("peak RSS (VmHWM)     {:.1} MiB", mib(peak));
    println!(
        "peak above start     {:.1} MiB = {:.3} x grid memory",
        mib(peak.saturating_sub(before)),
        peak.saturating_sub(before) as f64 / memory as f64
    );
}
