//! `niebla bench photons --time-to-error`: the CPU time `volpath`, `ppm` and
//! `ppb` need to reach a per-pixel relative MSE (1e-2 by default) against a
//! converged `volpath` reference, averaged over several seeds.
//!
//! Each method renders progressively: the sample (pass) ranges `[0, 1)`,
//! `[1, 2)`, `[2, 4)`, ... are rendered as separate calls that continue the
//! same sequence (`first_sample`), their fixed-point sums are added, and the
//! image after 1, 2, 4, ... samples is compared with the reference. So one
//! sweep to `N` samples costs `N` samples, and the image after `n` samples is
//! exactly the one a single `n`-sample render gives. Seconds are process CPU
//! seconds (user + system, all threads) of the render calls alone, so other
//! work on a shared machine does not inflate them; use `--threads 1`.
//!
//! The reference is rendered once as two independent `volpath` halves
//! (seeds 101 and 102) and cached as an EXR (`--reference-exr`) with its
//! scene, size, sample count and own relative MSE as header attributes.

use std::path::{Path, PathBuf};

use niebla::film::{read_exr, write_exr_with_attributes, Image, SampleSums};
use niebla::integrator::photon::{PpbSettings, VolumeQuery};
use niebla::integrator::IntegratorSettings;
use niebla::render::{render_sums, RenderOptions};
use niebla::scene::Scene;

use crate::bench_photons::{photon_settings, ppb_settings, PhotonBenchArgs};
use crate::error::CliError;

/// CPU seconds (user + system, all threads, exited ones included) the
/// process has spent, from `clock_gettime(CLOCK_PROCESS_CPUTIME_ID)`
/// (nanosecond resolution; /proc's ticks of 10 ms are too coarse for
/// renders of a few milliseconds).
pub(crate) fn process_cpu_seconds() -> Result<f64, CliError> {
    let mut ts = libc::timespec { tv_sec: 0, tv_nsec: 0 };
    // SAFETY: `ts` is a valid, writable timespec for the duration of the call.
    let rc = unsafe { libc::clock_gettime(libc::CLOCK_PROCESS_CPUTIME_ID, &mut ts) };
    if rc != 0 {
        return Err(CliError::invalid_option(
            "--time-to-error",
            format!("cannot read the process CPU clock ({})", std::io::Error::last_os_error()),
        ));
    }
    Ok(ts.tv_sec as f64 + ts.tv_nsec as f64 * 1e-9)
}

/// Header attribute names of a cached reference.
const ATTR_SCENE: &str = "niebla.bench.scene";
const ATTR_SPP: &str = "niebla.bench.spp";
const ATTR_NOISE: &str = "niebla.bench.noise";

/// One method's sweep with one seed: after `spp[k]` samples, `cpu[k]`
/// cumulative CPU seconds, relative MSE `error[k]` (reference noise
/// subtracted) and image mean / reference mean `ratio[k]`.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct Sweep {
    /// Samples (passes) per pixel after each level.
    pub spp: Vec<u32>,
    /// Cumulative process CPU seconds of the render calls.
    pub cpu: Vec<f64>,
    /// Relative MSE against the reference, the reference's own subtracted.
    pub error: Vec<f64>,
    /// Image mean / reference mean (average over channels).
    pub ratio: Vec<f64>,
}

impl Sweep {
    /// `(cpu, error)` points.
    fn points(&self) -> Vec<(f64, f64)> {
        self.cpu.iter().copied().zip(self.error.iter().copied()).collect()
    }
}

/// Mean and standard error of the mean (from the sample standard deviation;
/// 0 for fewer than two values).
pub(crate) fn mean_se(values: &[f64]) -> (f64, f64) {
    let n = values.len();
    if n == 0 {
        return (f64::NAN, f64::NAN);
    }
    let mean = values.iter().sum::<f64>() / n as f64;
    if n < 2 {
        return (mean, 0.0);
    }
    let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1) as f64;
    (mean, (var / n as f64).sqrt())
}

/// A measured relative MSE less the reference's own (the two are
/// independent, so their relative MSEs add), floored at 1e-3 of the measured
/// value so a log stays finite.
pub(crate) fn error_minus_noise(measured: f64, noise: f64) -> f64 {
    (measured - noise).max(measured * 1e-3)
}

