use std::ops::{Add, AddAssign, Div, DivAssign, Index, IndexMut, Mul, MulAssign, Sub};

/// Linear RGB triple (Rec.709 primaries). Used for radiance, coefficients
/// (per unit length) and throughput alike; the meaning is in the variable name.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Rgb(pub [f32; 3]);

impl Rgb {
    /// All channels zero.
    pub const ZERO: Rgb = Rgb([0.0; 3]);
    /// All channels one.
    pub const ONE: Rgb = Rgb([1.0; 3]);

    /// A triple from its channels.
    #[inline]
    pub const fn new(r: f32, g: f32, b: f32) -> Rgb {
        Rgb([r, g, b])
    }
    /// The same value in every channel.
    #[inline]
    pub const fn splat(v: f32) -> Rgb {
        Rgb([v; 3])
    }
    /// Red channel.
    #[inline]
    pub fn r(&self) -> f32 {
        self.0[0]
    }
    /// Green channel.
    #[inline]
    pub fn g(&self) -> f32 {
        self.0[1]
    }
    /// Blue channel.
    #[inline]
    pub fn b(&self) -> f32 {
        self.0[2]
    }
    /// Apply `f` to every channel.
    #[inline]
    pub fn map(self, f: impl Fn(f32) -> f32) -> Rgb {
        Rgb([f(self.0[0]), f(self.0[1]), f(self.0[2])])
    }
    /// Channel-wise `exp(-x)`: transmittance from an optical depth.
    #[inline]
    pub fn exp_neg(self) -> Rgb {
        self.map(|x| (-x).exp())
    }
    /// Largest channel.
    #[inline]
    pub fn max_channel(&self) -> f32 {
        self.0[0].max(self.0[1]).max(self.0[2])
    }
    /// Smallest channel.
    #[inline]
    pub fn min_channel(&self) -> f32 {
        self.0[0].min(self.0[1]).min(self.0[2])
    }
    /// Mean of the channels.
    #[inline]
    pub fn average(&self) -> f32 {
        (self.0[0] + self.0[1] + self.0[2]) / 3.0
    }
    /// Rec.709 luminance Y.
    #[inline]
    pub fn luminance(&self) -> f32 {
        0.2126 * self.0[0] + 0.7152 * self.0[1] + 0.0722 * self.0[2]
    }
    /// True when every channel is exactly zero.
    #[inline]
    pub fn is_black(&self) -> bool {
        self.0 == [0.0; 3]
    }
    /// True when every channel is finite.
    #[inline]
    pub fn is_finite(&self) -> bool {
        self.0.iter().all(|v| v.is_finite())
    }
    /// Channel-wise division that yields 0 where the divisor is 0.
    #[inline]
    pub fn safe_div(self, d: Rgb) -> Rgb {
        Rgb(std::array::from_fn(|i| if d.0[i] != 0.0 { self.0[i] / d.0[i] } else { 0.0 }))
    }
}

impl Index<usize> for Rgb {
    type Output = f32;
    #[inline]
    fn index(&self, i: usize) -> &f32 {
        &self.0[i]
    }
}
impl IndexMut<usize> for Rgb {
    #[inline]
    fn index_mut(&mut self, i: usize) -> &mut f32 {
        &mut self.0[i]
    }
}

macro_rules! channelwise {
    ($trait:ident, $f:ident, $assign_trait:ident, $assign_f:ident, $op:tt) => {
        impl $trait for Rgb {
            type Output = Rgb;
            #[inline]
            fn $f(self, o: Rgb) -> Rgb {
                Rgb([self.0[0] $op o.0[0], self.0[1] $op o.0[1], self.0[2] $op o.0[2]])
            }
        }
        impl $trait<f32> for Rgb {
            type Output = Rgb;
            #[inline]
            fn $f(self, o: f32) -> Rgb {
                Rgb([self.0[0] $op o, self.0[1] $op o, self.0[2] $op o])
            }
        }
        impl $assign_trait for Rgb {
            #[inline]
            fn $assign_f(&mut self, o: Rgb) {
                *self = *self $op o;
            }
        }
        impl $assign_trait<f32> for Rgb {
            #[inline]
            fn $assign_f(&mut self, o: f32) {
                *self = *self $op o;
            }
        }
    };
}
channelwise!(Add, add, AddAssign, add_assign, +);
channelwise!(Mul, mul, MulAssign, mul_assign, *);
channelwise!(Div, div, DivAssign, div_assign, /);

impl Sub for Rgb {
    type Output = Rgb;
    #[inline]
    fn sub(self, o: Rgb) -> Rgb {
        Rgb([self.0[0] - o.0[0], self.0[1] - o.0[1], self.0[2] - o.0[2]])
    }
}
impl Mul<Rgb> for f32 {
    type Output = Rgb;
    #[inline]
    fn mul(self, o: Rgb) -> Rgb {
        o * self
    }
}
