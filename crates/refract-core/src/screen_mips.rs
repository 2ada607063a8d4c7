//! The mip-mapped screen texture the engines blur rough transmission with, and three.js's
//! lookup in it (`transmission_pars_fragment`: `getTransmissionSample`, `textureBicubic`).
//!
//! The pyramid: level 0 is the screen texture (`W × H`, the frame's size, as three.js's
//! transmission target at `transmissionResolutionScale` 1); level `k` is `max(1, W >> k) ×
//! max(1, H >> k)` texels, texel `(x, y)` the mean of the level-0 texels in the block
//! `[x 2^k, (x + 1) 2^k) × [y 2^k, (y + 1) 2^k)` cut to the image (on power-of-two sizes the
//! 2 × 2 box recursion of WebGL's `generateMipmap`; on others, whose mips WebGL leaves to the
//! driver, the last partial block is dropped as a floor-sized level drops it), up to the
//! `1 × 1` level.
//!
//! three.js reads it at `lod = log2(W) · r · clamp(2 n − 2, 0, 1)` ([`threejs_lod`]) with a
//! cubic B-spline filter at levels `⌊lod⌋` and `⌈lod⌉`, mixed by `fract(lod)`
//! ([`sample_threejs`]), edges clamped.

use glam::{UVec2, Vec2, Vec3};

use crate::math;

/// The most levels a pyramid has (a 16 384-texel side has 15).
pub const MAX_MIP_LEVELS: usize = 16;

/// The number of levels of a `size` pyramid: down to `1 × 1`.
#[inline]
pub fn level_count(size: UVec2) -> u32 {
    32 - size.x.max(size.y).max(1).leading_zeros()
}

/// The size of level `level` of a `size` pyramid.
#[inline]
pub fn level_size(size: UVec2, level: u32) -> UVec2 {
    UVec2::new((size.x >> level).max(1), (size.y >> level).max(1))
}

/// The level-0 block texel `texel` of level `level` averages: `[start, end)`, cut to `size`.
#[inline]
pub fn level_block(size: UVec2, level: u32, texel: UVec2) -> (UVec2, UVec2) {
    let start = texel << level;
    let end = ((texel + UVec2::ONE) << level).min(size);
    (start, end.max(start + UVec2::ONE).min(size))
}

/// three.js's transmission LOD for roughness `roughness` on glass of index `ior`, over a
/// target `width` texels wide: `log2(width) · roughness · clamp(2 ior − 2, 0, 1)`
/// (`applyIorToRoughness`: no blur at index 1, the full roughness from 1.5).
#[inline]
pub fn threejs_lod(width: u32, roughness: f32, ior: f32) -> f32 {
    math::log2(width.max(1) as f32) * roughness * (2.0 * ior - 2.0).clamp(0.0, 1.0)
}

/// Godot 4's screen-texture LOD for roughness `roughness`: `8 r` (`BaseMaterial3D`'s
/// refraction, `textureLod(screen_texture, uv, ROUGHNESS * 8.0)`), read trilinearly
/// ([`sample_trilinear`]).
#[inline]
pub fn godot_lod(roughness: f32) -> f32 {
    8.0 * roughness
}

/// Unity HDRP's colour-pyramid mip for roughness `roughness` in a pyramid of `levels` levels:
/// `r^1.3 · (levels − 1)` (`transparentSSMipLevel`), read trilinearly.
#[inline]
pub fn hdrp_mip(roughness: f32, levels: u32) -> f32 {
    if roughness <= 0.0 {
        return 0.0;
    }
    math::exp(1.3 * math::ln(roughness)) * levels.saturating_sub(1) as f32
}

/// The standard deviation, in texels, of the Gaussian Filament blurs each level of its
/// refraction pyramid with: `σ0 = (21 + 1)/6` for its 21-tap kernel
/// (`PostProcessManager::prepareMipmapSSR`).
pub const FILAMENT_SIGMA0: f32 = 22.0 / 6.0;

/// Filament's `1 / log2 √5`: the standard deviation of its pyramid grows by `√5` a level (a
/// level's blur adds to the previous one's), so `lod = log2(σ / σ0) · 0.8614`.
pub const FILAMENT_LOD_SCALE: f32 = 0.8614;

