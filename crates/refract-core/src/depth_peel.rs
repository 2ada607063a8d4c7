//! Refraction through any number of interfaces in screen space (method `depth-peel`): the
//! surfaces of every refractor depth-peeled into `K` layers seen from the eye (Everitt 2001),
//! then each eye ray followed through them: refracted (or totally reflected) at the nearest
//! layer, marched in 3D against the layers' surfaces at the texels it projects to (the
//! layered linear search of Krueger et al. 2006, refined by bisection), refracted again at the
//! next crossing, up to a budget of interactions; then the opaque objects' screen texture
//! (marched the same way, with a thickness as McGuire & Mara 2014's screen-space tracing has)
//! or the environment. Davis & Wyman 2007 follow total internal reflection the same way.
//!
//! A crossing of layer `j` between two samples of the ray is a change of sign of `f_j(t)`, the
//! signed distance of the ray point `q(t)` from the plane of layer `j`'s fragment at the texel
//! `q(t)` projects to (`±(q − P_j)·N_j`, negative toward the eye), where layer `j` is covered
//! at both samples: the plane, not the texel's one depth, so that a steep surface sampled once
//! per texel is crossed where the ray crosses it, not at a texel edge. Bisection narrows it to
//! `[a, b]` ([`REFINE_STEPS`] halvings), and it is accepted where `|f_j(a)|` and `|f_j(b)|`
//! are at most the thickness (else the sign changed across a depth discontinuity: the ray
//! passed behind a surface, not through it). The interaction at a crossing follows only the
//! layer's shading normal `N` and refractor `r` (never the path's history): the ray enters `r`
//! where `d·N < 0`, from the medium around `r` into `r`, and leaves it otherwise (the
//! reference's nested-media rule, `docs/reference.md`). Absorption (Beer-Lambert) follows the
//! medium the path's crossings put it in.
//!
//! One body serves the CPU backend ([`PeeledLayers`] over its buffers) and, line by line, the
//! WGSL twin `depth_peel.wgsl` of refract-gpu (over its layer textures).

use glam::{UVec2, Vec3, Vec4};

use crate::camera::Camera;
use crate::math;
use crate::nearby_geometry::ClipRay;
use crate::optics::{reflect, refract};

/// The most layers a frame peels (the `layers` parameter's upper bound).
pub const MAX_PEEL_LAYERS: u32 = 8;
/// Bisection halvings of a crossing's bracket: `2⁻⁸` of a march step.
pub const REFINE_STEPS: u32 = 8;
/// The layer index that stands for the opaque objects' surface in a [`Crossing`].
pub const OPAQUE_LAYER: u32 = u32::MAX;

/// The peeled layers and the opaque objects' screen texture as the march reads them; texels
/// are those of the eye's camera.
pub trait PeeledLayers {
    /// The plane of layer `layer`'s fragment (`0..K`, nearest first) at `texel`, facing away
    /// from the eye ([`facing_plane`] of its position at the texel's centre and its shading
    /// normal), all NaN where the layer is empty there. Layers are peeled in order: where
    /// layer `j` is empty, so is every layer after it.
    fn layer_plane(&self, texel: UVec2, layer: u32) -> Vec4;
    /// The unit shading normal of layer `layer` at `texel` (a covered texel).
    fn layer_normal(&self, texel: UVec2, layer: u32) -> Vec3;
    /// The index of the refractor of layer `layer` at `texel` (a covered texel).
    fn layer_refractor(&self, texel: UVec2, layer: u32) -> u32;
    /// The plane of the opaque objects' surface drawn at `texel` ([`facing_plane`]), all NaN
    /// where none is drawn.
    fn opaque_plane(&self, texel: UVec2) -> Vec4;
}

/// The plane through `p` with unit normal `±n`, oriented away from `eye`: `(N', w)` with
/// `N' = n` where `(p − eye)·n > 0`, else `−n`, and `w = −N'·p`, so that `N'·q + w` is the
/// signed distance of `q` from the plane, negative on the eye's side.
#[inline]
pub fn facing_plane(p: Vec3, n: Vec3, eye: Vec3) -> Vec4 {
    let n = if (p - eye).dot(n) > 0.0 { n } else { -n };
    n.extend(-n.dot(p))
}

