//! Umenhoffer, Patow and Szirmay-Kalos 2007, "Robust Multiple Specular Reflections and
//! Refractions" (GPU Gems 3, ch. 17): rays traced against *layered distance maps*, cube maps
//! around a reference point `o` that store per texel the Euclidean distance from `o` of the
//! surface seen through it (negative where nothing is), its normal and its material.
//!
//! Everything here works in cube-map space (`o` at the origin): a ray `x + R d` with `R` a unit
//! vector. [`hit`] is the chapter's `Hit()`: a linear search per layer uniform in texture space
//! (§17.2.1, Listing 17-1), the nearest layer, then secant refinement in it (Listing 17-2),
//! optionally restricted by each layer's distance range (min-max acceleration, Figure 17-4).
//! [`trace_path`] is the multiple reflection/refraction loop of §17.3 (Listing 17-5).
//!
//! The maps are read through [`DistanceLayers`] (CPU buffers, a test's analytic layers); the
//! WGSL twin is `refract-gpu/shaders/distance_search.wgsl`, held to this file by the conformance tests.

use glam::{UVec2, Vec3};

use crate::camera::{CubeCoordinates, CubeFace, cube_coordinates};
use crate::fresnel::schlick;
use crate::lanes::{F32x8, I32x8, LANES, Vec3x8};
use crate::optics::{reflect, refract};
use crate::real::{Real, Vector3};
use crate::vector::angle_between;

/// Layers of one distance map at most (`layers` parameter).
pub const MAX_LAYERS: usize = 8;

/// The linear search starts at `t = T_START` (Listing 17-1), i.e. `d = a·10⁻⁴/(1 − 10⁻⁴)`.
pub const T_START: f32 = 1e-4;

/// The linear search ends at `t = T_END = 1 − T_START` (`d = a·(1 − 10⁻⁴)/10⁻⁴ ≈ 10⁴ a`: the
/// listing's `while (t < 1)`, kept finite).
pub const T_END: f32 = 1.0 - T_START;

/// Min-max acceleration widens each layer's distance range by this fraction on both sides, so
/// that the search segment's end samples fall on both sides of a surface at the extreme
/// distance (a sphere around `o` has `min = max`).
pub const MIN_MAX_MARGIN: f32 = 0.01;

/// Secant refinement stops when `|r/r' − 1|` is below this (Listing 17-2: 0.9999 … 1.0001).
pub const SECANT_TOLERANCE: f32 = 1e-4;

/// The texel of a `size × size` cube map that direction `dir` falls in: WebGPU's face
/// selection ([`CubeFace::of_direction`]) and texel `(⌊s·size⌋, ⌊t·size⌋)` clamped to the face.
/// `None` for a zero or non-finite direction.
#[inline]
pub fn cube_texel(dir: Vec3, size: u32) -> Option<(CubeFace, UVec2)> {
    let c = cube_texel_lanes(dir, size);
    c.valid.then(|| {
        let face = CubeFace::ALL[c.face as usize];
        (face, UVec2::new(c.s as u32, c.t as u32))
    })
}

/// [`cube_texel`] of one direction or eight: [`cube_coordinates`] with `s`, `t` turned into
/// the texel's column and row, `⌊q·size⌋` clamped to `size − 1` (`q ∈ [0, 1]`: never below 0).
#[inline]
fn cube_texel_lanes<V: Vector3>(dir: V, size: u32) -> CubeCoordinates<V::Real> {
    let c = cube_coordinates(dir);
    let (n, max) = (
        V::Real::splat(size as f32),
        V::Real::splat((size - 1) as f32),
    );
    let texel = |q: V::Real| (q * n).floor().min(max);
    CubeCoordinates {
        s: texel(c.s),
        t: texel(c.t),
        ..c
    }
}

/// The largest face size whose texel indices [`cube_texel_indices_x8`] computes in `i32`
/// lanes (`6·size² < 2³¹`); larger faces take the indices lane by lane.
const MAX_LANE_INDEX_SIZE: u32 = 18_918;

/// [`cube_texel`] then [`cube_texel_index`] of eight directions on lanes (the linear search's
/// samples): lane `i` is `cube_texel(dirs[i], size).map(|(f, t)| cube_texel_index(f, t, size))`.
#[inline]
pub fn cube_texel_indices_x8(dirs: Vec3x8, size: u32) -> [Option<u32>; LANES] {
    let c = cube_texel_lanes(dirs, size);
    let valid = c.valid.to_bitmask();
    let mut indices = [None; LANES];
    if size <= MAX_LANE_INDEX_SIZE {
        // Small non-negative integers: the truncation is `as u32`'s; the index fits in `i32`.
        let n = I32x8::splat(size as i32);
        let (s, t, face) = (c.s.trunc_int(), c.t.trunc_int(), c.face.trunc_int());
        let index = ((face * n + t) * n + s).to_array();
        for (i, out) in indices.iter_mut().enumerate() {
            if valid & (1 << i) != 0 {
                *out = Some(index[i] as u32);
            }
        }
    } else {
        let (s, t, face) = (c.s.to_array(), c.t.to_array(), c.face.to_array());
        for (i, out) in indices.iter_mut().enumerate() {
            if valid & (1 << i) != 0 {
                *out = Some((face[i] as u32 * size + t[i] as u32) * size + s[i] as u32);
            }
        }
    }
    indices
}

/// The (not normalised) direction through the centre of texel `texel` of face `face` of a
/// `size × size` cube map: the major axis component ±1 and the two others in `(−1, 1)`; the
/// inverse of [`cube_texel`].
#[inline]
pub fn cube_texel_direction(face: CubeFace, texel: UVec2, size: u32) -> Vec3 {
    let st = (texel.as_vec2() + 0.5) / size as f32 * 2.0 - 1.0;
    let (sc, tc) = (st.x, st.y);
    match face {
        CubeFace::PosX => Vec3::new(1.0, -tc, -sc),
        CubeFace::NegX => Vec3::new(-1.0, -tc, sc),
        CubeFace::PosY => Vec3::new(sc, 1.0, tc),
        CubeFace::NegY => Vec3::new(sc, -1.0, -tc),
        CubeFace::PosZ => Vec3::new(sc, -tc, 1.0),
        CubeFace::NegZ => Vec3::new(-sc, -tc, -1.0),
    }
}

/// A texel's index in a layer of six `size × size` faces in layer order: `(face·size + y)·size + x`.
#[inline]
pub fn cube_texel_index(face: CubeFace, texel: UVec2, size: u32) -> u32 {
    (face as u32 * size + texel.y) * size + texel.x
}

