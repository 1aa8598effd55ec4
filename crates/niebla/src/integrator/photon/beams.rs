//! Photon beams (Jarosz, Nowrouzezahrai, Sadeghi and Jensen 2011): the
//! stored beam segments of photon free flights, a BVH over their bounding
//! boxes, and the beam x beam crossing query of camera rays.
//!
//! Beams are "short" (the paper's section on heterogeneous media): a beam
//! runs from the start of a free flight to the real collision (absorption
//! or scattering) that ended it, or to the surface it reached, and carries
//! the photon's power at its start, constant along it. Its collision was
//! sampled by delta tracking with the photon's hero channel `h`, so the
//! beam covers a point at distance `s` with probability `T_h(s)`; weighting
//! channel `c` by `T_c(s) / T_h(s)` ([`Beam::weight`]) makes the expected
//! power at `s` exactly `Phi T_c(s)` for every channel. The ratio is 1 in
//! media whose extinction is the same in every channel and is in closed
//! form in homogeneous media; grid media with chromatic extinction are not
//! supported (see [`beams_supported`]).

use crate::color::Rgb;
use crate::math::{Ray, Vec3};
use crate::medium::Medium;
use crate::world::Scene;

/// A photon beam: a segment of a photon's free flight in a medium.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Beam {
    /// Start of the free flight (world).
    pub o: Vec3,
    /// Unit direction of travel.
    pub d: Vec3,
    /// Length to the collision or surface that ended the flight, scene units.
    pub length: f32,
    /// Flux the photon carries at the start, W per channel (already divided
    /// by the number of photons emitted).
    pub power: Rgb,
    /// Index of the medium ([`crate::medium::MediumId`]).
    pub medium: u32,
    /// The channel whose extinction sampled the flight's collisions.
    pub hero: u8,
}

impl Beam {
    /// The factor `T_c(s) / T_h(s)` per channel at distance `s` from the
    /// start, for a beam in `medium`: 1 where the extinction is grey, the
    /// closed form `exp(-(sigma_c - sigma_h) s)` in homogeneous media.
    #[inline]
    pub fn weight(&self, medium: &Medium, s: f32) -> Rgb {
        match medium {
            Medium::Homogeneous(h) => {
                let sigma = h.sigma_t();
                let hero = sigma[self.hero as usize];
                if sigma.0.iter().all(|&x| x == hero) {
                    return Rgb::ONE;
                }
                sigma.map(|x| (-(x - hero) * s).exp())
            }
            Medium::Grid(_) => Rgb::ONE,
        }
    }
}

/// Whether every medium of `scene` supports short beams: homogeneous media
/// always; grid media when their extinction per unit density is the same
/// in every channel. The first grid medium that does not, by index, as `Err`.
pub fn beams_supported(scene: &Scene) -> Result<(), u32> {
    for (i, m) in scene.media.iter().enumerate() {
        if let Medium::Grid(g) = m {
            let s = g.sigma_t();
            if !(s[0] == s[1] && s[1] == s[2]) {
                return Err(i as u32);
            }
        }
    }
    Ok(())
}

/// A piece `[s0, s1)` of beam `beam`, the unit the BVH stores (long beams
/// are cut into pieces so that boxes stay tight).
#[derive(Clone, Copy, Debug)]
struct Piece {
    beam: u32,
    s0: f32,
    s1: f32,
}

/// A BVH node: a box (pieces' boxes grown by the radius); a leaf holds
/// `count > 0` pieces from `first`, an inner node has its left child next
/// in the array and its right child at `first`.
#[derive(Clone, Copy, Debug)]
struct Node {
    min: Vec3,
    max: Vec3,
    first: u32,
    count: u32,
}

/// Most pieces in a leaf.
const LEAF: usize = 4;

