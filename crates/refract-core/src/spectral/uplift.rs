//! Linear sRGB to spectra: Jakob and Hanika 2019 (*A Low-Dimensional Function Space for
//! Efficient Spectral Upsampling*), as Mitsuba 3 uses it (`rgb2spec` at its pinned commit).
//!
//! A reflectance `rgb ∈ [0, 1]³` becomes the sigmoid spectrum
//! [`super::sigmoid_spectrum`] whose colour under D65 is `rgb`: its three polynomial
//! coefficients minimise the CIELAB distance between that colour and `rgb`
//! (Levenberg–Marquardt, [`UpliftSolver::solve`]). They are tabulated once on a
//! `3 × res³` grid (the largest channel, its value warped by a double smoothstep, and the
//! other two relative to it; [`UpliftSolver::solve_slice`]) and looked up trilinearly
//! ([`UpliftTable::fetch`]); greys have a closed form. Emitters (the environment, the light)
//! are scaled to a largest channel of ½ and multiplied by D65 ([`emission`]).
//!
//! Building a table allocates and takes seconds; the caller owns it and builds it once
//! (refract-scene's `spectral` module builds Mitsuba's `res = 64` in parallel).

use glam::Vec3;
use wide::f32x8;

use super::{
    CIE_SAMPLES, LAMBDA_MAX, LAMBDA_MIN, LINEAR_SRGB_TO_XYZ, WAVELENGTHS, XYZ_TO_LINEAR_SRGB, d65,
    sigmoid_spectrum, tables,
};
use crate::math;

/// Samples of the quadrature: Simpson's 3/8 rule on each 5 nm segment (`(95 − 1) · 3 + 1`).
const FINE_SAMPLES: usize = (CIE_SAMPLES - 1) * 3 + 1;
/// The quadrature in eight-lane blocks, padded with weight-0 samples (as `rgb2spec_opt` pads
/// to its SIMD width).
const FINE_BLOCKS: usize = FINE_SAMPLES.div_ceil(8);

/// The table resolution Mitsuba 3 ships (`srgb.coeff`).
pub const MITSUBA_RESOLUTION: usize = 64;

/// The fitting problem: the CIE observer under D65 as linear-sRGB weights at the quadrature's
/// wavelengths, and the CIELAB white point.
#[derive(Clone, Debug)]
pub struct UpliftSolver {
    /// Quadrature wavelengths mapped to [0, 1], eight per block.
    lambda01: [f32x8; FINE_BLOCKS],
    /// Per channel, the weight of the spectrum's value at each quadrature wavelength.
    rgb_weights: [[f32x8; FINE_BLOCKS]; 3],
    /// XYZ of the white (D65) the weights integrate to.
    white_xyz: [f32; 3],
}

/// The table's `D65 / 10 566.864` (luminance 1 at the 5 nm quadrature of `rgb2spec`).
const D65_UNIT_LUMINANCE: f64 = 1.0 / 10_566.864_005_283_874;

impl Default for UpliftSolver {
    fn default() -> Self {
        Self::new()
    }
}