/// The seed-averaged curve: per level, the mean CPU seconds and the mean
/// relative MSE over the sweeps (all of the same length). The mean of the
/// relative MSE estimates its expectation, which is what a heavy-tailed
/// estimator's error should be judged by.
pub(crate) fn average_curve(sweeps: &[Sweep]) -> Vec<(f64, f64)> {
    let levels = sweeps.iter().map(|s| s.cpu.len()).min().unwrap_or(0);
    (0..levels)
        .map(|k| {
            let cpu: Vec<f64> = sweeps.iter().map(|s| s.cpu[k]).collect();
            let err: Vec<f64> = sweeps.iter().map(|s| s.error[k]).collect();
            (mean_se(&cpu).0, mean_se(&err).0)
        })
        .collect()
}

/// `y` at `x` on a curve of `(x, y)` points with increasing `x`, linear in
/// log-log between the two bracketing points; outside the curve, `y ~ 1/x`
/// from the nearest end (the rate of an unbiased estimator's variance) and
/// `true` for "extrapolated". `None` for an empty curve or non-positive
/// values.
pub(crate) fn loglog_at(points: &[(f64, f64)], x: f64) -> Option<(f64, bool)> {
    if points.is_empty() || x <= 0.0 || points.iter().any(|&(a, b)| a <= 0.0 || b <= 0.0) {
        return None;
    }
    let (first, last) = (points[0], points[points.len() - 1]);
    if x < first.0 {
        return Some((first.1 * first.0 / x, true));
    }
    if x > last.0 {
        return Some((last.1 * last.0 / x, true));
    }
    for w in points.windows(2) {
        let ((x0, y0), (x1, y1)) = (w[0], w[1]);
        if x >= x0 && x <= x1 {
            if x1 == x0 {
                return Some((y0, false));
            }
            let f = (x.ln() - x0.ln()) / (x1.ln() - x0.ln());
            return Some(((y0.ln() + f * (y1.ln() - y0.ln())).exp(), false));
        }
    }
    Some((first.1, false))
}

/// Time at which a `(time, error)` curve first falls below `target`,
/// linear in log-log between the last point above and the first below it;
/// if no point is below, extrapolated from the last point as
/// `error ~ 1/time`; if the first point already is, back from it the same
/// way. `true` marks an extrapolated time. `None` for an empty curve or
/// non-positive values.
pub(crate) fn time_to_target(points: &[(f64, f64)], target: f64) -> Option<(f64, bool)> {
    if points.is_empty() || target <= 0.0 || points.iter().any(|&(t, e)| t <= 0.0 || e <= 0.0) {
        return None;
    }
    match points.iter().position(|&(_, e)| e < target) {
        Some(0) => Some((points[0].0 * points[0].1 / target, true)),
        Some(i) => {
            let ((t0, e0), (t1, e1)) = (points[i - 1], points[i]);
            let f = (target.ln() - e0.ln()) / (e1.ln() - e0.ln());
            Some(((t0.ln() + f * (t1.ln() - t0.ln())).exp(), false))
        }
        None => {
            let (t, e) = points[points.len() - 1];
            Some((t * e / target, true))
        }
    }
}

