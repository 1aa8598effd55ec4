//! Channel grouping: which RGB channels one `volpath` path traces together.
//!
//! Channels whose medium coefficients differ by more than
//! [`MAX_SHARED_RATIO`] are traced by separate paths, one per group of
//! similar channels, each with its hero and spectral MIS over its group only:
//! a path sampled for a thick channel serves a much thinner one poorly (its
//! nearly constant estimate turns bimodal), which spectral MIS cannot repair.
//! Grey media keep a single path.

use crate::color::Rgb;
use crate::medium::Medium;
use crate::world::Scene;

/// A set of RGB channels traced together by one path.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct Channels(u8);

impl Channels {
    pub(super) const ALL: Channels = Channels(0b111);

    #[inline]
    pub(super) fn contains(self, c: usize) -> bool {
        self.0 & (1 << c) != 0
    }

    #[inline]
    pub(super) fn len(self) -> usize {
        self.0.count_ones() as usize
    }

    /// The `k`-th channel of the set.
    #[inline]
    pub(super) fn nth(self, k: usize) -> usize {
        (0..3).filter(|&c| self.contains(c)).nth(k).unwrap_or(0)
    }

    /// 1 in the set's channels, 0 elsewhere.
    #[inline]
    pub(super) fn indicator(self) -> Rgb {
        per_channel(|c| if self.contains(c) { 1.0 } else { 0.0 })
    }

    /// Mean over the set's channels.
    #[inline]
    pub(super) fn average(self, x: Rgb) -> f32 {
        if self == Channels::ALL {
            return x.average();
        }
        (0..3).filter(|&c| self.contains(c)).map(|c| x[c]).sum::<f32>() / self.len() as f32
    }
}

/// Largest ratio between two channels' extinction (or scattering)
/// coefficients in some medium for them to share a path: beyond it, one path
/// sampled for either channel serves the other poorly.
const MAX_SHARED_RATIO: f32 = 3.0;

/// The channel groups traced by separate paths (at most three, `count` of
/// them used): channels whose coefficients
/// are within [`MAX_SHARED_RATIO`] of each other in every medium share one
/// (grey media: one group of all three).
pub(super) fn channel_groups(scene: &Scene) -> ([Channels; 3], usize) {
    groups_for(scene.media.iter().map(|m| match m {
        Medium::Homogeneous(h) => (h.sigma_s, h.sigma_t()),
        // With an albedo field, its largest value per channel.
        Medium::Grid(g) => (g.albedo.as_ref().map_or(g.sigma_s, |a| g.sigma_t() * a.max_value()), g.sigma_t()),
    }))
}

/// [`channel_groups`] for media given by `(sigma_s, sigma_t)` (per unit density).
fn groups_for(media: impl Iterator<Item = (Rgb, Rgb)>) -> ([Channels; 3], usize) {
    let mut compatible = [[true; 3]; 3];
    for (sigma_s, sigma_t) in media {
        for coefficients in [sigma_s, sigma_t] {
            let scale = coefficients.max_channel();
            for i in 0..3 {
                for j in 0..3 {
                    let (lo, hi) = (coefficients[i].min(coefficients[j]), coefficients[i].max(coefficients[j]));
                    if hi > MAX_SHARED_RATIO * lo + 1e-3 * scale {
                        compatible[i][j] = false;
                    }
                }
            }
        }
    }
    let mut groups = [Channels(0); 3];
    let mut count = 0;
    let mut assigned = 0u8;
    for i in 0..3 {
        if assigned & (1 << i) != 0 {
            continue;
        }
        // Channels compatible with a member join the group (transitively).
        let mut members = 1u8 << i;
        for _ in 0..2 {
            for (k, row) in compatible.iter().enumerate() {
                if members & (1 << k) != 0 {
                    for (j, &ok) in row.iter().enumerate() {
                        if ok {
                            members |= 1 << j;
                        }
                    }
                }
            }
        }
        assigned |= members;
        groups[count] = Channels(members);
        count += 1;
    }
    (groups, count)
}

/// The colour whose channel `c` is `f(c)`.
#[inline]
pub(super) fn per_channel(f: impl Fn(usize) -> f32) -> Rgb {
    Rgb::new(f(0), f(1), f(2))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn groups(media: &[(Rgb, Rgb)]) -> Vec<u8> {
        let (g, n) = groups_for(media.iter().copied());
        g[..n].iter().map(|c| c.0).collect()
    }

    #[test]
    fn channel_groups_split_only_dissimilar_channels() {
        // No media, grey media, a spread within the ratio: one path.
        assert_eq!(groups(&[]), vec![0b111]);
        assert_eq!(groups(&[(Rgb::splat(0.9), Rgb::splat(1.0))]), vec![0b111]);
        assert_eq!(groups(&[(Rgb::new(1.8, 2.7, 4.5), Rgb::new(2.0, 3.0, 5.0))]), vec![0b111]);
        // Tenfold spread: red alone, green with blue.
        assert_eq!(groups(&[(Rgb::new(0.4, 2.0, 4.0), Rgb::new(0.44, 2.2, 4.4))]), vec![0b001, 0b110]);
        // Similar extinction but very different albedo also splits.
        assert_eq!(groups(&[(Rgb::new(1.0, 1.0, 0.1), Rgb::splat(1.0))]), vec![0b011, 0b100]);
        // Compatibility is transitive within a group, over all media.
        assert_eq!(
            groups(&[(Rgb::splat(1.0), Rgb::splat(1.0)), (Rgb::new(1.0, 2.5, 6.0), Rgb::new(1.0, 2.5, 6.0))]),
            vec![0b111]
        );
        assert_eq!(groups(&[(Rgb::new(1.0, 20.0, 400.0), Rgb::new(1.0, 20.0, 400.0))]), vec![0b001, 0b010, 0b100]);
        let all: Vec<usize> = (0..3).map(|k| Channels::ALL.nth(k)).collect();
        assert_eq!(all, vec![0, 1, 2]);
        assert_eq!(Channels(0b110).nth(0), 1);
        assert_eq!(Channels(0b110).average(Rgb::new(9.0, 1.0, 3.0)), 2.0);
    }
}
