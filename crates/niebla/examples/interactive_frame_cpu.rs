//! CPU seconds per frame of the interactive integrators (`hegeman`, `zhou`,
//! each with the scene file's settings or the defaults) at 256x256 and 1 spp,
//! as `niebla bench interactive` times its frames (precomputation
//! excluded), and a hash of the frames' bits: two builds that print the same
//! hash rendered the same images.
//!
//! `cargo run --release -p niebla --example interactive_frame_cpu -- [--frames N] [--threads T] [--only hegeman|zhou] SCENE...`
//!
//! CPU time is the process's user + system time (`/proc/self/stat`, clock
//! ticks of 10 ms), so it is meaningful on a loaded machine where wall time
//! is not; with `--threads 1` it is the time of one core per frame.

use std::path::Path;
use std::process::ExitCode;

use niebla::film::Image;
use niebla::integrator::{
    HegemanIntegrator, HegemanSettings, Integrator, IntegratorSettings, ZhouIntegrator, ZhouSettings,
};
use niebla::render::{render_with, RenderOptions};
use niebla::world::Scene;

/// User + system CPU seconds of this process so far.
fn cpu_seconds() -> f64 {
    let stat = std::fs::read_to_string("/proc/self/stat").expect("/proc/self/stat");
    // Fields after the command name (which may hold spaces) start at its closing parenthesis.
    let rest = &stat[stat.rfind(')').expect("a command name") + 2..];
    let fields: Vec<&str> = rest.split_whitespace().collect();
    // utime and stime are fields 14 and 15 of the whole line, 12 and 13 here.
    let ticks: f64 = fields[11].parse::<f64>().unwrap() + fields[12].parse::<f64>().unwrap();
    ticks / 100.0
}

/// FNV-1a over the bits of every pixel, chained into `hash`.
fn hash_image(mut hash: u64, image: &Image) -> u64 {
    for p in &image.pixels {
        for c in 0..3 {
            for b in p[c].to_bits().to_le_bytes() {
                hash = (hash ^ b as u64).wrapping_mul(0x100_0000_01b3);
            }
        }
    }
    hash
}

/// CPU seconds per frame and the frames' hash.
fn time_frames<I: Integrator>(scene: &Scene, integrator: &I, frames: u32, threads: usize) -> (f64, u64) {
    let mut hash = 0xcbf2_9ce4_8422_2325u64;
    let start = cpu_seconds();
    for k in 0..frames {
        let options = RenderOptions {
            spp: 1,
            seed: k as u64,
            first_sample: 0,
            threads: Some(threads),
            sampler: Default::default(),
        };
        let image = render_with(scene, integrator, &options, &|_, _| {}, None).expect("render without cancel flag");
        hash = hash_image(hash, &image);
    }
    ((cpu_seconds() - start) / frames as f64, hash)
}

fn main() -> ExitCode {
    let mut frames = 10u32;
    let mut threads = 1usize;
    let mut only: Option<String> = None;
    let mut scenes = Vec::new();
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--frames" => frames = args.next().and_then(|s| s.parse().ok()).unwrap_or(frames),
            "--threads" => threads = args.next().and_then(|s| s.parse().ok()).unwrap_or(threads),
            "--only" => only = args.next(),
            _ => scenes.push(a),
        }
    }
    if scenes.is_empty() {
        eprintln!("usage: interactive_frame_cpu [--frames N] [--threads T] [--only hegeman|zhou] SCENE...");
        return ExitCode::from(2);
    }
    for path in &scenes {
        let built = match niebla::scene::load_scene(Path::new(path)) {
            Ok(b) => b,
            Err(e) => {
                eprintln!("error: {e}");
                return ExitCode::from(2);
            }
        };
        let mut scene = built.scene;
        scene.camera.width = 256;
        scene.camera.height = 256;
        let hegeman_settings = match built.settings.integrator {
            IntegratorSettings::Hegeman(h) => h,
            _ => HegemanSettings::default(),
        };
        let zhou_settings = match built.settings.integrator {
            IntegratorSettings::Zhou(z) => z,
            _ => ZhouSettings::default(),
        };
        if matches!(only.as_deref(), None | Some("hegeman")) {
            let hegeman = HegemanIntegrator::new(&scene, hegeman_settings);
            let (cpu, hash) = time_frames(&scene, &hegeman, frames, threads);
            println!("{path} hegeman: {cpu:.4} CPU s/frame ({frames} frames, {threads} threads), hash {hash:016x}");
        }
        if matches!(only.as_deref(), None | Some("zhou")) {
            let zhou = ZhouIntegrator::new(&scene, zhou_settings);
            let (cpu, hash) = time_frames(&scene, &zhou, frames, threads);
            println!("{path} zhou:    {cpu:.4} CPU s/frame ({frames} frames, {threads} threads), hash {hash:016x}");
        }
    }
    ExitCode::SUCCESS
}
