//! The number types every per-pixel leaf is written over, once: [`Real`] (a real number with
//! its [`LaneMask`]) and [`Vector3`] (a 3-vector over it), implemented for `f32`/[`Vec3`] (one
//! pixel; the mask is `bool`) and for the eight-lane [`F32x8`]/[`Vec3x8`] of [`crate::lanes`].
//!
//! A leaf such as [`crate::optics::refract`] is one generic body: called with glam types it is
//! the scalar function, with lanes the SIMD one. Where scalar code would branch, a leaf selects
//! ([`Real::select`], as Mitsuba 3's `dr::select`), and it may skip work that no lane needs with
//! [`LaneMask::all`] / [`LaneMask::any`] (for one pixel, the branch itself). Each operation performs
//! exactly the IEEE operations of its glam/`f32` counterpart in the same order (`dot =
//! (x·x' + y·y') + z·z'`, `1/√(v·v)` as a division), so a lane computes the bits the scalar
//! function computes for that pixel; `tests/properties.rs` and the lane kernels' tests hold them
//! to it.
//!
//! Rare cases that take a different algorithm (a vector too long for the one-division
//! normalisation, say) are computed lane by lane with [`Vector3::lane`] /
//! [`Vector3::set_lane`] over [`LaneMask::lanes`].

use core::ops::{Add, BitAnd, BitOr, Div, Mul, Neg, Not, Sub};

use glam::{Mat4, Vec3};

use crate::lanes::{F32x8, LANES, Vec3x8, mask_from_lanes, mask_lanes};

/// A lane mask: `bool` for one pixel, a SIMD mask for eight.
pub trait LaneMask:
    Copy
    + core::fmt::Debug
    + PartialEq
    + BitAnd<Output = Self>
    + BitOr<Output = Self>
    + Not<Output = Self>
{
    /// The same truth value in every lane.
    fn splat(value: bool) -> Self;
    /// Every lane set.
    fn all(self) -> bool;
    /// Some lane set.
    fn any(self) -> bool;
    /// Each lane's truth value, lane 0 first (`LANES` of the real type; one for `bool`).
    fn lanes(self) -> impl Iterator<Item = bool>;
    /// Sets lane `i` to `value`.
    fn set(&mut self, i: usize, value: bool);
    /// Bit `i` set where lane `i` is.
    fn bits(self) -> u32;
}

/// A real number, one per lane.
pub trait Real:
    Copy
    + core::fmt::Debug
    + PartialEq
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
{
    /// The mask that comparisons of this type return.
    type Mask: LaneMask;
    /// The lanes as an array (`[f32; 1]` or `[f32; 8]`).
    type Array: AsRef<[f32]>;
    /// The number of lanes.
    const LANES: usize;
    /// `0` in every lane.
    const ZERO: Self;
    /// `1` in every lane.
    const ONE: Self;
    /// `v` in every lane.
    fn splat(v: f32) -> Self;
    /// Every lane's value (to read several lanes one by one: one store, not one per lane).
    fn to_lane_array(self) -> Self::Array;
    /// `√x` (IEEE, correctly rounded).
    fn sqrt(self) -> Self;
    /// `|x|`.
    fn abs(self) -> Self;
    /// `⌊x⌋`.
    fn floor(self) -> Self;
    /// `x` rounded toward zero.
    fn trunc(self) -> Self;
    /// `f` of each lane (for the functions without a lane form, such as `sin`).
    fn map(self, f: impl FnMut(f32) -> f32) -> Self;
    /// The smaller operand, the other where one is NaN (as [`f32::min`]), and `rhs` where they
    /// compare equal (`min(0, −0) = −0`, `min(−0, 0) = 0`: x86's `minps`, which `f32::min` leaves
    /// unspecified).
    fn min(self, rhs: Self) -> Self;
    /// The larger operand, the other where one is NaN, `rhs` where they compare equal.
    fn max(self, rhs: Self) -> Self;
    /// The magnitude of `self` with the sign of `sign`.
    fn copysign(self, sign: Self) -> Self;
    /// `self < rhs` (false for NaN).
    fn lt(self, rhs: Self) -> Self::Mask;
    /// `self ≤ rhs`.
    fn le(self, rhs: Self) -> Self::Mask;
    /// `self > rhs`.
    fn gt(self, rhs: Self) -> Self::Mask;
    /// `self ≥ rhs`.
    fn ge(self, rhs: Self) -> Self::Mask;
    /// `self == rhs`.
    fn eq(self, rhs: Self) -> Self::Mask;
    /// Finite (neither infinite nor NaN).
    fn is_finite(self) -> Self::Mask;
    /// NaN.
    fn is_nan(self) -> Self::Mask;
    /// The sign bit is set (`−0` and negative NaNs included).
    fn is_sign_negative(self) -> Self::Mask;
    /// Lane-wise `if mask { a } else { b }`.
    fn select(mask: Self::Mask, a: Self, b: Self) -> Self;

    /// [`f32::clamp`]: `lo` below, `hi` above, NaN stays NaN.
    #[inline]
    fn clamp(self, lo: Self, hi: Self) -> Self {
        let x = Self::select(self.lt(lo), lo, self);
        Self::select(x.gt(hi), hi, x)
    }
}