impl UpliftSolver {
    /// The sRGB problem (`rgb2spec_opt`'s `init_tables(SRGB)`), integrated in `f64`.
    pub fn new() -> Self {
        let h = f64::from(LAMBDA_MAX - LAMBDA_MIN) / (FINE_SAMPLES - 1) as f64;
        let mut lambda01 = [0.0f32; FINE_BLOCKS * 8];
        let mut rgb_weights = [[0.0f32; FINE_BLOCKS * 8]; 3];
        let mut white = [0.0f64; 3];
        let interp = |i: usize, lambda: f64| -> f64 {
            let x = (lambda - f64::from(LAMBDA_MIN)) * (CIE_SAMPLES - 1) as f64
                / f64::from(LAMBDA_MAX - LAMBDA_MIN);
            let offset = (x as usize).min(CIE_SAMPLES - 2);
            let w = x - offset as f64;
            let at = |k: usize| {
                if i < 3 {
                    f64::from(tables::CIE_1931_XYZ[k][i])
                } else {
                    f64::from(tables::D65[k]) * D65_UNIT_LUMINANCE
                }
            };
            (1.0 - w) * at(offset) + w * at(offset + 1)
        };
        for i in 0..FINE_SAMPLES {
            let lambda = f64::from(LAMBDA_MIN) + i as f64 * h;
            let xyz = [interp(0, lambda), interp(1, lambda), interp(2, lambda)];
            let illuminant = interp(3, lambda);
            let mut weight = 3.0 / 8.0 * h;
            if i == 0 || i == FINE_SAMPLES - 1 {
            } else if (i - 1) % 3 == 2 {
                weight *= 2.0;
            } else {
                weight *= 3.0;
            }
            lambda01[i] =
                ((lambda - f64::from(LAMBDA_MIN)) / f64::from(LAMBDA_MAX - LAMBDA_MIN)) as f32;
            for (k, row) in XYZ_TO_LINEAR_SRGB.iter().enumerate() {
                let acc: f64 = (0..3)
                    .map(|j| f64::from(row[j]) * xyz[j] * illuminant * weight)
                    .sum();
                rgb_weights[k][i] = acc as f32;
            }
            for (c, w) in white.iter_mut().enumerate() {
                *w += xyz[c] * illuminant * weight;
            }
        }
        let blocks = |v: &[f32]| -> [f32x8; FINE_BLOCKS] {
            core::array::from_fn(|b| f32x8::new(core::array::from_fn(|k| v[b * 8 + k])))
        };
        Self {
            lambda01: blocks(&lambda01),
            rgb_weights: rgb_weights.map(|w| blocks(&w)),
            white_xyz: white.map(|w| w as f32),
        }
    }

    /// CIELAB of linear sRGB `rgb` under this white, and its Jacobian `∂Lab/∂rgb` when asked.
    fn lab(&self, rgb: [f32; 3], jacobian: Option<&mut [[f32; 3]; 3]>) -> [f32; 3] {
        let xyz = super::mul3(&LINEAR_SRGB_TO_XYZ, Vec3::from(rgb));
        let delta = 6.0f32 / 29.0;
        let mut f = [0.0; 3];
        let mut df = [0.0; 3];
        for k in 0..3 {
            let t = xyz[k] / self.white_xyz[k];
            if t > delta * delta * delta {
                let c = math::cbrt(t);
                f[k] = c;
                df[k] = (1.0 / 3.0) / (c * c * self.white_xyz[k]);
            } else {
                f[k] = t / (delta * delta * 3.0) + 4.0 / 29.0;
                df[k] = 1.0 / (delta * delta * 3.0 * self.white_xyz[k]);
            }
        }
        if let Some(jac) = jacobian {
            let g = [
                [0.0, 116.0 * df[1], 0.0],
                [500.0 * df[0], -500.0 * df[1], 0.0],
                [0.0, 200.0 * df[1], -200.0 * df[2]],
            ];
            for a in 0..3 {
                for b in 0..3 {
                    jac[a][b] = (0..3).map(|k| g[a][k] * LINEAR_SRGB_TO_XYZ[k][b]).sum();
                }
            }
        }
        [
            116.0 * f[1] - 16.0,
            500.0 * (f[0] - f[1]),
            200.0 * (f[1] - f[2]),
        ]
    }