/// Read access to the layers of a distance map (cube-map space: the reference point at 0).
pub trait DistanceLayers {
    /// The number of layers (at most [`MAX_LAYERS`]).
    fn layer_count(&self) -> usize;
    /// Texels per face edge (the start of a ray skips about [`START_SKIP_TEXELS`] of them).
    fn face_size(&self) -> u32;
    /// The distance `|l'|` stored in layer `layer` in direction `dir` (not necessarily unit),
    /// negative where the texel is empty.
    fn distance(&self, layer: usize, dir: Vec3) -> f32;
    /// The smallest and largest valid distance of layer `layer`, `None` when it is empty.
    fn range(&self, layer: usize) -> Option<(f32, f32)>;
    /// Whether rays may cross layer `layer`'s surfaces from behind (seen from the reference
    /// point): the specular object's layers (rays inside glass); the other geometry is opaque
    /// and only hit from the reference point's side.
    fn two_sided(&self, layer: usize) -> bool;
    /// A hint that [`Self::distance`] is about to be read in these eight directions (the
    /// linear search's next samples): an implementation may prefetch the texels' memory. The
    /// default does nothing.
    #[inline]
    fn prefetch_x8(&self, _layer: usize, _dirs: &Vec3x8) {}
    /// [`Self::distance`] in eight directions (the linear search's lanes); an implementation
    /// may look them up together (a cube map: [`cube_texel_indices_x8`]), with the same
    /// results.
    #[inline]
    fn distance_x8(&self, layer: usize, dirs: &Vec3x8) -> [f32; LANES] {
        let mut out = [0.0; LANES];
        for (o, d) in out.iter_mut().zip(dirs.to_lanes()) {
            *o = self.distance(layer, d);
        }
        out
    }
}

/// A ray leaving a surface of layer `L` ignores layer `L` while its direction from the
/// reference point is within this many texel widths (`2/size` radians) of its start's:
/// there the sampled surface (a texel-centre distance of a faceted mesh) and the true surface
/// the ray starts on differ by more than the ray's progress, and every sign change is noise.
pub const START_SKIP_TEXELS: f32 = 1.5;

/// The search settings of [`hit`] (the chapter's step-size and iteration choices, §17.4).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct SearchParams {
    /// Fewest linear steps per layer (a short segment `s → e`).
    pub min_steps: u32,
    /// Most linear steps per layer (a segment spanning `π` radians seen from `o`).
    pub max_steps: u32,
    /// Secant refinement steps at most (Listing 17-2's `NITER`).
    pub secant_steps: u32,
    /// Min-max acceleration (Figure 17-4): search only where the ray is between the spheres of
    /// the layer's smallest and largest distance.
    pub min_max: bool,
}

impl Default for SearchParams {
    /// 15 to 80 linear steps, 5 secant steps, min-max on.
    fn default() -> Self {
        Self {
            min_steps: 15,
            max_steps: 80,
            secant_steps: 5,
            min_max: true,
        }
    }
}

/// The ray parameter of texture-space parameter `t` (§17.2.1): `d = a t / (1 − t)`, `a = |x|/|R|`.
#[inline]
pub fn ray_parameter(t: f32, a: f32) -> f32 {
    a * t / (1.0 - t)
}

/// The inverse of [`ray_parameter`]: `t = d / (a + d)` (1 for `d = ∞`).
#[inline]
pub fn texture_parameter(d: f32, a: f32) -> f32 {
    if d == f32::INFINITY { 1.0 } else { d / (a + d) }
}

/// The linear steps for a segment whose ends are seen from `o` in directions `s` and `e`:
/// `clamp(⌈max_steps · θ/π⌉, min_steps, max_steps)` with `θ` the angle between them (§17.4:
/// the step is set "proportionally to the length of line segment of s and e").
#[inline]
pub fn linear_steps(s: Vec3, e: Vec3, params: &SearchParams) -> u32 {
    let theta = angle_between(s, e);
    let steps = -crate::math::floor(-(params.max_steps as f32 * theta / core::f32::consts::PI));
    let lo = params.min_steps.max(1);
    (steps as u32).clamp(lo, params.max_steps.max(lo))
}

/// The part `[d_lo, d_hi]` of the ray `x + R d`, `d ≥ 0`, between the spheres of radii `r_min`
/// and `r_max` around `o` (the convex hull of where a surface of the layer can be; Figure
/// 17-4), `None` when the ray misses the outer sphere.
#[inline]
pub fn shell_segment(x: Vec3, r: Vec3, r_min: f32, r_max: f32) -> Option<(f32, f32)> {
    // |x + R d|² = ρ²  ⇔  d² + 2 b d + c = 0 with b = x·R, c = |x|² − ρ².
    let b = x.dot(r);
    let xx = x.dot(x);
    let disc_max = b * b - (xx - r_max * r_max);
    if disc_max < 0.0 {
        return None;
    }
    let root = crate::math::sqrt(disc_max);
    let d_hi = -b + root;
    if d_hi < 0.0 {
        return None;
    }
    let d_lo = if xx > r_max * r_max {
        -b - root
    } else if xx < r_min * r_min {
        // Inside the inner sphere: the ray leaves it first.
        -b + crate::math::sqrt((b * b - (xx - r_min * r_min)).max(0.0))
    } else {
        0.0
    };
    Some((d_lo.max(0.0), d_hi))
}

/// Two ray parameters around a crossing of a layer's surface, with their ratios `|r|/|r'|`
/// on opposite sides of 1.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bracket {
    /// The nearer parameter and its ratio.
    pub d_near: f32,
    /// `|r|/|r'|` at `d_near`.
    pub ratio_near: f32,
    /// The farther parameter.
    pub d_far: f32,
    /// `|r|/|r'|` at `d_far`.
    pub ratio_far: f32,
}

