//! Deterministic stratified samples: positions inside a pixel, and the microfacet normals of
//! the rough interfaces a path meets.
//!
//! Every number depends only on the pixel, the sample's index and the node of the path tree
//! (the sequence of reflect/transmit choices that led there), never on the order work is
//! done in, so images are bit-identical whatever the thread count, and the GPU twin
//! (`refract-gpu`'s `reference.wgsl`) draws the same numbers for the same node.

use glam::Vec2;

/// Van der Corput radical inverse in base 2 of `i`, in `[0, 1)`.
#[inline]
fn radical_inverse_base2(i: u32) -> f32 {
    (i.reverse_bits() as f64 / 4_294_967_296.0) as f32
}

/// A 32-bit integer hash (lowbias32 by Chris Wellons): decorrelates neighbouring pixels.
#[inline]
pub fn hash(mut x: u32) -> u32 {
    x ^= x >> 16;
    x = x.wrapping_mul(0x7feb_352d);
    x ^= x >> 15;
    x = x.wrapping_mul(0x846c_a68b);
    x ^= x >> 16;
    x
}

/// Offset in `[0, 1)²` of sample `index` of `count` in pixel `(x, y)`.
///
/// One sample is the pixel centre `(½, ½)`, as in every other backend. More samples form a
/// Hammersley set `((i + ½)/N, φ₂(i))`, stratified in both dimensions, shifted per pixel by a
/// hashed Cranley–Patterson rotation so that neighbouring pixels do not share a pattern. The
/// positions depend only on `(x, y, index, count)`, so the image is bit-identical whatever the
/// thread count.
#[inline]
pub fn pixel_sample(x: u32, y: u32, index: u32, count: u32) -> Vec2 {
    if count <= 1 {
        return Vec2::splat(0.5);
    }
    let h = hash(x.wrapping_mul(0x9E37_79B9) ^ hash(y));
    let shift = Vec2::new((h & 0xFFFF) as f32 / 65536.0, (h >> 16) as f32 / 65536.0);
    let p = Vec2::new(
        (index as f32 + 0.5) / count as f32,
        radical_inverse_base2(index),
    );
    (p + shift).fract()
}

/// `u ∈ [0, 1)` of the wavelengths of sample `index` of `count` in pixel `(x, y)`
/// ([`refract_core::spectral::Wavelengths::sample`]): `(i + ½) / N`, stratified over the
/// pixel's samples, shifted per pixel by a hashed Cranley–Patterson rotation independent of
/// the position's.
#[inline]
pub fn wavelength_sample(x: u32, y: u32, index: u32, count: u32) -> f32 {
    let h = hash(path_root(x, y) ^ 0x5BD1_E995);
    let shift = (h >> 8) as f32 / 16_777_216.0;
    let u = (index as f32 + 0.5) / count.max(1) as f32 + shift;
    if u >= 1.0 { u - 1.0 } else { u }
}

/// The key of the root of pixel `(x, y)`'s path tree.
#[inline]
pub fn path_root(x: u32, y: u32) -> u32 {
    hash(hash(x ^ 0xA511_E9B3).wrapping_add(y))
}

/// The key of the child of node `key` along `branch` (0: reflected, 1: transmitted).
#[inline]
pub fn path_child(key: u32, branch: u32) -> u32 {
    hash(key ^ branch.wrapping_add(1).wrapping_mul(0x9E37_79B9))
}

/// The Halton bases of the first [`STRATIFIED_DEPTHS`] interactions' 2D samples.
const HALTON_BASES: [(u32, u32); 4] = [(3, 5), (7, 11), (13, 17), (19, 23)];

/// Interactions up to this depth draw stratified samples; deeper ones draw hashed ones.
pub const STRATIFIED_DEPTHS: u32 = 4;

/// Radical inverse of `i` in `base`: the digits of `i` mirrored about the point, exact as a
/// ratio of integers for `i < 2¹⁶` and bases ≤ 23 (the sample counts and bases used here).
#[inline]
fn radical_inverse(base: u32, index: u32) -> f32 {
    let (mut i, mut reversed, mut denominator) = (index, 0u32, 1u32);
    while i > 0 {
        reversed = reversed * base + i % base;
        denominator *= base;
        i /= base;
    }
    reversed as f32 / denominator as f32
}

/// `u ∈ [0, 1)²` for the rough interface met at path-tree node `key`, `depth` interactions
/// into the path, by the pixel's sample `index`: for the first [`STRATIFIED_DEPTHS`]
/// interactions a randomised Halton point (bases [`HALTON_BASES`] of the depth, shifted by a
/// Cranley–Patterson rotation hashed from the node), so that the samples of a pixel stratify
/// the microfacet normals of each node; past them, a hash of node and index.
#[inline]
pub fn interface_sample(key: u32, depth: u32, index: u32) -> Vec2 {
    if depth < STRATIFIED_DEPTHS {
        let (b1, b2) = HALTON_BASES[depth as usize];
        let h = hash(key);
        let shift = Vec2::new((h & 0xFFFF) as f32 / 65536.0, (h >> 16) as f32 / 65536.0);
        let p = Vec2::new(radical_inverse(b1, index), radical_inverse(b2, index));
        return (p + shift).fract();
    }
    let h1 = hash(key ^ hash(index));
    let h2 = hash(h1 ^ 0x85EB_CA6B);
    Vec2::new(
        (h1 >> 8) as f32 / 16_777_216.0,
        (h2 >> 8) as f32 / 16_777_216.0,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn samples_are_stratified() {
        // 16 samples: one per column of a 16-strata partition in x, and in y.
        let mut xs = [false; 16];
        let mut ys = [false; 16];
        for i in 0..16 {
            let s = pixel_sample(3, 7, i, 16);
            assert!((0.0..1.0).contains(&s.x) && (0.0..1.0).contains(&s.y));
            xs[(s.x * 16.0) as usize] = true;
            ys[(s.y * 16.0) as usize] = true;
        }
        assert!(xs.iter().all(|&b| b) && ys.iter().all(|&b| b));
        assert_eq!(pixel_sample(3, 7, 0, 1), Vec2::splat(0.5));
    }

    /// The first interactions' samples stratify: 3⁴ = 81 samples of base-3 Halton cover
    /// each of 81 strata once (before the shift, which moves every stratum alike).
    #[test]
    fn interface_samples_stratify_and_differ_by_node() {
        let mut strata = [false; 81];
        for i in 0..81 {
            strata[(radical_inverse(3, i) * 81.0).round() as usize] = true;
        }
        assert!(strata.iter().all(|&b| b));
        let root = path_root(5, 9);
        let a = interface_sample(root, 0, 3);
        assert_ne!(a, interface_sample(path_child(root, 0), 0, 3));
        assert_ne!(a, interface_sample(path_child(root, 1), 0, 3));
        assert_ne!(path_child(root, 0), path_child(root, 1));
        for depth in 0..8 {
            let u = interface_sample(root, depth, 7);
            assert!((0.0..1.0).contains(&u.x) && (0.0..1.0).contains(&u.y));
        }
    }
}
