//! `niebla bench trackers`: efficiency of the transmittance estimators on a
//! grid medium, with the scene's majorant grid and with one global majorant.
//! Efficiency is reported as variance x time per estimate (lower is better),
//! averaged over camera rays and shadow rays through the medium.

use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

use crate::error::CliError;
use clap::Args;
use niebla::math::{Ray, Vec3};
use niebla::medium::{DensityGrid, GridMedium, Medium};
use niebla::sampling::PixelSampler;
use niebla::scene::Scene;
use niebla::tracking::{segment_transmittance, MarchStep, TransmittanceMethod};
use niebla_volume::MajorantGrid;

/// Options of `niebla bench trackers`.
#[derive(Args, Debug)]
pub struct TrackerBenchArgs {
    /// Scene with a grid medium (default: scenes/smoke.json).
    pub scene: Option<PathBuf>,
    /// Rays through the medium.
    #[arg(long, default_value_t = 400)]
    pub rays: u32,
    /// Estimates per ray (for the variance).
    #[arg(long, default_value_t = 256)]
    pub estimates: u32,
}

fn first_grid(scene: &Scene) -> Option<&GridMedium> {
    scene.media.iter().find_map(|m| match m {
        Medium::Grid(g) => Some(g),
        _ => None,
    })
}

/// The same medium with one majorant cell (the global maximum).
fn with_global_majorant(g: &GridMedium) -> GridMedium {
    let (majorant, minorant) = match &g.density {
        DensityGrid::Dense(d) => {
            (MajorantGrid::from_dense(d, [1, 1, 1]), Some(MajorantGrid::minorant_from_dense(d, [1, 1, 1])))
        }
        DensityGrid::Sparse(s) => (MajorantGrid::from_sparse(s, 1), Some(MajorantGrid::minorant_from_sparse(s, 1))),
    };
    GridMedium::new(
        g.sigma_a,
        g.sigma_s,
        g.density.clone(),
        g.world_to_grid,
        majorant,
        minorant,
        g.emission.clone(),
        g.phase.clone(),
    )
}

/// Rays through the medium: camera rays and rays toward the first
/// directional light (or straight up) from random points in its box.
fn rays(scene: &Scene, g: &GridMedium, n: u32) -> Vec<(Ray, f32, f32)> {
    let mut s = PixelSampler::from_key(2024);
    let (lo, hi) = g.world_bounds;
    let to_light = scene
        .lights
        .iter()
        .find_map(|l| match l {
            niebla::light::Light::Directional(d) => Some(-d.direction),
            _ => None,
        })
        .unwrap_or(Vec3::Y);
    let mut out = Vec::new();
    let mut tries = 0;
    while out.len() < n as usize && tries < 100 * n {
        tries += 1;
        let ray = if out.len() % 2 == 0 {
            let (x, y) =
                ((s.next_1d() * scene.camera.width as f32) as u32, (s.next_1d() * scene.camera.height as f32) as u32);
            scene.camera.generate_ray(x, y, s.next_2d())
        } else {
            let p = lo + (hi - lo) * Vec3::new(s.next_1d(), s.next_1d(), s.next_1d());
            if g.density_at(p) <= 0.0 {
                continue;
            }
            Ray::new(p, to_light)
        };
        if let Some((t0, t1)) = g.clip(&ray, 0.0, f32::INFINITY) {
            out.push((ray, t0, t1));
        }
    }
    out
}

/// `niebla bench trackers`.
pub fn run(args: &TrackerBenchArgs) -> Result<(), CliError> {
    let path = args.scene.clone().unwrap_or_else(|| PathBuf::from("scenes/smoke.json"));
    let (built, _) = crate::load::load(Some(&path))?;
    let scene = built.scene;
    let Some(grid) = first_grid(&scene) else {
        return Err(CliError::SceneUnsuitable { scene: path, problem: "the scene has no grid medium to measure" });
    };
    let rays = rays(&scene, grid, args.rays);
    if rays.is_empty() {
        return Err(CliError::SceneUnsuitable { scene: path, problem: "no ray passes through the grid medium" });
    }
    println!(
        "bench trackers: {} rays ({} camera, {} toward the light) x {} estimates, majorant grid {:?}",
        rays.len(),
        rays.len().div_ceil(2),
        rays.len() / 2,
        args.estimates,
        grid.majorant.res()
    );
    println!(
        "{:<10} {:<16} {:>12} {:>14} {:>16} {:>14}",
        "majorant", "estimator", "mean T", "variance", "ns / estimate", "var x time"
    );
    let global = with_global_majorant(grid);
    for (label, medium) in [("grid", Medium::Grid(grid.clone())), ("global", Medium::Grid(global))] {
        for (name, method) in [
            ("delta", TransmittanceMethod::Delta),
            ("ratio", TransmittanceMethod::Ratio),
            ("residual ratio", TransmittanceMethod::ResidualRatio),
            ("ray march 1/64", TransmittanceMethod::RayMarch(MarchStep::Count(64))),
        ] {
            let medium = Arc::new(medium.clone());
            let mut variance = 0.0f64;
            let mut mean = 0.0f64;
            let start = Instant::now();
            for (i, (ray, t0, t1)) in rays.iter().enumerate() {
                let (mut sum, mut sum2) = (0.0f64, 0.0f64);
                for k in 0..args.estimates {
                    let mut sampler = PixelSampler::from_key(((i as u64) << 32) | k as u64);
                    let tr = segment_transmittance(&medium, ray, *t0, *t1, method, &mut sampler).g() as f64;
                    sum += tr;
                    sum2 += tr * tr;
                }
                let n = args.estimates as f64;
                let m = sum / n;
                mean += m;
                variance += (sum2 / n - m * m).max(0.0) * n / (n - 1.0);
            }
            let seconds = start.elapsed().as_secs_f64();
            let count = (rays.len() as f64) * args.estimates as f64;
            let per = seconds / count;
            let var = variance / rays.len() as f64;
            println!(
                "{label:<10} {name:<16} {:>12.5} {var:>14.3e} {:>16.1} {:>14.3e}",
                mean / rays.len() as f64,
                per * 1e9,
                var * per
            );
        }
    }
    println!("(ray marching is biased; its variance is that of the jitter only)");
    Ok(())
}