/// Filament's per-view `refractionLodOffset` for a frame `height` texels tall under the vertical
/// field of view `fov_y` (radians): `−log2(√2 σ0 s)`, with `s = tan(fov_y) / height` the size of
/// a texel at 1 m as Filament writes it (the tangent of the whole angle;
/// `PostProcessManager::prepareMipmapSSR`).
#[inline]
pub fn filament_lod_offset(height: u32, fov_y: f32) -> f32 {
    let texel_at_one_meter = math::tan(fov_y) / height.max(1) as f32;
    -math::log2(core::f32::consts::SQRT_2 * FILAMENT_SIGMA0 * texel_at_one_meter)
}

/// The levels Filament's refraction pyramid keeps of a `size` frame: `max(min(4, L), L − 4)` of
/// the `L` down to `1 × 1` (`prepareMipmapSSR`: never below 16 texels a side where it can).
#[inline]
pub fn filament_level_count(size: UVec2) -> u32 {
    let levels = level_count(size);
    levels.min(4).max(levels.saturating_sub(4))
}

/// Filament's refraction LOD for roughness `roughness` on glass of index `ior`, a `size` frame
/// under the vertical field of view `fov_y` (`light_indirect.fs`, `evaluateRefraction`): the
/// roughness remapped to 0 at index 1 and kept whole from 1.5, `r' = mix(r, 0, saturate(3/ior −
/// 2))`; `lod = max(0, (2 log2 r' + offset) · 0.8614)` with the offset of
/// [`filament_lod_offset`], clamped to the last level Filament keeps
/// ([`filament_level_count`]), as `textureLod` clamps it. It depends on the field of view and the
/// height, not on the distance: Filament's blur is a fixed angle on screen.
#[inline]
pub fn filament_lod(size: UVec2, fov_y: f32, roughness: f32, ior: f32) -> f32 {
    let remapped = roughness * (1.0 - (3.0 / ior - 2.0).clamp(0.0, 1.0));
    if remapped <= 0.0 {
        return 0.0;
    }
    let lod =
        (2.0 * math::log2(remapped) + filament_lod_offset(size.y, fov_y)) * FILAMENT_LOD_SCALE;
    lod.clamp(0.0, filament_level_count(size).saturating_sub(1) as f32)
}

/// How far HDRP's rough lookup moves from the fragment toward the hit:
/// `k = max(0, 1 − 0.08 · mip)` (`EvaluateBSDF_ScreenspaceRefraction`), `uv = lerp(frag, hit, k)`.
#[inline]
pub fn hdrp_hit_share(mip: f32) -> f32 {
    (1.0 - 0.08 * mip).max(0.0)
}

/// The uniform cubic B-spline's weights of the four texels around a sample at fraction `a` in
/// `[0, 1)` past the second: `(1 − a)³/6`, `(3a³ − 6a² + 4)/6`, `(−3a³ + 3a² + 3a + 1)/6`,
/// `a³/6` (three.js's `w0`–`w3`); they sum to 1.
#[inline]
pub fn bspline_weights(a: f32) -> [f32; 4] {
    let a2 = a * a;
    let a3 = a2 * a;
    let b = 1.0 - a;
    [
        b * b * b / 6.0,
        (3.0 * a3 - 6.0 * a2 + 4.0) / 6.0,
        (-3.0 * a3 + 3.0 * a2 + 3.0 * a + 1.0) / 6.0,
        a3 / 6.0,
    ]
}

/// A screen pyramid as a lookup reads it.
pub trait ScreenMips {
    /// The size of level 0.
    fn size(&self) -> UVec2;
    /// Texel `texel` of level `level` (inside the level).
    fn texel(&self, level: u32, texel: UVec2) -> Vec3;
}

