//! Linear RGB radiometric quantities (radiance, irradiance, reflectance), as in Mitsuba 3's `*_rgb`
//! variants: no spectral upsampling, three independent channels.

use std::ops::{Add, AddAssign, Div, DivAssign, Index, Mul, MulAssign, Sub};

use crate::Vec3;

/// Rec. 709 luminance weights of R, G and B (the weights Mitsuba and the reference tools use).
pub const LUMINANCE: [f32; 3] = [0.2126, 0.7152, 0.0722];

/// The luminance of a vector given per channel (R, G, B), such as a gradient of each channel.
#[must_use]
pub fn luminance_of(channels: &[Vec3; 3]) -> Vec3 {
    channels[0] * LUMINANCE[0] + channels[1] * LUMINANCE[1] + channels[2] * LUMINANCE[2]
}

/// A linear RGB triple.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Rgb {
    /// Red.
    pub r: f32,
    /// Green.
    pub g: f32,
    /// Blue.
    pub b: f32,
}

impl Rgb {
    /// Black.
    pub const ZERO: Rgb = Rgb {
        r: 0.0,
        g: 0.0,
        b: 0.0,
    };
    /// White (1, 1, 1).
    pub const ONE: Rgb = Rgb {
        r: 1.0,
        g: 1.0,
        b: 1.0,
    };

    /// A colour from its three channels.
    #[must_use]
    pub const fn new(r: f32, g: f32, b: f32) -> Self {
        Rgb { r, g, b }
    }
    /// The same value in all three channels.
    #[must_use]
    pub const fn splat(v: f32) -> Self {
        Rgb { r: v, g: v, b: v }
    }
    /// From an array `[r, g, b]`.
    #[must_use]
    pub const fn from_array(a: [f32; 3]) -> Self {
        Rgb {
            r: a[0],
            g: a[1],
            b: a[2],
        }
    }
    /// As an array `[r, g, b]`.
    #[must_use]
    pub const fn to_array(self) -> [f32; 3] {
        [self.r, self.g, self.b]
    }
    /// Rec. 709 luminance (the weights Mitsuba and the reference tools use).
    #[must_use]
    pub fn luminance(self) -> f32 {
        LUMINANCE[0] * self.r + LUMINANCE[1] * self.g + LUMINANCE[2] * self.b
    }
    /// Largest channel.
    #[must_use]
    pub fn max_channel(self) -> f32 {
        self.r.max(self.g).max(self.b)
    }
    /// Mean of the channels.
    #[must_use]
    pub fn mean(self) -> f32 {
        (self.r + self.g + self.b) / 3.0
    }
    /// True when every channel is exactly zero.
    #[must_use]
    pub fn is_black(self) -> bool {
        self.r == 0.0 && self.g == 0.0 && self.b == 0.0
    }
    /// True when every channel is finite.
    #[must_use]
    pub fn is_finite(self) -> bool {
        self.r.is_finite() && self.g.is_finite() && self.b.is_finite()
    }
    /// True when no channel is negative and every channel is finite.
    #[must_use]
    pub fn is_valid_radiance(self) -> bool {
        self.is_finite() && self.r >= 0.0 && self.g >= 0.0 && self.b >= 0.0
    }
    /// Applies `f` to each channel.
    #[must_use]
    pub fn map(self, f: impl Fn(f32) -> f32) -> Self {
        Rgb::new(f(self.r), f(self.g), f(self.b))
    }
    /// Channel-wise exponential.
    #[must_use]
    pub fn exp(self) -> Self {
        self.map(f32::exp)
    }
    /// Channel-wise square root.
    #[must_use]
    pub fn sqrt(self) -> Self {
        self.map(f32::sqrt)
    }
    /// Channel-wise minimum.
    #[must_use]
    pub fn min(self, o: Rgb) -> Self {
        Rgb::new(self.r.min(o.r), self.g.min(o.g), self.b.min(o.b))
    }
    /// Channel-wise maximum.
    #[must_use]
    pub fn max(self, o: Rgb) -> Self {
        Rgb::new(self.r.max(o.r), self.g.max(o.g), self.b.max(o.b))
    }
}

impl Index<usize> for Rgb {
    type Output = f32;
    fn index(&self, i: usize) -> &f32 {
        match i {
            0 => &self.r,
            1 => &self.g,
            _ => &self.b,
        }
    }
}

macro_rules! binop {
    ($tr:ident, $f:ident, $tra:ident, $fa:ident, $op:tt) => {
        impl $tr for Rgb {
            type Output = Rgb;
            fn $f(self, o: Rgb) -> Rgb {
                Rgb::new(self.r $op o.r, self.g $op o.g, self.b $op o.b)
            }
        }
        impl $tr<f32> for Rgb {
            type Output = Rgb;
            fn $f(self, s: f32) -> Rgb {
                Rgb::new(self.r $op s, self.g $op s, self.b $op s)
            }
        }
        impl $tra for Rgb {
            fn $fa(&mut self, o: Rgb) {
                *self = *self $op o;
            }
        }
        impl $tra<f32> for Rgb {
            fn $fa(&mut self, s: f32) {
                *self = *self $op s;
            }
        }
    };
}
binop!(Add, add, AddAssign, add_assign, +);
binop!(Mul, mul, MulAssign, mul_assign, *);
binop!(Div, div, DivAssign, div_assign, /);

impl Sub for Rgb {
    type Output = Rgb;
    fn sub(self, o: Rgb) -> Rgb {
        Rgb::new(self.r - o.r, self.g - o.g, self.b - o.b)
    }
}

impl Mul<Rgb> for f32 {
    type Output = Rgb;
    fn mul(self, c: Rgb) -> Rgb {
        c * self
    }
}

impl std::iter::Sum for Rgb {
    fn sum<I: Iterator<Item = Rgb>>(iter: I) -> Rgb {
        iter.fold(Rgb::ZERO, |a, b| a + b)
    }
}