    /// The residual `Lab(target) − Lab(colour of coefficients c)` (coefficients of `λ` mapped
    /// to [0, 1]) and, when asked, its Jacobian with respect to `c`.
    fn residual(
        &self,
        c: [f32; 3],
        target_lab: [f32; 3],
        jacobian: Option<&mut [[f32; 3]; 3]>,
    ) -> [f32; 3] {
        let zero = f32x8::ZERO;
        let mut rgb_lanes = [zero; 3];
        let mut d_lanes = [[zero; 3]; 3];
        let (c0, c1, c2) = (f32x8::splat(c[0]), f32x8::splat(c[1]), f32x8::splat(c[2]));
        let (half, one) = (f32x8::splat(0.5), f32x8::ONE);
        let want_jacobian = jacobian.is_some();
        for b in 0..FINE_BLOCKS {
            let l = self.lambda01[b];
            let x = (c0 * l + c1) * l + c2;
            let q = one / (one + x * x).sqrt();
            let s = half * x * q + half;
            for (sum, weights) in rgb_lanes.iter_mut().zip(&self.rgb_weights) {
                *sum += weights[b] * s;
            }
            if want_jacobian {
                let ds = half * q * q * q;
                for (d, weights) in d_lanes.iter_mut().zip(&self.rgb_weights) {
                    let wd = weights[b] * ds;
                    d[0] += wd * l * l;
                    d[1] += wd * l;
                    d[2] += wd;
                }
            }
        }
        let rgb = rgb_lanes.map(|v| v.reduce_add());
        let d_rgb = d_lanes.map(|row| row.map(|v| v.reduce_add()));
        let mut lab_jac = [[0.0f32; 3]; 3];
        let lab = self.lab(rgb, want_jacobian.then_some(&mut lab_jac));
        if let Some(jac) = jacobian {
            for a in 0..3 {
                for b in 0..3 {
                    jac[a][b] = -(0..3).map(|k| lab_jac[a][k] * d_rgb[k][b]).sum::<f32>();
                }
            }
        }
        [
            target_lab[0] - lab[0],
            target_lab[1] - lab[1],
            target_lab[2] - lab[2],
        ]
    }

    /// Refines `c` (coefficients of `λ` mapped to [0, 1], the previous solution or zeros) so
    /// that the colour of the sigmoid spectrum is `rgb`: up to 15 Levenberg–Marquardt
    /// iterations on the squared CIELAB distance (`rgb2spec_opt`'s `LM`). Returns the final
    /// CIELAB distance.
    pub fn solve(&self, rgb: [f32; 3], c: &mut [f32; 3]) -> f32 {
        let target = self.lab(rgb, None);
        let cost_of = |r: [f32; 3]| r[0] * r[0] + r[1] * r[1] + r[2] * r[2];
        let mut jac = [[0.0f32; 3]; 3];
        let mut residual = self.residual(*c, target, Some(&mut jac));
        let mut cost = cost_of(residual);
        let mut damping = 1e-3f32;
        for _ in 0..15 {
            if cost <= 1e-12 {
                break;
            }
            let mut a = [[0.0f32; 3]; 3];
            let mut g = [0.0f32; 3];
            for i in 0..3 {
                for j in 0..3 {
                    a[i][j] = (0..3).map(|k| jac[k][i] * jac[k][j]).sum();
                }
                g[i] = (0..3).map(|k| jac[k][i] * residual[k]).sum();
            }
            let mut accepted = false;
            for _ in 0..10 {
                let mut m = a;
                for (i, row) in m.iter_mut().enumerate() {
                    row[i] += damping;
                }
                let Some(step) = solve_3x3(m, g) else {
                    damping *= 10.0;
                    continue;
                };
                let trial = [c[0] - step[0], c[1] - step[1], c[2] - step[2]];
                let trial_cost = cost_of(self.residual(trial, target, None));
                if trial_cost < cost {
                    *c = trial;
                    cost = trial_cost;
                    damping = (damping * 0.5).max(1e-12);
                    accepted = true;
                    break;
                }
                damping *= 10.0;
                if damping > 1e12 {
                    break;
                }
            }
            if !accepted {
                break;
            }
            residual = self.residual(*c, target, Some(&mut jac));
        }
        math::sqrt(cost)
    }

