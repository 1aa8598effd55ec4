//! `niebla bench photons`: figures, not tests. On each scene: photons traced
//! per second, kd-tree gather queries per second (fixed radius and k
//! nearest), and the time `photon`, `ppm` and `volpath` take to reach a
//! relative MSE of 1e-2 against a high-spp `volpath` reference (renders at
//! doubling sample or pass counts, log-log interpolation between the two
//! bracketing renders, as `niebla bench single` does).

use std::collections::BinaryHeap;
use std::path::PathBuf;
use std::time::Instant;

use clap::Args;

use crate::bench::time_to_reach;
use niebla::film::Image;
use niebla::integrator::photon::{
    auto_radius, photon_stream, trace_photons, PhotonSettings, PhotonTree, PpmSettings, TraceSettings, VolumeQuery,
};
use niebla::integrator::IntegratorSettings;
use niebla::render::{render, RenderOptions};
use niebla::scene::Scene;

/// Options of `niebla bench photons`.
#[derive(Args, Debug)]
pub struct PhotonBenchArgs {
    /// Scenes to measure (default: scenes/caustic_fog_area.json and
    /// scenes/cloud_photons.json).
    pub scenes: Vec<PathBuf>,
    /// Image width used for the renders (height keeps the aspect ratio).
    #[arg(long, default_value_t = 64)]
    pub width: u32,
    /// Samples per pixel of the `volpath` reference.
    #[arg(long, default_value_t = 4096)]
    pub reference_spp: u32,
    /// Largest sample (pass) count tried per integrator.
    #[arg(long, default_value_t = 1024)]
    pub max_spp: u32,
    /// Photons per `ppm` pass.
    #[arg(long, default_value_t = 20_000)]
    pub ppm_photons: u32,
    /// Photons of the `photon` integrator's map.
    #[arg(long, default_value_t = 200_000)]
    pub photons: u32,
    /// Target relative MSE.
    #[arg(long, default_value_t = 1e-2)]
    pub target: f64,
    /// Worker threads of the renders (default: all cores; the tracing
    /// figure always uses all cores).
    #[arg(long)]
    pub threads: Option<usize>,
}

fn timed(
    scene: &Scene,
    settings: &IntegratorSettings,
    spp: u32,
    threads: Option<usize>,
) -> Result<(Image, f64), String> {
    let options = RenderOptions { spp, seed: 7, first_sample: 0, threads };
    let start = Instant::now();
    let image = render(scene, settings, &options, &|_, _| {}, None).map_err(|e| e.to_string())?;
    Ok((image, start.elapsed().as_secs_f64()))
}

/// `niebla bench photons`.
pub fn run(args: &PhotonBenchArgs) -> Result<(), String> {
    let scenes = if args.scenes.is_empty() {
        vec![PathBuf::from("scenes/caustic_fog_area.json"), PathBuf::from("scenes/cloud_photons.json")]
    } else {
        args.scenes.clone()
    };
    for path in &scenes {
        let (built, _) = crate::render_cmd::load(Some(path))?;
        let mut scene = built.scene;
        let aspect = scene.camera.height as f64 / scene.camera.width as f64;
        scene.camera.width = args.width.clamp(1, 16384);
        scene.camera.height = ((scene.camera.width as f64 * aspect).round() as u32).max(1);
        println!("== {} ({}x{} pixels)", path.display(), scene.camera.width, scene.camera.height);
        tracing_and_queries(&scene, args.photons);
        convergence(&scene, args)?;
    }
    Ok(())
}

/// Photons traced per second and gather queries per second on one map.
fn tracing_and_queries(scene: &Scene, photons: u32) {
    let settings = TraceSettings { photons: photons as u64, max_depth: 1024, store_direct: false };
    let start = Instant::now();
    let traced = trace_photons(scene, &settings, photon_stream(1, 0));
    let trace_s = start.elapsed().as_secs_f64();
    let stored = traced.volume.len() + traced.surface.len();
    let start = Instant::now();
    let tree = PhotonTree::build(traced.volume);
    let build_s = start.elapsed().as_secs_f64();
    println!(
        "tracing: {photons} photons in {trace_s:.3} s = {:.3e} photons/s ({stored} stored, {:.3e} stored/s); \
         kd-tree build {build_s:.3} s",
        photons as f64 / trace_s,
        stored as f64 / trace_s
    );
    if tree.is_empty() {
        println!("queries: no volume photons");
        return;
    }
    // Queries at stored photons' positions (where estimates are asked for).
    let radius = auto_radius(&tree, true);
    let points: Vec<_> = tree.photons().iter().step_by((tree.len() / 20_000).max(1)).map(|p| p.p).collect();
    let start = Instant::now();
    let mut found = 0usize;
    for &x in &points {
        tree.for_each_within(x, radius * radius, |_, _| found += 1);
    }
    let radius_s = start.elapsed().as_secs_f64();
    let mut heap = BinaryHeap::new();
    let start = Instant::now();
    for &x in &points {
        tree.nearest(x, 50, f32::INFINITY, |_| true, &mut heap);
    }
    let knn_s = start.elapsed().as_secs_f64();
    println!(
        "queries (one thread, {} volume photons): radius {radius:.4} ({:.1} photons each) {:.3e}/s; 50 nearest {:.3e}/s",
        tree.len(),
        found as f64 / points.len() as f64,
        points.len() as f64 / radius_s,
        points.len() as f64 / knn_s
    );
}

/// Time of `photon`, `ppm` (point and beam queries) and `volpath` to the target error.
fn convergence(scene: &Scene, args: &PhotonBenchArgs) -> Result<(), String> {
    let volpath = IntegratorSettings::VolPath { max_depth: IntegratorSettings::DEFAULT_MAX_DEPTH };
    let (reference, seconds) = timed(scene, &volpath, args.reference_spp, args.threads)?;
    println!("reference: volpath {} spp in {seconds:.1} s", args.reference_spp);
    let ppm = |query| {
        IntegratorSettings::Ppm(PpmSettings {
            photon: PhotonSettings { photons: args.ppm_photons, query, ..PhotonSettings::ppm() },
            ..PpmSettings::default()
        })
    };
    let photon = IntegratorSettings::Photon(PhotonSettings { photons: args.photons, ..PhotonSettings::photon() });
    println!("{:<12} {:>6} {:>10} {:>12}", "integrator", "spp", "time s", "rel MSE");
    for (name, settings) in [
        ("volpath", volpath),
        ("photon", photon),
        ("ppm", ppm(VolumeQuery::March)),
        ("ppm beam", ppm(VolumeQuery::Beam)),
    ] {
        let mut points: Vec<(f64, f64)> = Vec::new();
        let mut spp = 1;
        while spp <= args.max_spp {
            let (image, seconds) = timed(scene, &settings, spp, args.threads)?;
            let error = image.relative_mse(&reference);
            println!("{name:<12} {spp:>6} {seconds:>10.3} {error:>12.3e}");
            points.push((seconds, error));
            if error < args.target {
                break;
            }
            spp *= 2;
        }
        match time_to_reach(&points, args.target) {
            Some(t) => println!("{name:<12} reaches relative MSE {:.0e} in {t:.2} s", args.target),
            None => println!("{name:<12} does not reach relative MSE {:.0e} within {} spp", args.target, args.max_spp),
        }
    }
    Ok(())
}
