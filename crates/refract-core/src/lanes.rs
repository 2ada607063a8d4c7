//! Eight pixels at a time: structure-of-arrays vectors over `wide::f32x8`, the lane types of
//! [`crate::real`] (whose traits give them their arithmetic: `dot`, `cross`, `select`, ...).
//!
//! A pixel of the two-interface kernel is a chain of ~20 dependent square roots, divisions and
//! polynomials: one pixel at a time the CPU mostly waits. Eight independent pixels per
//! instruction keep its pipelines full. Every operation here performs exactly the IEEE
//! operations of its glam counterpart in the same order, so a lane computes the same bits as the
//! scalar code.

use core::ops::{Add, Mul, Neg, Sub};

use glam::{Vec2, Vec3};
use wide::f32x8;

/// The number of lanes.
pub const LANES: usize = 8;

/// Eight `f32` lanes.
pub type F32x8 = f32x8;

/// A lane mask: all bits set where true (as `wide`'s comparisons return).
pub type Mask = f32x8;

/// Eight `i32` lanes (texel and patch indices).
pub type I32x8 = wide::i32x8;

/// Eight 3D vectors, one per lane.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Vec3x8 {
    /// The `x` components.
    pub x: F32x8,
    /// The `y` components.
    pub y: F32x8,
    /// The `z` components.
    pub z: F32x8,
}

impl Vec3x8 {
    /// All lanes zero.
    pub const ZERO: Self = Self::splat(Vec3::ZERO);

    /// The same vector in every lane.
    #[inline]
    pub const fn splat(v: Vec3) -> Self {
        Self {
            x: F32x8::splat(v.x),
            y: F32x8::splat(v.y),
            z: F32x8::splat(v.z),
        }
    }

    /// Lane `i` of each array.
    #[inline]
    pub fn from_lanes(lanes: &[Vec3; LANES]) -> Self {
        // Plain loops: `array::map`/`from_fn` are not always inlined, and these run per pixel.
        let (mut x, mut y, mut z) = ([0.0; LANES], [0.0; LANES], [0.0; LANES]);
        for (i, v) in lanes.iter().enumerate() {
            (x[i], y[i], z[i]) = (v.x, v.y, v.z);
        }
        Self {
            x: F32x8::new(x),
            y: F32x8::new(y),
            z: F32x8::new(z),
        }
    }

    /// The vector of each lane.
    #[inline]
    pub fn to_lanes(self) -> [Vec3; LANES] {
        let (x, y, z) = (self.x.to_array(), self.y.to_array(), self.z.to_array());
        let mut lanes = [Vec3::ZERO; LANES];
        for (i, v) in lanes.iter_mut().enumerate() {
            *v = Vec3::new(x[i], y[i], z[i]);
        }
        lanes
    }

    /// The vector of lane `i` (`i < LANES`).
    #[inline]
    pub fn lane(self, i: usize) -> Vec3 {
        Vec3::new(
            self.x.to_array()[i],
            self.y.to_array()[i],
            self.z.to_array()[i],
        )
    }
}

/// Component by component, as glam's `Vec3` operators: `+`, `-` and `*` of two vectors.
macro_rules! componentwise {
    ($($trait:ident $method:ident),*) => {$(
        impl $trait for Vec3x8 {
            type Output = Self;
            #[inline]
            fn $method(self, rhs: Self) -> Self {
                Self {
                    x: self.x.$method(rhs.x),
                    y: self.y.$method(rhs.y),
                    z: self.z.$method(rhs.z),
                }
            }
        }
    )*};
}

componentwise!(Add add, Sub sub, Mul mul);

impl Neg for Vec3x8 {
    type Output = Self;
    #[inline]
    fn neg(self) -> Self {
        Self {
            x: -self.x,
            y: -self.y,
            z: -self.z,
        }
    }
}

/// Scales each lane's vector by that lane's scalar.
impl Mul<F32x8> for Vec3x8 {
    type Output = Self;
    #[inline]
    fn mul(self, s: F32x8) -> Self {
        Self {
            x: self.x * s,
            y: self.y * s,
            z: self.z * s,
        }
    }
}

/// Scales each lane's vector by that lane's scalar.
impl Mul<Vec3x8> for F32x8 {
    type Output = Vec3x8;
    #[inline]
    fn mul(self, v: Vec3x8) -> Vec3x8 {
        v * self
    }
}

/// Eight 2D points, one per lane.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Vec2x8 {
    /// The `x` components.
    pub x: F32x8,
    /// The `y` components.
    pub y: F32x8,
}

impl Vec2x8 {
    /// Lane `i` of each array.
    #[inline]
    pub fn from_lanes(lanes: &[Vec2; LANES]) -> Self {
        let (mut x, mut y) = ([0.0; LANES], [0.0; LANES]);
        for (i, v) in lanes.iter().enumerate() {
            (x[i], y[i]) = (v.x, v.y);
        }
        Self {
            x: F32x8::new(x),
            y: F32x8::new(y),
        }
    }

    /// The same point in every lane.
    #[inline]
    pub const fn splat(v: Vec2) -> Self {
        Self {
            x: F32x8::splat(v.x),
            y: F32x8::splat(v.y),
        }
    }

    /// Each lane's point.
    #[inline]
    pub fn to_lanes(self) -> [Vec2; LANES] {
        let (x, y) = (self.x.to_array(), self.y.to_array());
        let mut lanes = [Vec2::ZERO; LANES];
        for (i, lane) in lanes.iter_mut().enumerate() {
            *lane = Vec2::new(x[i], y[i]);
        }
        lanes
    }
}

/// The lanes of a mask as booleans.
#[inline]
pub fn mask_lanes(mask: Mask) -> [bool; LANES] {
    let bits = mask.to_bitmask();
    let mut lanes = [false; LANES];
    for (i, lane) in lanes.iter_mut().enumerate() {
        *lane = bits & (1 << i) != 0;
    }
    lanes
}

/// A mask from booleans.
#[inline]
pub fn mask_from_lanes(lanes: [bool; LANES]) -> Mask {
    let mut bits = [0.0; LANES];
    for (bit, lane) in bits.iter_mut().zip(lanes) {
        *bit = if lane { f32::from_bits(u32::MAX) } else { 0.0 };
    }
    F32x8::new(bits)
}