/// The linear search of one layer (Listing 17-1) over `t ∈ [t_lo, t_hi]` in `steps` uniform
/// steps: the first pair of consecutive valid samples on opposite sides of the surface
/// (`|r|/|r'| < 1` undershooting, `≥ 1` overshooting): in either order for a two-sided layer,
/// only undershooting then overshooting (a surface met from the reference point's side)
/// otherwise. An empty texel restarts the search; so do samples whose direction is within
/// `skip_cos` (a cosine) of the start direction `x`. The search ends, without a bracket, after
/// the first sample at or beyond ray parameter `d_stop` (`None`: no limit): [`hit`]
/// passes the best hit so far, since every later bracket would start behind it (the samples'
/// `d` never decrease). Returns the bracket and the samples taken.
///
/// The samples are independent of one another: they are computed eight at a time on SIMD lanes
/// (each lane the scalar operations in the scalar order, so the same bits as one at a time:
/// `lane_search_equals_scalar_search`), then scanned in order; a group past the bracket costs
/// at most seven extra samples, not counted in the samples taken.
#[allow(clippy::too_many_arguments)]
#[inline]
pub fn linear_search<L: DistanceLayers + ?Sized>(
    layers: &L,
    layer: usize,
    x: Vec3,
    r: Vec3,
    a: f32,
    t_lo: f32,
    t_hi: f32,
    steps: u32,
    skip_cos: f32,
    d_stop: Option<f32>,
) -> (Option<Bracket>, u32) {
    let dt = (t_hi - t_lo) / steps as f32;
    let two_sided = layers.two_sided(layer);
    let x_len = x.length();
    let (x8, r8) = (Vec3x8::splat(x), Vec3x8::splat(r));
    // Samples `first..first + 8`: ray parameters and points.
    let samples = |first: u32| {
        let mut index = [0.0f32; LANES];
        for (k, i) in index.iter_mut().enumerate() {
            *i = (first + k as u32) as f32;
        }
        let t = (F32x8::splat(t_lo) + F32x8::splat(dt) * F32x8::new(index)).min(F32x8::splat(t_hi));
        let d = F32x8::splat(a) * t / (F32x8::ONE - t);
        (d, x8 + r8 * d)
    };
    let mut previous: Option<(f32, f32)> = None;
    let mut first = 0u32;
    let (mut d, mut p) = samples(0);
    while first <= steps {
        // The next eight samples' texels are announced before this group's are read: the
        // search waits on memory (layers of megabytes).
        let next = first + LANES as u32;
        let upcoming = (next <= steps).then(|| samples(next));
        if let Some((_, p_next)) = upcoming {
            layers.prefetch_x8(layer, &p_next);
        }
        let stored = F32x8::new(layers.distance_x8(layer, &p));
        let p_len = p.length();
        // Empty texels and samples within the start's skip cone break the bracket; the ratio
        // `|p| / stored` of the others.
        let split = stored.simd_le(F32x8::ZERO)
            | p.dot(x8)
                .simd_gt(F32x8::splat(skip_cos) * p_len * F32x8::splat(x_len));
        let (split, ratios) = (split.to_bitmask(), (p_len / stored).to_array());
        let d_lanes = d.to_array();
        for k in 0..LANES.min((steps - first + 1) as usize) {
            let d = d_lanes[k];
            if split & (1 << k) != 0 {
                previous = None;
            } else {
                let ratio = ratios[k];
                if let Some((d_prev, ratio_prev)) = previous
                    && (ratio_prev < 1.0) != (ratio < 1.0)
                    && (two_sided || ratio_prev < 1.0)
                {
                    return (
                        Some(Bracket {
                            d_near: d_prev,
                            ratio_near: ratio_prev,
                            d_far: d,
                            ratio_far: ratio,
                        }),
                        first + k as u32 + 1,
                    );
                }
                previous = Some((d, ratio));
            }
            if d_stop.is_some_and(|stop| d >= stop) {
                return (None, first + k as u32 + 1);
            }
        }
        let Some(upcoming) = upcoming else {
            break;
        };
        (first, (d, p)) = (next, upcoming);
    }
    (None, steps + 1)
}

/// Secant refinement in one layer (Listing 17-2, generalised to either crossing direction):
/// `d_new = d_a + (d_b − d_a)(1 − r_a)/(r_b − r_a)`, replacing the end on the same side, until
/// `|r − 1| <` [`SECANT_TOLERANCE`] or `steps` steps. An empty texel ends the refinement.
/// Returns the ray parameter and the steps taken.
#[inline]
pub fn secant<L: DistanceLayers + ?Sized>(
    layers: &L,
    layer: usize,
    x: Vec3,
    r: Vec3,
    bracket: Bracket,
    steps: u32,
) -> (f32, u32) {
    let (mut da, mut ra) = (bracket.d_near, bracket.ratio_near);
    let (mut db, mut rb) = (bracket.d_far, bracket.ratio_far);
    // Without refinement the overshooting end is the hit (Listing 17-1 returns dp).
    let mut d = if ra >= 1.0 { da } else { db };
    for i in 0..steps {
        let denom = rb - ra;
        if denom == 0.0 {
            return (d, i);
        }
        let d_new = da + (db - da) * (1.0 - ra) / denom;
        let p = x + r * d_new;
        let stored = layers.distance(layer, p);
        if stored <= 0.0 {
            return (d, i + 1);
        }
        d = d_new;
        let ratio = p.length() / stored;
        if (ratio - 1.0).abs() < SECANT_TOLERANCE {
            return (d, i + 1);
        }
        if (ratio < 1.0) == (ra < 1.0) {
            (da, ra) = (d_new, ratio);
        } else {
            (db, rb) = (d_new, ratio);
        }
    }
    (d, steps)
}

/// What [`hit`] found.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LayerHit {
    /// The layer of the nearest crossing.
    pub layer: u32,
    /// The ray parameter of the hit `l = x + R d`.
    pub d: f32,
}

/// The work [`hit`] did, for the AOVs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SearchWork {
    /// Linear-search samples over all layers.
    pub linear_steps: u32,
    /// Secant steps.
    pub secant_steps: u32,
}

/// The texture-space parameters `[t_lo, t_hi]` of the ray `x + R d` that [`hit`] searches in
/// layer `layer` (`a = |x|`): `[T_START, T_END]`, or with min-max the part inside the layer's
/// shell widened by [`MIN_MAX_MARGIN`] ([`shell_segment`]); `None` where there is nothing to
/// search (an empty layer, a ray that misses the shell).
#[inline]
pub fn layer_segment<L: DistanceLayers + ?Sized>(
    layers: &L,
    layer: usize,
    x: Vec3,
    r: Vec3,
    a: f32,
    params: &SearchParams,
) -> Option<(f32, f32)> {
    if !params.min_max {
        return Some((T_START, T_END));
    }
    let (r_min, r_max) = layers.range(layer)?;
    let (r_min, r_max) = (
        r_min * (1.0 - MIN_MAX_MARGIN),
        r_max * (1.0 + MIN_MAX_MARGIN),
    );
    let (d_lo, d_hi) = shell_segment(x, r, r_min, r_max)?;
    let t_lo = texture_parameter(d_lo, a).max(T_START);
    let t_hi = texture_parameter(d_hi, a).min(T_END);
    (t_hi > t_lo).then_some((t_lo, t_hi))
}