/// The cubic B-spline sample of level `level` at `uv` (`[0, 1]²` over the image, `y` down),
/// edges clamped: the 4 × 4 texels around `uv · size − ½` weighted by [`bspline_weights`]
/// (three.js's `bicubic`, which reaches the same sum with four bilinear taps).
pub fn sample_bspline<M: ScreenMips>(mips: &M, uv: Vec2, level: u32) -> Vec3 {
    let size = level_size(mips.size(), level);
    let t = uv * size.as_vec2() - Vec2::splat(0.5);
    let base = Vec2::new(math::floor(t.x), math::floor(t.y));
    let f = t - base;
    let (wx, wy) = (bspline_weights(f.x), bspline_weights(f.y));
    let max = size.as_ivec2() - glam::IVec2::ONE;
    let mut sum = Vec3::ZERO;
    for (j, wy) in wy.iter().enumerate() {
        let y = (base.y as i32 - 1 + j as i32).clamp(0, max.y) as u32;
        let mut row = Vec3::ZERO;
        for (i, wx) in wx.iter().enumerate() {
            let x = (base.x as i32 - 1 + i as i32).clamp(0, max.x) as u32;
            row += *wx * mips.texel(level, UVec2::new(x, y));
        }
        sum += *wy * row;
    }
    sum
}

/// The bilinear sample of level `level` at `uv` (`[0, 1]²`, `y` down), edges clamped.
pub fn sample_bilinear<M: ScreenMips>(mips: &M, uv: Vec2, level: u32) -> Vec3 {
    let size = level_size(mips.size(), level);
    let t = uv * size.as_vec2() - Vec2::splat(0.5);
    let base = Vec2::new(math::floor(t.x), math::floor(t.y));
    let f = t - base;
    let max = size.as_ivec2() - glam::IVec2::ONE;
    let at = |dx: i32, dy: i32| {
        let x = (base.x as i32 + dx).clamp(0, max.x) as u32;
        let y = (base.y as i32 + dy).clamp(0, max.y) as u32;
        mips.texel(level, UVec2::new(x, y))
    };
    let top = at(0, 0) + (at(1, 0) - at(0, 0)) * f.x;
    let bottom = at(0, 1) + (at(1, 1) - at(0, 1)) * f.x;
    top + (bottom - top) * f.y
}

/// A trilinear sample at `lod` (`textureLod` with linear filtering between and within levels,
/// as Godot's screen texture and HDRP's colour pyramid are read): the bilinear samples at
/// levels `⌊lod⌋` and `⌈lod⌉` (clamped to the pyramid) mixed by `fract(lod)`.
pub fn sample_trilinear<M: ScreenMips>(mips: &M, uv: Vec2, lod: f32) -> Vec3 {
    between_levels(mips, lod, |level| sample_bilinear(mips, uv, level))
}

/// `sample(⌊lod⌋)` and `sample(⌈lod⌉)` (levels clamped to the pyramid) mixed by `fract(lod)`.
fn between_levels<M: ScreenMips>(mips: &M, lod: f32, sample: impl Fn(u32) -> Vec3) -> Vec3 {
    let top = level_count(mips.size()) - 1;
    let lod = lod.max(0.0);
    let floor = math::floor(lod);
    let fraction = lod - floor;
    let low = (floor as u32).min(top);
    let high = (low + u32::from(fraction > 0.0)).min(top);
    let fine = sample(low);
    if high == low {
        return fine;
    }
    let coarse = sample(high);
    fine + (coarse - fine) * fraction
}

/// three.js's `textureBicubic(map, uv, lod)`: the B-spline samples at levels `⌊lod⌋` and
/// `⌈lod⌉` (each clamped to the pyramid), mixed by `fract(lod)`.
pub fn sample_threejs<M: ScreenMips>(mips: &M, uv: Vec2, lod: f32) -> Vec3 {
    between_levels(mips, lod, |level| sample_bspline(mips, uv, level))
}

#[cfg(test)]
mod tests {
    use super::*;
    use alloc::vec::Vec;

    /// A pyramid built by the definition, for the tests.
    struct Pyramid {
        size: UVec2,
        levels: Vec<Vec<Vec3>>,
    }

    impl Pyramid {
        fn new(size: UVec2, f: impl Fn(UVec2) -> Vec3) -> Self {
            let levels = (0..level_count(size))
                .map(|k| {
                    let s = level_size(size, k);
                    (0..s.y)
                        .flat_map(|y| (0..s.x).map(move |x| UVec2::new(x, y)))
                        .map(|t| {
                            let (a, b) = level_block(size, k, t);
                            let mut sum = Vec3::ZERO;
                            for y in a.y..b.y {
                                for x in a.x..b.x {
                                    sum += f(UVec2::new(x, y));
                                }
                            }
                            sum / ((b.x - a.x) * (b.y - a.y)) as f32
                        })
                        .collect()
                })
                .collect();
            Self { size, levels }
        }
    }

