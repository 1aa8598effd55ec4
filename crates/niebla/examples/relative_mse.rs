//! Relative MSE of EXR images against a reference EXR
//! ([`niebla::film::Image::relative_mse`]: the mean over pixels and channels
//! of `(x - r)^2 / (r^2 + (0.01 mean(r))^2)`). Prints one line per image;
//! exits 2 when a file is unreadable or of another size.
//!
//! `cargo run --release -p niebla --example relative_mse -- REFERENCE.exr A.exr [B.exr ...]`

use std::path::Path;
use std::process::ExitCode;

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let Some((reference, images)) = args.split_first().filter(|(_, rest)| !rest.is_empty()) else {
        eprintln!("usage: relative_mse REFERENCE.exr A.exr [B.exr ...]");
        return ExitCode::from(2);
    };
    let read = |p: &str| niebla::film::read_exr(Path::new(p)).map(|e| e.image);
    let reference = match read(reference) {
        Ok(r) => r,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::from(2);
        }
    };
    for path in images {
        match read(path) {
            Ok(image) if (image.width, image.height) == (reference.width, reference.height) => {
                println!("{:.6e}  {path}", image.relative_mse(&reference));
            }
            Ok(image) => {
                eprintln!(
                    "error: {path} is {}x{}, the reference {}x{}",
                    image.width, image.height, reference.width, reference.height
                );
                return ExitCode::from(2);
            }
            Err(e) => {
                eprintln!("error: {e}");
                return ExitCode::from(2);
            }
        }
    }
    ExitCode::SUCCESS
}