    /// One `(l, j)` slice of a table of resolution `res` (`rgb2spec_opt`'s unit of work): for
    /// the largest channel `l` and the third channel's ratio `y = j / (res − 1)`, every
    /// `(k, i)` cell, coefficients of `λ` in nm, written to `out[(k · res + i) · 3 ..]`
    /// (`out.len() = res² · 3`). Cells are solved along `k` from `res / 5` up and down, each
    /// from its neighbour's solution.
    pub fn solve_slice(&self, res: usize, l: usize, j: usize, out: &mut [f32]) {
        assert!(res >= 2 && l < 3 && j < res && out.len() == res * res * 3);
        let scale = table_scale(res);
        let y = j as f32 / (res - 1) as f32;
        for i in 0..res {
            let x = i as f32 / (res - 1) as f32;
            let start = res / 5;
            let mut solve_at = |k: usize, c: &mut [f32; 3]| {
                let b = scale(k);
                let mut rgb = [0.0; 3];
                rgb[l] = b;
                rgb[(l + 1) % 3] = x * b;
                rgb[(l + 2) % 3] = y * b;
                self.solve(rgb, c);
                let (c0, c1) = (
                    f64::from(LAMBDA_MIN),
                    1.0 / f64::from(LAMBDA_MAX - LAMBDA_MIN),
                );
                let (a, b, cc) = (f64::from(c[0]), f64::from(c[1]), f64::from(c[2]));
                let cell = &mut out[(k * res + i) * 3..][..3];
                cell[0] = (a * c1 * c1) as f32;
                cell[1] = (b * c1 - 2.0 * a * c0 * c1 * c1) as f32;
                cell[2] = (cc - b * c0 * c1 + a * (c0 * c1) * (c0 * c1)) as f32;
            };
            let mut c = [0.0f32; 3];
            for k in start..res {
                solve_at(k, &mut c);
            }
            let mut c = [0.0f32; 3];
            for k in (0..=start).rev() {
                solve_at(k, &mut c);
            }
        }
    }
}

/// The table's brightness axis: `scale(k) = smoothstep(smoothstep(k / (res − 1)))`.
pub fn table_scale(res: usize) -> impl Fn(usize) -> f32 {
    let smoothstep = |x: f32| x * x * (3.0 - 2.0 * x);
    move |k| smoothstep(smoothstep(k as f32 / (res - 1) as f32))
}

/// `m x = b` for a 3 × 3 system by LU with partial pivoting; `None` when a pivot is below
/// `1e-30` (the system is singular).
fn solve_3x3(mut m: [[f32; 3]; 3], b: [f32; 3]) -> Option<[f32; 3]> {
    let mut p = [0usize, 1, 2];
    for i in 0..3 {
        let (mut best, mut imax) = (0.0f32, i);
        for (k, row) in m.iter().enumerate().skip(i) {
            if row[i].abs() > best {
                best = row[i].abs();
                imax = k;
            }
        }
        if best < 1e-30 {
            return None;
        }
        m.swap(i, imax);
        p.swap(i, imax);
        for j in i + 1..3 {
            m[j][i] /= m[i][i];
            for k in i + 1..3 {
                m[j][k] -= m[j][i] * m[i][k];
            }
        }
    }
    let mut x = [0.0f32; 3];
    for i in 0..3 {
        x[i] = b[p[i]];
        for k in 0..i {
            x[i] -= m[i][k] * x[k];
        }
    }
    for i in (0..3).rev() {
        for k in i + 1..3 {
            x[i] -= m[i][k] * x[k];
        }
        x[i] /= m[i][i];
    }
    Some(x)
}

/// A tabulated uplift, borrowed: `scale` (the brightness axis, `res` values) and `data`
/// (`3 · res³` cells of three coefficients, index `((l · res + k) · res + j) · res + i`),
/// laid out as Mitsuba's `srgb.coeff`.
#[derive(Clone, Copy, Debug)]
pub struct UpliftTable<'a> {
    /// Resolution per axis.
    pub res: usize,
    /// The brightness axis ([`table_scale`]).
    pub scale: &'a [f32],
    /// The coefficients.
    pub data: &'a [f32],
}