    impl ScreenMips for Pyramid {
        fn size(&self) -> UVec2 {
            self.size
        }
        fn texel(&self, level: u32, texel: UVec2) -> Vec3 {
            let w = level_size(self.size, level).x;
            self.levels[level as usize][(texel.y * w + texel.x) as usize]
        }
    }

    #[test]
    fn levels_halve_down_to_one_texel() {
        assert_eq!(level_count(UVec2::new(256, 256)), 9);
        assert_eq!(level_count(UVec2::new(320, 240)), 9);
        assert_eq!(level_count(UVec2::new(1, 1)), 1);
        assert_eq!(level_size(UVec2::new(320, 240), 8), UVec2::new(1, 1));
        assert_eq!(level_size(UVec2::new(320, 240), 3), UVec2::new(40, 30));
        assert_eq!(
            level_block(UVec2::new(5, 5), 1, UVec2::new(1, 1)),
            (UVec2::new(2, 2), UVec2::new(4, 4))
        );
    }

    /// `applyIorToRoughness`: no blur at index 1, the full roughness from 1.5.
    #[test]
    fn threejs_lod_scales_roughness_by_the_index() {
        assert_eq!(threejs_lod(256, 0.5, 1.5), 4.0);
        assert_eq!(threejs_lod(256, 0.5, 2.4), 4.0);
        assert_eq!(threejs_lod(256, 0.5, 1.25), 2.0);
        assert_eq!(threejs_lod(256, 0.5, 1.0), 0.0);
        assert_eq!(threejs_lod(1024, 0.0, 1.5), 0.0);
    }

    /// Godot's `8 r`; HDRP's `r^1.3 (levels − 1)` and the share of the hit it keeps.
    #[test]
    fn godot_and_hdrp_rules() {
        assert_eq!(godot_lod(0.25), 2.0);
        assert_eq!(hdrp_mip(0.0, 9), 0.0);
        assert!((hdrp_mip(1.0, 9) - 8.0).abs() < 1e-5);
        assert!((hdrp_mip(0.5, 9) - 8.0 * 0.5f32.powf(1.3)).abs() < 1e-5);
        assert_eq!(hdrp_hit_share(0.0), 1.0);
        assert!((hdrp_hit_share(5.0) - 0.6).abs() < 1e-6);
        assert_eq!(hdrp_hit_share(20.0), 0.0);
    }

    /// Filament's offset, level count and LOD, from its formulas written out by hand.
    #[test]
    fn filament_rule() {
        // A 45° field of view, 256 texels tall: s = 1/256.
        let offset = filament_lod_offset(256, core::f32::consts::FRAC_PI_4);
        let expected = -(2.0f32.sqrt() * 22.0 / 6.0 / 256.0).log2();
        assert!((offset - expected).abs() < 1e-5, "{offset} vs {expected}");
        // L = 9 levels at 256: Filament keeps 5; at 8 × 8 (L = 4) all 4; at 4 × 4, 3.
        assert_eq!(filament_level_count(UVec2::new(256, 256)), 5);
        assert_eq!(filament_level_count(UVec2::new(8, 8)), 4);
        assert_eq!(filament_level_count(UVec2::new(4, 4)), 3);
        let size = UVec2::new(256, 256);
        let fov = core::f32::consts::FRAC_PI_4;
        let lod = filament_lod(size, fov, 0.5, 1.5);
        assert!((lod - (offset - 2.0) * 0.8614).abs() < 1e-5, "{lod}");
        // Index 1 and roughness 0 do not blur; below 1.5 the roughness shrinks; clamped at the
        // last kept level; a smaller roughness reads no mip at all.
        assert_eq!(filament_lod(size, fov, 0.5, 1.0), 0.0);
        assert_eq!(filament_lod(size, fov, 0.0, 1.5), 0.0);
        assert!(filament_lod(size, fov, 0.5, 1.25) < lod);
        assert_eq!(filament_lod(size, fov, 1.0, 1.5), 4.0);
        assert_eq!(filament_lod(size, fov, 0.05, 1.5), 0.0);
        // A narrower field of view or a taller frame: more texels for the same angle.
        assert!(filament_lod(UVec2::new(512, 512), fov, 0.5, 1.5) > lod);
        assert!(filament_lod(size, fov / 2.0, 0.5, 1.5) > lod);
    }

