//! What a `pvrr` frame reads of each map: the texels its bilinear lookups touch, kept as one
//! span of columns per map row. A map view shades only its demanded texels (Kakimoto et al.
//! §3.1 step 4 reads a map only where a reflector pixel looks it up; a convex mirror's lookups
//! touch about three quarters of its map, a map no reflector pixel sees is not read at all).

use std::ops::Range;
use std::sync::atomic::AtomicU32;
use std::sync::atomic::Ordering::Relaxed;

/// The demanded texels of one view: per row, the columns `[first, end)` that cover every
/// column a lookup reads in that row (a superset: the columns between two read ones count as
/// read). Marked concurrently by the pass that looks the map up, read after that pass ends.
#[derive(Debug, Default)]
pub(super) struct Demand {
    /// Per row `[first, end)`; `[u32::MAX, 0]` for a row nothing reads.
    rows: Vec<[AtomicU32; 2]>,
}

impl Demand {
    /// `height` rows, none demanded.
    pub fn clear(&mut self, height: u32) {
        self.set(height, [u32::MAX, 0]);
    }

    /// Every texel of a `width × height` view demanded (the eye's pixels are all shown).
    pub fn fill(&mut self, width: u32, height: u32) {
        self.set(height, [0, width]);
    }

    fn set(&mut self, height: u32, span: [u32; 2]) {
        let new = || span.map(AtomicU32::new);
        self.rows.resize_with(height as usize, new);
        for row in &mut self.rows {
            for (value, &v) in row.iter_mut().zip(&span) {
                *value.get_mut() = v;
            }
        }
    }

    /// Demands columns `x[0]..=x[1]` of rows `y[0]..=y[1]`. Rows whose span already covers the
    /// columns are only read (neighbouring lookups mostly fall inside what is marked).
    ///
    /// # Panics
    /// If a row is outside the view.
    #[inline]
    pub fn mark(&self, x: [u32; 2], y: [u32; 2]) {
        for [first, end] in &self.rows[y[0] as usize..=y[1] as usize] {
            if first.load(Relaxed) > x[0] {
                first.fetch_min(x[0], Relaxed);
            }
            if end.load(Relaxed) <= x[1] {
                end.fetch_max(x[1] + 1, Relaxed);
            }
        }
    }

    /// The demanded columns of row `y` (empty when none).
    #[inline]
    pub fn span(&self, y: u32) -> Range<u32> {
        let [first, end] = &self.rows[y as usize];
        let (first, end) = (first.load(Relaxed), end.load(Relaxed));
        if first < end { first..end } else { 0..0 }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rayon::prelude::*;

    #[test]
    fn a_row_spans_every_marked_column_and_nothing_unmarked_rows() {
        let mut demand = Demand::default();
        demand.clear(6);
        demand.mark([7, 9], [1, 2]);
        demand.mark([3, 3], [2, 2]);
        demand.mark([8, 12], [4, 4]);
        let spans: Vec<_> = (0..6).map(|y| demand.span(y)).collect();
        assert_eq!(spans, [0..0, 7..10, 3..10, 0..0, 8..13, 0..0]);
        // A frame's clear forgets the last frame's marks; a fill demands everything.
        demand.clear(6);
        assert!((0..6).all(|y| demand.span(y).is_empty()));
        demand.fill(5, 3);
        assert_eq!(
            (0..3).map(|y| demand.span(y)).collect::<Vec<_>>(),
            [0..5, 0..5, 0..5]
        );
    }

    /// Marks from many threads at once give each row the hull of its marks, as one thread.
    #[test]
    fn concurrent_marks_give_the_same_spans_as_sequential_ones() {
        let marks: Vec<([u32; 2], [u32; 2])> = (0..20_000u32)
            .map(|i| {
                let (x, y) = (i.wrapping_mul(2_654_435_761) % 1000, i % 97);
                ([x, x + i % 5], [y, (y + i % 3).min(99)])
            })
            .collect();
        let (mut parallel, mut sequential) = (Demand::default(), Demand::default());
        parallel.clear(100);
        sequential.clear(100);
        marks.par_iter().for_each(|&(x, y)| parallel.mark(x, y));
        marks.iter().for_each(|&(x, y)| sequential.mark(x, y));
        for y in 0..100 {
            assert_eq!(parallel.span(y), sequential.span(y), "row {y}");
        }
        assert!((0..99).all(|y| !sequential.span(y).is_empty()));
    }
}
