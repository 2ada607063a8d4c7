//! Scan conversion: the entry points, bands of rows rasterised in parallel (each band owned by
//! one task), a row's inside pixels solved as one run from the three edge functions, the depth
//! test per pixel.

use glam::Vec4;
use rayon::prelude::*;
use refract_core::Camera;

use super::buffer::{Band, SurfaceBuffer, band_pixels, span};
use super::setup::{Projected, TriangleStore, project};
use super::triangle::is_top_left;
use super::{BAND_ROWS, DepthInterpolation, DepthTest, Faces, RasterMesh, Visibility};

/// Rasterises `mesh` seen by `camera`, keeping `faces` and the fragment chosen by `test`.
///
/// Deterministic: triangles are binned into bands of rows in index order and each band is owned
/// by one task, so the result does not depend on the thread count.
pub fn rasterize(
    mesh: &RasterMesh<'_>,
    camera: &Camera,
    faces: Faces,
    test: DepthTest,
) -> SurfaceBuffer {
    let mut buffer = SurfaceBuffer::new();
    rasterize_into(mesh, camera, faces, test, &mut buffer);
    buffer
}

/// [`rasterize`] into an existing buffer, reusing its memory (a renderer's per-frame path: no
/// allocation, no page faults once the buffer has reached its size).
pub fn rasterize_into(
    mesh: &RasterMesh<'_>,
    camera: &Camera,
    faces: Faces,
    test: DepthTest,
    buffer: &mut SurfaceBuffer,
) {
    let bands = camera.height().div_ceil(BAND_ROWS) as usize;
    rasterize_bands(
        mesh,
        camera,
        faces,
        test,
        buffer,
        rayon::iter::repeat_n((), bands),
        |_, ()| {},
    );
}