/// One crossing of a camera ray with a beam piece, handed to
/// [`BeamMap::for_each_crossing`].
#[derive(Clone, Copy, Debug)]
pub enum Crossing<'a> {
    /// The lines meet at an angle with `sin theta >= min_sin`: the points
    /// of closest approach (the beam x beam 1D estimate's query).
    Line {
        /// The beam.
        beam: &'a Beam,
        /// Ray parameter of the point of the camera ray closest to the beam's line.
        t: f32,
        /// Distance along the beam of its point closest to the camera ray's line.
        s: f32,
        /// Distance between the two points (`< radius`).
        u: f32,
        /// `sin` of the angle between the ray and the beam.
        sin_theta: f32,
    },
    /// The lines are nearly parallel (`sin theta < min_sin`): the interval
    /// `[s_a, s_b)` of the piece whose points lie within the radius of the
    /// camera ray's line (distance measured perpendicular to the ray) and
    /// project onto the ray inside `[0, t_end)` (the beam x beam 2D
    /// estimate's query, a tube of the radius around the camera ray).
    Tube {
        /// The beam.
        beam: &'a Beam,
        /// Start of the interval, distance along the beam.
        s_a: f32,
        /// End of the interval (`> s_a`), distance along the beam.
        s_b: f32,
    },
}

impl Crossing<'_> {
    /// The beam crossed.
    pub fn beam(&self) -> &Beam {
        match self {
            Crossing::Line { beam, .. } | Crossing::Tube { beam, .. } => beam,
        }
    }
}

/// The interval of beam parameters `s` in `[s0, s1)` whose points
/// `o_b + s d_b` lie within `r` of the line `o + t d` (unit `d`; the
/// distance measured perpendicular to that line) and project onto it at
/// `t` in `[0, t_end)`; `None` when it is empty. Solved in `f64` from
/// cross products (`|p + s q|^2 < r^2` with `p = (o_b - o) x d`,
/// `q = d_b x d`), stable for parallel lines.
pub fn tube_interval(o: Vec3, d: Vec3, beam: &Beam, s0: f32, s1: f32, t_end: f32, r: f32) -> Option<(f32, f32)> {
    let w = beam.o - o;
    let p = w.cross(d);
    let q = beam.d.cross(d);
    let (px, py, pz) = (p.x as f64, p.y as f64, p.z as f64);
    let (qx, qy, qz) = (q.x as f64, q.y as f64, q.z as f64);
    let a = qx * qx + qy * qy + qz * qz;
    let b = px * qx + py * qy + pz * qz;
    let c = px * px + py * py + pz * pz - (r as f64) * (r as f64);
    let (mut lo, mut hi) = (s0 as f64, s1 as f64);
    // Distance: a s^2 + 2 b s + c < 0.
    if a > 0.0 {
        let disc = b * b - a * c;
        if disc <= 0.0 {
            return None;
        }
        let root = disc.sqrt();
        lo = lo.max((-b - root) / a);
        hi = hi.min((-b + root) / a);
    } else if c >= 0.0 {
        return None;
    }
    // Projection: t(s) = w.d + s (d_b.d) in [0, t_end).
    let e0 = w.dot(d) as f64;
    let k = beam.d.dot(d) as f64;
    let t_end = t_end as f64;
    if k > 0.0 {
        lo = lo.max(-e0 / k);
        hi = hi.min((t_end - e0) / k);
    } else if k < 0.0 {
        lo = lo.max((t_end - e0) / k);
        hi = hi.min(-e0 / k);
    } else if !(e0 >= 0.0 && e0 < t_end) {
        return None;
    }
    if hi > lo {
        Some((lo as f32, (hi as f32).max(lo as f32)))
    } else {
        None
    }
}

/// The beams of one pass with a BVH over their pieces, for one query radius.
#[derive(Clone, Debug, Default)]
pub struct BeamMap {
    beams: Vec<Beam>,
    pieces: Vec<Piece>,
    nodes: Vec<Node>,
    radius: f32,
}

impl BeamMap {
    /// Build the BVH over `beams` for queries of radius `radius` (> 0):
    /// beams longer than `max_piece` are cut into equal pieces no longer
    /// than it. Deterministic (median splits on the longest axis).
    pub fn build(beams: Vec<Beam>, radius: f32, max_piece: f32) -> BeamMap {
        let max_piece = if max_piece > 0.0 { max_piece } else { f32::INFINITY };
        let mut pieces = Vec::with_capacity(beams.len());
        for (i, b) in beams.iter().enumerate() {
            let n = if b.length.is_finite() { (b.length / max_piece).ceil().clamp(1.0, 1024.0) as u32 } else { 1 };
            for k in 0..n {
                let s0 = b.length * k as f32 / n as f32;
                let s1 = if k + 1 == n { b.length } else { b.length * (k + 1) as f32 / n as f32 };
                pieces.push(Piece { beam: i as u32, s0, s1 });
            }
        }
        let mut map = BeamMap { beams, pieces: Vec::new(), nodes: Vec::new(), radius };
        if pieces.is_empty() {
            return map;
        }
        let boxes: Vec<(Vec3, Vec3)> = pieces.iter().map(|p| map.piece_box(p)).collect();
        let mut order: Vec<u32> = (0..pieces.len() as u32).collect();
        map.nodes.reserve(2 * pieces.len() / LEAF + 1);
        build_node(&mut map.nodes, &boxes, &mut order, 0);
        map.pieces = order.iter().map(|&i| pieces[i as usize]).collect();
        map
    }