/// The cached `volpath` reference at `path` (read when it exists, checked
/// against the scene and size; otherwise rendered with `spp` samples in two
/// halves and written). The image (mean of the halves) and its own relative
/// MSE (a quarter of the halves' relative MSE to each other).
fn cached_reference(
    scene: &Scene,
    scene_path: &Path,
    path: &Path,
    spp: u32,
    threads: Option<usize>,
) -> Result<(Image, f64), CliError> {
    let scene_name = scene_path.display().to_string();
    if path.exists() {
        let read = read_exr(path)
            .map_err(|e| CliError::ReferenceUnreadable { path: path.to_path_buf(), reason: e.to_string() })?;
        let size = (read.image.width, read.image.height);
        if size != (scene.camera.width, scene.camera.height) {
            return Err(CliError::ReferenceSize {
                path: path.to_path_buf(),
                size,
                scene_size: (scene.camera.width, scene.camera.height),
            });
        }
        let attr = |name: &str| {
            read.text_attributes.get(name).cloned().ok_or_else(|| CliError::ReferenceUnreadable {
                path: path.to_path_buf(),
                reason: format!("no {name} attribute (not written by `niebla bench photons --time-to-error`)"),
            })
        };
        let cached_scene = attr(ATTR_SCENE)?;
        if cached_scene != scene_name {
            return Err(CliError::ReferenceUnreadable {
                path: path.to_path_buf(),
                reason: format!("it is the reference of {cached_scene}, not of {scene_name}"),
            });
        }
        let noise = attr(ATTR_NOISE)?.parse::<f64>().map_err(|_| CliError::ReferenceUnreadable {
            path: path.to_path_buf(),
            reason: format!("{ATTR_NOISE} is not a number"),
        })?;
        println!("reference: {} (volpath {} spp, its own relative MSE {noise:.2e})", path.display(), attr(ATTR_SPP)?);
        return Ok((read.image, noise));
    }
    let half = (spp / 2).max(1);
    let volpath = IntegratorSettings::VolPath {
        max_depth: IntegratorSettings::DEFAULT_MAX_DEPTH,
        volume_light_sampling: true,
        emitter_guiding: true,
    };
    let cpu0 = process_cpu_seconds()?;
    let render_half = |seed: u64| -> Result<Image, CliError> {
        let options = RenderOptions { spp: half, seed, first_sample: 0, threads, sampler: Default::default() };
        Ok(render_sums(scene, &volpath, &options, &|_, _| {}, None)?.mean(half as u64))
    };
    let a = render_half(101)?;
    let b = render_half(102)?;
    let noise = a.relative_mse(&b) / 4.0;
    let pixels = a.pixels.iter().zip(&b.pixels).map(|(x, y)| (*x + *y) * 0.5).collect();
    let mean = Image { width: a.width, height: a.height, pixels };
    write_exr_with_attributes(
        &mean,
        path,
        &[(ATTR_SCENE, scene_name), (ATTR_SPP, format!("2 x {half}")), (ATTR_NOISE, format!("{noise:e}"))],
    )?;
    println!(
        "reference: volpath 2 x {half} spp in {:.1} CPU s; its own relative MSE {noise:.2e}; cached in {}",
        process_cpu_seconds()? - cpu0,
        path.display()
    );
    Ok((mean, noise))
}

/// One progressive sweep of `settings` with `seed`: samples to 1, 2, 4, ...
/// while `keep_going(spp, cpu, error)` says so and `spp < max_spp`, or to
/// exactly `levels` levels when given.
#[allow(clippy::too_many_arguments)]
fn sweep(
    scene: &Scene,
    settings: &IntegratorSettings,
    seed: u64,
    threads: Option<usize>,
    reference: &Image,
    noise: f64,
    max_spp: u32,
    levels: Option<usize>,
    keep_going: impl Fn(u32, f64, f64) -> bool,
) -> Result<Sweep, CliError> {
    let reference_mean = reference.mean().average() as f64;
    let mut sums = SampleSums::new(scene.camera.width, scene.camera.height);
    let mut out = Sweep::default();
    let mut done = 0u32;
    let mut cpu = 0.0;
    loop {
        let target_spp = if done == 0 { 1 } else { done * 2 };
        let options = RenderOptions {
            spp: target_spp - done,
            seed,
            first_sample: done as u64,
            threads,
            sampler: Default::default(),
        };
        let cpu0 = process_cpu_seconds()?;
        let part = render_sums(scene, settings, &options, &|_, _| {}, None)?;
        cpu += process_cpu_seconds()? - cpu0;
        sums.add(&part);
        done = target_spp;
        let image = sums.mean(done as u64);
        let error = error_minus_noise(image.relative_mse(reference), noise);
        out.spp.push(done);
        out.cpu.push(cpu);
        out.error.push(error);
        out.ratio.push(image.mean().average() as f64 / reference_mean);
        let more = match levels {
            Some(n) => out.spp.len() < n,
            None => done < max_spp && keep_going(done, cpu, error),
        };
        if !more {
            return Ok(out);
        }
    }
}