/// A 3-vector over a [`Real`]: [`Vec3`] for one pixel, [`Vec3x8`] for eight.
pub trait Vector3:
    Copy
    + core::fmt::Debug
    + PartialEq
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Neg<Output = Self>
    + Mul<<Self as Vector3>::Real, Output = Self>
{
    /// The component type.
    type Real: Real;
    /// The vector `(x, y, z)`.
    fn new(x: Self::Real, y: Self::Real, z: Self::Real) -> Self;
    /// `v` in every lane.
    fn constant(v: Vec3) -> Self;
    /// The `x` components.
    fn x(self) -> Self::Real;
    /// The `y` components.
    fn y(self) -> Self::Real;
    /// The `z` components.
    fn z(self) -> Self::Real;
    /// The vector of lane `i`.
    fn lane(self, i: usize) -> Vec3;
    /// Sets the vector of lane `i`.
    fn set_lane(&mut self, i: usize, v: Vec3);
    /// Lane-wise `if mask { a } else { b }`.
    fn select(mask: Msk<Self>, a: Self, b: Self) -> Self;
    /// The vector whose lane `i` is `f(i)` (`f` called for lanes 0, 1, ... in order).
    fn gather(f: impl FnMut(usize) -> Vec3) -> Self;

    /// `(x·x' + y·y') + z·z'`, as [`Vec3::dot`].
    #[inline]
    fn dot(self, rhs: Self) -> Self::Real {
        self.x() * rhs.x() + self.y() * rhs.y() + self.z() * rhs.z()
    }

    /// As [`Vec3::cross`].
    #[inline]
    fn cross(self, rhs: Self) -> Self {
        Self::new(
            self.y() * rhs.z() - rhs.y() * self.z(),
            self.z() * rhs.x() - rhs.z() * self.x(),
            self.x() * rhs.y() - rhs.x() * self.y(),
        )
    }

    /// `√(v·v)`, as [`Vec3::length`].
    #[inline]
    fn length(self) -> Self::Real {
        self.dot(self).sqrt()
    }

    /// Lanes equal to the zero vector (either sign of zero), as `v == Vec3::ZERO`.
    #[inline]
    fn is_zero(self) -> Msk<Self> {
        let zero = Self::Real::ZERO;
        self.x().eq(zero) & self.y().eq(zero) & self.z().eq(zero)
    }

    /// Lanes where all three components are finite.
    #[inline]
    fn is_finite(self) -> Msk<Self> {
        self.x().is_finite() & self.y().is_finite() & self.z().is_finite()
    }

    /// `v · (1/√(v·v))` and the lanes where `1/√(v·v)` is finite and positive, as
    /// [`Vec3::try_normalize`] (the other lanes hold garbage).
    #[inline]
    fn try_normalize(self) -> (Self, Msk<Self>) {
        let rcp = Self::Real::ONE / self.length();
        (self * rcp, rcp.is_finite() & rcp.gt(Self::Real::ZERO))
    }

    /// [`Vec3::normalize_or_zero`]: [`Self::try_normalize`], zero where it fails.
    #[inline]
    fn normalize_or_zero(self) -> Self {
        let (n, ok) = self.try_normalize();
        Self::select(ok, n, Self::constant(Vec3::ZERO))
    }

    /// `M · (v, 0)`, as [`Mat4::transform_vector3`]: `((c₀ x) + c₁ y) + c₂ z` with `cₖ` the
    /// columns' `xyz`.
    #[inline]
    fn transform_vector3(m: &Mat4, v: Self) -> Self {
        let column = |c: glam::Vec4| Self::constant(c.truncate());
        column(m.x_axis) * v.x() + column(m.y_axis) * v.y() + column(m.z_axis) * v.z()
    }

    /// [`Vec3::lerp`]: `a (1 − s) + b s`.
    #[inline]
    fn lerp(self, rhs: Self, s: Self::Real) -> Self {
        self * (Self::Real::ONE - s) + rhs * s
    }
}

