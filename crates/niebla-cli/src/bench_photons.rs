//! `niebla bench photons`: figures, not tests. On each scene: photons traced
//! per second, kd-tree gather queries per second (fixed radius and k
//! nearest), and the time `photon`, `ppm`, `ppb` and `volpath` take to reach a
//! relative MSE of 1e-2 against a high-spp `volpath` reference (renders at
//! doubling sample or pass counts, log-log interpolation between the two
//! bracketing renders, as `niebla bench single` does).

use std::collections::BinaryHeap;
use std::path::PathBuf;
use std::time::Instant;

use clap::Args;

use crate::bench::{time_to_reach, timed};
use niebla::film::Image;
use niebla::integrator::photon::{
    auto_radius, photon_stream, trace_photons, PhotonSettings, PhotonTree, PpbSettings, PpmSettings, TraceSettings,
    VolumeQuery,
};
use niebla::integrator::IntegratorSettings;
use niebla::scene::Scene;

use crate::error::CliError;
use crate::flags::ThreadsFlag;

/// Options of `niebla bench photons`.
#[derive(Args, Debug)]
pub struct PhotonBenchArgs {
    /// Scenes to measure (default: scenes/caustic_fog_area.json and
    /// scenes/cloud_photons.json).
    pub scenes: Vec<PathBuf>,
    /// Image width used for the renders (height keeps the aspect ratio).
    #[arg(long, default_value_t = 64)]
    pub width: u32,
    /// Seconds spent on the `volpath` reference of each scene (two
    /// independent halves; the larger, the less its own noise matters).
    #[arg(long, default_value_t = 120.0)]
    pub reference_seconds: f64,
    /// Largest sample (pass) count tried per integrator.
    #[arg(long, default_value_t = 1 << 20)]
    pub max_spp: u32,
    /// Longest single render of a sweep, seconds.
    #[arg(long, default_value_t = 60.0)]
    pub sweep_seconds: f64,
    /// Photons per `ppm` pass (when the scene file does not name `ppm`).
    #[arg(long, default_value_t = 20_000)]
    pub ppm_photons: u32,
    /// Photons per `ppb` pass (when the scene file does not name `ppb`).
    #[arg(long, default_value_t = PpbSettings::DEFAULT_PHOTONS)]
    pub ppb_photons: u32,
    /// Photons of the `photon` integrator's map (when the scene file does
    /// not name `photon`).
    #[arg(long, default_value_t = 200_000)]
    pub photons: u32,
    /// Only these rows of the convergence table, comma separated (volpath,
    /// photon, ppm, "ppm beam", ppb); all by default.
    #[arg(long, value_delimiter = ',')]
    pub only: Vec<String>,
    /// Target relative MSE.
    #[arg(long, default_value_t = 1e-2)]
    pub target: f64,
    /// Seed of the sweep renders (the `volpath` reference keeps its own).
    #[arg(long, default_value_t = 7)]
    pub seed: u64,
    /// Instead of the sweep: this many independent renders of `--max-spp`
    /// samples (passes) per integrator, seeds `--seed`, `--seed + 1`, ...;
    /// prints the mean over the renders of the image mean / reference mean
    /// with its standard error (from the spread of the renders).
    #[arg(long, default_value_t = 0)]
    pub repeats: u32,
    /// Instead of the tracing figures and the sweep: the CPU time of each
    /// method to reach `--target` against a cached `volpath` reference,
    /// averaged over `--seeds` progressive sweeps (see docs/photon-beams.md).
    #[arg(long)]
    pub time_to_error: bool,
    /// `--time-to-error`: the cached reference EXR (rendered and written when
    /// missing; default `<scene stem>_ref_<W>x<H>.exr` in the current folder).
    #[arg(long)]
    pub reference_exr: Option<PathBuf>,
    /// `--time-to-error`: samples per pixel of a reference that has to be
    /// rendered (two halves of half as many).
    #[arg(long, default_value_t = 8192)]
    pub reference_spp: u32,
    /// `--time-to-error`: independent sweeps per method (seeds `--seed`,
    /// `--seed + 1`, ...).
    #[arg(long, default_value_t = 4)]
    pub seeds: u32,
    /// `--time-to-error`: one `ppb` row per value of `tube_sin` (comma
    /// separated, each in [0, 1]); by default one row with the scene's or
    /// the default settings.
    #[arg(long, value_delimiter = ',')]
    pub tube_sin: Vec<f32>,
    /// Worker threads of the renders (the tracing figure always uses all cores).
    #[command(flatten)]
    pub threads: ThreadsFlag,
}