/// [`rasterize_into`], then `per_band(band, output)` for each band of [`BAND_ROWS`] rows as
/// soon as it is rasterised, on the task that rasterised it. `outputs` yields one item per band
/// in order, e.g. `pixels.par_chunks_mut(band_pixels(width))`.
///
/// # Panics
/// If `outputs` does not have one item per band (`height.div_ceil(BAND_ROWS)`).
pub fn rasterize_bands<O, F>(
    mesh: &RasterMesh<'_>,
    camera: &Camera,
    faces: Faces,
    test: DepthTest,
    buffer: &mut SurfaceBuffer,
    outputs: O,
    per_band: F,
) where
    O: IndexedParallelIterator,
    F: Fn(&Band<'_>, O::Item) + Sync + Send,
{
    rasterize_bands_above(mesh, camera, faces, test, buffer, None, outputs, per_band);
}

/// [`rasterize_into`] keeping at each pixel only fragments deeper than `floor[pixel]` (window
/// depth, row-major, one per pixel; `+∞` rejects every fragment): one step of depth peeling
/// (Everitt 2001), as the distance-map layers beyond the first use it.
///
/// # Panics
/// If `floor` does not have one value per pixel.
pub fn rasterize_peel_into(
    mesh: &RasterMesh<'_>,
    camera: &Camera,
    faces: Faces,
    floor: &[f32],
    buffer: &mut SurfaceBuffer,
) {
    assert_eq!(
        floor.len(),
        (camera.width() * camera.height()) as usize,
        "one floor depth per pixel"
    );
    let bands = camera.height().div_ceil(BAND_ROWS) as usize;
    rasterize_bands_above(
        mesh,
        camera,
        faces,
        DepthTest::Nearest,
        buffer,
        Some(floor),
        rayon::iter::repeat_n((), bands),
        |_, ()| {},
    );
}

// The one worker behind `rasterize_bands` and `rasterize_peel_into`: their parameters plus the
// peeling floor; a struct would only rename them.
#[allow(clippy::too_many_arguments)]
pub(super) fn rasterize_bands_above<O, F>(
    mesh: &RasterMesh<'_>,
    camera: &Camera,
    faces: Faces,
    test: DepthTest,
    buffer: &mut SurfaceBuffer,
    floor: Option<&[f32]>,
    outputs: O,
    per_band: F,
) where
    O: IndexedParallelIterator,
    F: Fn(&Band<'_>, O::Item) + Sync + Send,
{
    let (width, height) = (camera.width(), camera.height());
    let bands = height.div_ceil(BAND_ROWS) as usize;
    assert_eq!(outputs.len(), bands, "one output per band of rows");
    let SurfaceBuffer {
        width: buffer_width,
        height: buffer_height,
        visibility,
        extents,
        triangles,
        clip,
        projected,
        bins,
        cleared_for,
    } = buffer;
    *buffer_width = width;
    *buffer_height = height;

    let world_to_clip = camera.world_to_clip();
    clip.resize(mesh.positions.len(), Vec4::ZERO);
    let (w, h) = (width as f32, height as f32);
    projected.resize(mesh.positions.len(), Projected::default());
    clip.par_iter_mut()
        .zip(projected.par_iter_mut())
        .zip(mesh.positions.par_iter())
        .for_each(|((c, v), p)| {
            *c = world_to_clip * p.extend(1.0);
            *v = project(*c, w, h);
        });
    triangles.set_up(mesh, clip, projected, camera, faces);

    // Bin into bands of rows, preserving triangle order within each band.
    bins.resize_with(bands, Vec::new);
    bins.iter_mut().for_each(Vec::clear);
    for (id, t) in triangles.iter() {
        for band in t.min[1] / BAND_ROWS..=t.max[1] / BAND_ROWS {
            bins[band as usize].push(id);
        }
    }

    visibility.resize((width * height) as usize, test.cleared());
    extents.resize(height as usize, EMPTY_EXTENT);
    // Outside the last frame's extents the pixels still hold the cleared value when it was
    // the same shape and test; otherwise (and once a frame panicked) every pixel is cleared.
    let clear_extents_only = cleared_for.take() == Some((width, height, test));
    let triangles = &*triangles;
    visibility
        .par_chunks_mut(band_pixels(width))
        .zip(extents.par_chunks_mut(BAND_ROWS as usize))
        .zip(bins.par_iter())
        .zip(outputs)
        .enumerate()
        .for_each(|(band, (((rows, extents), bin), output))| {
            let first_row = band as u32 * BAND_ROWS;
            if clear_extents_only {
                for (row, extent) in rows.chunks_exact_mut(width as usize).zip(&*extents) {
                    let run = span(*extent);
                    row[run.start as usize..run.end as usize].fill(test.cleared());
                }
            } else {
                rows.fill(test.cleared());
            }
            extents.fill(EMPTY_EXTENT);
            let floor = floor.map(|f| &f[(first_row * width) as usize..][..rows.len()]);
            let target = BandTarget {
                first_row,
                width,
                rows,
                extents,
            };
            rasterize_band(triangles, bin, target, test, mesh.depth, floor);
            let band = Band {
                first_row,
                width,
                visibility: rows,
                extents,
                triangles,
            };
            per_band(&band, output);
        });
    *cleared_for = Some((width, height, test));
}

/// Triangles wider than this many pixels have each row's inside run solved ([`inside_run`]);
/// narrower ones test each pixel of their bounds.
pub(super) const RUN_MIN_COLUMNS: i64 = 8;

/// The pixels `i` of a row (`0 ≤ i < columns`, from the triangle's left bound) whose centres
/// are inside: `eₖ + biasₖ + stepₖ·i ≥ 0` for the three edges, where `eₖ` is edge `k` at pixel
/// 0. Each inequality is linear in `i`, so the solution is one run `first..=last` (`None`:
/// empty), solved exactly in integers: the same pixels as testing each one.
#[inline]
pub(super) fn inside_run(
    e: [i64; 3],
    step: [i64; 3],
    bias: [i64; 3],
    columns: i64,
) -> Option<(i64, i64)> {
    let (mut first, mut last) = (0, columns - 1);
    for k in 0..3 {
        let v = e[k] + bias[k];
        let s = step[k];
        if s > 0 {
            // v + s·i ≥ 0 ⇔ i ≥ ⌈−v / s⌉ (only binding while v < 0).
            if v < 0 {
                first = first.max((-v + s - 1) / s);
            }
        } else if v < 0 {
            return None; // s ≤ 0: the edge only falls to the right
        } else if s < 0 {
            // v + s·i ≥ 0 ⇔ i ≤ ⌊v / −s⌋.
            last = last.min(v / -s);
        }
    }
    (first <= last).then_some((first, last))
}

/// The extent of a row without a covered pixel.
pub(super) const EMPTY_EXTENT: [u32; 2] = [u32::MAX, 0];

/// The rows of one band being rasterised: their visibility (full width, from `first_row`) and
/// the extent of each row's covered pixels.
pub(super) struct BandTarget<'r> {
    pub(super) first_row: u32,
    pub(super) width: u32,
    pub(super) rows: &'r mut [Visibility],
    pub(super) extents: &'r mut [[u32; 2]],
}

/// Scan-converts the triangles of `bin` into `target`: per pixel an edge test and, inside, a
/// depth compare; each row's extent grows to the pixels written.
pub(super) fn rasterize_band(
    triangles: &TriangleStore,
    bin: &[u32],
    target: BandTarget<'_>,
    test: DepthTest,
    depth: DepthInterpolation,
    floor: Option<&[f32]>,
) {
    // One loop per depth test, peeling and depth interpolation, so that the per-pixel loop has
    // no branch on them.
    let plane = depth == DepthInterpolation::Plane;
    match (test, floor, plane) {
        (DepthTest::Nearest, None, false) => {
            scan_convert::<false, false, false>(triangles, bin, target, &[]);
        }
        (DepthTest::Furthest, None, false) => {
            scan_convert::<true, false, false>(triangles, bin, target, &[]);
        }
        (DepthTest::Nearest, None, true) => {
            scan_convert::<false, false, true>(triangles, bin, target, &[]);
        }
        (DepthTest::Furthest, None, true) => {
            scan_convert::<true, false, true>(triangles, bin, target, &[]);
        }
        (DepthTest::Nearest, Some(floor), false) => {
            scan_convert::<false, true, false>(triangles, bin, target, floor);
        }
        (DepthTest::Furthest, Some(floor), false) => {
            scan_convert::<true, true, false>(triangles, bin, target, floor);
        }
        (DepthTest::Nearest, Some(floor), true) => {
            scan_convert::<false, true, true>(triangles, bin, target, floor);
        }
        (DepthTest::Furthest, Some(floor), true) => {
            scan_convert::<true, true, true>(triangles, bin, target, floor);
        }
    }
}

/// [`rasterize_band`] for one depth test (`FURTHEST`: Greater, else Less), with or without
/// a peeling `floor` (`PEEL`; else `floor` is not read), and the depth from the triangles'
/// depth planes (`PLANE_DEPTH`: the mesh's [`DepthInterpolation::Plane`], so every triangle
/// has one) or from the exact edge functions.
pub(super) fn scan_convert<const FURTHEST: bool, const PEEL: bool, const PLANE_DEPTH: bool>(
    triangles: &TriangleStore,
    bin: &[u32],
    target: BandTarget<'_>,
    floor: &[f32],
) {
    let BandTarget {
        first_row,
        width,
        rows,
        extents,
    } = target;
    let last_row = first_row + (rows.len() as u32 / width) - 1;
    for &id in bin {
        let t = triangles.get(id);
        let [a, b, c] = t.xy;
        let (tl0, tl1, tl2) = (is_top_left(b, c), is_top_left(c, a), is_top_left(a, b));
        // Edge functions step by −Δy·SUBPIXEL per pixel to the right (exact integer arithmetic).
        // A pixel centre on an edge is inside when the edge is top-left: for integers,
        // `e > 0 || (e == 0 && top_left)` is `e + bias ≥ 0` with bias −1, or 0 on a top-left
        // edge. Each row's inside pixels are one run; on wide triangles it is found from the
        // three edges at once ([`inside_run`]), so the loop below visits only them.
        let step = t.edge_steps();
        let bias = [tl0, tl1, tl2].map(|tl| i64::from(tl) - 1);
        let columns = i64::from(t.max[0] - t.min[0]) + 1;
        for y in t.min[1].max(first_row)..=t.max[1].min(last_row) {
            let e = t.edges_at(t.min[0], y);
            // Narrow triangles (dense meshes: a few pixels a row) test each pixel; solving the run
            // (three divisions) pays from about a group of eight pixels up.
            let solved = columns > RUN_MIN_COLUMNS;
            let (first, last) = if solved {
                match inside_run(e, step, bias, columns) {
                    Some(run) => run,
                    None => continue,
                }
            } else {
                (0, columns - 1)
            };
            let row = &mut rows[((y - first_row) * width) as usize..][..width as usize];
            let (mut first_written, mut last_written) = (u32::MAX, 0);
            // The depth test and write of an inside pixel with edge values `f`.
            // Set up from the same mesh as `PLANE_DEPTH`: a plane exactly when it is set.
            debug_assert_eq!(PLANE_DEPTH, t.depth_plane.is_some());
            let depth_plane = t.depth_plane.unwrap_or_default();
            let row_depth = depth_plane.row((y as i32 - t.anchor[1]) as f32);
            let mut fragment = |x: u32, f: [i64; 3]| {
                let depth = match PLANE_DEPTH {
                    true => depth_plane.at(row_depth, (x as i32 - t.anchor[0]) as f32),
                    false => t.depth_from_edges(f),
                };
                if depth > 1.0 {
                    return; // beyond the far plane (the near plane is clipped geometrically)
                }
                if PEEL && depth <= floor[((y - first_row) * width + x) as usize] {
                    return; // peeled: at or in front of the previous layer
                }
                let stored = &mut row[x as usize];
                let passes = if FURTHEST {
                    depth > stored.depth
                } else {
                    depth < stored.depth
                };
                if passes {
                    *stored = Visibility {
                        depth,
                        triangle: id,
                    };
                    first_written = first_written.min(x);
                    last_written = x;
                }
            };
            let mut e = [0, 1, 2].map(|k| e[k] + step[k] * first);
            let pixels = t.min[0] + first as u32..=t.min[0] + last as u32;
            if solved {
                // Every pixel of a solved run is inside: no edge test.
                for x in pixels {
                    fragment(x, e);
                    e = [e[0] + step[0], e[1] + step[1], e[2] + step[2]];
                }
            } else {
                for x in pixels {
                    let f = e;
                    e = [e[0] + step[0], e[1] + step[1], e[2] + step[2]];
                    // All three `e + bias ≥ 0` exactly when their bitwise OR is (no sign bit
                    // set).
                    if ((f[0] + bias[0]) | (f[1] + bias[1]) | (f[2] + bias[2])) >= 0 {
                        fragment(x, f);
                    }
                }
            }
            if first_written <= last_written {
                let extent = &mut extents[(y - first_row) as usize];
                *extent = [
                    extent[0].min(first_written),
                    extent[1].max(last_written + 1),
                ];
            }
        }
    }
}