    /// Box of a piece grown by the radius.
    fn piece_box(&self, p: &Piece) -> (Vec3, Vec3) {
        let b = &self.beams[p.beam as usize];
        let a = b.o + b.d * p.s0;
        let c = b.o + b.d * p.s1;
        let r = Vec3::splat(self.radius);
        (a.min(c) - r, a.max(c) + r)
    }

    /// Number of beams.
    pub fn len(&self) -> usize {
        self.beams.len()
    }

    /// True when no beam is stored.
    pub fn is_empty(&self) -> bool {
        self.beams.is_empty()
    }

    /// The beams, in storage order.
    pub fn beams(&self) -> &[Beam] {
        &self.beams
    }

    /// The query radius the BVH was built for.
    pub fn radius(&self) -> f32 {
        self.radius
    }

    /// Call `f` for every beam piece near the segment `[0, t_end)` of
    /// `ray` (unit direction). Where `sin theta >= min_sin` (the angle
    /// between ray and beam) a [`Crossing::Line`]: the lines pass within
    /// the radius at their points of closest approach, `0 <= t < t_end`,
    /// the beam parameter inside the piece (each beam reported at most
    /// once). Where `sin theta < min_sin` a [`Crossing::Tube`]: the
    /// non-empty interval of the piece inside the tube of the radius
    /// around the ray (see `tube_interval`; a long beam may report one
    /// interval per piece, they do not overlap).
    pub fn for_each_crossing(&self, ray: &Ray, t_end: f32, min_sin: f32, mut f: impl FnMut(Crossing)) {
        if self.nodes.is_empty() {
            return;
        }
        let inv = Vec3::ONE / ray.d;
        let r = self.radius;
        let min_sin2 = min_sin * min_sin;
        let mut stack = [0u32; 64];
        let mut top = 1usize;
        while top > 0 {
            top -= 1;
            let node = &self.nodes[stack[top] as usize];
            if !slab_hit(ray.o, inv, node.min, node.max, t_end) {
                continue;
            }
            if node.count > 0 {
                for piece in &self.pieces[node.first as usize..(node.first + node.count) as usize] {
                    let beam = &self.beams[piece.beam as usize];
                    let sin2 = ray.d.cross(beam.d).length_squared();
                    if !(sin2 >= min_sin2 && sin2 > 0.0) {
                        if let Some((s_a, s_b)) = tube_interval(ray.o, ray.d, beam, piece.s0, piece.s1, t_end, r) {
                            f(Crossing::Tube { beam, s_a, s_b });
                        }
                        continue;
                    }
                    let w0 = ray.o - beam.o;
                    let b = ray.d.dot(beam.d);
                    let d = ray.d.dot(w0);
                    let e = beam.d.dot(w0);
                    let t = (b * e - d) / sin2;
                    let s = (e - b * d) / sin2;
                    if !(t >= 0.0 && t < t_end && s >= piece.s0 && s < piece.s1) {
                        continue;
                    }
                    let u = (w0 + ray.d * t - beam.d * s).length();
                    if u < r {
                        f(Crossing::Line { beam, t, s, u, sin_theta: sin2.sqrt() });
                    }
                }
            } else {
                let index = stack[top];
                // Inner node: left child follows it, right child at `first`.
                if top + 2 > stack.len() {
                    continue;
                }
                stack[top] = index + 1;
                stack[top + 1] = node.first;
                top += 2;
            }
        }
    }
}

/// Ray `o + t d` (`inv = 1 / d`) meets the box within `[0, t_end]`.
#[inline]
fn slab_hit(o: Vec3, inv: Vec3, min: Vec3, max: Vec3, t_end: f32) -> bool {
    let a = (min - o) * inv;
    let b = (max - o) * inv;
    // NaN (0 * inf for a ray in a box face's plane) counts as inside.
    let lo = a.min(b);
    let hi = a.max(b);
    let t0 = lo.x.max(lo.y).max(lo.z).max(0.0);
    let t1 = hi.x.min(hi.y).min(hi.z).min(t_end);
    !(t0 > t1)
}

