//! The shading of the opaque objects every method sees: procedural albedos and the directional
//! light, for one pixel or eight ([`crate::real`]).

use glam::{Vec2, Vec3};

use crate::lanes::{Vec2x8, Vec3x8};
use crate::real::{LaneMask, Real, Vector3};

/// The reflectance of an opaque diffuse surface.
#[derive(Clone, Debug, PartialEq)]
pub enum Albedo {
    /// One colour.
    Constant(Vec3),
    /// A checkerboard of two colours with `squares` squares per unit of uv (or of world `x`/`z`
    /// when the mesh has no uvs).
    Checker {
        /// First colour.
        a: Vec3,
        /// Second colour.
        b: Vec3,
        /// Squares per unit.
        squares: f32,
    },
    /// A 6 × 4 colour chart over the uv square (approximate linear-sRGB values of the 24
    /// patches of the classic ColorChecker), grey elsewhere.
    ColorChart,
    /// Wood-like rings: with `r = ‖(u − ½, (v − ½)/4)‖` and
    /// `f = fract(rings · r + 0.15 sin(40 u))`, the albedo `light + (dark − light) f²`.
    Wood {
        /// Colour between rings.
        light: Vec3,
        /// Colour at the ring edges.
        dark: Vec3,
        /// Rings per unit of `r`.
        rings: f32,
    },
}

/// Linear sRGB of the 24 ColorChecker patches, row by row (approximate published values).
pub const COLOR_CHART: [[f32; 3]; 24] = [
    [0.173, 0.085, 0.059],
    [0.554, 0.300, 0.222],
    [0.117, 0.195, 0.335],
    [0.107, 0.148, 0.058],
    [0.236, 0.221, 0.432],
    [0.132, 0.515, 0.409],
    [0.680, 0.198, 0.025],
    [0.072, 0.103, 0.386],
    [0.545, 0.085, 0.117],
    [0.109, 0.045, 0.142],
    [0.327, 0.503, 0.049],
    [0.741, 0.364, 0.020],
    [0.030, 0.046, 0.287],
    [0.066, 0.291, 0.066],
    [0.428, 0.031, 0.040],
    [0.816, 0.578, 0.010],
    [0.505, 0.083, 0.288],
    [0.000, 0.235, 0.383],
    [0.887, 0.887, 0.869],
    [0.588, 0.591, 0.590],
    [0.361, 0.367, 0.368],
    [0.191, 0.191, 0.192],
    [0.088, 0.089, 0.090],
    [0.031, 0.032, 0.032],
];

/// [`Albedo::ColorChart`] outside the unit square: a mid grey.
const COLOR_CHART_OUTSIDE: f32 = 0.18;

impl Albedo {
    /// The albedo of the built-in wood texture.
    pub const WOOD: Albedo = Albedo::Wood {
        light: Vec3::new(0.60, 0.36, 0.16),
        dark: Vec3::new(0.22, 0.10, 0.04),
        rings: 24.0,
    };

    /// The albedo at texture coordinates `uv` (or world `xz` for meshes without uvs).
    #[inline]
    pub fn at(&self, uv: Vec2) -> Vec3 {
        self.at_uv(uv.x, uv.y)
    }

    /// [`Self::at`] at eight texture coordinates: lane `i` is `at(uv_i)`, bit for bit.
    #[inline]
    pub fn at_x8(&self, uv: Vec2x8) -> Vec3x8 {
        self.at_uv(uv.x, uv.y)
    }

    /// [`Self::at`] at `(u, v)` for one pixel or eight. The checker's parity and the wood's
    /// fraction are exact (`a − 2⌊a/2⌋` of an integer-valued float; `a − trunc(a)`, plus 1
    /// below 0), the numbers `rem_euclid` gives; the wood's `sin` and the colour chart's table
    /// are per lane.
    #[inline]
    pub fn at_uv<V: Vector3>(&self, u: V::Real, v: V::Real) -> V {
        let splat = V::Real::splat;
        match *self {
            Self::Constant(c) => V::constant(c),
            Self::Checker { a, b, squares } => {
                let cells = (u * splat(squares)).floor() + (v * splat(squares)).floor();
                let parity = cells - splat(2.0) * (cells * splat(0.5)).floor();
                V::select(parity.lt(V::Real::ONE), V::constant(a), V::constant(b))
            }
            Self::ColorChart => {
                // `color_chart` with the range test and the patch index on lanes (inside the
                // unit square `(u·6) as usize` is the truncation), then one load per lane.
                let (zero, one) = (V::Real::ZERO, V::Real::ONE);
                let inside = (u.ge(zero) & u.lt(one) & v.ge(zero) & v.lt(one)).bits();
                let index = (v * splat(4.0)).trunc() * splat(6.0) + (u * splat(6.0)).trunc();
                let index = index.to_lane_array();
                let index = index.as_ref();
                V::gather(|i| {
                    if inside & (1 << i) != 0 {
                        Vec3::from_array(COLOR_CHART[index[i] as usize])
                    } else {
                        Vec3::splat(COLOR_CHART_OUTSIDE)
                    }
                })
            }
            Self::Wood { light, dark, rings } => {
                let (dx, dy) = (u - splat(0.5), (v - splat(0.5)) * splat(0.25));
                let r = (dx * dx + dy * dy).sqrt();
                let wave = u.map(|u| crate::math::sin(40.0 * u));
                let a = splat(rings) * r + splat(0.15) * wave;
                let rem = a - a.trunc();
                let f = V::Real::select(rem.lt(V::Real::ZERO), rem + V::Real::ONE, rem);
                V::constant(light) + V::constant(dark - light) * (f * f)
            }
        }
    }
}

/// View-independent lighting of opaque objects: `albedo × (ambient + |N·L| · radiance)`.
/// No shadows: image-space methods that store nearby geometry in a texture (Wyman 2005b) see
/// exactly this, so the comparison stays fair.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DirectionalLight {
    /// Unit direction toward the light.
    pub direction: Vec3,
    /// Radiance scale of the light.
    pub radiance: Vec3,
    /// Ambient term.
    pub ambient: Vec3,
}

impl Default for DirectionalLight {
    fn default() -> Self {
        Self {
            direction: Vec3::new(0.4, 0.6, -0.7).normalize(),
            radiance: Vec3::splat(0.8),
            ambient: Vec3::splat(0.25),
        }
    }
}

impl DirectionalLight {
    /// Diffuse radiance leaving a surface of `albedo` with unit normal `n`, seen from either
    /// side; one pixel (glam types) or eight lanes.
    #[inline]
    pub fn shade<V: Vector3>(&self, albedo: V, n: V) -> V {
        let cos = n.dot(V::constant(self.direction)).abs();
        albedo * (V::constant(self.ambient) + V::constant(self.radiance) * cos)
    }
}
