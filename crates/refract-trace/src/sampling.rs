//! Deterministic stratified sample positions inside a pixel.

use glam::Vec2;

/// Van der Corput radical inverse in base 2 of `i`, in `[0, 1)`.
#[inline]
fn radical_inverse_base2(i: u32) -> f32 {
    (i.reverse_bits() as f64 / 4_294_967_296.0) as f32
}

/// A 32-bit integer hash (lowbias32 by Chris Wellons): decorrelates neighbouring pixels.
#[inline]
fn hash(mut x: u32) -> u32 {
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
}
