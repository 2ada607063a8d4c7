//! The visibility buffer of one pass ([`SurfaceBuffer`]: depth and triangle id per pixel, the
//! covered extent of each row) and its bands of rows ([`Band`]), read texel by texel or eight at a
//! time.

use core::ops::Range;

use glam::Vec4;
use refract_core::lanes::LANES;

use super::resolve::{TexelLanes, row_texel_lanes};
use super::setup::{Projected, TriangleStore};
use super::{Attribute, BAND_ROWS, DepthTest, EMPTY, Texel, Visibility};

/// Per-pixel surface data of one pass, row-major from the top: which fragment survived the
/// depth test at each pixel, with its attributes interpolated on demand.
///
/// The buffer keeps all its memory between frames: after the first frame at a resolution,
/// rasterising into it allocates nothing.
#[derive(Clone, Debug, Default)]
pub struct SurfaceBuffer {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    pub(super) visibility: Vec<Visibility>,
    /// Per row, the pixels `[first, end)` between its first and last covered pixel
    /// (`[u32::MAX, 0]` for an empty row).
    pub(super) extents: Vec<[u32; 2]>,
    pub(super) triangles: TriangleStore,
    /// Scratch: clip-space and projected vertex positions, and the per-band triangle lists.
    pub(super) clip: Vec<Vec4>,
    pub(super) projected: Vec<Projected>,
    pub(super) bins: Vec<Vec<u32>>,
    /// The frame shape and depth test whose cleared value every pixel outside its row's
    /// extent holds (`None`: unknown, clear everything): the next frame of that shape clears
    /// only the last frame's extents.
    pub(super) cleared_for: Option<(u32, u32, DepthTest)>,
}

impl SurfaceBuffer {
    /// An empty buffer (no pixels).
    pub fn new() -> Self {
        Self::default()
    }

    /// The fragment covering pixel `index` (row-major), or `None` where the pixel is empty.
    #[inline]
    pub fn texel(&self, index: usize) -> Option<Texel> {
        let v = self.visibility.get(index)?;
        (v.triangle != EMPTY).then(|| {
            let (x, y) = (index as u32 % self.width, index as u32 / self.width);
            self.triangles.get(v.triangle).texel(x, y)
        })
    }

    /// The fragments covering eight pixels of row `y` (`x[i]`), all of which must be covered
    /// (see [`Self::is_covered`]); each is [`Self::texel`]'s, bit for bit.
    ///
    /// # Panics
    /// If one of the pixels is empty or outside the buffer.
    pub fn texels_x8(&self, x: &[u32; LANES], y: u32) -> [Texel; LANES] {
        self.attribute_lanes::<{ Attribute::ALL }>(x, y).to_texels()
    }

    /// [`Self::texels_x8`] as lanes, with only the position, the normal and the
    /// [`Attribute`]s in `ATTRIBUTES` (the others zero): the same bits for those, less work.
    ///
    /// # Panics
    /// If one of the pixels is empty or outside the buffer.
    #[inline]
    pub fn attribute_lanes<const ATTRIBUTES: u8>(&self, x: &[u32; LANES], y: u32) -> TexelLanes {
        let row = (y * self.width) as usize;
        row_texel_lanes::<ATTRIBUTES>(&self.visibility[row..], &self.triangles, x, y)
    }

    /// The pixels of row `y` between its first and last covered pixel: no pixel outside is
    /// covered (empty when the row is).
    #[inline]
    pub fn covered_span(&self, y: u32) -> Range<u32> {
        span(self.extents[y as usize])
    }

    /// Whether pixel `index` (row-major) is covered.
    #[inline]
    pub fn is_covered(&self, index: usize) -> bool {
        self.visibility
            .get(index)
            .is_some_and(|v| v.triangle != EMPTY)
    }
}

/// The rows of one band right after they were rasterised, for per-pixel work while they are in
/// cache (see [`rasterize_bands`](super::rasterize_bands)).
pub struct Band<'a> {
    /// The first row of the band (rows `first_row..first_row + rows()`).
    pub first_row: u32,
    pub(super) width: u32,
    pub(super) visibility: &'a [Visibility],
    pub(super) extents: &'a [[u32; 2]],
    pub(super) triangles: &'a TriangleStore,
}

/// A row extent as a range (empty rows: `0..0`).
#[inline]
pub(super) fn span([first, end]: [u32; 2]) -> Range<u32> {
    if first < end { first..end } else { 0..0 }
}

impl Band<'_> {
    /// The image width in pixels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Whether pixel `(x, y)` (`y` an image row inside this band) is covered.
    #[inline]
    pub fn is_covered(&self, x: u32, y: u32) -> bool {
        self.visibility[((y - self.first_row) * self.width + x) as usize].triangle != EMPTY
    }

    /// The fragment covering pixel `(x, y)` (`y` an image row inside this band), as
    /// [`SurfaceBuffer::texel`] computes it.
    #[inline]
    pub fn texel(&self, x: u32, y: u32) -> Option<Texel> {
        let v = self.visibility[((y - self.first_row) * self.width + x) as usize];
        (v.triangle != EMPTY).then(|| self.triangles.get(v.triangle).texel(x, y))
    }

    /// The window depth of the fragment covering pixel `(x, y)` (`y` an image row inside this
    /// band), `None` where the pixel is empty: no interpolation.
    #[inline]
    pub fn depth(&self, x: u32, y: u32) -> Option<f32> {
        let v = self.visibility[((y - self.first_row) * self.width + x) as usize];
        (v.triangle != EMPTY).then_some(v.depth)
    }

    /// The number of rows of this band.
    pub fn rows(&self) -> u32 {
        (self.visibility.len() / self.width as usize) as u32
    }

    /// [`SurfaceBuffer::attribute_lanes`] for eight pixels of row `y` of this band.
    #[inline]
    pub fn attribute_lanes<const ATTRIBUTES: u8>(&self, x: &[u32; LANES], y: u32) -> TexelLanes {
        let row = ((y - self.first_row) * self.width) as usize;
        row_texel_lanes::<ATTRIBUTES>(&self.visibility[row..], self.triangles, x, y)
    }

    /// The pixels of row `y` (an image row inside this band) between its first and last
    /// covered pixel: no pixel outside is covered (empty when the row is).
    #[inline]
    pub fn covered_span(&self, y: u32) -> Range<u32> {
        span(self.extents[(y - self.first_row) as usize])
    }
}

/// The number of pixels in a full band at `width` (the chunk size of per-band outputs for
/// [`rasterize_bands`](super::rasterize_bands)).
pub fn band_pixels(width: u32) -> usize {
    (BAND_ROWS * width) as usize
}