/// The medium of one refractor, as the march reads it: its IOR, the IOR of the medium around
/// it (1 for air, the enclosing refractor's where it is immersed), which medium that is
/// (0: air, `k + 1`: refractor `k`) and its absorption coefficient per scene unit
/// (Beer-Lambert; 0 for clear glass). `#[repr(C)]`: the WGSL twin's `PeelMedium`, 32 bytes.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct PeelMedium {
    /// The refractor's IOR.
    pub ior: f32,
    /// The IOR around it.
    pub outside_ior: f32,
    /// The medium around it: 0 for air, `k + 1` for refractor `k`.
    pub within: u32,
    /// Padding.
    pub _padding: u32,
    /// The absorption coefficient `σ_a` per scene unit (RGB, `w` unused).
    pub sigma: [f32; 4],
}

const _: () = assert!(core::mem::size_of::<PeelMedium>() == 32);

/// The march's settings for one frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PeelSettings {
    /// Layers peeled, `1..=`[`MAX_PEEL_LAYERS`].
    pub layers: u32,
    /// Interactions (refractions and total internal reflections) per path, at least 1.
    pub max_interfaces: u32,
    /// Samples per marched segment, at least 1.
    pub steps: u32,
    /// The largest `|z − depth|` at an accepted crossing, scene units.
    pub thickness: f32,
    /// The sphere `(centre, radius)` holding every refractor: a segment is marched to where
    /// the ray leaves it.
    pub refractor_bound: Vec4,
    /// The sphere holding every refractor and opaque object, `radius ≤ 0` for a scene
    /// without objects: the last ray is marched against the opaque objects to where it leaves
    /// it.
    pub scene_bound: Vec4,
}

/// [`PeelSettings`] as the WGSL twin's uniform block `PeelUniforms` (48 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct PeelUniforms {
    /// [`PeelSettings::refractor_bound`].
    pub refractor_bound: [f32; 4],
    /// [`PeelSettings::scene_bound`].
    pub scene_bound: [f32; 4],
    /// [`PeelSettings::layers`].
    pub layers: u32,
    /// [`PeelSettings::max_interfaces`].
    pub max_interfaces: u32,
    /// [`PeelSettings::steps`].
    pub steps: u32,
    /// [`PeelSettings::thickness`].
    pub thickness: f32,
}

const _: () = assert!(core::mem::size_of::<PeelUniforms>() == 48);

impl From<&PeelSettings> for PeelUniforms {
    fn from(s: &PeelSettings) -> Self {
        Self {
            refractor_bound: s.refractor_bound.to_array(),
            scene_bound: s.scene_bound.to_array(),
            layers: s.layers,
            max_interfaces: s.max_interfaces,
            steps: s.steps,
            thickness: s.thickness,
        }
    }
}

/// How the layered part of a path ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PeelEnd {
    /// The ray left the refractors in air: no further crossing before the refractors' sphere.
    Left,
    /// No further crossing was found while the path was inside a medium (a miss: the exit
    /// fell between samples, behind a layer that was not peeled, or off every layer).
    Lost,
    /// The ray left the screen (or went behind the eye) before leaving the refractors.
    OffScreen,
    /// The interaction budget ran out before the ray left the refractors.
    Budget,
}

impl PeelEnd {
    /// Its code in the WGSL twin (`PEEL_END_*`).
    pub const fn code(self) -> u32 {
        match self {
            PeelEnd::Left => 0,
            PeelEnd::Lost => 1,
            PeelEnd::OffScreen => 2,
            PeelEnd::Budget => 3,
        }
    }
}

