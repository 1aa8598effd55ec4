//! Fitting the RBF approximation `D~ = sum_l w_l exp(-|x - c_l|^2 / r_l^2)`
//! to a density sampled on a lattice (Zhou et al. 2008, Section 5.1): least
//! squares over centres, radii and weights with
//! analytic gradients, minimized by a projected L-BFGS (bounds enforced by
//! clamping after each step: the "ours" substitute for the paper's
//! L-BFGS-B), with teleportation of the least important RBF to the
//! location of largest error every `teleport_every` iterations (kept only when
//! it lowers the objective).
//!
//! Bounds (the paper's): radii in 0.015-0.09 of the
//! longest side (and at least half a lattice cell), weights in 0.01-1 of the
//! largest density, centres inside the lattice. Not done: the paper's final
//! alternation of teleports at convergence and its per-frame insertion scheme
//! for animations (niebla renders one density per scene).

use std::sync::atomic::{AtomicBool, Ordering};

use rayon::prelude::*;

use super::lattice::Lattice;
use super::rbf::{Buckets, Rbf, SUPPORT};
use crate::math::Vec3;

/// Parameters of the fit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FitSettings {
    /// Number of RBFs.
    pub count: usize,
    /// L-BFGS iterations.
    pub iterations: usize,
    /// Teleport the least important RBF every this many iterations (0: never).
    pub teleport_every: usize,
    /// Seed of the initial placement.
    pub seed: u64,
}

/// What the fit achieved.
#[derive(Clone, Debug, PartialEq)]
pub struct FitReport {
    /// `||D - D~||_2 / ||D||_2` over the lattice nodes.
    pub relative_error: f64,
    /// Relative error after each iteration.
    pub history: Vec<f64>,
    /// Teleports that lowered the objective and were kept.
    pub teleports_kept: usize,
}

/// Parameters per RBF in the optimizer: centre (3, lattice units), radius
/// (lattice units), weight (fraction of the largest density).
const P: usize = 5;

struct Problem<'a> {
    unit: Lattice,
    target: &'a [f32],
    lower: Vec<f64>,
    upper: Vec<f64>,
}

impl Problem<'_> {
    fn rbfs(&self, x: &[f64]) -> Vec<Rbf> {
        x.chunks(P)
            .map(|p| Rbf {
                center: Vec3::new(p[0] as f32, p[1] as f32, p[2] as f32),
                radius: p[3] as f32,
                weight: p[4] as f32,
            })
            .collect()
    }

    /// Residual `e = D - D~` at every node (lattice units).
    fn residual(&self, x: &[f64]) -> Vec<f32> {
        let rbfs = self.rbfs(x);
        let buckets = Buckets::new(&self.unit, &rbfs);
        let unit = self.unit;
        (0..unit.len())
            .into_par_iter()
            .with_min_len(512)
            .map(|node| {
                let p = unit.position_of(node);
                let approx: f32 = buckets
                    .near(unit.coords(node))
                    .iter()
                    .map(|&l| rbfs[l as usize].weight * rbfs[l as usize].kernel(p))
                    .sum();
                self.target[node] - approx
            })
            .collect()
    }

    fn objective(e: &[f32]) -> f64 {
        e.par_chunks(4096).map(|c| c.iter().map(|v| (*v as f64) * (*v as f64)).sum::<f64>()).sum()
    }

    fn gradient(&self, x: &[f64], e: &[f32]) -> Vec<f64> {
        let unit = self.unit;
        x.par_chunks(P)
            .flat_map_iter(|p| {
                let (c, r, w) = (Vec3::new(p[0] as f32, p[1] as f32, p[2] as f32), p[3], p[4]);
                let b = unit.node_box(c, SUPPORT * r as f32);
                let mut g = [0f64; P];
                if b.iter().all(|(lo, hi)| lo <= hi) {
                    let r2 = r * r;
                    for k in b[2].0..=b[2].1 {
                        for j in b[1].0..=b[1].1 {
                            for i in b[0].0..=b[0].1 {
                                let v = [i as f64 - p[0], j as f64 - p[1], k as f64 - p[2]];
                                let d2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
                                if d2 >= (SUPPORT as f64).powi(2) * r2 {
                                    continue;
                                }
                                let bv = (-d2 / r2).exp();
                                let ev = e[unit.index(i, j, k)] as f64;
                                let web = ev * w * bv;
                                for a in 0..3 {
                                    g[a] -= 4.0 * web * v[a] / r2;
                                }
                                g[3] -= 4.0 * web * d2 / (r2 * r);
                                g[4] -= 2.0 * ev * bv;
                            }
                        }
                    }
                }
                g
            })
            .collect()
    }

    fn project(&self, x: &mut [f64]) {
        for ((v, lo), hi) in x.iter_mut().zip(&self.lower).zip(&self.upper) {
            *v = v.clamp(*lo, *hi);
        }
    }
}

