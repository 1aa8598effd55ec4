//! Multiple scattering by diffusion (Zhou et al. 2008, Section 5.4, after
//! Stam 1995, "Multiple scattering as a diffusion process"; the P1
//! diffusion approximation of the radiative transfer equation):
//! `div(kappa grad L0) - alpha L0 + S = 0`, `kappa = 1 / (3 sigma (1 - albedo g))`,
//! `alpha = sigma (1 - albedo)`, `S = sigma J0 - div(J1) / (3 (1 - albedo g))`,
//! then `L1 = 3 kappa (sigma J1 - grad L0)` (propagation convention), turned
//! into an order-2 SH source `J_ms = albedo (L0, g L1)` in the arriving
//! convention.
//!
//! **Ours, not the paper's discretization:** the paper collocates the
//! equation at the RBF centres and solves by least squares. Collocation at
//! the centres alone carries no boundary condition (the uniform
//! `L0 = J0 / (1 - albedo)` satisfies every row however small the cloud), so
//! this solves the same equation by finite volumes on the lattice over the
//! RBF approximation `D~` (Stam's grid variant of the same equation), with a zero-incoming-flux (Marshak) condition
//! `-kappa dL0/dn = L0 / 2` on the faces where the medium ends (lattice nodes
//! with `D~` below 1e-3 of its maximum, and the lattice boundary). Light
//! thereby leaves the cloud through its surface. Solved by Jacobi-
//! preconditioned conjugate gradients (the operator is symmetric positive
//! definite).

use super::lattice::Lattice;

/// Per lattice node: `J0` (mean single-scattering source radiance) and
/// `J1` (its first moment, propagation convention, x y z), one channel.
pub struct DiffusionSource<'a> {
    /// `J0` per node.
    pub j0: &'a [f64],
    /// `J1` per node (3 per node).
    pub j1: &'a [f64],
}

/// Result: `L0` and `L1` (propagation convention) per node of one channel.
pub struct DiffusionSolution {
    /// Mean radiance `L0` (W/(sr m^2)) per node; 0 outside the medium.
    pub l0: Vec<f64>,
    /// Flux vector `L1` per node (3 per node).
    pub l1: Vec<f64>,
    /// Conjugate-gradient iterations used.
    pub iterations: usize,
}

/// Solve for one channel. `sigma` is the extinction per node (1/length),
/// `albedo` and `g` (mean cosine) uniform.
pub fn solve(lattice: &Lattice, sigma: &[f64], albedo: f64, g: f64, source: &DiffusionSource) -> DiffusionSolution {
    let nodes = lattice.len();
    let h = lattice.h as f64;
    let max_sigma = sigma.iter().copied().fold(0.0, f64::max);
    let inside: Vec<bool> = sigma.iter().map(|s| *s > 1e-3 * max_sigma && *s > 0.0).collect();
    let reduced = (1.0 - albedo * g).max(1e-6);
    let kappa: Vec<f64> = sigma.iter().map(|s| if *s > 0.0 { 1.0 / (3.0 * s * reduced) } else { 0.0 }).collect();
    let alpha: Vec<f64> = sigma.iter().map(|s| s * (1.0 - albedo).max(0.0)).collect();
    let neighbours = |node: usize| -> [Option<usize>; 6] {
        let [i, j, k] = lattice.coords(node);
        let n = lattice.n;
        [
            (i > 0).then(|| lattice.index(i - 1, j, k)),
            (i + 1 < n[0]).then(|| lattice.index(i + 1, j, k)),
            (j > 0).then(|| lattice.index(i, j - 1, k)),
            (j + 1 < n[1]).then(|| lattice.index(i, j + 1, k)),
            (k > 0).then(|| lattice.index(i, j, k - 1)),
            (k + 1 < n[2]).then(|| lattice.index(i, j, k + 1)),
        ]
    };
    // Matrix: diagonal and the six couplings per node.
    let mut diagonal = vec![1.0; nodes];
    let mut coupling = vec![[0.0f64; 6]; nodes];
    let mut rhs = vec![0.0; nodes];
    for node in 0..nodes {
        if !inside[node] {
            continue;
        }
        let mut d = alpha[node];
        for (f, nb) in neighbours(node).iter().enumerate() {
            match nb {
                Some(m) if inside[*m] => {
                    let kf = 2.0 * kappa[node] * kappa[*m] / (kappa[node] + kappa[*m]);
                    coupling[node][f] = kf / (h * h);
                    d += kf / (h * h);
                }
                _ => d += 4.0 * kappa[node] / (4.0 * kappa[node] + h) / (2.0 * h),
            }
        }
        diagonal[node] = d;
        // Source: sigma J0 - div(J1) / (3 (1 - albedo g)), central differences.
        let nb = neighbours(node);
        let mut div = 0.0;
        for axis in 0..3 {
            let value = |m: Option<usize>| m.map(|m| source.j1[3 * m + axis]);
            let here = source.j1[3 * node + axis];
            div += match (value(nb[2 * axis]), value(nb[2 * axis + 1])) {
                (Some(a), Some(b)) => (b - a) / (2.0 * h),
                (None, Some(b)) => (b - here) / h,
                (Some(a), None) => (here - a) / h,
                (None, None) => 0.0,
            };
        }
        rhs[node] = sigma[node] * source.j0[node] - div / (3.0 * reduced);
    }
    let apply = |x: &[f64], out: &mut [f64]| {
        use rayon::prelude::*;
        out.par_iter_mut().enumerate().with_min_len(1024).for_each(|(node, o)| {
            if !inside[node] {
                *o = x[node];
                return;
            }
            let mut v = diagonal[node] * x[node];
            for (f, nb) in neighbours(node).iter().enumerate() {
                if let Some(m) = nb {
                    v -= coupling[node][f] * x[*m];
                }
            }
            *o = v;
        });
    };
    let (l0, iterations) = conjugate_gradient(&apply, &rhs, &diagonal, 1e-7, 5000);
    // L1 = 3 kappa (sigma J1 - grad L0); one-sided differences at the edge.
    let mut l1 = vec![0.0; 3 * nodes];
    for node in 0..nodes {
        if !inside[node] {
            continue;
        }
        let nb = neighbours(node);
        for axis in 0..3 {
            let value = |m: Option<usize>| m.filter(|m| inside[*m]).map(|m| l0[m]);
            let here = l0[node];
            let grad = match (value(nb[2 * axis]), value(nb[2 * axis + 1])) {
                (Some(a), Some(b)) => (b - a) / (2.0 * h),
                (None, Some(b)) => (b - here) / h,
                (Some(a), None) => (here - a) / h,
                (None, None) => 0.0,
            };
            l1[3 * node + axis] = 3.0 * kappa[node] * (sigma[node] * source.j1[3 * node + axis] - grad);
        }
    }
    let l0 = l0.into_iter().zip(&inside).map(|(v, i)| if *i { v.max(0.0) } else { 0.0 }).collect();
    DiffusionSolution { l0, l1, iterations }
}

