//! Exact per-pixel sums of the layers' samples (the fixed point of
//! `film::sums`, so passes, checkpoints and resumes add up bit for bit)
//! and the layer images made from them.

use crate::color::Rgb;
use crate::film::{mean_of_sum, quantize_sample, SampleSums, FRACTION_BITS};
use crate::math::Vec3;

use super::features::Features;
use super::{Aov, AovSet, LayerSplit};

/// One stored channel of the layer sums.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AovChannel {
    /// `1 - transmittance`.
    Alpha,
    /// Channel `c` of split layer `class` (0 direct, 1 indirect, 2 emission, 3 surface).
    Split(usize, usize),
    /// Channel `c` of the albedo.
    Albedo(usize),
    /// Component `c` of the normal.
    Normal(usize),
    /// Distance to the first collision or surface (0 where none).
    DepthSum,
    /// 1 where the ray met a collision or surface.
    Coverage,
    /// Square of channel `c` of the beauty sample.
    Square(usize),
}

impl AovChannel {
    /// The channel's name in checkpoints (`niebla.aovsum.NAME.WORD`).
    pub fn name(self) -> String {
        const RGB: [&str; 3] = ["R", "G", "B"];
        match self {
            AovChannel::Alpha => "A".into(),
            AovChannel::Split(l, c) => format!("{}.{}", ["direct", "indirect", "emission", "surface"][l], RGB[c]),
            AovChannel::Albedo(c) => format!("albedo.{}", RGB[c]),
            AovChannel::Normal(c) => format!("normal.{}", ["X", "Y", "Z"][c]),
            AovChannel::DepthSum => "depth.Z".into(),
            AovChannel::Coverage => "coverage".into(),
            AovChannel::Square(c) => format!("square.{}", RGB[c]),
        }
    }

    /// The channel's value in one sample.
    #[inline]
    fn value(self, s: &AovSample) -> f32 {
        match self {
            AovChannel::Alpha => 1.0 - s.features.transmittance,
            AovChannel::Split(l, c) => s.split.layers[l][c],
            AovChannel::Albedo(c) => s.features.albedo[c],
            AovChannel::Normal(c) => s.features.normal[c],
            AovChannel::DepthSum => s.features.depth,
            AovChannel::Coverage => s.features.coverage,
            AovChannel::Square(c) => s.split.total[c] * s.split.total[c],
        }
    }
}

/// Everything one camera sample gives the layers.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct AovSample {
    /// The beauty sample and its split.
    pub split: LayerSplit,
    /// What the camera ray met first.
    pub features: Features,
}

/// Per-pixel fixed-point sums of the stored channels of a set of layers.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct AovSums {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// The layers these sums serve.
    pub set: AovSet,
    /// The stored channels ([`AovSums::channels_for`] of `set`).
    pub channels: Vec<AovChannel>,
    /// Sums, `values[pixel * channels.len() + k]`, units of 2^-60.
    pub values: Vec<i128>,
}

impl AovSums {
    /// The channels stored for `set`, in a fixed order.
    pub fn channels_for(set: AovSet) -> Vec<AovChannel> {
        let mut out = Vec::new();
        for aov in set.iter() {
            match aov {
                Aov::Alpha => out.push(AovChannel::Alpha),
                Aov::Direct | Aov::Indirect | Aov::Emission | Aov::Surface => {
                    let l = aov as usize - Aov::Direct as usize;
                    out.extend((0..3).map(|c| AovChannel::Split(l, c)));
                }
                Aov::Albedo => out.extend((0..3).map(AovChannel::Albedo)),
                Aov::Normal => out.extend((0..3).map(AovChannel::Normal)),
                Aov::Depth => out.extend([AovChannel::DepthSum, AovChannel::Coverage]),
                Aov::Variance => out.extend((0..3).map(AovChannel::Square)),
            }
        }
        out
    }

    /// All sums zero.
    pub fn new(width: u32, height: u32, set: AovSet) -> AovSums {
        let channels = AovSums::channels_for(set);
        let values = vec![0; width as usize * height as usize * channels.len()];
        AovSums { width, height, set, channels, values }
    }

    /// Add the quantized channels of `sample` to the `k` sums in `out`.
    #[inline]
    pub fn accumulate(channels: &[AovChannel], sample: &AovSample, out: &mut [i128]) {
        for (sum, ch) in out.iter_mut().zip(channels) {
            *sum += quantize_sample(ch.value(sample));
        }
    }

    /// Adds the sums of another sample range (exact, in any order).
    ///
    /// # Panics
    /// If the sizes or layer sets differ.
    pub fn add(&mut self, other: &AovSums) {
        assert_eq!((self.width, self.height, self.set), (other.width, other.height, other.set), "different layer sums");
        for (a, b) in self.values.iter_mut().zip(&other.values) {
            *a += b;
        }
    }