/// Fit `settings.count` RBFs to `density` sampled at the nodes of `lattice`;
/// returns them in lattice units (centres in node coordinates, radii in
/// cells, weights in density units; see [`Lattice::rbf_to_world`]) with the
/// fit's report. An all-zero density
/// gives no RBFs.
pub fn fit_rbfs(lattice: &Lattice, density: &[f32], settings: &FitSettings) -> (Vec<Rbf>, FitReport) {
    fit_rbfs_cancellable(lattice, density, settings, None).expect("no cancel flag")
}

/// [`fit_rbfs`], giving up (`None`) at the first iteration that finds
/// `cancel` set.
pub fn fit_rbfs_cancellable(
    lattice: &Lattice,
    density: &[f32],
    settings: &FitSettings,
    cancel: Option<&AtomicBool>,
) -> Option<(Vec<Rbf>, FitReport)> {
    let max = density.iter().copied().fold(0.0f32, f32::max);
    let norm2: f64 = density.iter().map(|v| (*v as f64).powi(2)).sum();
    if max <= 0.0 || settings.count == 0 || norm2 == 0.0 {
        return Some((
            Vec::new(),
            FitReport { relative_error: if norm2 > 0.0 { 1.0 } else { 0.0 }, history: vec![], teleports_kept: 0 },
        ));
    }
    let target: Vec<f32> = density.iter().map(|v| v / max).collect();
    let unit = Lattice { lo: Vec3::splat(-0.5), h: 1.0, n: lattice.n };
    let longest = *lattice.n.iter().max().unwrap() as f64;
    let r_min = (0.015 * longest).max(0.5);
    let r_max = (0.09 * longest).max(2.0 * r_min);
    let n = settings.count;
    let mut lower = Vec::with_capacity(n * P);
    let mut upper = Vec::with_capacity(n * P);
    for _ in 0..n {
        lower.extend_from_slice(&[0.0, 0.0, 0.0, r_min, 0.01]);
        upper.extend_from_slice(&[
            (lattice.n[0] - 1) as f64,
            (lattice.n[1] - 1) as f64,
            (lattice.n[2] - 1) as f64,
            r_max,
            1.0,
        ]);
    }
    let problem = Problem { unit, target: &target, lower, upper };
    let occupied = target.iter().filter(|v| **v > 0.01).count().max(1) as f64;
    let r0 = ((occupied / n as f64).cbrt() * 0.8).clamp(r_min, r_max);
    let mut x = initial_placement(&problem, n, r0, settings.seed);
    let mut e = problem.residual(&x);
    let mut f = Problem::objective(&e);
    let mut g = problem.gradient(&x, &e);
    let mut memory: Vec<(Vec<f64>, Vec<f64>, f64)> = Vec::new();
    let mut history = Vec::with_capacity(settings.iterations);
    let mut teleports_kept = 0;
    let target_norm2: f64 = target.iter().map(|v| (*v as f64).powi(2)).sum();
    for iteration in 0..settings.iterations {
        if cancel.is_some_and(|c| c.load(Ordering::Relaxed)) {
            return None;
        }
        if settings.teleport_every > 0 && iteration > 0 && iteration % settings.teleport_every == 0 {
            if let Some((x_new, e_new, f_new)) = teleport(&problem, &x, &e, f, (2.0 * r_min).min(r0)) {
                x = x_new;
                e = e_new;
                f = f_new;
                g = problem.gradient(&x, &e);
                memory.clear();
                teleports_kept += 1;
            }
        }
        let mut step = None;
        for attempt in 0..2 {
            let d = if attempt == 0 { two_loop(&g, &memory) } else { g.iter().map(|v| -v).collect() };
            if let Some(s) = line_search(&problem, &x, f, &g, &d, memory.is_empty() || attempt == 1) {
                step = Some(s);
                break;
            }
            memory.clear();
        }
        let Some((x_new, e_new, f_new)) = step else { break };
        let g_new = problem.gradient(&x_new, &e_new);
        let s: Vec<f64> = x_new.iter().zip(&x).map(|(a, b)| a - b).collect();
        let y: Vec<f64> = g_new.iter().zip(&g).map(|(a, b)| a - b).collect();
        let sy: f64 = s.iter().zip(&y).map(|(a, b)| a * b).sum();
        if sy > 1e-12 * norm(&s) * norm(&y) && sy > 0.0 {
            if memory.len() == 8 {
                memory.remove(0);
            }
            memory.push((s, y, 1.0 / sy));
        }
        x = x_new;
        e = e_new;
        f = f_new;
        g = g_new;
        history.push((f / target_norm2).sqrt());
    }
    let rbfs = problem.rbfs(&x).into_iter().map(|r| Rbf { weight: r.weight * max, ..r }).collect();
    Some((rbfs, FitReport { relative_error: (f / target_norm2).sqrt(), history, teleports_kept }))
}