/// The mask of a vector type's components.
pub type Msk<V> = <<V as Vector3>::Real as Real>::Mask;

/// Trait methods that forward to a function of the implementing type: `name(args) -> ret = path`
/// becomes `fn name(self, args) -> ret { path(self, args) }`.
macro_rules! forward {
    ($(fn $name:ident($($arg:ident),*) -> $ret:ty = $path:path;)*) => {$(
        #[inline]
        fn $name(self $(, $arg: Self)*) -> $ret {
            $path(self $(, $arg)*)
        }
    )*};
}

impl LaneMask for bool {
    #[inline]
    fn splat(value: bool) -> Self {
        value
    }
    #[inline]
    fn all(self) -> bool {
        self
    }
    #[inline]
    fn any(self) -> bool {
        self
    }
    #[inline]
    fn lanes(self) -> impl Iterator<Item = bool> {
        core::iter::once(self)
    }
    #[inline]
    fn set(&mut self, _i: usize, value: bool) {
        *self = value;
    }
    #[inline]
    fn bits(self) -> u32 {
        u32::from(self)
    }
}

impl Real for f32 {
    type Mask = bool;
    type Array = [f32; 1];
    const LANES: usize = 1;
    const ZERO: Self = 0.0;
    const ONE: Self = 1.0;
    #[inline]
    fn splat(v: f32) -> Self {
        v
    }
    #[inline]
    fn to_lane_array(self) -> [f32; 1] {
        [self]
    }
    #[inline]
    fn sqrt(self) -> Self {
        crate::math::sqrt(self)
    }
    #[inline]
    fn floor(self) -> Self {
        crate::math::floor(self)
    }
    #[inline]
    fn trunc(self) -> Self {
        crate::math::trunc(self)
    }
    #[inline]
    fn map(self, mut f: impl FnMut(f32) -> f32) -> Self {
        f(self)
    }
    #[inline]
    fn min(self, rhs: Self) -> Self {
        if rhs.is_nan() || self < rhs {
            self
        } else {
            rhs
        }
    }
    #[inline]
    fn max(self, rhs: Self) -> Self {
        if rhs.is_nan() || self > rhs {
            self
        } else {
            rhs
        }
    }
    #[inline]
    fn lt(self, rhs: Self) -> bool {
        self < rhs
    }
    #[inline]
    fn le(self, rhs: Self) -> bool {
        self <= rhs
    }
    #[inline]
    fn gt(self, rhs: Self) -> bool {
        self > rhs
    }
    #[inline]
    fn ge(self, rhs: Self) -> bool {
        self >= rhs
    }
    #[inline]
    fn eq(self, rhs: Self) -> bool {
        self == rhs
    }
    forward! {
        fn abs() -> Self = f32::abs;
        fn copysign(sign) -> Self = f32::copysign;
        fn is_finite() -> bool = f32::is_finite;
        fn is_nan() -> bool = f32::is_nan;
        fn is_sign_negative() -> bool = f32::is_sign_negative;
    }
    #[inline]
    fn select(mask: bool, a: Self, b: Self) -> Self {
        if mask { a } else { b }
    }
}

impl Vector3 for Vec3 {
    type Real = f32;
    #[inline]
    fn new(x: f32, y: f32, z: f32) -> Self {
        Vec3::new(x, y, z)
    }
    #[inline]
    fn constant(v: Vec3) -> Self {
        v
    }
    #[inline]
    fn x(self) -> f32 {
        self.x
    }
    #[inline]
    fn y(self) -> f32 {
        self.y
    }
    #[inline]
    fn z(self) -> f32 {
        self.z
    }
    #[inline]
    fn lane(self, _i: usize) -> Vec3 {
        self
    }
    #[inline]
    fn set_lane(&mut self, _i: usize, v: Vec3) {
        *self = v;
    }
    #[inline]
    fn select(mask: bool, a: Self, b: Self) -> Self {
        if mask { a } else { b }
    }
    #[inline]
    fn gather(mut f: impl FnMut(usize) -> Vec3) -> Self {
        f(0)
    }
    #[inline]
    fn dot(self, rhs: Self) -> f32 {
        Vec3::dot(self, rhs)
    }
    #[inline]
    fn cross(self, rhs: Self) -> Self {
        Vec3::cross(self, rhs)
    }
    #[inline]
    fn length(self) -> f32 {
        Vec3::length(self)
    }
    #[inline]
    fn is_zero(self) -> bool {
        self == Vec3::ZERO
    }
    #[inline]
    fn is_finite(self) -> bool {
        Vec3::is_finite(self)
    }
    #[inline]
    fn try_normalize(self) -> (Self, bool) {
        match Vec3::try_normalize(self) {
            Some(n) => (n, true),
            None => (self, false),
        }
    }
    #[inline]
    fn normalize_or_zero(self) -> Self {
        Vec3::normalize_or_zero(self)
    }
    #[inline]
    fn lerp(self, rhs: Self, s: f32) -> Self {
        Vec3::lerp(self, rhs, s)
    }
    #[inline]
    fn transform_vector3(m: &Mat4, v: Self) -> Self {
        m.transform_vector3(v)
    }
}