/// A path through the layers from the nearest surface of a pixel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PeelPath {
    /// How the layered part ended.
    pub end: PeelEnd,
    /// The last ray: from the last interaction point (`P2` of a two-interface path) ...
    pub origin: Vec3,
    /// ... along this unit direction (looked up in the environment where no object is hit).
    pub dir: Vec3,
    /// The opaque objects' texel the last ray hits, and the point there on the ray.
    pub opaque: Option<(UVec2, Vec3)>,
    /// The first exit `P2` (the second interaction: the first surface met from the inside,
    /// refracting or not) and the direction leaving it `T2`, as the reference's AOVs define
    /// them; `None` for a path with one interaction.
    pub first_exit: Option<(Vec3, Vec3)>,
    /// Refractions (interfaces crossed).
    pub interfaces: u32,
    /// Total internal reflections.
    pub reflections: u32,
    /// Bit `k`: the path refracted through refractor `k` (`k < 32`).
    pub refractors_met: u32,
    /// Beer-Lambert transmittance of the segments inside absorbing media.
    pub transmittance: Vec3,
}

/// What one marched segment met first.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Crossing {
    /// Layer `layer` (or [`OPAQUE_LAYER`]) at ray parameter `t`, read at `texel`.
    Surface {
        /// The ray parameter.
        t: f32,
        /// The texel the surface is read at.
        texel: UVec2,
        /// The layer crossed.
        layer: u32,
    },
    /// The ray left the screen at a sample before `t`.
    OffScreen,
    /// Nothing before the end of the segment.
    Nothing,
}

/// The far parameter where `origin + t dir` (unit `dir`) leaves the sphere `bound`
/// (`centre, radius`), 0 where it does not meet it ahead.
#[inline]
pub fn sphere_exit(origin: Vec3, dir: Vec3, bound: Vec4) -> f32 {
    let oc = origin - bound.truncate();
    let b = oc.dot(dir);
    let c = oc.dot(oc) - bound.w * bound.w;
    let disc = b * b - c;
    // NaN inputs fail this test too.
    if disc.partial_cmp(&0.0) != Some(core::cmp::Ordering::Greater) {
        return 0.0;
    }
    (math::sqrt(disc) - b).max(0.0)
}

/// A point of the marched ray: the texel it projects to and its position.
#[derive(Clone, Copy, Debug)]
struct Sample {
    texel: UVec2,
    q: Vec3,
}

/// The marched ray `origin + t dir` in the eye's clip space.
struct MarchRay {
    clip: ClipRay,
    origin: Vec3,
    dir: Vec3,
}

impl MarchRay {
    fn new(camera: &Camera, origin: Vec3, dir: Vec3) -> Self {
        Self {
            clip: ClipRay::new(camera, origin, dir),
            origin,
            dir,
        }
    }

    /// The point at `t` (`None`: off the screen or behind the eye).
    #[inline]
    fn sample(&self, t: f32) -> Option<Sample> {
        Some(Sample {
            texel: self.clip.texel(t)?,
            q: self.origin + t * self.dir,
        })
    }
}

/// Which side of layer `layer` (or [`OPAQUE_LAYER`]) the ray point `s` is on, as a signed
/// distance, negative in front (toward the eye), NaN where the layer is empty at its texel.
/// A layer is the plane of its fragment at the texel ([`facing_plane`]), so that a surface
/// sampled once per texel is still crossed where the ray crosses it inside the texel (a
/// view-depth difference per texel, as McGuire and Mara 2014 compare, steps at every texel edge
/// of a steep surface). The opaque objects' surface is such a plane too.
#[inline]
fn layer_offset<L: PeeledLayers>(layers: &L, s: &Sample, layer: u32) -> f32 {
    let plane = if layer == OPAQUE_LAYER {
        layers.opaque_plane(s.texel)
    } else {
        layers.layer_plane(s.texel, layer)
    };
    plane.truncate().dot(s.q) + plane.w
}

