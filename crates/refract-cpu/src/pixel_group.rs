//! Up to eight pixels of one row, gathered for the eight-lane kernels and resolves.

use core::ops::Range;

use refract_core::lanes::LANES;

/// The `x` coordinates of up to [`LANES`] pixels of a row. Unused lanes are padded with copies
/// of lane 0 before the group is processed, and their results are dropped.
#[derive(Clone, Copy, Debug)]
pub(crate) struct PixelGroup {
    /// The pixels' `x`; lanes `len..` are padding once [`Self::pad`] has run.
    pub x: [u32; LANES],
    /// How many lanes hold pixels.
    pub len: usize,
}

impl PixelGroup {
    pub fn new() -> Self {
        Self {
            x: [0; LANES],
            len: 0,
        }
    }

    /// Adds pixel `x`; true when the group is full.
    #[inline]
    pub fn push(&mut self, x: u32) -> bool {
        self.x[self.len] = x;
        self.len += 1;
        self.len == LANES
    }

    /// Pads the unused lanes with copies of lane 0.
    pub fn pad(&mut self) {
        let first = self.x[0];
        self.x[self.len..].fill(first);
    }
}

/// Pixels `xs` of a row gathered into groups of eight: those `covered` says see a surface and
/// the others, each group handed to `process` with whether it is covered as soon as it is
/// full, the last partial ones padded ([`PixelGroup::pad`]) at the end.
#[inline]
pub(crate) fn for_each_group(
    xs: Range<u32>,
    covered: impl Fn(u32) -> bool,
    mut process: impl FnMut(&PixelGroup, bool),
) {
    let (mut surface, mut background) = (PixelGroup::new(), PixelGroup::new());
    for x in xs {
        let (group, is_covered) = match covered(x) {
            true => (&mut surface, true),
            false => (&mut background, false),
        };
        if group.push(x) {
            process(group, is_covered);
            group.len = 0;
        }
    }
    for (group, is_covered) in [(&mut surface, true), (&mut background, false)] {
        if group.len > 0 {
            group.pad();
            process(group, is_covered);
        }
    }
}
