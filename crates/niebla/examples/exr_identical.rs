//! Compares the RGB pixels of two EXR images bit for bit (header attributes
//! are ignored). Prints the number of differing pixels and the largest
//! absolute difference; exits 1 when they differ, 2 when a file is unreadable.
//!
//! `cargo run --release -p niebla --example exr_identical -- A.exr B.exr`

use std::path::Path;
use std::process::ExitCode;

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [a, b] = args.as_slice() else {
        eprintln!("usage: exr_identical A.exr B.exr");
        return ExitCode::from(2);
    };
    let (ia, ib) = match (niebla::film::read_exr(Path::new(a)), niebla::film::read_exr(Path::new(b))) {
        (Ok(ia), Ok(ib)) => (ia.image, ib.image),
        (Err(e), _) | (_, Err(e)) => {
            eprintln!("error: {e}");
            return ExitCode::from(2);
        }
    };
    if (ia.width, ia.height) != (ib.width, ib.height) {
        println!("{a} vs {b}: sizes differ ({}x{} vs {}x{})", ia.width, ia.height, ib.width, ib.height);
        return ExitCode::from(1);
    }
    let mut differing = 0usize;
    let mut max_diff = 0f32;
    for (pa, pb) in ia.pixels.iter().zip(&ib.pixels) {
        let same = (0..3).all(|c| pa[c].to_bits() == pb[c].to_bits());
        if !same {
            differing += 1;
            for c in 0..3 {
                max_diff = max_diff.max((pa[c] - pb[c]).abs());
            }
        }
    }
    if differing == 0 {
        println!("identical  {b}");
        ExitCode::SUCCESS
    } else {
        println!("DIFFERENT  {b}: {differing} pixels, max |diff| {max_diff:e}");
        ExitCode::from(1)
    }
}