/// Narrows a sign change of `f_layer` in `[a, b]` by bisection and accepts it where both ends
/// are within `thickness` of the layer: `(t, texel)` with `t` the root of the line through the
/// final bracket's ends (the distance to a plane is linear in `t`) and the texel of its far end
/// (where the layer is covered), or `None`.
fn refine<L: PeeledLayers>(
    ray: &MarchRay,
    layers: &L,
    layer: u32,
    thickness: f32,
    (mut a, mut f_a): (f32, f32),
    (mut b, mut f_b, mut texel_b): (f32, f32, UVec2),
) -> Option<(f32, UVec2)> {
    for _ in 0..REFINE_STEPS {
        let m = 0.5 * (a + b);
        let s = ray.sample(m)?;
        let f_m = layer_offset(layers, &s, layer);
        if f_m.is_nan() {
            return None;
        }
        if (f_m < 0.0) == (f_a < 0.0) {
            (a, f_a) = (m, f_m);
        } else {
            (b, f_b, texel_b) = (m, f_m, s.texel);
        }
    }
    // The signed distance is linear along the ray within a texel: the final bracket's root.
    let t = a + (b - a) * (f_a / (f_a - f_b)).clamp(0.0, 1.0);
    (f_a.abs() <= thickness && f_b.abs() <= thickness).then_some((t, texel_b))
}

/// Marches `origin + t dir`, `t ∈ [0, t_end]`, in `steps` equal steps against the first
/// `layer_count` layers and, with `opaque`, the opaque objects (a crossing of theirs only from
/// in front to behind); layer `exclude` is not tested in the first step (the surface the ray
/// starts on). The first accepted crossing in the first step that has one, the nearest of that
/// step's.
#[allow(clippy::too_many_arguments)]
pub fn march<L: PeeledLayers>(
    camera: &Camera,
    layers: &L,
    origin: Vec3,
    dir: Vec3,
    t_end: f32,
    settings: &PeelSettings,
    layer_count: u32,
    opaque: bool,
    exclude: Option<u32>,
) -> Crossing {
    let ray = MarchRay::new(camera, origin, dir);
    let Some(s_a) = ray.sample(0.0) else {
        return Crossing::OffScreen;
    };
    let count = layer_count.min(MAX_PEEL_LAYERS) as usize;
    let mut f_a = [f32::NAN; MAX_PEEL_LAYERS as usize];
    for (j, f) in f_a.iter_mut().enumerate().take(count) {
        if exclude != Some(j as u32) {
            *f = layer_offset(layers, &s_a, j as u32);
        }
    }
    let mut f_opaque_a = if opaque {
        layer_offset(layers, &s_a, OPAQUE_LAYER)
    } else {
        f32::NAN
    };
    let steps = settings.steps.max(1);
    let dt = t_end / steps as f32;
    let mut t_a = 0.0;
    for i in 1..=steps {
        let t_b = dt * i as f32;
        let Some(s_b) = ray.sample(t_b) else {
            return Crossing::OffScreen;
        };
        let mut best: Option<(f32, UVec2, u32)> = None;
        for j in 0..count {
            let f_b = layer_offset(layers, &s_b, j as u32);
            if f_b.is_nan() {
                // Layers are peeled in order: none after an empty one is covered here.
                f_a[j..count].fill(f32::NAN);
                break;
            }
            if (f_a[j] < 0.0) != (f_b < 0.0) && !f_a[j].is_nan() {
                let hit = refine(
                    &ray,
                    layers,
                    j as u32,
                    settings.thickness,
                    (t_a, f_a[j]),
                    (t_b, f_b, s_b.texel),
                );
                if let Some((t, texel)) = hit
                    && best.is_none_or(|(t_best, _, _)| t < t_best)
                {
                    best = Some((t, texel, j as u32));
                }
            }
            f_a[j] = f_b;
        }
        if opaque {
            let f_b = layer_offset(layers, &s_b, OPAQUE_LAYER);
            if f_opaque_a < 0.0 && f_b >= 0.0 {
                let hit = refine(
                    &ray,
                    layers,
                    OPAQUE_LAYER,
                    settings.thickness,
                    (t_a, f_opaque_a),
                    (t_b, f_b, s_b.texel),
                );
                if let Some((t, texel)) = hit
                    && best.is_none_or(|(t_best, _, _)| t < t_best)
                {
                    best = Some((t, texel, OPAQUE_LAYER));
                }
            }
            f_opaque_a = f_b;
        }
        if let Some((t, texel, layer)) = best {
            return Crossing::Surface { t, texel, layer };
        }
        t_a = t_b;
    }
    Crossing::Nothing
}