impl LaneMask for F32x8 {
    #[inline]
    fn splat(value: bool) -> Self {
        F32x8::splat(if value { f32::from_bits(u32::MAX) } else { 0.0 })
    }
    #[inline]
    fn all(self) -> bool {
        F32x8::all(self)
    }
    #[inline]
    fn any(self) -> bool {
        F32x8::any(self)
    }
    #[inline]
    fn lanes(self) -> impl Iterator<Item = bool> {
        mask_lanes(self).into_iter()
    }
    #[inline]
    fn set(&mut self, i: usize, value: bool) {
        let mut lanes = mask_lanes(*self);
        lanes[i] = value;
        *self = mask_from_lanes(lanes);
    }
    #[inline]
    fn bits(self) -> u32 {
        self.to_bitmask()
    }
}

impl Real for F32x8 {
    type Mask = F32x8;
    type Array = [f32; LANES];
    const LANES: usize = LANES;
    const ZERO: Self = F32x8::ZERO;
    const ONE: Self = F32x8::ONE;
    #[inline]
    fn splat(v: f32) -> Self {
        F32x8::splat(v)
    }
    #[inline]
    fn to_lane_array(self) -> [f32; LANES] {
        self.to_array()
    }
    #[inline]
    fn map(self, mut f: impl FnMut(f32) -> f32) -> Self {
        let mut lanes = self.to_array();
        for lane in &mut lanes {
            *lane = f(*lane);
        }
        F32x8::new(lanes)
    }
    forward! {
        fn sqrt() -> Self = F32x8::sqrt;
        fn abs() -> Self = F32x8::abs;
        fn floor() -> Self = F32x8::floor;
        fn trunc() -> Self = F32x8::trunc;
        fn min(rhs) -> Self = F32x8::min;
        fn max(rhs) -> Self = F32x8::max;
        fn copysign(sign) -> Self = F32x8::copysign;
        fn lt(rhs) -> Self = F32x8::simd_lt;
        fn le(rhs) -> Self = F32x8::simd_le;
        fn gt(rhs) -> Self = F32x8::simd_gt;
        fn ge(rhs) -> Self = F32x8::simd_ge;
        fn eq(rhs) -> Self = F32x8::simd_eq;
        fn is_finite() -> Self = F32x8::is_finite;
        fn is_nan() -> Self = F32x8::is_nan;
        fn is_sign_negative() -> Self = F32x8::is_sign_negative;
    }
    #[inline]
    fn select(mask: Self, a: Self, b: Self) -> Self {
        mask.select(a, b)
    }
}

impl Vector3 for Vec3x8 {
    type Real = F32x8;
    #[inline]
    fn new(x: F32x8, y: F32x8, z: F32x8) -> Self {
        Vec3x8 { x, y, z }
    }
    #[inline]
    fn constant(v: Vec3) -> Self {
        Vec3x8::splat(v)
    }
    #[inline]
    fn x(self) -> F32x8 {
        self.x
    }
    #[inline]
    fn y(self) -> F32x8 {
        self.y
    }
    #[inline]
    fn z(self) -> F32x8 {
        self.z
    }
    #[inline]
    fn lane(self, i: usize) -> Vec3 {
        Vec3x8::lane(self, i)
    }
    #[inline]
    fn set_lane(&mut self, i: usize, v: Vec3) {
        let mut lanes = self.to_lanes();
        lanes[i] = v;
        *self = Vec3x8::from_lanes(&lanes);
    }
    #[inline]
    fn select(mask: F32x8, a: Self, b: Self) -> Self {
        Vec3x8 {
            x: mask.select(a.x, b.x),
            y: mask.select(a.y, b.y),
            z: mask.select(a.z, b.z),
        }
    }
    #[inline]
    fn gather(mut f: impl FnMut(usize) -> Vec3) -> Self {
        // A plain loop: `array::from_fn` is not always inlined, and this runs per pixel.
        let mut lanes = [Vec3::ZERO; LANES];
        for (i, lane) in lanes.iter_mut().enumerate() {
            *lane = f(i);
        }
        Vec3x8::from_lanes(&lanes)
    }
}