/// The methods measured: `volpath`, `ppm` (point photons, ray marching and
/// beam queries), and `ppb` once per `--tube-sin` value (or with the scene's
/// or default settings).
fn methods(scene_integrator: &IntegratorSettings, args: &PhotonBenchArgs) -> Vec<(String, IntegratorSettings)> {
    let volpath = IntegratorSettings::VolPath {
        max_depth: IntegratorSettings::DEFAULT_MAX_DEPTH,
        volume_light_sampling: true,
        emitter_guiding: true,
    };
    let mut rows = vec![
        ("volpath".to_string(), volpath),
        ("ppm".to_string(), photon_settings(scene_integrator, args, Some(VolumeQuery::March))),
        ("ppm beam".to_string(), photon_settings(scene_integrator, args, Some(VolumeQuery::Beam))),
    ];
    let ppb = ppb_settings(scene_integrator, args);
    if args.tube_sin.is_empty() {
        rows.push(("ppb".to_string(), ppb));
    } else if let IntegratorSettings::Ppb(base) = ppb {
        for &t in &args.tube_sin {
            rows.push((format!("ppb ts={t}"), IntegratorSettings::Ppb(PpbSettings { tube_sin: t, ..base })));
        }
    }
    rows.retain(|(name, _)| {
        args.only.is_empty() || args.only.iter().any(|o| o == name || (o == "ppb" && name.starts_with("ppb")))
    });
    rows
}

/// `--time-to-error` on one scene: per method, `--seeds` progressive sweeps
/// (seeds `--seed`, `--seed + 1`, ...); the first seed's sweep runs until its
/// relative MSE is below half the target, its CPU time passes
/// `--sweep-seconds` or `--max-spp` is reached, and the other seeds render
/// the same sample counts. Prints the seed-averaged curve, the time to the
/// target on it, and the relative MSE of every method at equal CPU times.
pub(crate) fn run_scene(
    scene: &Scene,
    scene_path: &Path,
    scene_integrator: &IntegratorSettings,
    args: &PhotonBenchArgs,
) -> Result<(), CliError> {
    let threads = args.threads.threads;
    if args.seeds == 0 {
        return Err(CliError::invalid_option("--seeds", "must be at least 1"));
    }
    if args.tube_sin.iter().any(|t| !(0.0..=1.0).contains(t)) {
        return Err(CliError::invalid_option("--tube-sin", "every value must be in [0, 1]"));
    }
    let reference_path = args.reference_exr.clone().unwrap_or_else(|| {
        let stem = scene_path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
        PathBuf::from(format!("{stem}_ref_{}x{}.exr", scene.camera.width, scene.camera.height))
    });
    let (reference, noise) = cached_reference(scene, scene_path, &reference_path, args.reference_spp, threads)?;
    println!(
        "CPU seconds of the render calls (process time, {} thread(s)); relative MSE minus the reference's; \
         mean over {} seed(s) from {}",
        threads.map_or("all".to_string(), |t| t.to_string()),
        args.seeds,
        args.seed
    );
    let mut results: Vec<(String, Vec<Sweep>)> = Vec::new();
    for (name, settings) in methods(scene_integrator, args) {
        let mut sweeps: Vec<Sweep> = Vec::new();
        for k in 0..args.seeds as u64 {
            let levels = sweeps.first().map(|s| s.spp.len());
            let s = sweep(
                scene,
                &settings,
                args.seed.wrapping_add(k),
                threads,
                &reference,
                noise,
                args.max_spp,
                levels,
                |_, cpu, error| error >= 0.5 * args.target && cpu * 2.0 <= args.sweep_seconds,
            )?;
            sweeps.push(s);
        }
        println!("{name}:");
        println!("  {:>7} {:>10} {:>12} {:>10} {:>10} {:>10}", "spp", "CPU s", "rel MSE", "+- SE", "mean/ref", "+- SE");
        for k in 0..sweeps[0].spp.len() {
            let col = |f: &dyn Fn(&Sweep) -> f64| mean_se(&sweeps.iter().map(f).collect::<Vec<_>>());
            let (cpu, _) = col(&|s| s.cpu[k]);
            let (e, e_se) = col(&|s| s.error[k]);
            let (r, r_se) = col(&|s| s.ratio[k]);
            println!("  {:>7} {cpu:>10.3} {e:>12.3e} {e_se:>10.2e} {r:>10.4} {r_se:>10.4}", sweeps[0].spp[k]);
        }
        results.push((name, sweeps));
    }
    println!(
        "-- time to relative MSE {:.0e} ({} x {} pixels, CPU s; ~ = extrapolated as error ~ 1/time):",
        args.target, scene.camera.width, scene.camera.height
    );
    for (name, sweeps) in &results {
        let per_seed: Vec<String> = sweeps
            .iter()
            .filter_map(|s| time_to_target(&s.points(), args.target))
            .map(|(t, x)| format!("{}{}", if x { "~" } else { "" }, seconds(t)))
            .collect();
        match time_to_target(&average_curve(sweeps), args.target) {
            Some((t, x)) => println!(
                "   {name:<14} {}{} s  (per seed: {})",
                if x { "~" } else { "" },
                seconds(t),
                per_seed.join(", ")
            ),
            None => println!("   {name:<14} -"),
        }
    }
    equal_time(&results);
    Ok(())
}