fn norm(v: &[f64]) -> f64 {
    v.iter().map(|a| a * a).sum::<f64>().sqrt()
}

/// Centres drawn with probability proportional to the density (stratified
/// over its cumulative sum), radius `r0`, weight half the local density.
fn initial_placement(problem: &Problem, n: usize, r0: f64, seed: u64) -> Vec<f64> {
    let mut cumulative = Vec::with_capacity(problem.target.len());
    let mut total = 0.0f64;
    for v in problem.target {
        total += v.max(0.0) as f64;
        cumulative.push(total);
    }
    let mut state = seed ^ 0x9e37_79b9_7f4a_7c15;
    let mut x = Vec::with_capacity(n * P);
    for k in 0..n {
        let u = (k as f64 + unit_random(&mut state)) / n as f64 * total;
        let node = cumulative.partition_point(|c| *c < u).min(problem.target.len() - 1);
        let c = problem.unit.coords(node);
        let jitter = [0, 1, 2].map(|_| unit_random(&mut state) - 0.5);
        x.extend_from_slice(&[
            c[0] as f64 + jitter[0],
            c[1] as f64 + jitter[1],
            c[2] as f64 + jitter[2],
            r0,
            0.5 * problem.target[node] as f64,
        ]);
    }
    problem.project(&mut x);
    x
}

/// splitmix64 mapped to [0, 1).
fn unit_random(state: &mut u64) -> f64 {
    *state = state.wrapping_add(0x9e37_79b9_7f4a_7c15);
    let mut z = *state;
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^= z >> 31;
    (z >> 11) as f64 / (1u64 << 53) as f64
}

/// L-BFGS two-loop recursion: the quasi-Newton direction `-H g`.
fn two_loop(g: &[f64], memory: &[(Vec<f64>, Vec<f64>, f64)]) -> Vec<f64> {
    let mut q = g.to_vec();
    let mut alphas = vec![0.0; memory.len()];
    for (k, (s, y, rho)) in memory.iter().enumerate().rev() {
        let a = rho * s.iter().zip(&q).map(|(a, b)| a * b).sum::<f64>();
        alphas[k] = a;
        for (qi, yi) in q.iter_mut().zip(y) {
            *qi -= a * yi;
        }
    }
    if let Some((s, y, _)) = memory.last() {
        let gamma = s.iter().zip(y).map(|(a, b)| a * b).sum::<f64>() / y.iter().map(|a| a * a).sum::<f64>();
        for qi in q.iter_mut() {
            *qi *= gamma;
        }
    }
    for (k, (s, y, rho)) in memory.iter().enumerate() {
        let b = rho * y.iter().zip(&q).map(|(a, b)| a * b).sum::<f64>();
        for (qi, si) in q.iter_mut().zip(s) {
            *qi += (alphas[k] - b) * si;
        }
    }
    q.iter().map(|v| -v).collect()
}