/// The interaction of direction `dir` (unit) with refractor `refractor`'s interface of unit
/// shading normal `n`: `Some((T, medium after))` where it refracts, `None` for total internal
/// reflection (then the ray reflects about `n`). The ray enters the refractor where `d·N < 0`
/// (from the medium around it, IOR `outside_ior`, into IOR `ior`) and leaves it otherwise.
#[inline]
pub fn interact(dir: Vec3, n: Vec3, medium: &PeelMedium, refractor: u32) -> Option<(Vec3, u32)> {
    let entering = dir.dot(n) < 0.0;
    let (n_facing, eta, after) = if entering {
        (n, medium.outside_ior / medium.ior, refractor + 1)
    } else {
        (-n, medium.ior / medium.outside_ior, medium.within)
    };
    let t = refract(dir, n_facing, eta);
    (t != Vec3::ZERO).then(|| (t.normalize_or(dir), after))
}

/// The path from the nearest surface `p1` (layer 0 at pixel `texel`, shading normal `n1`,
/// refractor `refractor`), seen from the eye, through the layers: refracted or reflected at
/// each crossing ([`interact`]), each segment marched ([`march`]) to the refractors' sphere,
/// until no crossing is left, the ray leaves the screen or [`PeelSettings::max_interfaces`]
/// interactions are spent; then the last ray marched against the opaque objects (where the
/// scene has them and the ray is still on the screen). `media[k]` is refractor `k`'s.
pub fn peel_path<L: PeeledLayers>(
    camera: &Camera,
    layers: &L,
    media: &[PeelMedium],
    settings: &PeelSettings,
    p1: Vec3,
    n1: Vec3,
    refractor: u32,
) -> PeelPath {
    let mut path = PeelPath {
        end: PeelEnd::Left,
        origin: p1,
        dir: (p1 - camera.eye()).normalize_or(camera.look_dir()),
        opaque: None,
        interfaces: 0,
        reflections: 0,
        refractors_met: 0,
        first_exit: None,
        transmittance: Vec3::ONE,
    };
    // The medium the path is in: 0 air, k + 1 refractor k.
    let mut current = 0u32;
    let (mut n, mut r, mut layer) = (n1, refractor, 0u32);
    let has_objects = settings.scene_bound.w > 0.0;
    loop {
        if path.interfaces + path.reflections >= settings.max_interfaces.max(1) {
            path.end = PeelEnd::Budget;
            break;
        }
        let medium = media.get(r as usize).copied().unwrap_or_default();
        match interact(path.dir, n, &medium, r) {
            Some((t, after)) => {
                path.dir = t;
                current = after;
                path.interfaces += 1;
                path.refractors_met |= 1u32.checked_shl(r).unwrap_or(0);
            }
            None => {
                let n_facing = if path.dir.dot(n) < 0.0 { n } else { -n };
                path.dir = reflect(path.dir, n_facing);
                path.reflections += 1;
            }
        }
        if path.interfaces + path.reflections == 2 {
            path.first_exit = Some((path.origin, path.dir));
        }
        let t_end = sphere_exit(path.origin, path.dir, settings.refractor_bound);
        let crossing = march(
            camera,
            layers,
            path.origin,
            path.dir,
            t_end,
            settings,
            settings.layers,
            has_objects,
            Some(layer),
        );
        match crossing {
            Crossing::Surface {
                t,
                texel,
                layer: crossed,
            } => {
                path.transmittance *= segment_transmittance(media, current, t);
                if crossed == OPAQUE_LAYER {
                    path.opaque = Some((texel, path.origin + t * path.dir));
                    return path;
                }
                path.origin += t * path.dir;
                // The far end of a kept bracket is covered by the layer.
                n = layers.layer_normal(texel, crossed);
                r = layers.layer_refractor(texel, crossed);
                layer = crossed;
            }
            Crossing::OffScreen => {
                path.end = PeelEnd::OffScreen;
                return path;
            }
            Crossing::Nothing => {
                path.end = if current == 0 {
                    PeelEnd::Left
                } else {
                    PeelEnd::Lost
                };
                break;
            }
        }
    }
    if has_objects {
        let t_end = sphere_exit(path.origin, path.dir, settings.scene_bound);
        let crossing = march(
            camera,
            layers,
            path.origin,
            path.dir,
            t_end,
            settings,
            0,
            true,
            None,
        );
        if let Crossing::Surface { t, texel, .. } = crossing {
            path.opaque = Some((texel, path.origin + t * path.dir));
        }
    }
    path
}