/// A method's name and its sweeps, one per seed.
type Rows = [(String, Vec<Sweep>)];

/// Seconds with three significant digits at most (milliseconds stay visible).
fn seconds(t: f64) -> String {
    if t < 1.0 {
        format!("{t:.3}")
    } else if t < 100.0 {
        format!("{t:.2}")
    } else {
        format!("{t:.0}")
    }
}

/// Relative MSE of the methods at common CPU times (powers of 2 of a
/// second inside at least two methods' seed-averaged curves; `-` where a
/// method's curve does not reach): the mean over seeds of each seed's curve
/// at that time (log-log interpolation) +- its SE; for `ppb` variants after
/// the first, also the geometric mean of the per-seed ratios to the first
/// variant (the variants share each seed's photons, so the ratio is paired)
/// with its 2-SE range.
fn equal_time(results: &Rows) {
    let ranges: Vec<Option<(f64, f64)>> = results
        .iter()
        .map(|(_, s)| {
            let c = average_curve(s);
            Some((c.first()?.0, c.last()?.0))
        })
        .collect();
    let covers = |r: &Option<(f64, f64)>, t: f64| r.is_some_and(|(lo, hi)| t >= lo && t <= hi);
    let times: Vec<f64> =
        (-12..=12).map(|k| 2f64.powi(k)).filter(|&t| ranges.iter().filter(|r| covers(r, t)).count() >= 2).collect();
    if times.is_empty() {
        println!("-- equal CPU time: no two methods' time ranges overlap");
        return;
    }
    println!("-- relative MSE at equal CPU time (mean over seeds +- SE):");
    print!("   {:<14}", "CPU s");
    for t in &times {
        print!(" {:>20}", seconds(*t));
    }
    println!();
    let at = |s: &Sweep, t: f64| loglog_at(&s.points(), t).map_or(f64::NAN, |v| v.0);
    for ((name, sweeps), range) in results.iter().zip(&ranges) {
        print!("   {name:<14}");
        for &t in &times {
            if covers(range, t) {
                let (m, se) = mean_se(&sweeps.iter().map(|s| at(s, t)).collect::<Vec<_>>());
                print!(" {:>20}", format!("{m:.3e} +- {se:.1e}"));
            } else {
                print!(" {:>20}", "-");
            }
        }
        println!();
    }
    let variants: Vec<_> = results.iter().zip(&ranges).filter(|((n, _), _)| n.starts_with("ppb ts=")).collect();
    for (v, range) in variants.iter().skip(1) {
        let (first, first_range) = variants[0];
        print!("   {:<14}", format!("{}/{}", v.0.trim_start_matches("ppb "), first.0.trim_start_matches("ppb ")));
        for &t in &times {
            if covers(range, t) && covers(first_range, t) {
                let logs: Vec<f64> = v.1.iter().zip(&first.1).map(|(a, b)| (at(a, t) / at(b, t)).ln()).collect();
                let (m, se) = mean_se(&logs);
                print!(" {:>20}", format!("{:.3} [{:.2},{:.2}]", m.exp(), (m - 2.0 * se).exp(), (m + 2.0 * se).exp()));
            } else {
                print!(" {:>20}", "-");
            }
        }
        println!();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use niebla::color::Rgb;

    fn close(a: f64, b: f64, tol: f64) -> bool {
        (a - b).abs() <= tol * b.abs().max(1e-300)
    }

    #[test]
    fn loglog_interpolation_is_exact_on_power_laws_and_extrapolates_as_one_over_x() {
        // y = 3 x^-0.7 at x = 1, 2, 4, 8: any x inside is on the line.
        let pts: Vec<(f64, f64)> = [1.0, 2.0, 4.0, 8.0].iter().map(|&x: &f64| (x, 3.0 * x.powf(-0.7))).collect();
        for x in [1.0, 1.5, 3.0, 5.5, 8.0] {
            let (y, ext) = loglog_at(&pts, x).unwrap();
            assert!(close(y, 3.0 * f64::powf(x, -0.7), 1e-12), "x {x}: {y}");
            assert!(!ext);
        }
        // Beyond the ends: y ~ 1/x from the end point, marked.
        let (y, ext) = loglog_at(&pts, 16.0).unwrap();
        assert!(ext && close(y, 3.0 * 8f64.powf(-0.7) * 8.0 / 16.0, 1e-12));
        let (y, ext) = loglog_at(&pts, 0.5).unwrap();
        assert!(ext && close(y, 3.0 * 2.0, 1e-12));
        assert_eq!(loglog_at(&[], 1.0), None);
        assert_eq!(loglog_at(&[(1.0, 0.0)], 1.0), None);
    }

    #[test]
    fn time_to_target_interpolates_between_brackets_and_marks_extrapolation() {
        // error = 0.5 / t: reaches 1e-2 at t = 50, between 32 and 64.
        let pts: Vec<(f64, f64)> = (0..8).map(|k| 2f64.powi(k)).map(|t| (t, 0.5 / t)).collect();
        let (t, ext) = time_to_target(&pts, 1e-2).unwrap();
        assert!(close(t, 50.0, 1e-12) && !ext, "{t}");
        // A bend: from (1, 0.1) to (4, 0.001): halfway in log error = 1e-2 at t = 2.
        let (t, ext) = time_to_target(&[(1.0, 0.1), (4.0, 0.001)], 1e-2).unwrap();
        assert!(close(t, 2.0, 1e-12) && !ext, "{t}");
        // Never below: extrapolated from the last point as error ~ 1/t.
        let (t, ext) = time_to_target(&[(1.0, 0.2), (2.0, 0.05)], 1e-2).unwrap();
        assert!(close(t, 10.0, 1e-12) && ext, "{t}");
        // Already below at the first point: extrapolated back.
        let (t, ext) = time_to_target(&[(2.0, 5e-3), (4.0, 1e-3)], 1e-2).unwrap();
        assert!(close(t, 1.0, 1e-12) && ext, "{t}");
        assert_eq!(time_to_target(&[], 1e-2), None);
    }

    #[test]
    fn seed_averages_mean_and_standard_error() {
        let (m, se) = mean_se(&[1.0, 2.0, 3.0, 4.0]);
        // var = 5/3, se = sqrt(5/12).
        assert!(close(m, 2.5, 1e-15) && close(se, (5.0f64 / 12.0).sqrt(), 1e-14));
        assert_eq!(mean_se(&[7.0]), (7.0, 0.0));
        let a = Sweep { spp: vec![1, 2], cpu: vec![1.0, 2.0], error: vec![0.4, 0.1], ratio: vec![1.0, 1.0] };
        let b = Sweep { spp: vec![1, 2, 4], cpu: vec![3.0, 4.0, 9.0], error: vec![0.2, 0.3, 0.0], ratio: vec![1.0; 3] };
        // Levels common to both only; CPU and error averaged level by level.
        let c = average_curve(&[a, b]);
        assert_eq!(c.len(), 2);
        assert!(close(c[0].0, 2.0, 1e-15) && close(c[0].1, 0.3, 1e-15));
        assert!(close(c[1].0, 3.0, 1e-15) && close(c[1].1, 0.2, 1e-15));
        // Reference noise: subtracted, floored at 1e-3 of the measurement.
        assert!(close(error_minus_noise(0.05, 0.01), 0.04, 1e-15));
        assert!(close(error_minus_noise(0.05, 0.2), 5e-5, 1e-15));
    }

    #[test]
    fn relative_mse_of_a_synthetic_image_matches_its_closed_form() {
        // Reference: pixels 1 and 3 (mean 2, eps = (0.02)^2); the image is
        // 10% high in the first pixel and exact in the second.
        let reference = Image { width: 2, height: 1, pixels: vec![Rgb::new(1.0, 1.0, 1.0), Rgb::new(3.0, 3.0, 3.0)] };
        let image = Image { width: 2, height: 1, pixels: vec![Rgb::new(1.1, 1.1, 1.1), Rgb::new(3.0, 3.0, 3.0)] };
        let expected = (0.1f64 * 0.1 / (1.0 + 4e-4)) / 2.0;
        let got = image.relative_mse(&reference);
        assert!(close(got, expected, 1e-6), "{got} vs {expected}");
    }
}