/// Projected backtracking (Armijo) line search along `d`.
fn line_search(
    problem: &Problem,
    x: &[f64],
    f: f64,
    g: &[f64],
    d: &[f64],
    first: bool,
) -> Option<(Vec<f64>, Vec<f32>, f64)> {
    if g.iter().zip(d).map(|(a, b)| a * b).sum::<f64>() >= 0.0 {
        return None;
    }
    // Without curvature information, start with a step that moves the
    // largest coordinate by half a lattice cell.
    let mut alpha = if first { 0.5 / d.iter().fold(0.0f64, |m, v| m.max(v.abs())).max(1e-30) } else { 1.0 };
    for _ in 0..30 {
        let mut x_new: Vec<f64> = x.iter().zip(d).map(|(a, b)| a + alpha * b).collect();
        problem.project(&mut x_new);
        let decrease: f64 = g.iter().zip(x_new.iter().zip(x)).map(|(gi, (a, b))| gi * (a - b)).sum();
        if decrease < 0.0 {
            let e = problem.residual(&x_new);
            let f_new = Problem::objective(&e);
            if f_new <= f + 1e-4 * decrease {
                return Some((x_new, e, f_new));
            }
        }
        alpha *= 0.5;
    }
    None
}

/// Move the least important RBF to the node of largest positive error (with
/// a small radius `r` and the error as weight); the new state if that lowers
/// the objective.
fn teleport(problem: &Problem, x: &[f64], e: &[f32], f: f64, r: f64) -> Option<(Vec<f64>, Vec<f32>, f64)> {
    let (node, err) = e.iter().enumerate().max_by(|a, b| a.1.total_cmp(b.1))?;
    if *err <= 0.0 {
        return None;
    }
    let least =
        x.chunks(P).enumerate().min_by(|a, b| (a.1[4] * a.1[3].powi(3)).total_cmp(&(b.1[4] * b.1[3].powi(3))))?.0;
    let c = problem.unit.coords(node);
    let mut x_new = x.to_vec();
    x_new[least * P..(least + 1) * P].copy_from_slice(&[c[0] as f64, c[1] as f64, c[2] as f64, r, *err as f64]);
    problem.project(&mut x_new);
    let e_new = problem.residual(&x_new);
    let f_new = Problem::objective(&e_new);
    (f_new < f).then_some((x_new, e_new, f_new))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A density made of a few Gaussians of the same family is fitted well.
    #[test]
    fn gradient_matches_finite_differences() {
        let lattice = Lattice::over_box(Vec3::ZERO, Vec3::ONE, 12);
        let density: Vec<f32> = (0..lattice.len())
            .map(|i| {
                let p = lattice.position_of(i);
                (-(p - Vec3::splat(0.5)).length_squared() / 0.05).exp()
            })
            .collect();
        let unit = Lattice { lo: Vec3::splat(-0.5), h: 1.0, n: lattice.n };
        let problem = Problem { unit, target: &density, lower: vec![-1e9; 10], upper: vec![1e9; 10] };
        // Radii with 3r away from every node distance, so that the truncation
        // of the kernel does not put jumps into the finite differences.
        let x = vec![5.2, 6.1, 4.7, 2.3, 0.6, 7.0, 5.0, 6.0, 1.6, 0.3];
        let e = problem.residual(&x);
        let g = problem.gradient(&x, &e);
        for k in 0..10 {
            let h = 1e-3;
            let (mut xp, mut xm) = (x.clone(), x.clone());
            xp[k] += h;
            xm[k] -= h;
            let fd =
                (Problem::objective(&problem.residual(&xp)) - Problem::objective(&problem.residual(&xm))) / (2.0 * h);
            assert!((fd - g[k]).abs() < 2e-3 * (1.0 + g[k].abs()), "parameter {k}: {fd} vs {}", g[k]);
        }
    }
}