/// Beer-Lambert `exp(−σ t)` of `t` scene units in medium `current` (0: air, 1).
#[inline]
fn segment_transmittance(media: &[PeelMedium], current: u32, t: f32) -> Vec3 {
    match current.checked_sub(1).and_then(|k| media.get(k as usize)) {
        Some(m) => {
            let sigma = Vec3::new(m.sigma[0], m.sigma[1], m.sigma[2]);
            Vec3::new(
                math::exp(-sigma.x * t),
                math::exp(-sigma.y * t),
                math::exp(-sigma.z * t),
            )
        }
        None => Vec3::ONE,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::CameraDesc;

    /// Concentric spheres about the origin seen by an analytic "rasteriser": layer `j` at a
    /// texel is the `j`-th intersection of the texel's centre ray with the spheres (outer then
    /// inner), the normal the sphere's outward normal, refractor 0 the outer one.
    struct Spheres<'a> {
        camera: &'a Camera,
        radii: &'a [f32],
        wall: Option<f32>,
    }

    impl Spheres<'_> {
        fn hits(&self, texel: UVec2) -> ([(f32, Vec3, u32); 8], usize) {
            let ray = self
                .camera
                .pixel_ray(Camera::pixel_center(texel.x, texel.y));
            let mut hits = [(f32::INFINITY, Vec3::Z, 0); 8];
            let mut n = 0;
            for (k, &radius) in self.radii.iter().enumerate() {
                let b = ray.origin.dot(ray.dir);
                let disc = b * b - (ray.origin.length_squared() - radius * radius);
                if disc > 0.0 {
                    for t in [-b - disc.sqrt(), -b + disc.sqrt()] {
                        let p = ray.at(t);
                        hits[n] = (
                            (p - self.camera.eye()).dot(self.camera.look_dir()),
                            p / radius,
                            k as u32,
                        );
                        n += 1;
                    }
                }
            }
            hits[..n].sort_by(|a, b| a.0.total_cmp(&b.0));
            (hits, n)
        }
    }

    impl PeeledLayers for Spheres<'_> {
        fn layer_plane(&self, texel: UVec2, layer: u32) -> Vec4 {
            let (depth, n, k) = self.hits(texel).0[layer as usize];
            // Concentric about the origin: the point is the normal times the radius.
            if depth.is_finite() {
                facing_plane(n * self.radii[k as usize], n, self.camera.eye())
            } else {
                Vec4::NAN
            }
        }
        fn layer_normal(&self, texel: UVec2, layer: u32) -> Vec3 {
            self.hits(texel).0[layer as usize].1
        }
        fn layer_refractor(&self, texel: UVec2, layer: u32) -> u32 {
            self.hits(texel).0[layer as usize].2
        }
        fn opaque_plane(&self, texel: UVec2) -> Vec4 {
            // A wall z = wall facing the camera.
            let Some(z) = self.wall else {
                return Vec4::NAN;
            };
            let ray = self
                .camera
                .pixel_ray(Camera::pixel_center(texel.x, texel.y));
            let t = (z - ray.origin.z) / ray.dir.z;
            if t > 0.0 {
                facing_plane(ray.at(t), Vec3::Z, self.camera.eye())
            } else {
                Vec4::NAN
            }
        }
    }

    fn camera(size: u32) -> Camera {
        Camera::new(CameraDesc {
            eye: Vec3::new(0.0, 0.0, 4.0),
            target: Vec3::ZERO,
            width: size,
            height: size,
            ..CameraDesc::default()
        })
        .expect("camera")
    }

    fn settings(layers: u32) -> PeelSettings {
        PeelSettings {
            layers,
            max_interfaces: 8,
            steps: 64,
            thickness: 0.05,
            refractor_bound: Vec4::new(0.0, 0.0, 0.0, 1.01),
            scene_bound: Vec4::ZERO,
        }
    }

    fn glass(ior: f32) -> PeelMedium {
        PeelMedium {
            ior,
            outside_ior: 1.0,
            ..PeelMedium::default()
        }
    }

    /// The exact path through a glass sphere (two refractions) for the ray through `texel`.
    fn exact_sphere_exit(camera: &Camera, texel: UVec2, ior: f32) -> (Vec3, Vec3) {
        let ray = camera.pixel_ray(Camera::pixel_center(texel.x, texel.y));
        let b = ray.origin.dot(ray.dir);
        let disc = b * b - (ray.origin.length_squared() - 1.0);
        let p1 = ray.at(-b - disc.sqrt());
        let t1 = refract(ray.dir, p1, 1.0 / ior);
        let t = -2.0 * p1.dot(t1);
        let p2 = p1 + t * t1;
        (p2, refract(t1, -p2, ior).normalize())
    }

    #[test]
    fn a_glass_sphere_is_crossed_twice_at_its_exact_exit() {
        let camera = camera(128);
        let spheres = Spheres {
            camera: &camera,
            radii: &[1.0],
            wall: None,
        };
        let mut checked = 0;
        for (x, y) in [(64, 64), (80, 70), (50, 90), (70, 40), (90, 64)] {
            let texel = UVec2::new(x, y);
            let (depth, n, r) = spheres.hits(texel).0[0];
            if !depth.is_finite() {
                continue;
            }
            let ray = camera.pixel_ray(Camera::pixel_center(x, y));
            let p1 = ray.origin + ray.dir * (depth / ray.dir.dot(camera.look_dir()));
            let path = peel_path(&camera, &spheres, &[glass(1.5)], &settings(2), p1, n, r);
            let (p2, t2) = exact_sphere_exit(&camera, texel, 1.5);
            assert_eq!(path.end, PeelEnd::Left, "texel {texel}");
            assert_eq!((path.interfaces, path.reflections), (2, 0));
            assert_eq!(path.refractors_met, 1);
            // A texel's layer is read at its centre: the exit is within about a texel.
            assert!(
                (path.origin - p2).length() < 0.03,
                "{} vs {p2}",
                path.origin
            );
            assert!(path.dir.angle_between(t2) < 0.03, "{} vs {t2}", path.dir);
            checked += 1;
        }
        assert_eq!(checked, 5);
    }

    #[test]
    fn one_layer_refracts_once_and_is_lost_inside() {
        let camera = camera(64);
        let spheres = Spheres {
            camera: &camera,
            radii: &[1.0],
            wall: None,
        };
        let (depth, n, r) = spheres.hits(UVec2::new(40, 30)).0[0];
        let ray = camera.pixel_ray(Camera::pixel_center(40, 30));
        let p1 = ray.origin + ray.dir * (depth / ray.dir.dot(camera.look_dir()));
        let path = peel_path(&camera, &spheres, &[glass(1.5)], &settings(1), p1, n, r);
        assert_eq!(path.end, PeelEnd::Lost);
        assert_eq!(path.interfaces, 1);
        assert!(path.dir.angle_between(refract(ray.dir, n, 1.0 / 1.5)) < 1e-5);
    }

    #[test]
    fn nested_spheres_refract_at_the_ratio_of_their_media_and_absorb() {
        let camera = camera(128);
        let spheres = Spheres {
            camera: &camera,
            radii: &[1.0, 0.5],
            wall: None,
        };
        let media = [
            PeelMedium {
                sigma: [0.5, 0.0, 0.0, 0.0],
                ..glass(1.5)
            },
            PeelMedium {
                ior: 1.33,
                outside_ior: 1.5,
                within: 1,
                _padding: 0,
                sigma: [0.0; 4],
            },
        ];
        // The centre pixel's ray goes straight through all four interfaces.
        let texel = UVec2::new(64, 64);
        let (depth, n, r) = spheres.hits(texel).0[0];
        let ray = camera.pixel_ray(Camera::pixel_center(64, 64));
        let p1 = ray.origin + ray.dir * (depth / ray.dir.dot(camera.look_dir()));
        let path = peel_path(&camera, &spheres, &media, &settings(4), p1, n, r);
        assert_eq!(path.end, PeelEnd::Left);
        assert_eq!(path.interfaces, 4);
        assert_eq!(path.refractors_met, 0b11);
        // Inside the outer glass for 2 × 0.5 units: exp(−0.5 · 1).
        let expected = (-0.5f32).exp();
        assert!(
            (path.transmittance.x - expected).abs() < 0.02,
            "{}",
            path.transmittance
        );
        assert_eq!(path.transmittance.y, 1.0);
        // Two layers only: the inner sphere is never reached, the exit is the outer front's
        // refraction lost inside.
        let two = peel_path(&camera, &spheres, &media, &settings(2), p1, n, r);
        assert_eq!(two.end, PeelEnd::Lost);
    }

    #[test]
    fn the_last_ray_hits_the_wall_behind() {
        let camera = camera(64);
        let spheres = Spheres {
            camera: &camera,
            radii: &[1.0],
            wall: Some(-2.0),
        };
        let texel = UVec2::new(36, 30);
        let (depth, n, r) = spheres.hits(texel).0[0];
        let ray = camera.pixel_ray(Camera::pixel_center(36, 30));
        let p1 = ray.origin + ray.dir * (depth / ray.dir.dot(camera.look_dir()));
        let mut s = settings(2);
        s.scene_bound = Vec4::new(0.0, 0.0, 0.0, 3.0);
        let path = peel_path(&camera, &spheres, &[glass(1.5)], &s, p1, n, r);
        let (_, p_geom) = path.opaque.expect("the wall is hit");
        assert!((p_geom.z + 2.0).abs() < 0.05, "{p_geom}");
        let (p2, t2) = exact_sphere_exit(&camera, texel, 1.5);
        let exact = p2 + t2 * ((-2.0 - p2.z) / t2.z);
        assert!((p_geom - exact).length() < 0.06, "{p_geom} vs {exact}");
    }

    #[test]
    fn total_internal_reflection_reflects_and_is_counted() {
        let medium = glass(1.5);
        // Leaving the glass at 60° from the normal: beyond the critical angle (41.8°).
        let dir = Vec3::new(0.75f32.sqrt(), 0.5, 0.0);
        assert_eq!(interact(dir, Vec3::Y, &medium, 0), None);
        let (t, after) = interact(-Vec3::Y, Vec3::Y, &medium, 3).expect("refracts");
        assert_eq!((t, after), (-Vec3::Y, 4));
    }

    #[test]
    fn sphere_exit_is_the_far_root() {
        let bound = Vec4::new(0.0, 0.0, 0.0, 2.0);
        assert!((sphere_exit(Vec3::ZERO, Vec3::X, bound) - 2.0).abs() < 1e-6);
        assert!((sphere_exit(Vec3::new(-3.0, 0.0, 0.0), Vec3::X, bound) - 5.0).abs() < 1e-6);
        assert_eq!(sphere_exit(Vec3::new(0.0, 3.0, 0.0), Vec3::X, bound), 0.0);
    }
}
