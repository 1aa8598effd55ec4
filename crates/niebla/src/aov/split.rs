//! The beauty split by path class: which layer a contribution of a path
//! tracer belongs to, and the accumulator that keeps the split.

use crate::color::Rgb;

/// What the first vertex of a camera path was.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FirstVertex {
    /// No scattering yet.
    None,
    /// A real scattering collision in a medium.
    Medium,
    /// A surface (diffuse, glass or metal).
    Surface,
}

/// The layer of a contribution (see the module documentation of `aov`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PathClass {
    /// One scattering event, in a medium.
    Direct = 0,
    /// First vertex in a medium, more than one scattering event.
    Indirect = 1,
    /// No scattering event.
    Emission = 2,
    /// First vertex on a surface.
    Surface = 3,
}

impl PathClass {
    /// The class of a contribution found after `events` scattering events
    /// on a path whose first vertex was `first`.
    ///
    /// ```
    /// use niebla::aov::{FirstVertex, PathClass};
    /// assert_eq!(PathClass::of(FirstVertex::None, 0), PathClass::Emission);
    /// assert_eq!(PathClass::of(FirstVertex::Medium, 1), PathClass::Direct);
    /// assert_eq!(PathClass::of(FirstVertex::Medium, 3), PathClass::Indirect);
    /// assert_eq!(PathClass::of(FirstVertex::Surface, 2), PathClass::Surface);
    /// ```
    #[inline]
    pub fn of(first: FirstVertex, events: u32) -> PathClass {
        match (first, events) {
            (_, 0) | (FirstVertex::None, _) => PathClass::Emission,
            (FirstVertex::Surface, _) => PathClass::Surface,
            (FirstVertex::Medium, 1) => PathClass::Direct,
            (FirstVertex::Medium, _) => PathClass::Indirect,
        }
    }
}

/// Where a path tracer adds its contributions: plain radiance ([`Rgb`],
/// the class ignored and never computed) or a [`LayerSplit`]. Generic, so
/// the plain render pays nothing for the split.
pub trait RadianceSum: Default + Copy {
    /// Add radiance `l` (W/(sr m^2)) of class `class()`.
    fn add(&mut self, l: Rgb, class: impl FnOnce() -> PathClass);
    /// Add another sum (of a path of another channel group).
    fn merge(&mut self, other: Self);
}

impl RadianceSum for Rgb {
    #[inline]
    fn add(&mut self, l: Rgb, _class: impl FnOnce() -> PathClass) {
        *self += l;
    }
    #[inline]
    fn merge(&mut self, other: Rgb) {
        *self += other;
    }
}

/// Radiance of one camera sample, in total and per [`PathClass`]
/// (indexed by the class's value). `total` is summed in the order the
/// contributions came, as the plain render sums them, so it is the beauty
/// sample bit for bit; the layers add up to it within float rounding.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LayerSplit {
    /// The beauty sample.
    pub total: Rgb,
    /// Per class: direct, indirect, emission, surface.
    pub layers: [Rgb; 4],
}

impl LayerSplit {
    /// A sample of an integrator that does not split: the total alone.
    pub fn unsplit(total: Rgb) -> LayerSplit {
        LayerSplit { total, layers: [Rgb::ZERO; 4] }
    }
}

impl RadianceSum for LayerSplit {
    #[inline]
    fn add(&mut self, l: Rgb, class: impl FnOnce() -> PathClass) {
        self.total += l;
        self.layers[class() as usize] += l;
    }
    #[inline]
    fn merge(&mut self, other: LayerSplit) {
        self.total += other.total;
        for (a, b) in self.layers.iter_mut().zip(other.layers) {
            *a += b;
        }
    }
}