/// `Hit()` of §17.2: the first intersection of the ray `x + R d` (`R` unit, `x` in cube-map
/// space) with the layers. Each layer is searched linearly in `t` from [`T_START`] (or, with
/// min-max, from the layer's shell widened by [`MIN_MAX_MARGIN`], [`shell_segment`]) in
/// [`linear_steps`] steps, ending at the best hit so far (a bracket that starts behind it
/// cannot win: the secant stays inside its bracket); each layer's bracket is refined by
/// [`secant`] and the nearest refined hit wins: the hit of searching every layer to its end,
/// with fewer samples. (The chapter refines only the layer with the nearest overshooting
/// sample; with per-layer step counts a coarse bracket in the front layer can then lose to a
/// finer one behind it, which showed as surfaces seen through walls once depth-peeled layers
/// were added.) `start` is the layer the ray starts on, ignored near the start
/// ([`START_SKIP_TEXELS`]; no self-intersection).
#[inline]
pub fn hit<L: DistanceLayers + ?Sized>(
    layers: &L,
    x: Vec3,
    r: Vec3,
    start: Option<usize>,
    params: &SearchParams,
) -> (Option<LayerHit>, SearchWork) {
    let a = x.length().max(1e-6);
    let skip_cos_start =
        crate::math::sin_cos(START_SKIP_TEXELS * 2.0 / layers.face_size().max(1) as f32).1;
    let mut work = SearchWork::default();
    let mut best: Option<LayerHit> = None;
    for layer in 0..layers.layer_count().min(MAX_LAYERS) {
        let Some((t_lo, t_hi)) = layer_segment(layers, layer, x, r, a, params) else {
            continue;
        };
        // A bracket that starts behind the best hit so far cannot beat it (the secant stays
        // inside its bracket): the search stops there, and a layer whose first sample lies
        // behind it is not searched.
        let d_stop = best.map(|b| b.d);
        let d_first = ray_parameter(t_lo, a);
        if d_stop.is_some_and(|stop| d_first >= stop) {
            continue;
        }
        let s = x + r * d_first;
        let e = x + r * ray_parameter(t_hi, a);
        let steps = linear_steps(s, e, params);
        let skip_cos = if start == Some(layer) {
            skip_cos_start
        } else {
            2.0 // no direction is that close
        };
        let (found, taken) =
            linear_search(layers, layer, x, r, a, t_lo, t_hi, steps, skip_cos, d_stop);
        work.linear_steps += taken;
        let Some(bracket) = found else {
            continue;
        };
        let (d, secant_steps) = secant(layers, layer, x, r, bracket, params.secant_steps);
        work.secant_steps += secant_steps;
        if best.is_none_or(|b| d < b.d) {
            best = Some(LayerHit {
                layer: layer as u32,
                d,
            });
        }
    }
    (best, work)
}

/// A texel's material with the chapter's sign code (§17.3): `ior < 0` a mirror or metal whose
/// `rgb` is `F_p` per channel; `ior = 0` a diffuse surface whose `rgb` is its outgoing
/// radiance; `ior > 0` a refractor of that index, `rgb` its `F0`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TexelMaterial {
    /// Radiance (diffuse) or `F_p` (specular).
    pub rgb: Vec3,
    /// The sign code.
    pub ior: f32,
}

/// What a distance-map texel says about the surface at a hit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TexelSurface {
    /// Outward unit normal.
    pub normal: Vec3,
    /// Its material.
    pub material: TexelMaterial,
}

/// The surfaces behind the layers and what lies beyond them.
pub trait DistanceMapScene: DistanceLayers {
    /// The surface of layer `layer` in direction `dir`.
    fn surface(&self, layer: usize, dir: Vec3) -> TexelSurface;
    /// Radiance arriving from infinitely far away along unit `dir` (the environment).
    fn background(&self, dir: Vec3) -> Vec3;
}

/// How dielectric interfaces weigh the path (conductors always use Schlick's `F`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum DielectricFresnel {
    /// Follow the refracted path with weight 1 (TIR reflects): the reference's
    /// `transmission` mode and the image-space methods.
    #[default]
    Ignore,
    /// Listing 17-5: refraction weighted by `1 − F` (Schlick), TIR reflects with weight 1.
    Schlick,
    /// Listing 17-5 plus, at the first interface, the reflected branch weighted by `F`
    /// (Figure 17-9's glass that both reflects and refracts); compare with the reference's
    /// `full` mode.
    Split,
}

/// The code of a [`DielectricFresnel`] in the WGSL twin (`DM_FRESNEL_*`).
pub const fn fresnel_code(fresnel: DielectricFresnel) -> u32 {
    match fresnel {
        DielectricFresnel::Ignore => 0,
        DielectricFresnel::Schlick => 1,
        DielectricFresnel::Split => 2,
    }
}

/// The settings of [`trace_path`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct PathParams {
    /// The ray search.
    pub search: SearchParams,
    /// Specular interactions per path, the first (the visible surface) included: 1 reflects or
    /// refracts once (`MAXDEPTH` of Listing 17-5).
    pub max_depth: u32,
    /// Dielectric weighting.
    pub fresnel: DielectricFresnel,
}

impl Default for PathParams {
    /// Depth 2 (the chapter's video, §17.4), the default search, no dielectric Fresnel.
    fn default() -> Self {
        Self {
            search: SearchParams::default(),
            max_depth: 2,
            fresnel: DielectricFresnel::Ignore,
        }
    }
}

/// The specular surface a path starts on (the one the eye sees).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PathStart {
    /// The point, in cube-map space.
    pub x: Vec3,
    /// Unit direction of the incoming ray (toward the surface).
    pub v: Vec3,
    /// Outward unit normal.
    pub n: Vec3,
    /// Its material (a specular one: `ior ≠ 0`).
    pub material: TexelMaterial,
    /// The layer that holds this surface, if any (its start texel is skipped).
    pub layer: Option<usize>,
}

/// What [`trace_path`] computed for one pixel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PathResult {
    /// Radiance toward the eye.
    pub radiance: Vec3,
    /// Secondary rays traced (`Hit()` calls).
    pub bounces: u32,
    /// The layer of the last hit (`None` if the last ray left every layer).
    pub last_layer: Option<u32>,
    /// Some ray left every layer and read the environment.
    pub miss: bool,
    /// Total internal reflection somewhere on the path.
    pub tir: bool,
    /// The path ran out of depth on a specular surface (black).
    pub truncated: bool,
    /// Work of the searches.
    pub work: SearchWork,
}