    #[test]
    fn bspline_weights_sum_to_one_and_reproduce_lines() {
        for k in 0..16 {
            let a = k as f32 / 16.0;
            let w = bspline_weights(a);
            assert!((w.iter().sum::<f32>() - 1.0).abs() < 1e-6, "{a}");
            // The B-spline reproduces linear functions: Σ wᵢ (i − 1) = a.
            let mean: f32 = w
                .iter()
                .enumerate()
                .map(|(i, w)| w * (i as f32 - 1.0))
                .sum();
            assert!((mean - a).abs() < 1e-6, "{a}: {mean}");
        }
    }

    /// A linear ramp is sampled exactly inside the image at every level (the filter reproduces
    /// lines and a box mean of a line is the line at the block's centre), a constant image
    /// anywhere; a lod between two levels mixes them.
    #[test]
    fn samples_of_a_ramp_and_a_constant() {
        let size = UVec2::new(64, 32);
        let ramp = Pyramid::new(size, |t| Vec3::new(t.x as f32 + 0.5, t.y as f32 + 0.5, 1.0));
        for level in 0..3 {
            for uv in [
                Vec2::new(0.5, 0.5),
                Vec2::new(0.3, 0.6),
                Vec2::new(0.41, 0.37),
            ] {
                let c = sample_bspline(&ramp, uv, level);
                let expected = Vec3::new(uv.x * 64.0, uv.y * 32.0, 1.0);
                assert!(
                    (c - expected).abs().max_element() < 1e-3,
                    "{level} {uv}: {c}"
                );
            }
        }
        for level in 0..3 {
            let uv = Vec2::new(0.41, 0.37);
            let c = sample_bilinear(&ramp, uv, level);
            let expected = Vec3::new(uv.x * 64.0, uv.y * 32.0, 1.0);
            assert!((c - expected).abs().max_element() < 1e-3, "{level}: {c}");
        }
        let trilinear = sample_trilinear(&ramp, Vec2::new(0.3, 0.6), 1.5);
        assert!((trilinear - Vec3::new(19.2, 19.2, 1.0)).abs().max_element() < 1e-3);
        let mixed = sample_threejs(&ramp, Vec2::new(0.3, 0.6), 1.25);
        assert!(
            (mixed - Vec3::new(19.2, 19.2, 1.0)).abs().max_element() < 1e-3,
            "{mixed}"
        );
        let grey = Pyramid::new(size, |_| Vec3::splat(0.25));
        for lod in [0.0, 0.5, 3.7, 6.0, 40.0] {
            for uv in [Vec2::ZERO, Vec2::ONE, Vec2::new(-0.5, 2.0)] {
                let c = sample_threejs(&grey, uv, lod);
                assert!(
                    (c - Vec3::splat(0.25)).abs().max_element() < 1e-6,
                    "{lod} {uv}"
                );
                let c = sample_trilinear(&grey, uv, lod);
                assert!(
                    (c - Vec3::splat(0.25)).abs().max_element() < 1e-6,
                    "{lod} {uv}"
                );
            }
        }
        // The top level is the image's mean.
        let top = level_count(size) - 1;
        let mean = sample_threejs(&ramp, Vec2::new(0.1, 0.9), 100.0);
        assert!(
            (mean - Vec3::new(32.0, 16.0, 1.0)).abs().max_element() < 1e-3,
            "{top} {mean}"
        );
    }

    /// A bright texel spreads further with the LOD: the blur of a point grows with `lod`.
    #[test]
    fn a_point_spreads_with_the_lod() {
        let size = UVec2::new(64, 64);
        let point = Pyramid::new(size, |t| {
            if t == UVec2::new(32, 32) {
                Vec3::ONE
            } else {
                Vec3::ZERO
            }
        });
        let at = |lod: f32, dx: f32| {
            sample_threejs(&point, Vec2::new((32.5 + dx) / 64.0, 32.5 / 64.0), lod).x
        };
        assert!(at(0.0, 4.0) < 1e-6, "lod 0 stays within two texels");
        assert!(at(3.0, 4.0) > 1e-3, "{}", at(3.0, 4.0));
        assert!(at(0.0, 0.0) > at(2.0, 0.0) && at(2.0, 0.0) > at(4.0, 0.0));
    }
}