/// Jacobi-preconditioned conjugate gradients for a symmetric positive
/// definite operator; stops at relative residual `tolerance`.
fn conjugate_gradient(
    apply: &dyn Fn(&[f64], &mut [f64]),
    b: &[f64],
    diagonal: &[f64],
    tolerance: f64,
    max_iterations: usize,
) -> (Vec<f64>, usize) {
    let n = b.len();
    let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
    let b_norm = dot(b, b).sqrt();
    let mut x: Vec<f64> = b.iter().zip(diagonal).map(|(b, d)| b / d).collect();
    if b_norm == 0.0 {
        return (vec![0.0; n], 0);
    }
    let mut ax = vec![0.0; n];
    apply(&x, &mut ax);
    let mut r: Vec<f64> = b.iter().zip(&ax).map(|(b, a)| b - a).collect();
    let mut z: Vec<f64> = r.iter().zip(diagonal).map(|(r, d)| r / d).collect();
    let mut p = z.clone();
    let mut rz = dot(&r, &z);
    let mut ap = vec![0.0; n];
    for iteration in 0..max_iterations {
        if dot(&r, &r).sqrt() <= tolerance * b_norm {
            return (x, iteration);
        }
        apply(&p, &mut ap);
        let pap = dot(&p, &ap);
        if pap <= 0.0 {
            return (x, iteration);
        }
        let a = rz / pap;
        for k in 0..n {
            x[k] += a * p[k];
            r[k] -= a * ap[k];
            z[k] = r[k] / diagonal[k];
        }
        let rz_new = dot(&r, &z);
        let beta = rz_new / rz;
        rz = rz_new;
        for k in 0..n {
            p[k] = z[k] + beta * p[k];
        }
    }
    (x, max_iterations)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Vec3;

    /// T5: a large uniform medium with a uniform source: the interior
    /// approaches the infinite-medium value `J0 / (1 - albedo)`; light leaks
    /// at the boundary (Marshak), so the edge is darker.
    #[test]
    fn uniform_medium_reaches_the_infinite_medium_value_inside() {
        let lattice = Lattice::over_box(Vec3::ZERO, Vec3::splat(1.0), 40);
        let n = lattice.len();
        // sigma 60 per unit: 60 mean free paths across; diffusion length ~0.014.
        let sigma = vec![60.0; n];
        let (albedo, g) = (0.5, 0.3);
        let j0 = vec![2.0; n];
        let j1 = vec![0.0; 3 * n];
        let s = solve(&lattice, &sigma, albedo, g, &DiffusionSource { j0: &j0, j1: &j1 });
        let centre = s.l0[lattice.index(20, 20, 20)];
        assert!((centre - 2.0 / (1.0 - albedo)).abs() < 0.01 * 4.0, "centre {centre}");
        let edge = s.l0[lattice.index(0, 20, 20)];
        assert!(edge < 0.95 * centre, "edge {edge} centre {centre}");
        // Flux at the edge points outward (-x).
        assert!(s.l1[3 * lattice.index(0, 20, 20)] < 0.0);
    }
}