/// `niebla bench photons`.
pub fn run(args: &PhotonBenchArgs) -> Result<(), CliError> {
    args.threads.get()?;
    let scenes = if args.scenes.is_empty() {
        vec![PathBuf::from("scenes/caustic_fog_area.json"), PathBuf::from("scenes/cloud_photons.json")]
    } else {
        args.scenes.clone()
    };
    for path in &scenes {
        let (built, _) = crate::load::load(Some(path))?;
        let scene_integrator = built.settings.integrator;
        let mut scene = built.scene;
        let aspect = scene.camera.height as f64 / scene.camera.width as f64;
        scene.camera.width = args.width.clamp(1, 16384);
        scene.camera.height = ((scene.camera.width as f64 * aspect).round() as u32).max(1);
        println!("== {} ({}x{} pixels)", path.display(), scene.camera.width, scene.camera.height);
        if args.time_to_error {
            crate::bench_photons_time::run_scene(&scene, path, &scene_integrator, args)?;
            continue;
        }
        tracing_and_queries(&scene, args.photons);
        convergence(&scene, &scene_integrator, args)?;
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

/// The `volpath` reference: two independent halves (seeds 101 and 102) of
/// about `seconds` in all, sized by a 16-spp probe, and the reference's own
/// relative MSE estimated from the halves (their relative MSE is twice each
/// half's, four times the mean's).
fn reference(scene: &Scene, args: &PhotonBenchArgs) -> Result<(Image, f64), CliError> {
    let volpath = IntegratorSettings::VolPath {
        max_depth: IntegratorSettings::DEFAULT_MAX_DEPTH,
        volume_light_sampling: true,
        emitter_guiding: true,
    };
    let (_, probe_s) = timed(scene, &volpath, 16, 100, args.threads.threads)?;
    let half = (args.reference_seconds / 2.0 / probe_s.max(1e-6) * 16.0).clamp(16.0, 1e8);
    let half = 1u32 << (half.log2().floor() as u32).min(30);
    let start = Instant::now();
    let (a, _) = timed(scene, &volpath, half, 101, args.threads.threads)?;
    let (b, _) = timed(scene, &volpath, half, 102, args.threads.threads)?;
    let noise = a.relative_mse(&b) / 4.0;
    let pixels = a.pixels.iter().zip(&b.pixels).map(|(x, y)| (*x + *y) * 0.5).collect();
    let mean = Image { width: a.width, height: a.height, pixels };
    println!(
        "reference: volpath 2 x {half} spp in {:.1} s; its own relative MSE {noise:.2e} (from the two halves)",
        start.elapsed().as_secs_f64()
    );
    Ok((mean, noise))
}

/// `ppm` or `photon` settings: the scene file's own when it names that
/// integrator (its radius, photon count, query), else the defaults with
/// `--ppm-photons` / `--photons`; `query` overrides the volume query of `ppm`.
pub(crate) fn photon_settings(
    scene_integrator: &IntegratorSettings,
    args: &PhotonBenchArgs,
    query: Option<VolumeQuery>,
) -> IntegratorSettings {
    match (scene_integrator, query) {
        (IntegratorSettings::Ppm(ppm), Some(query)) => {
            IntegratorSettings::Ppm(PpmSettings { photon: PhotonSettings { query, ..ppm.photon }, ..*ppm })
        }
        (IntegratorSettings::Photon(photon), None) => IntegratorSettings::Photon(*photon),
        (_, Some(query)) => IntegratorSettings::Ppm(PpmSettings {
            photon: PhotonSettings { photons: args.ppm_photons, query, ..PhotonSettings::ppm() },
            ..PpmSettings::default()
        }),
        (_, None) => IntegratorSettings::Photon(PhotonSettings { photons: args.photons, ..PhotonSettings::photon() }),
    }
}

/// `ppb` settings: the scene file's own when it names `ppb`, else the
/// defaults with `--ppb-photons` photons per pass.
pub(crate) fn ppb_settings(scene_integrator: &IntegratorSettings, args: &PhotonBenchArgs) -> IntegratorSettings {
    match scene_integrator {
        IntegratorSettings::Ppb(ppb) => IntegratorSettings::Ppb(*ppb),
        _ => IntegratorSettings::Ppb(PpbSettings { photons: args.ppb_photons, ..PpbSettings::default() }),
    }
}

/// `--repeats`: independent renders of `--max-spp` samples with seeds
/// `--seed + k`; the mean of their image-mean / reference-mean ratios with
/// its standard error, the median, the smallest and largest ratio and the
/// mean relative MSE, as a summary line.
fn repeated_means(
    scene: &Scene,
    name: &str,
    settings: &IntegratorSettings,
    reference_mean: f64,
    args: &PhotonBenchArgs,
) -> Result<String, CliError> {
    let n = args.repeats as usize;
    let mut ratios = Vec::with_capacity(n);
    let start = Instant::now();
    for k in 0..args.repeats as u64 {
        let (image, _) = timed(scene, settings, args.max_spp, args.seed.wrapping_add(k), args.threads.threads)?;
        ratios.push(image.mean().average() as f64 / reference_mean);
    }
    let seconds = start.elapsed().as_secs_f64();
    let mean = ratios.iter().sum::<f64>() / n as f64;
    let var = if n > 1 { ratios.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1) as f64 } else { 0.0 };
    let se = (var / n as f64).sqrt();
    let mut sorted = ratios.clone();
    sorted.sort_by(f64::total_cmp);
    let line = format!(
        "{name:<12} {n} renders x {} spp ({seconds:.1} s): mean/ref {mean:.4} +- {se:.4} (SE), median {:.4}, \
         min {:.4}, max {:.4}, std {:.4}",
        args.max_spp,
        sorted[n / 2],
        sorted[0],
        sorted[n - 1],
        var.sqrt()
    );
    println!("{line}");
    Ok(line)
}

/// Time of `photon`, `ppm` (point and beam queries), `ppb` and `volpath` to the
/// target error. Each sweep renders at 1, 2, 4, ... spp (passes), each a
/// separate timed render with seed 7, until the error is below the target or
/// the next render would exceed `--sweep-seconds`. Errors are against the
/// `volpath` reference with the reference's own error subtracted (the two
/// are independent, so their relative MSEs add); a sweep that stops short
/// is extrapolated as error ~ 1 / time and marked `~`.
fn convergence(scene: &Scene, scene_integrator: &IntegratorSettings, args: &PhotonBenchArgs) -> Result<(), CliError> {
    let (reference, noise) = reference(scene, args)?;
    let volpath = IntegratorSettings::VolPath {
        max_depth: IntegratorSettings::DEFAULT_MAX_DEPTH,
        volume_light_sampling: true,
        emitter_guiding: true,
    };
    println!(
        "{:<12} {:>7} {:>10} {:>12} {:>12} {:>10}",
        "integrator", "spp", "time s", "rel MSE", "- ref noise", "mean/ref"
    );
    let reference_mean = reference.mean().average() as f64;
    let mut summary = Vec::new();
    for (name, settings) in [
        ("volpath", volpath),
        ("photon", photon_settings(scene_integrator, args, None)),
        ("ppm", photon_settings(scene_integrator, args, Some(VolumeQuery::March))),
        ("ppm beam", photon_settings(scene_integrator, args, Some(VolumeQuery::Beam))),
        ("ppb", ppb_settings(scene_integrator, args)),
    ] {
        if !args.only.is_empty() && !args.only.iter().any(|o| o == name) {
            continue;
        }
        if args.repeats > 0 {
            summary.push(repeated_means(scene, name, &settings, reference_mean, args)?);
            continue;
        }
        let mut points: Vec<(f64, f64)> = Vec::new();
        let mut spp = 1u32;
        loop {
            let (image, seconds) = timed(scene, &settings, spp, args.seed, args.threads.threads)?;
            let measured = image.relative_mse(&reference);
            let error = (measured - noise).max(measured * 1e-3);
            let mean_ratio = image.mean().average() as f64 / reference_mean;
            println!("{name:<12} {spp:>7} {seconds:>10.3} {measured:>12.3e} {error:>12.3e} {mean_ratio:>10.4}");
            points.push((seconds, error));
            let next_too_long = seconds * 2.0 > args.sweep_seconds;
            if error < args.target || next_too_long || spp >= args.max_spp {
                break;
            }
            spp *= 2;
        }
        let line = match time_to_reach(&points, args.target) {
            Some(t) => format!("{name:<12} reaches relative MSE {:.0e} in {t:.2} s", args.target),
            None => {
                let &(t, e) = points.last().unwrap();
                // Doubling the samples should halve a variance-dominated error;
                // an error that falls less than 20% has stalled (the bias of a
                // fixed photon map) and is not extrapolated.
                let stalled = points.len() >= 2 && e > 0.8 * points[points.len() - 2].1;
                if stalled {
                    format!(
                        "{name:<12} does not reach relative MSE {:.0e}: the error stalls at {e:.2e} ({t:.2} s)",
                        args.target
                    )
                } else {
                    // Extrapolate the last point as error ~ 1 / time.
                    format!(
                        "{name:<12} reaches relative MSE {:.0e} in ~{:.2} s (extrapolated from {e:.2e} at {t:.2} s)",
                        args.target,
                        t * e / args.target
                    )
                }
            }
        };
        println!("{line}");
        summary.push(line);
    }
    println!("-- summary ({} x {} pixels):", scene.camera.width, scene.camera.height);
    for line in summary {
        println!("   {line}");
    }
    Ok(())
}