impl UpliftTable<'_> {
    /// The sigmoid coefficients (of `λ` in nm) of reflectance `rgb`, clamped to [0, 1]
    /// (`rgb2spec_fetch`): greys in closed form (`c₂ = (v − ½) / √(v (1 − v))`, ±8192 for
    /// black and white), other colours trilinearly from the table.
    pub fn fetch(&self, rgb: Vec3) -> [f32; 3] {
        let rgb = rgb.clamp(Vec3::ZERO, Vec3::ONE).to_array();
        if rgb[0] == rgb[1] && rgb[1] == rgb[2] {
            let v = rgb[0];
            let c2 = if v <= 0.0 {
                -8192.0
            } else if v >= 1.0 {
                8192.0
            } else {
                (v - 0.5) / math::sqrt(v * (1.0 - v))
            };
            return [0.0, 0.0, c2];
        }
        let res = self.res;
        let mut i = 0;
        for j in 1..3 {
            if rgb[j] >= rgb[i] {
                i = j;
            }
        }
        let z = rgb[i];
        if z <= 0.0 {
            return [self.data[0], self.data[1], self.data[2]];
        }
        let scale = (res - 1) as f32 / z;
        let x = rgb[(i + 1) % 3] * scale;
        let y = rgb[(i + 2) % 3] * scale;
        let xi = (x as usize).min(res - 2);
        let yi = (y as usize).min(res - 2);
        let zi = self.find_interval(z);
        let offset = (((i * res + zi) * res + yi) * res + xi) * 3;
        let (dx, dy, dz) = (3, 3 * res, 3 * res * res);
        let x1 = x - xi as f32;
        let x0 = 1.0 - x1;
        let y1 = y - yi as f32;
        let y0 = 1.0 - y1;
        let z1 = (z - self.scale[zi]) / (self.scale[zi + 1] - self.scale[zi]);
        let z0 = 1.0 - z1;
        let d = self.data;
        core::array::from_fn(|c| {
            let o = offset + c;
            ((d[o] * x0 + d[o + dx] * x1) * y0 + (d[o + dy] * x0 + d[o + dy + dx] * x1) * y1) * z0
                + ((d[o + dz] * x0 + d[o + dz + dx] * x1) * y0
                    + (d[o + dz + dy] * x0 + d[o + dz + dy + dx] * x1) * y1)
                    * z1
        })
    }

    /// The last `k` with `scale[k] ≤ z`, at most `res − 2`.
    fn find_interval(&self, z: f32) -> usize {
        let last = self.res - 2;
        let (mut left, mut size) = (0usize, last);
        while size > 0 {
            let half = size >> 1;
            let middle = left + half + 1;
            if self.scale[middle] <= z {
                left = middle;
                size -= half + 1;
            } else {
                size = half;
            }
        }
        left.min(last)
    }

    /// The spectral reflectance of `rgb` at the wavelengths `lambda`.
    #[inline]
    pub fn reflectance(&self, rgb: Vec3, lambda: &[f32; WAVELENGTHS]) -> [f32; WAVELENGTHS] {
        let c = self.fetch(rgb);
        lambda.map(|l| sigmoid_spectrum(c, l))
    }
}

/// The emitter form of a coefficient set: `(c, f)` of linear-sRGB radiance `rgb ≥ 0`, scaled to
/// a largest channel of ½ (`f = 2 max(rgb)`; Mitsuba 3's `d65` and `envmap`), so that the
/// radiance is `f · S_c(λ) · D65(λ)`.
#[inline]
pub fn emission_coefficients(table: &UpliftTable<'_>, rgb: Vec3) -> ([f32; 3], f32) {
    let f = 2.0 * rgb.max_element().max(0.0);
    let normalised = rgb / f.max(1e-8);
    (table.fetch(normalised), f)
}