    /// The sum of channel `ch` at pixel `i`, if stored.
    fn get(&self, i: usize, ch: AovChannel) -> Option<i128> {
        let k = self.channels.iter().position(|&c| c == ch)?;
        Some(self.values[i * self.channels.len() + k])
    }

    /// The layer images of `n` samples per pixel, with `beauty` the sums of
    /// the same samples' beauty.
    pub fn layers(&self, beauty: &SampleSums, n: u64) -> AovImage {
        let pixels = self.width as usize * self.height as usize;
        let mut layers = Vec::new();
        for aov in self.set.iter() {
            let components = match aov {
                Aov::Alpha | Aov::Depth => 1,
                _ => 3,
            };
            let mut data = Vec::with_capacity(pixels * components);
            for i in 0..pixels {
                let mean = |ch| mean_of_sum(self.get(i, ch).unwrap_or(0), n);
                match aov {
                    Aov::Alpha => data.push(mean(AovChannel::Alpha)),
                    Aov::Direct | Aov::Indirect | Aov::Emission | Aov::Surface => {
                        let l = aov as usize - Aov::Direct as usize;
                        data.extend((0..3).map(|c| mean(AovChannel::Split(l, c))));
                    }
                    Aov::Albedo => data.extend((0..3).map(|c| mean(AovChannel::Albedo(c)))),
                    Aov::Normal => data.extend((0..3).map(|c| mean(AovChannel::Normal(c)))),
                    Aov::Depth => {
                        let hits = self.get(i, AovChannel::Coverage).unwrap_or(0);
                        let depth = self.get(i, AovChannel::DepthSum).unwrap_or(0);
                        data.push(if hits > 0 { (depth as f64 / hits as f64) as f32 } else { 0.0 });
                    }
                    Aov::Variance => {
                        for c in 0..3 {
                            let square = self.get(i, AovChannel::Square(c)).unwrap_or(0);
                            data.push(variance_of_mean(beauty.sums[i][c], square, n));
                        }
                    }
                }
            }
            layers.push(AovLayer { aov, components, data });
        }
        AovImage { width: self.width, height: self.height, layers }
    }
}

/// Variance of the mean of `n` samples whose fixed-point sum is `sum` and
/// sum of squares `square`: `(square - n mean^2) / (n (n - 1))`, at least 0;
/// 0 for fewer than two samples.
pub fn variance_of_mean(sum: i128, square: i128, n: u64) -> f32 {
    if n < 2 {
        return 0.0;
    }
    let scale = (2f64).powi(-FRACTION_BITS);
    let (n, s, q) = (n as f64, sum as f64 * scale, square as f64 * scale);
    let mean = s / n;
    ((q - n * mean * mean) / (n * (n - 1.0))).max(0.0) as f32
}

/// One layer image: `components` floats per pixel, row-major from the top.
#[derive(Clone, Debug, PartialEq)]
pub struct AovLayer {
    /// Which layer.
    pub aov: Aov,
    /// Floats per pixel: 1 (alpha, depth) or 3.
    pub components: usize,
    /// `data[pixel * components + c]`.
    pub data: Vec<f32>,
}

impl AovLayer {
    /// The EXR channel names of the layer: `A` for alpha, `depth.Z`,
    /// `normal.X/Y/Z`, else `NAME.R/G/B`.
    pub fn channel_names(&self) -> Vec<String> {
        match self.aov {
            Aov::Alpha => vec!["A".into()],
            Aov::Depth => vec!["depth.Z".into()],
            Aov::Normal => ["X", "Y", "Z"].iter().map(|c| format!("normal.{c}")).collect(),
            a => ["R", "G", "B"].iter().map(|c| format!("{}.{c}", a.name())).collect(),
        }
    }

    /// The value of component `c` of pixel `i` as RGB (for 3-component layers).
    pub fn rgb(&self, i: usize) -> Rgb {
        let k = i * self.components;
        Rgb::new(self.data[k], self.data[k + 1], self.data[k + 2])
    }

    /// A normal layer's value at pixel `i` as a vector.
    pub fn vec3(&self, i: usize) -> Vec3 {
        let k = i * self.components;
        Vec3::new(self.data[k], self.data[k + 1], self.data[k + 2])
    }
}

/// The layer images of a render.
#[derive(Clone, Debug, PartialEq)]
pub struct AovImage {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// The layers, in [`Aov::ALL`]'s order.
    pub layers: Vec<AovLayer>,
}

impl AovImage {
    /// The layer `aov`, if rendered.
    pub fn get(&self, aov: Aov) -> Option<&AovLayer> {
        self.layers.iter().find(|l| l.aov == aov)
    }
}
