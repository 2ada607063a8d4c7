//! The mip-mapped screen texture of the engines' rough transmission on the CPU: the levels of
//! [`refract_core::screen_mips`] built from a frame's screen colours, each level's texels the
//! block means of level 0's (in parallel), its memory kept between frames.

use glam::{UVec2, Vec3};
use rayon::prelude::*;
use refract_core::screen_mips::{ScreenMips, level_block, level_count, level_size};

/// The levels of one frame's screen texture a frame reads (from level 0), level after level in
/// one buffer.
#[derive(Default)]
pub struct ScreenPyramid {
    size: UVec2,
    /// Where level `k` starts in `texels`.
    offsets: Vec<usize>,
    texels: Vec<Vec3>,
}

impl ScreenPyramid {
    /// Rebuilds the first `levels` levels (at least 1, at most the pyramid's) of a `size`
    /// screen whose texel `t` shows `color(t)`; a read of a level above them is out of range
    /// ([`refract_core::engine::EngineModel::rough_levels`] says how many a frame reads).
    pub fn build(&mut self, size: UVec2, levels: u32, color: impl Fn(UVec2) -> Vec3 + Sync) {
        self.size = size;
        self.offsets.clear();
        let levels = levels.clamp(1, level_count(size));
        let mut total = 0;
        for level in 0..levels {
            self.offsets.push(total);
            let s = level_size(size, level);
            total += (s.x * s.y) as usize;
        }
        self.texels.resize(total, Vec3::ZERO);
        let (base, above) = self.texels.split_at_mut((size.x * size.y) as usize);
        base.par_chunks_mut(size.x as usize)
            .enumerate()
            .for_each(|(y, row)| {
                for (x, texel) in row.iter_mut().enumerate() {
                    *texel = color(UVec2::new(x as u32, y as u32));
                }
            });
        let base = &*base;
        let mut rest = above;
        for level in 1..levels {
            let s = level_size(size, level);
            let (this, next) = rest.split_at_mut((s.x * s.y) as usize);
            this.par_chunks_mut(s.x as usize)
                .enumerate()
                .for_each(|(y, row)| {
                    for (x, texel) in row.iter_mut().enumerate() {
                        let (a, b) = level_block(size, level, UVec2::new(x as u32, y as u32));
                        let mut sum = Vec3::ZERO;
                        for by in a.y..b.y {
                            let line = &base[(by * size.x) as usize..][..size.x as usize];
                            for c in &line[a.x as usize..b.x as usize] {
                                sum += *c;
                            }
                        }
                        *texel = sum / ((b.x - a.x) * (b.y - a.y)) as f32;
                    }
                });
            rest = next;
        }
    }
}

impl ScreenMips for ScreenPyramid {
    fn size(&self) -> UVec2 {
        self.size
    }

    #[inline]
    fn texel(&self, level: u32, texel: UVec2) -> Vec3 {
        let width = level_size(self.size, level).x;
        self.texels[self.offsets[level as usize] + (texel.y * width + texel.x) as usize]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every level holds the block means of level 0, by the definition.
    #[test]
    fn levels_are_block_means() {
        let size = UVec2::new(13, 6);
        let color = |t: UVec2| Vec3::new(t.x as f32, t.y as f32, (t.x * t.y) as f32);
        let mut pyramid = ScreenPyramid::default();
        pyramid.build(size, level_count(size), color);
        for level in 0..level_count(size) {
            let s = level_size(size, level);
            for y in 0..s.y {
                for x in 0..s.x {
                    let (a, b) = level_block(size, level, UVec2::new(x, y));
                    let n = ((b.x - a.x) * (b.y - a.y)) as f32;
                    let mean = (a.y..b.y)
                        .flat_map(|y| (a.x..b.x).map(move |x| color(UVec2::new(x, y))))
                        .sum::<Vec3>()
                        / n;
                    let got = pyramid.texel(level, UVec2::new(x, y));
                    assert!((got - mean).abs().max_element() < 1e-4, "{level} {x} {y}");
                }
            }
        }
        assert_eq!(pyramid.texel(3, UVec2::ZERO), {
            let all: Vec3 = (0..6)
                .flat_map(|y| (0..8).map(move |x| color(UVec2::new(x, y))))
                .sum();
            all / 48.0
        });
    }
}