/// Build the subtree over `order` (indices into `boxes`), whose first
/// element sits at `offset` of the final piece order; returns its node index.
fn build_node(nodes: &mut Vec<Node>, boxes: &[(Vec3, Vec3)], order: &mut [u32], offset: u32) -> u32 {
    let (mut min, mut max) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
    let (mut cmin, mut cmax) = (min, max);
    for &i in order.iter() {
        let (a, b) = boxes[i as usize];
        min = min.min(a);
        max = max.max(b);
        let c = (a + b) * 0.5;
        cmin = cmin.min(c);
        cmax = cmax.max(c);
    }
    let index = nodes.len() as u32;
    nodes.push(Node { min, max, first: offset, count: order.len() as u32 });
    if order.len() <= LEAF {
        return index;
    }
    let extent = cmax - cmin;
    let axis = if extent.x >= extent.y && extent.x >= extent.z {
        0
    } else if extent.y >= extent.z {
        1
    } else {
        2
    };
    let mid = order.len() / 2;
    let key = |i: &u32| {
        let (a, b) = boxes[*i as usize];
        (a[axis] + b[axis], *i)
    };
    order.select_nth_unstable_by(mid, |x, y| {
        let (kx, ix) = key(x);
        let (ky, iy) = key(y);
        kx.total_cmp(&ky).then(ix.cmp(&iy))
    });
    let (left, right) = order.split_at_mut(mid);
    build_node(nodes, boxes, left, offset);
    let right_index = build_node(nodes, boxes, right, offset + mid as u32);
    nodes[index as usize].count = 0;
    nodes[index as usize].first = right_index;
    index
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::{sample_uniform_sphere, PixelSampler};

    fn random_beams(n: usize, seed: u64) -> Vec<Beam> {
        let mut rng = PixelSampler::from_key(seed);
        (0..n)
            .map(|_| {
                let u = rng.next_2d();
                let v = rng.next_1d();
                Beam {
                    o: Vec3::new(u.x, u.y, v) * 4.0 - 2.0,
                    d: sample_uniform_sphere(rng.next_2d()),
                    length: rng.next_1d() * 3.0,
                    power: Rgb::ONE,
                    medium: 0,
                    hero: 0,
                }
            })
            .collect()
    }

    /// The brute-force crossings of every beam with a ray, sorted.
    fn brute(beams: &[Beam], ray: &Ray, t_end: f32, r: f32) -> Vec<(u32, f32)> {
        let mut out = Vec::new();
        for (i, beam) in beams.iter().enumerate() {
            let w0 = ray.o - beam.o;
            let b = ray.d.dot(beam.d);
            let sin2 = 1.0 - b * b;
            if !(sin2 > 1e-8) {
                continue;
            }
            let (d, e) = (ray.d.dot(w0), beam.d.dot(w0));
            let t = (b * e - d) / sin2;
            let s = (e - b * d) / sin2;
            if t >= 0.0 && t < t_end && s >= 0.0 && s < beam.length && (w0 + ray.d * t - beam.d * s).length() < r {
                out.push((i as u32, t));
            }
        }
        out.sort_by_key(|a| a.0);
        out
    }

    #[test]
    fn bvh_finds_exactly_the_brute_force_crossings() {
        let beams = random_beams(3000, 5);
        let r = 0.05;
        // Pieces of at most 0.2: long beams are cut, each crossing still reported once.
        let map = BeamMap::build(beams.clone(), r, 0.2);
        let mut rng = PixelSampler::from_key(9);
        let mut total = 0;
        for _ in 0..200 {
            let o = Vec3::new(rng.next_1d(), rng.next_1d(), rng.next_1d()) * 6.0 - 3.0;
            let ray = Ray::new(o, sample_uniform_sphere(rng.next_2d()));
            let t_end = rng.next_1d() * 6.0;
            let expected = brute(&beams, &ray, t_end, r);
            let mut found = Vec::new();
            map.for_each_crossing(&ray, t_end, 0.0, |c| {
                let Crossing::Line { beam, t, u, sin_theta, .. } = c else { panic!("no tube crossings at min_sin 0") };
                let index = (beam as *const Beam as usize - map.beams().as_ptr() as usize) / size_of::<Beam>();
                assert!(u < r && sin_theta > 0.0);
                found.push((index as u32, t));
            });
            found.sort_by_key(|a| a.0);
            assert_eq!(found.len(), expected.len());
            for (a, b) in found.iter().zip(&expected) {
                assert_eq!(a.0, b.0);
                assert!((a.1 - b.1).abs() < 1e-4);
            }
            total += found.len();
        }
        assert!(total > 100, "too few crossings to test: {total}");
    }

    #[test]
    fn empty_map_reports_nothing() {
        let map = BeamMap::build(Vec::new(), 0.1, 1.0);
        assert!(map.is_empty());
        map.for_each_crossing(&Ray::new(Vec3::ZERO, Vec3::X), 10.0, 1.0, |_| panic!("no beams"));
    }

    /// The length of the set of beam points inside the tube, by brute force
    /// (midpoint rule on a fine grid of the piece).
    fn brute_tube(ray: &Ray, beam: &Beam, s0: f32, s1: f32, t_end: f32, r: f32) -> f64 {
        let n = 200_000;
        let h = (s1 - s0) as f64 / n as f64;
        let mut inside = 0usize;
        for i in 0..n {
            let s = s0 as f64 + (i as f64 + 0.5) * h;
            let y = beam.o + beam.d * s as f32 - ray.o;
            let t = y.dot(ray.d);
            let dist2 = (y - ray.d * t).length_squared();
            if t >= 0.0 && t < t_end && dist2 < r * r {
                inside += 1;
            }
        }
        inside as f64 * h
    }

    #[test]
    fn tube_intervals_match_brute_force_lengths() {
        let mut rng = PixelSampler::from_key(17);
        let r = 0.1;
        let mut nonempty = 0;
        for k in 0..300 {
            let o = Vec3::new(rng.next_1d(), rng.next_1d(), rng.next_1d()) * 0.4 - 0.2;
            let d = sample_uniform_sphere(rng.next_2d());
            let ray = Ray::new(o, d);
            // Beams near the ray: parallel, antiparallel, slightly tilted, exactly parallel.
            let tilt = [0.0, 0.01, 0.1, 0.5][k % 4];
            let sign = if k % 8 < 4 { 1.0 } else { -1.0 };
            let bd = (d * sign + sample_uniform_sphere(rng.next_2d()) * tilt).normalize();
            let offset = Vec3::new(rng.next_1d(), rng.next_1d(), rng.next_1d()) * 0.2 - 0.1;
            let beam = Beam {
                o: o + d * (rng.next_1d() * 2.0 - 0.5) + offset,
                d: bd,
                length: rng.next_1d() * 2.0,
                power: Rgb::ONE,
                medium: 0,
                hero: 0,
            };
            let t_end = rng.next_1d() * 2.0;
            let expected = brute_tube(&ray, &beam, 0.0, beam.length, t_end, r);
            let got =
                tube_interval(ray.o, ray.d, &beam, 0.0, beam.length, t_end, r).map_or(0.0, |(a, b)| (b - a) as f64);
            assert!((got - expected).abs() < 1e-4 + 1e-4 * expected, "case {k}: {got} vs {expected}");
            if got > 0.0 {
                nonempty += 1;
            }
        }
        assert!(nonempty > 50, "too few non-empty intervals: {nonempty}");
    }

    #[test]
    fn near_parallel_beams_are_reported_as_tubes_once_per_piece() {
        let ray = Ray::new(Vec3::ZERO, Vec3::X);
        // A beam along the ray at distance 0.05, from x = 1 to 3, cut into pieces of 0.5.
        let beam = Beam { o: Vec3::new(1.0, 0.05, 0.0), d: Vec3::X, length: 2.0, power: Rgb::ONE, medium: 0, hero: 0 };
        let map = BeamMap::build(vec![beam], 0.1, 0.5);
        let mut total = 0.0;
        let mut count = 0;
        map.for_each_crossing(&ray, 2.5, 0.1, |c| {
            let Crossing::Tube { s_a, s_b, .. } = c else { panic!("parallel beams are tubes") };
            total += s_b - s_a;
            count += 1;
        });
        // Inside the tube from x = 1 to the ray's end at 2.5.
        assert_eq!(count, 3);
        assert!((total - 1.5).abs() < 1e-5, "{total}");
    }
}