/// The direction leaving a specular surface and the factor it carries (Listing 17-5):
/// conductors reflect with `F = F_p + (1 − F_p)(1 − |N·V|)⁵`; refractors refract (index
/// inverted and normal flipped from inside), reflecting under TIR with factor 1, otherwise
/// with `1 − F` when `fresnel` weighs dielectrics. Returns `(R, factor, tir)`.
#[inline]
pub fn scatter(
    v: Vec3,
    n: Vec3,
    material: TexelMaterial,
    fresnel: DielectricFresnel,
) -> (Vec3, Vec3, bool) {
    let cos = v.dot(n).abs();
    if material.ior < 0.0 {
        let f = Vec3::new(
            schlick(cos, material.rgb.x),
            schlick(cos, material.rgb.y),
            schlick(cos, material.rgb.z),
        );
        return (reflect(v, n), f, false);
    }
    let (n, eta) = if v.dot(n) > 0.0 {
        (-n, material.ior)
    } else {
        (n, 1.0 / material.ior)
    };
    let t = refract(v, n, eta);
    if t == Vec3::ZERO {
        return (reflect(v, n), Vec3::ONE, true);
    }
    let weight = match fresnel {
        DielectricFresnel::Ignore => Vec3::ONE,
        DielectricFresnel::Schlick | DielectricFresnel::Split => {
            Vec3::ONE - Vec3::splat(schlick(cos, material.rgb.x))
        }
    };
    (t.normalize(), weight, false)
}

/// The multiple reflection/refraction loop of §17.3 (Listing 17-5) from `start`, the first
/// direction given (`first`, or [`scatter`]'s): trace, and while the hit is specular and the
/// depth allows, scatter again; a diffuse hit ends the path with its radiance, a ray that
/// leaves every layer with the environment ([`DistanceMapScene::background`]).
///
/// Departure from Listing 17-5: a path that runs out of depth on a specular surface is black
/// (the listing returns the throughput, i.e. white light), as the reference's depth limit is.
pub fn trace_path<S: DistanceMapScene + ?Sized>(
    scene: &S,
    start: &PathStart,
    params: &PathParams,
) -> PathResult {
    let (r, weight, tir) = scatter(start.v, start.n, start.material, params.fresnel);
    let mut result = continue_path(scene, start, r, weight, params);
    result.tir |= tir;
    if params.fresnel == DielectricFresnel::Split && start.material.ior > 0.0 && !tir {
        let f = schlick(start.v.dot(start.n).abs(), start.material.rgb.x);
        let reflected = reflect(start.v, start.n);
        let other = continue_path(scene, start, reflected, Vec3::splat(f), params);
        result.radiance += other.radiance;
        result.bounces += other.bounces;
        result.miss |= other.miss;
        result.tir |= other.tir;
        result.truncated |= other.truncated;
        result.work.linear_steps += other.work.linear_steps;
        result.work.secant_steps += other.work.secant_steps;
    }
    result
}

fn continue_path<S: DistanceMapScene + ?Sized>(
    scene: &S,
    start: &PathStart,
    first: Vec3,
    first_weight: Vec3,
    params: &PathParams,
) -> PathResult {
    let mut result = PathResult {
        radiance: Vec3::ZERO,
        bounces: 0,
        last_layer: None,
        miss: false,
        tir: false,
        truncated: false,
        work: SearchWork::default(),
    };
    let (mut x, mut r, mut layer) = (start.x, first, start.layer);
    let mut throughput = first_weight;
    let mut depth = 1;
    loop {
        let (found, work) = hit(scene, x, r, layer, &params.search);
        result.bounces += 1;
        result.work.linear_steps += work.linear_steps;
        result.work.secant_steps += work.secant_steps;
        let Some(h) = found else {
            result.miss = true;
            result.last_layer = None;
            result.radiance = throughput * scene.background(r);
            return result;
        };
        result.last_layer = Some(h.layer);
        let l = x + r * h.d;
        let surface = scene.surface(h.layer as usize, l);
        if surface.material.ior == 0.0 {
            result.radiance = throughput * surface.material.rgb;
            return result;
        }
        if depth >= params.max_depth {
            result.truncated = true;
            return result;
        }
        depth += 1;
        let (next, weight, tir) = scatter(r, surface.normal, surface.material, params.fresnel);
        result.tir |= tir;
        throughput *= weight;
        x = l;
        r = next;
        layer = Some(h.layer as usize);
    }
}

/// Analytic layers for tests and the WGSL conformance harness (`refract-gpu/src/conformance.wgsl`
/// has the same): layer 0 a mirror sphere of radius 1 around `o` (`F_p` = 1; empty where the
/// texel-centre direction has `y > 0.8`), two-sided; layer 1 the diffuse cube `|p|∞ = 3` of
/// radiance `(0.5, 0.25, 0.125)`; a background of 7. Both sampled at texel centres of a
/// `size²` cube map, like a rasterised map.
pub struct AnalyticRoom {
    /// Texels per face edge.
    pub size: u32,
}

fn analytic_texel_centre(dir: Vec3, size: u32) -> (Vec3, u32) {
    match cube_texel(dir, size) {
        Some((face, texel)) => (
            cube_texel_direction(face, texel, size).normalize(),
            cube_texel_index(face, texel, size),
        ),
        None => (Vec3::Z, 0),
    }
}

impl DistanceLayers for AnalyticRoom {
    fn layer_count(&self) -> usize {
        2
    }
    fn face_size(&self) -> u32 {
        self.size
    }
    fn distance(&self, layer: usize, dir: Vec3) -> f32 {
        let (c, _) = analytic_texel_centre(dir, self.size);
        match layer {
            0 if c.y > 0.8 => -1.0,
            0 => 1.0,
            _ => 3.0 / c.abs().max_element(),
        }
    }
    fn two_sided(&self, layer: usize) -> bool {
        layer == 0
    }
    fn range(&self, layer: usize) -> Option<(f32, f32)> {
        Some(if layer == 0 {
            (1.0, 1.0)
        } else {
            (3.0, 3.0 * crate::math::sqrt(3.0))
        })
    }
}

