//! The `f32` functions core's `f32` lacks, from std or, without it, from the `libm` crate (the
//! same IEEE results for `sqrt` and `floor`; the transcendental ones may differ by an ulp from
//! the platform's libm).

#[cfg(feature = "std")]
mod imp {
    #[inline]
    pub fn sqrt(x: f32) -> f32 {
        x.sqrt()
    }
    #[inline]
    pub fn floor(x: f32) -> f32 {
        x.floor()
    }
    #[inline]
    pub fn trunc(x: f32) -> f32 {
        x.trunc()
    }
    #[inline]
    pub fn sin(x: f32) -> f32 {
        x.sin()
    }
    #[inline]
    pub fn tan(x: f32) -> f32 {
        x.tan()
    }
    #[inline]
    pub fn sin_cos(x: f32) -> (f32, f32) {
        x.sin_cos()
    }
    #[inline]
    pub fn atan2(y: f32, x: f32) -> f32 {
        y.atan2(x)
    }
    #[inline]
    pub fn exp(x: f32) -> f32 {
        x.exp()
    }
    #[inline]
    pub fn ln(x: f32) -> f32 {
        x.ln()
    }
    #[inline]
    pub fn cbrt(x: f32) -> f32 {
        x.cbrt()
    }
    #[inline]
    pub fn log2(x: f32) -> f32 {
        x.log2()
    }
}

#[cfg(not(feature = "std"))]
mod imp {
    #[inline]
    pub fn sqrt(x: f32) -> f32 {
        libm::sqrtf(x)
    }
    #[inline]
    pub fn floor(x: f32) -> f32 {
        libm::floorf(x)
    }
    #[inline]
    pub fn trunc(x: f32) -> f32 {
        libm::truncf(x)
    }
    #[inline]
    pub fn sin(x: f32) -> f32 {
        libm::sinf(x)
    }
    #[inline]
    pub fn tan(x: f32) -> f32 {
        libm::tanf(x)
    }
    #[inline]
    pub fn sin_cos(x: f32) -> (f32, f32) {
        libm::sincosf(x)
    }
    #[inline]
    pub fn atan2(y: f32, x: f32) -> f32 {
        libm::atan2f(y, x)
    }
    #[inline]
    pub fn exp(x: f32) -> f32 {
        libm::expf(x)
    }
    #[inline]
    pub fn ln(x: f32) -> f32 {
        libm::logf(x)
    }
    #[inline]
    pub fn cbrt(x: f32) -> f32 {
        libm::cbrtf(x)
    }
    #[inline]
    pub fn log2(x: f32) -> f32 {
        libm::log2f(x)
    }
}

pub(crate) use imp::{atan2, cbrt, exp, floor, ln, log2, sin, sin_cos, sqrt, tan, trunc};