/// Spectral radiance at `lambda` of an emitter of linear-sRGB radiance `rgb`:
/// `2 max(rgb) · S(λ) · D65(λ)` with `S` the sigmoid spectrum of `rgb / (2 max(rgb))`.
#[inline]
pub fn emission(
    table: &UpliftTable<'_>,
    rgb: Vec3,
    lambda: &[f32; WAVELENGTHS],
) -> [f32; WAVELENGTHS] {
    let (c, f) = emission_coefficients(table, rgb);
    lambda.map(|l| f * sigmoid_spectrum(c, l) * d65(l))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::spectral::{Wavelengths, cie_1931_xyz, mul3};

    /// The colour under D65 of coefficients `c` (nm), by the 5 nm table at 0.5 nm steps.
    fn colour(c: [f32; 3]) -> Vec3 {
        let mut xyz = Vec3::ZERO;
        let n = 940;
        let h = (LAMBDA_MAX - LAMBDA_MIN) / n as f32;
        for i in 0..=n {
            let l = LAMBDA_MIN + i as f32 * h;
            let w = if i == 0 || i == n { 0.5 } else { 1.0 };
            xyz += cie_1931_xyz(l) * (sigmoid_spectrum(c, l) * d65(l) * w * h);
        }
        mul3(&XYZ_TO_LINEAR_SRGB, xyz * super::super::CIE_Y_NORMALIZATION)
    }

    #[test]
    fn solver_reproduces_in_gamut_colours() {
        let solver = UpliftSolver::new();
        for rgb in [
            [0.5, 0.5, 0.5],
            [0.8, 0.2, 0.1],
            [0.1, 0.6, 0.3],
            [0.2, 0.3, 0.9],
            [0.9, 0.9, 0.2],
        ] {
            // Walk from grey to the colour, as the table does from its neighbours.
            let mut c = [0.0; 3];
            for t in 1..=8 {
                let t = t as f32 / 8.0;
                let step = rgb.map(|v| 0.5 + (v - 0.5) * t);
                solver.solve(step, &mut c);
            }
            let distance = solver.solve(rgb, &mut c);
            assert!(distance < 1e-2, "{rgb:?}: ΔE {distance}");
            // Coefficients of λ in [0, 1] → the colour of the spectrum.
            let (c0, c1) = (LAMBDA_MIN, 1.0 / (LAMBDA_MAX - LAMBDA_MIN));
            let nm = [
                c[0] * c1 * c1,
                c[1] * c1 - 2.0 * c[0] * c0 * c1 * c1,
                c[2] - c[1] * c0 * c1 + c[0] * (c0 * c1) * (c0 * c1),
            ];
            let got = colour(nm);
            assert!(
                (got - Vec3::from(rgb)).abs().max_element() < 5e-3,
                "{rgb:?} → {got}"
            );
        }
    }

    /// A small table (res 16) is a real table: its lookups reproduce colours between its
    /// nodes, and the emitter form's colour through the hero estimator is the emitter's.
    #[test]
    fn small_table_round_trips() {
        let res = 16;
        let solver = UpliftSolver::new();
        let mut data = vec![0.0; 3 * res * res * res * 3];
        let mut slice = vec![0.0; res * res * 3];
        for l in 0..3 {
            for j in 0..res {
                solver.solve_slice(res, l, j, &mut slice);
                for k in 0..res {
                    for i in 0..res {
                        let idx = ((l * res + k) * res + j) * res + i;
                        data[idx * 3..][..3].copy_from_slice(&slice[(k * res + i) * 3..][..3]);
                    }
                }
            }
        }
        let scale: Vec<f32> = (0..res).map(table_scale(res)).collect();
        let table = UpliftTable {
            res,
            scale: &scale,
            data: &data,
        };
        for rgb in [
            Vec3::new(0.6, 0.3, 0.2),
            Vec3::new(0.2, 0.5, 0.35),
            Vec3::splat(0.3),
        ] {
            let got = colour(table.fetch(rgb));
            assert!((got - rgb).abs().max_element() < 0.02, "{rgb} → {got}");
        }
        let emitter = Vec3::new(3.0, 1.5, 1.0);
        let n = 2048;
        let mut sum = Vec3::ZERO;
        for k in 0..n {
            let w = Wavelengths::sample((k as f32 + 0.5) / n as f32);
            sum += w.to_linear_srgb(emission(&table, emitter, &w.lambda));
        }
        let got = sum / n as f32;
        assert!(
            ((got - emitter) / emitter).abs().max_element() < 0.02,
            "{got}"
        );
    }

    #[test]
    fn solve_3x3_solves_and_refuses_singular() {
        let m = [[2.0, 1.0, 0.0], [0.0, 0.0, 3.0], [1.0, 4.0, 1.0]];
        let x = solve_3x3(m, [3.0, 6.0, 7.0]).unwrap_or_default();
        assert!(
            (Vec3::from(x) - Vec3::new(1.0, 1.0, 2.0))
                .abs()
                .max_element()
                < 1e-6
        );
        assert!(
            solve_3x3(
                [[1.0, 2.0, 3.0], [2.0, 4.0, 6.0], [0.0, 0.0, 1.0]],
                [1.0; 3]
            )
            .is_none()
        );
    }
}