impl DistanceMapScene for AnalyticRoom {
    fn surface(&self, layer: usize, dir: Vec3) -> TexelSurface {
        let (c, _) = analytic_texel_centre(dir, self.size);
        if layer == 0 {
            TexelSurface {
                normal: c,
                material: TexelMaterial {
                    rgb: Vec3::ONE,
                    ior: -1.0,
                },
            }
        } else {
            let a = c.abs();
            let n = if a.x >= a.y && a.x >= a.z {
                Vec3::new(-c.x.signum(), 0.0, 0.0)
            } else if a.y >= a.z {
                Vec3::new(0.0, -c.y.signum(), 0.0)
            } else {
                Vec3::new(0.0, 0.0, -c.z.signum())
            };
            TexelSurface {
                normal: n,
                material: TexelMaterial {
                    rgb: Vec3::new(0.5, 0.25, 0.125),
                    ior: 0.0,
                },
            }
        }
    }
    fn background(&self, _dir: Vec3) -> Vec3 {
        Vec3::splat(7.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn texel_selection_round_trips_through_texel_centres() {
        for size in [1, 2, 7, 64] {
            for face in CubeFace::ALL {
                for y in 0..size {
                    for x in 0..size {
                        let index = cube_texel_index(face, UVec2::new(x, y), size);
                        let d = cube_texel_direction(face, UVec2::new(x, y), size);
                        let (f, t) = cube_texel(d, size).expect("direction");
                        assert_eq!(cube_texel_index(f, t, size), index, "{face:?} {x} {y}");
                    }
                }
            }
        }
        assert_eq!(cube_texel(Vec3::ZERO, 4), None);
    }

    #[test]
    fn parameters_map_back_and_forth() {
        for (t, a) in [(0.25, 2.0), (0.5, 1.0), (0.9, 0.1)] {
            let d = ray_parameter(t, a);
            assert!((texture_parameter(d, a) - t).abs() < 1e-6);
        }
        assert_eq!(texture_parameter(f32::INFINITY, 1.0), 1.0);
    }

    #[test]
    fn steps_scale_with_the_angle_between_min_and_max() {
        let p = SearchParams::default();
        assert_eq!(linear_steps(Vec3::X, Vec3::X, &p), 15);
        assert_eq!(linear_steps(Vec3::X, -Vec3::X, &p), 80);
        assert_eq!(linear_steps(Vec3::X, Vec3::Y, &p), 40);
    }

    #[test]
    fn shell_segments_bound_the_crossings() {
        // From inside the inner sphere: leave it at d = 1 − 0.5, leave the outer at 2 − 0.5.
        let (lo, hi) = shell_segment(Vec3::new(0.5, 0.0, 0.0), Vec3::X, 1.0, 2.0).expect("hit");
        assert!((lo - 0.5).abs() < 1e-6 && (hi - 1.5).abs() < 1e-6);
        // From outside toward the centre: enter the outer at 3 − 2.
        let (lo, hi) = shell_segment(Vec3::new(3.0, 0.0, 0.0), -Vec3::X, 1.0, 2.0).expect("hit");
        assert!((lo - 1.0).abs() < 1e-6 && (hi - 5.0).abs() < 1e-6);
        // Away from the shell, outside it: no hit.
        assert_eq!(
            shell_segment(Vec3::new(3.0, 0.0, 0.0), Vec3::X, 1.0, 2.0),
            None
        );
    }

    /// From inside the sphere the ray meets the sphere at distance 1 from `o`; from the sphere
    /// outward it meets the cube wall at `|p|∞ = 3`, within a texel after the secant steps.
    #[test]
    fn hits_land_on_the_analytic_surfaces() {
        let layers = AnalyticRoom { size: 64 };
        for min_max in [false, true] {
            let params = SearchParams {
                min_max,
                ..SearchParams::default()
            };
            let x = Vec3::new(0.2, -0.1, 0.3);
            let r = Vec3::new(0.3, -0.5, 0.8).normalize();
            let (h, work) = hit(&layers, x, r, None, &params);
            let h = h.expect("inside the sphere");
            assert_eq!(h.layer, 0);
            assert!(((x + r * h.d).length() - 1.0).abs() < 1e-3, "{h:?}");
            assert!(work.linear_steps > 0);
            // From the sphere surface outward (skipping its own texel): the wall.
            let x = Vec3::new(0.0, -0.6, 0.8);
            let r = Vec3::new(0.5, -0.3, 0.8).normalize();
            let (h, _) = hit(&layers, x, r, Some(0), &params);
            let h = h.expect("the wall");
            assert_eq!(h.layer, 1);
            let l = x + r * h.d;
            assert!((l.abs().max_element() - 3.0).abs() < 0.05, "{l}");
        }
    }

    /// [`hit`] without its cut: every layer searched to its end, every bracket refined, the
    /// nearest refined hit (the first layer on a tie).
    fn exhaustive_hit<L: DistanceLayers + ?Sized>(
        layers: &L,
        x: Vec3,
        r: Vec3,
        start: Option<usize>,
        params: &SearchParams,
    ) -> (Option<LayerHit>, u32) {
        let a = x.length().max(1e-6);
        let skip_cos_start =
            crate::math::sin_cos(START_SKIP_TEXELS * 2.0 / layers.face_size() as f32).1;
        let (mut best, mut samples): (Option<LayerHit>, u32) = (None, 0);
        for layer in 0..layers.layer_count() {
            let Some((t_lo, t_hi)) = layer_segment(layers, layer, x, r, a, params) else {
                continue;
            };
            let (s, e) = (
                x + r * ray_parameter(t_lo, a),
                x + r * ray_parameter(t_hi, a),
            );
            let steps = linear_steps(s, e, params);
            let skip_cos = if start == Some(layer) {
                skip_cos_start
            } else {
                2.0
            };
            let (found, taken) =
                scalar_linear_search(layers, layer, x, r, a, t_lo, t_hi, steps, skip_cos, None);
            samples += taken;
            let Some(bracket) = found else { continue };
            let (d, _) = secant(layers, layer, x, r, bracket, params.secant_steps);
            if best.is_none_or(|b| d < b.d) {
                best = Some(LayerHit {
                    layer: layer as u32,
                    d,
                });
            }
        }
        (best, samples)
    }

    /// [`AnalyticRoom`] with its layers in the other order: the wall is searched first, so the
    /// sphere's search runs with a stop beyond its crossing.
    struct WallFirst(AnalyticRoom);

    impl DistanceLayers for WallFirst {
        fn layer_count(&self) -> usize {
            2
        }
        fn face_size(&self) -> u32 {
            self.0.face_size()
        }
        fn distance(&self, layer: usize, dir: Vec3) -> f32 {
            self.0.distance(1 - layer, dir)
        }
        fn range(&self, layer: usize) -> Option<(f32, f32)> {
            self.0.range(1 - layer)
        }
        fn two_sided(&self, layer: usize) -> bool {
            self.0.two_sided(1 - layer)
        }
    }

    /// Two concentric spheres close together (radii in layer order), the outer one first: a
    /// ray from inside crosses the inner one just before the outer one, often within one
    /// linear step.
    struct CloseShells([f32; 2]);

    impl DistanceLayers for CloseShells {
        fn layer_count(&self) -> usize {
            2
        }
        fn face_size(&self) -> u32 {
            256
        }
        fn distance(&self, layer: usize, _dir: Vec3) -> f32 {
            self.0[layer]
        }
        fn range(&self, layer: usize) -> Option<(f32, f32)> {
            Some((self.0[layer], self.0[layer]))
        }
        fn two_sided(&self, _layer: usize) -> bool {
            true
        }
    }

    /// Stopping each layer's search at the best hit so far changes no hit, on rays from inside
    /// the sphere, from its surface and from beyond it, in every direction, with and without
    /// min-max, with the layers in either order; and it saves samples (a search that never
    /// stops would fail the last check).
    #[test]
    fn stopping_at_the_best_hit_finds_the_exhaustive_hit() {
        let (mut rays, mut hits, mut saved) = (0, 0, 0);
        let room = AnalyticRoom { size: 48 };
        let wall_first = WallFirst(AnalyticRoom { size: 48 });
        let shells = CloseShells([1.03, 1.0]);
        let orders: [(&dyn DistanceLayers, usize); 3] =
            [(&room, 0), (&wall_first, 1), (&shells, 0)];
        for ((layers, sphere), min_max) in orders.into_iter().flat_map(|o| [(o, false), (o, true)])
        {
            let params = SearchParams {
                min_max,
                ..SearchParams::default()
            };
            for k in 0..600 {
                let phi = k as f32 * 2.399_963;
                let z = ((k * 7 % 600) as f32 / 600.0) * 1.96 - 0.98;
                let ring = (1.0 - z * z).sqrt();
                let r = Vec3::new(ring * phi.cos(), z, ring * phi.sin());
                let (x, start) = match k % 3 {
                    0 => (Vec3::new(0.3, -0.2, 0.5), None),
                    1 => (Vec3::new(0.0, -0.6, 0.8), Some(sphere)),
                    _ => (Vec3::new(-1.7, 0.4, 1.1), None),
                };
                let (found, work) = hit(layers, x, r, start, &params);
                let (expected, samples) = exhaustive_hit(layers, x, r, start, &params);
                assert_eq!(found, expected, "ray {k}, min-max {min_max}");
                assert!(work.linear_steps <= samples);
                rays += 1;
                hits += usize::from(found.is_some());
                saved += usize::from(work.linear_steps < samples);
            }
        }
        assert!(hits > rays * 3 / 4, "{hits} of {rays} rays hit");
        assert!(
            saved > rays / 4,
            "{saved} of {rays} rays took fewer samples"
        );
    }

    /// The linear search one sample at a time, as it was before the lanes (Listing 17-1).
    #[allow(clippy::too_many_arguments)]
    fn scalar_linear_search<L: DistanceLayers + ?Sized>(
        layers: &L,
        layer: usize,
        x: Vec3,
        r: Vec3,
        a: f32,
        t_lo: f32,
        t_hi: f32,
        steps: u32,
        skip_cos: f32,
        d_stop: Option<f32>,
    ) -> (Option<Bracket>, u32) {
        let dt = (t_hi - t_lo) / steps as f32;
        let two_sided = layers.two_sided(layer);
        let x_len = x.length();
        let mut previous: Option<(f32, f32)> = None;
        for i in 0..=steps {
            let t = (t_lo + dt * i as f32).min(t_hi);
            let d = ray_parameter(t, a);
            let beyond = |d: f32| d_stop.is_some_and(|stop| d >= stop);
            if previous.is_some_and(|(d_prev, _)| beyond(d_prev)) {
                return (None, i); // every bracket from here starts at or beyond d_stop
            }
            let p = x + r * d;
            let stored = layers.distance(layer, p);
            let p_len = p.length();
            if stored <= 0.0 || p.dot(x) > skip_cos * p_len * x_len {
                previous = None;
                if beyond(d) {
                    return (None, i + 1);
                }
                continue;
            }
            let ratio = p_len / stored;
            if let Some((d_prev, ratio_prev)) = previous
                && (ratio_prev < 1.0) != (ratio < 1.0)
                && (two_sided || ratio_prev < 1.0)
            {
                let bracket = Bracket {
                    d_near: d_prev,
                    ratio_near: ratio_prev,
                    d_far: d,
                    ratio_far: ratio,
                };
                return (Some(bracket), i + 1);
            }
            previous = Some((d, ratio));
        }
        (None, steps + 1)
    }

    proptest::proptest! {
        #[test]
        fn lane_search_equals_scalar_search(
            x in proptest::array::uniform3(-2.5f32..2.5),
            r in proptest::array::uniform3(-1.0f32..1.0),
            layer in 0usize..2,
            steps in 1u32..90,
            t in (0.0f32..0.9, 0.0f32..1.0),
            skip in proptest::bool::ANY,
            stop in proptest::option::of(0.0f32..6.0),
        ) {
            let layers = AnalyticRoom { size: 32 };
            let (x, r) = (Vec3::from_array(x), Vec3::from_array(r));
            let Some(r) = r.try_normalize() else { return Ok(()); };
            let a = x.length().max(1e-6);
            let t_lo = T_START + t.0;
            let t_hi = (t_lo + t.1 * (T_END - t_lo)).max(t_lo);
            let skip_cos = if skip { 0.999 } else { 2.0 };
            let lanes = linear_search(&layers, layer, x, r, a, t_lo, t_hi, steps, skip_cos, stop);
            let scalar =
                scalar_linear_search(&layers, layer, x, r, a, t_lo, t_hi, steps, skip_cos, stop);
            // Bit for bit (`PartialEq` on the floats, and the sample counts).
            proptest::prop_assert_eq!(lanes, scalar);
        }
    }

    /// The lane texel lookup is `cube_texel` + `cube_texel_index` lane by lane: random
    /// directions, the axes (both signs of zero), the cube's edges and corners (the major-axis
    /// ties), texel borders, zero and non-finite directions, several face sizes.
    #[test]
    fn lane_cube_texels_equal_the_scalar_texels() {
        let mut dirs = vec![
            Vec3::X,
            Vec3::NEG_X,
            Vec3::Y,
            Vec3::NEG_Y,
            Vec3::Z,
            Vec3::NEG_Z,
            Vec3::new(-0.0, 0.0, -1.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(-1.0, 1.0, 1.0),
            Vec3::new(0.0, -1.0, -1.0),
            Vec3::new(1.0, -1.0, -1.0),
            Vec3::new(0.5, 0.25, -1.0),
            Vec3::new(1.0, 0.999_999_9, 0.5),
            Vec3::ZERO,
            Vec3::new(f32::NAN, 1.0, 0.0),
            Vec3::new(f32::INFINITY, 0.0, 0.0),
            Vec3::new(1e-30, -2e-30, 3e-38),
            Vec3::new(3e38, -2e38, 1e38),
        ];
        let mut state = 0x9e37_79b9_u32;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 17;
            state ^= state << 5;
            state as f32 / u32::MAX as f32 * 2.0 - 1.0
        };
        for _ in 0..4000 {
            dirs.push(Vec3::new(next(), next(), next()) * (1.0 + 9.0 * next().abs()));
        }
        while !dirs.len().is_multiple_of(LANES) {
            dirs.push(Vec3::Y);
        }
        for size in [
            1,
            7,
            64,
            512,
            2048,
            MAX_LANE_INDEX_SIZE,
            MAX_LANE_INDEX_SIZE + 1,
        ] {
            for group in dirs.chunks_exact(LANES) {
                let lanes: [Vec3; LANES] = group.try_into().expect("eight");
                let indices = cube_texel_indices_x8(Vec3x8::from_lanes(&lanes), size);
                for (dir, index) in lanes.iter().zip(indices) {
                    let scalar = cube_texel(*dir, size).map(|(f, t)| cube_texel_index(f, t, size));
                    assert_eq!(index, scalar, "{dir} at size {size}");
                }
            }
        }
    }

    #[test]
    fn lane_search_finds_the_scalar_brackets_on_the_walls() {
        // Rays from inside the mirror sphere's shell to the diffuse cube: every one crosses
        // layer 1, so the comparison above is not only about misses.
        let layers = AnalyticRoom { size: 64 };
        let mut found = 0;
        for k in 0..200 {
            let phi = k as f32 * 0.731;
            let z = (k as f32 / 200.0) * 1.8 - 0.9;
            let r = Vec3::new(
                (1.0 - z * z).sqrt() * phi.cos(),
                z,
                (1.0 - z * z).sqrt() * phi.sin(),
            );
            let x = Vec3::new(0.3, -0.2, 0.5);
            let lanes = linear_search(&layers, 1, x, r, x.length(), T_START, T_END, 37, 2.0, None);
            let scalar =
                scalar_linear_search(&layers, 1, x, r, x.length(), T_START, T_END, 37, 2.0, None);
            assert_eq!(lanes, scalar, "ray {k}");
            found += usize::from(lanes.0.is_some());
        }
        assert!(found > 150, "{found} of 200 rays found the wall");
    }

    #[test]
    fn secant_steps_refine_the_linear_bracket() {
        let layers = AnalyticRoom { size: 64 };
        let x = Vec3::new(0.0, -0.6, 0.8);
        let r = Vec3::new(0.2, -0.3, 0.9).normalize();
        let exact = {
            // The wall z = 3 (the ray's major axis).
            (3.0 - x.z) / r.z
        };
        let coarse = SearchParams {
            min_steps: 4,
            max_steps: 4,
            secant_steps: 0,
            min_max: false,
        };
        let fine = SearchParams {
            secant_steps: 10,
            ..coarse
        };
        let (c, _) = hit(&layers, x, r, Some(0), &coarse);
        let (f, w) = hit(&layers, x, r, Some(0), &fine);
        let (c, f) = (c.expect("coarse"), f.expect("fine"));
        assert!(
            (f.d - exact).abs() < (c.d - exact).abs(),
            "{c:?} {f:?} {exact}"
        );
        assert!((f.d - exact).abs() < 0.05 * exact, "{f:?} {exact}");
        assert!(w.secant_steps >= 1);
    }

    #[test]
    fn paths_reflect_and_end_on_diffuse_or_background() {
        let scene = AnalyticRoom { size: 64 };
        // A mirror point on the sphere, seen from outside along −z: reflected back toward +z,
        // where the cube wall is diffuse.
        let start = PathStart {
            x: Vec3::new(0.0, 0.0, 1.0),
            v: Vec3::new(0.1, 0.0, -1.0).normalize(),
            n: Vec3::Z,
            material: TexelMaterial {
                rgb: Vec3::splat(0.9),
                ior: -1.0,
            },
            layer: Some(0),
        };
        let params = PathParams::default();
        let result = trace_path(&scene, &start, &params);
        assert_eq!(result.last_layer, Some(1));
        let f = schlick(start.v.dot(start.n).abs(), 0.9);
        assert!((result.radiance - f * Vec3::new(0.5, 0.25, 0.125)).length() < 1e-5);
        assert!(!result.miss && !result.truncated && result.bounces == 1);
        // Straight up from inside, through the sphere's hole, toward the top wall.
        let up = PathStart {
            x: Vec3::new(0.0, 0.95, 0.0),
            v: Vec3::new(0.0, -1.0, 0.05).normalize(),
            n: Vec3::Y,
            material: TexelMaterial {
                rgb: Vec3::ONE,
                ior: -1.0,
            },
            layer: None,
        };
        let result = trace_path(&scene, &up, &params);
        assert_eq!(result.last_layer, Some(1));
    }

    #[test]
    fn refraction_inverts_the_index_from_inside_and_reflects_under_tir() {
        let glass = TexelMaterial {
            rgb: Vec3::splat(0.04),
            ior: 1.5,
        };
        let v = Vec3::new(0.6, 0.0, -0.8);
        let (t, w, tir) = scatter(v, Vec3::Z, glass, DielectricFresnel::Ignore);
        assert!(!tir && w == Vec3::ONE);
        assert_eq!(t, refract(v, Vec3::Z, 1.0 / 1.5).normalize());
        // From inside at 60°: beyond the critical angle of glass (41.8°).
        let inside = Vec3::new(0.866, 0.0, 0.5);
        let (t, w, tir) = scatter(inside, Vec3::Z, glass, DielectricFresnel::Schlick);
        assert!(tir && w == Vec3::ONE);
        assert_eq!(t, reflect(inside, -Vec3::Z));
        let (_, w, _) = scatter(v, Vec3::Z, glass, DielectricFresnel::Schlick);
        assert!((w.x - (1.0 - schlick(0.8, 0.04))).abs() < 1e-6);
    }
}
