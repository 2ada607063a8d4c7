//! Exact recursive ray tracing through any number of refractors: Snell at every interface with
//! the same interpolated shading normals as the approximate methods, between the refractor's
//! medium and the one around it (air, or the refractor it lies within: see
//! [`refract_scene::scene`]), total internal reflection as internal reflection, Beer-Lambert
//! absorption along every segment inside an absorbing medium, conductors (mirrors, metals:
//! refractors or opaque objects) as reflection weighted by the exact conductor Fresnel
//! reflectance per channel, a depth limit on specular interactions. Rough surfaces (glass and
//! conductors of roughness above 0) scatter about one GGX microfacet normal per interaction,
//! drawn from the normals visible to the ray ([`refract_core::microfacet`], Mitsuba 3's
//! `roughdielectric`/`roughconductor` with `ggx` and visible-normal sampling), the normal's
//! `u` from [`crate::sampling::interface_sample`].
//!
//! A scene with dispersive glass is rendered spectrally ([`refract_core::spectral`], Mitsuba 3's
//! spectral variants): each sample carries four hero wavelengths; a path that meets a
//! dispersive interface keeps only the hero's and refracts with the index at its wavelength;
//! where a path ends, the environment's and the diffuse surfaces' spectra at its wavelengths
//! are turned into linear sRGB and weighted like the RGB radiance they replace.

use std::sync::Arc;

use glam::{Vec2, Vec3};
use rayon::prelude::*;
use refract_core::environment::Exact;
use refract_core::fresnel::{Conductor, fresnel_dielectric};
use refract_core::microfacet::{MicrofacetSample, alpha_from_roughness, sample_rough_interface};
use refract_core::optics::{face_forward_shading_normal, reflect, refract};
use refract_core::spectral::{UpliftTable, Wavelengths, dispersive_ior};
use refract_core::{Camera, Ray};
use refract_geometry::Hit;
use refract_scene::spectral::{SpectralLighting, uplift_tables};
use refract_scene::{Aov, Frame, InterfaceRule, Layer, Material, Scene, TraceMode, TraceSettings};

use crate::sampling::{interface_sample, path_child, path_root, pixel_sample, wavelength_sample};

/// Where a path's random numbers come from: the pixel's sample `index`, the node `key` of
/// the path tree it has reached ([`crate::sampling`]) and, in a spectral render, the sample's
/// wavelengths.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PathSampler {
    /// The sample's index among the pixel's samples.
    pub index: u32,
    /// The current node of the path tree.
    pub key: u32,
    /// The wavelengths the path carries (`None`: an RGB render).
    pub wavelengths: Option<Wavelengths>,
}

impl PathSampler {
    /// Sample `index` of pixel `(x, y)`, at the root of its path tree, in RGB.
    pub fn new(x: u32, y: u32, index: u32) -> Self {
        Self {
            index,
            key: path_root(x, y),
            wavelengths: None,
        }
    }

    /// Sample `index` of `count` of pixel `(x, y)` carrying its wavelengths
    /// ([`wavelength_sample`]).
    pub fn spectral(x: u32, y: u32, index: u32, count: u32) -> Self {
        Self {
            wavelengths: Some(Wavelengths::sample(wavelength_sample(x, y, index, count))),
            ..Self::new(x, y, index)
        }
    }

    /// The node after the reflected (`0`) or transmitted (`1`) branch.
    fn child(self, branch: u32) -> Self {
        Self {
            key: path_child(self.key, branch),
            ..self
        }
    }

    /// One visible microfacet normal of a rough interface at this node, `depth` interactions
    /// into the path.
    fn rough(self, depth: u32, dir: Vec3, facing: Vec3, eta: f32, alpha: f32) -> MicrofacetSample {
        let u = interface_sample(self.key, depth, self.index);
        sample_rough_interface(dir, facing, eta, alpha, u)
    }
}

/// The branch codes of [`PathSampler::child`].
const REFLECTED: u32 = 0;
const TRANSMITTED: u32 = 1;

/// Ground truth of one pixel, from the transmission path through its centre. Quantities that do
/// not exist for a pixel (no refractor there, no exit, no nearby geometry hit) are NaN.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PathRecord {
    /// First refractor hit `P1`.
    pub p1: Vec3,
    /// Outward shading normal at `P1`.
    pub n1: Vec3,
    /// Direction after the first interface (`T1`).
    pub t1: Vec3,
    /// Exact first exit point `P2`: the first hit from inside (whether it refracts or not).
    pub p2: Vec3,
    /// Outward shading normal at `P2`.
    pub n2: Vec3,
    /// Direction leaving the first exit point `P2` (refracted there, or reflected under TIR at
    /// `P2`): what the image-space methods approximate with their `T2`.
    pub t2: Vec3,
    /// Direction in which the path finally leaves the refractor (the environment lookup
    /// direction); equal to `t2` for paths that leave once.
    pub t_out: Vec3,
    /// Interfaces crossed by refraction (TIR bounces not counted).
    pub interfaces: u32,
    /// The refractors the path met (bit `i`: refractor `i` of `Scene::refractors`).
    pub refractors_met: u32,
    /// Total internal reflection anywhere on the path.
    pub tir: bool,
    /// Total internal reflection at the first exit `P2`.
    pub tir_first_exit: bool,
    /// Where the escaping ray hit nearby opaque geometry.
    pub p_geom: Vec3,
}

impl PathRecord {
    /// A pixel that does not see the refractor.
    pub const EMPTY: Self = Self {
        p1: Vec3::NAN,
        n1: Vec3::NAN,
        t1: Vec3::NAN,
        p2: Vec3::NAN,
        n2: Vec3::NAN,
        t2: Vec3::NAN,
        t_out: Vec3::NAN,
        interfaces: 0,
        refractors_met: 0,
        tir: false,
        tir_first_exit: false,
        p_geom: Vec3::NAN,
    };

    /// Whether the pixel's centre ray hits the refractor.
    pub fn covers_refractor(&self) -> bool {
        !self.p1.is_nan()
    }
}

/// Which surface a ray hit.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Surface {
    /// Refractor `i` of `Scene::refractors`.
    Refractor(usize),
    Object(usize),
}

/// What the tracer needs of refractor `i`'s two sides.
#[derive(Clone, Copy, Debug)]
struct Medium {
    /// Index inside.
    ior: f32,
    /// Index of the medium around it.
    outside_ior: f32,
    /// The refractor around it (`None`: air).
    within: Option<usize>,
    /// Its absorption coefficient per world unit (`None`: clear).
    absorption: Option<Vec3>,
    /// GGX `α` of its surface (0: smooth).
    alpha: f32,
    /// Abbe number of its glass (`+inf`: not dispersive).
    abbe: f32,
}

impl Medium {
    /// Its index at wavelength `lambda` (nm).
    fn ior_at(&self, lambda: f32) -> f32 {
        dispersive_ior(self.ior, self.abbe, lambda)
    }
}

/// What a spectral render needs besides the scene.
struct Spectral {
    table: UpliftTable<'static>,
    lighting: Arc<SpectralLighting>,
}

/// The spectra of a dispersive `scene`'s emitters (`None` for a scene rendered in RGB), once
/// per scene: a renderer keeps them between frames ([`Tracer::with_lighting`]).
pub fn spectral_lighting(scene: &Scene) -> Option<Arc<SpectralLighting>> {
    scene
        .has_dispersion()
        .then(|| Arc::new(SpectralLighting::new(scene, &uplift_tables().table())))
}

/// Where a branch of the full mode's splitting tree stands.
#[derive(Clone, Copy, Debug)]
struct Branch {
    /// The medium it travels in (`None`: air).
    medium: Option<usize>,
    /// Specular interactions so far.
    depth: u32,
    /// The scalar throughput the cutoff tests.
    throughput: f32,
    sampler: PathSampler,
}

/// Bit `i` of [`PathRecord::refractors_met`] (none past the 32nd refractor; scenes hold at most
/// `refract_scene::MAX_REFRACTORS`).
fn refractor_bit(i: usize) -> u32 {
    u32::try_from(i)
        .ok()
        .and_then(|i| 1u32.checked_shl(i))
        .unwrap_or(0)
}

/// `exp(−σ s)` per channel; a clear channel (`σ = 0`) keeps everything even over an infinite
/// segment (a ray that leaves a mesh that is not closed).
fn beer_lambert(sigma: Vec3, length: f32) -> Vec3 {
    let keep = |s: f32| if s == 0.0 { 1.0 } else { (-s * length).exp() };
    Vec3::new(keep(sigma.x), keep(sigma.y), keep(sigma.z))
}

/// The refraction geometry at a refractor hit.
struct Interface {
    /// Entering the refractor (by the settings' [`InterfaceRule`]).
    entering: bool,
    /// Shading normal facing the incoming ray.
    facing: Vec3,
    /// `n_i / n_t`.
    eta: f32,
    /// The factor of radiance carried through a refraction: `η²` under
    /// [`InterfaceRule::ShadingNormal`] (the camera-side radiance of a ray refracted from medium
    /// `i` into `t` is `(n_i/n_t)²` of the radiance on the other side), 1 under
    /// [`InterfaceRule::GeometricNormal`].
    transmitted_radiance: f32,
}

impl Interface {
    /// The interface of a refractor of index `ior` in a medium of index `outside_ior`.
    fn at(dir: Vec3, hit: &Hit, ior: f32, outside_ior: f32, rule: InterfaceRule) -> Self {
        match rule {
            InterfaceRule::ShadingNormal => {
                // Mitsuba 3's dielectric: the side from the shading frame, cos θi = −d·Ns ≥ 0
                // outside; the oriented shading normal faces the ray by construction.
                let entering = -dir.dot(hit.shading_normal) >= 0.0;
                let eta = if entering {
                    outside_ior / ior
                } else {
                    ior / outside_ior
                };
                Self {
                    entering,
                    facing: if entering {
                        hit.shading_normal
                    } else {
                        -hit.shading_normal
                    },
                    eta,
                    transmitted_radiance: eta * eta,
                }
            }
            InterfaceRule::GeometricNormal => {
                let entering = dir.dot(hit.geometric_normal) < 0.0;
                let oriented = if entering {
                    hit.shading_normal
                } else {
                    -hit.shading_normal
                };
                Self {
                    entering,
                    facing: face_forward_shading_normal(oriented, dir),
                    eta: if entering {
                        outside_ior / ior
                    } else {
                        ior / outside_ior
                    },
                    transmitted_radiance: 1.0,
                }
            }
        }
    }
}

/// The exact tracer over one scene.
pub struct Tracer<'a> {
    scene: &'a Scene,
    settings: TraceSettings,
    /// Per refractor, in `Scene::refractors` order.
    media: Vec<Medium>,
    /// Whether any surface is rough (the pixel-centre path then is not the colour).
    rough: bool,
    /// Present when the scene is dispersive: the render is spectral.
    spectral: Option<Spectral>,
}

/// Secondary rays start this far off the surface, relative to the hit point's magnitude:
/// `ε (1 + max|pᵢ|)` with `ε = 4e-6`, about 32 ulps of the coordinates, enough to clear the
/// rounding of the intersection and small enough not to shift rays measurably (a slab's
/// lateral shift is exact to 1e-5).
const OFFSET: f32 = 4e-6;

impl<'a> Tracer<'a> {
    /// A tracer of `scene`.
    pub fn new(scene: &'a Scene, settings: TraceSettings) -> Self {
        Self::with_lighting(scene, settings, spectral_lighting(scene))
    }

    /// A tracer of `scene` with its emitters' spectra computed before
    /// ([`spectral_lighting`]`(scene)`).
    pub fn with_lighting(
        scene: &'a Scene,
        settings: TraceSettings,
        lighting: Option<Arc<SpectralLighting>>,
    ) -> Self {
        let media = scene
            .refractors()
            .enumerate()
            .map(|(i, r)| Medium {
                ior: r.ior(),
                outside_ior: scene.outside_ior(i),
                within: r.within(),
                absorption: r.attenuation().map(|a| a.coefficient()),
                alpha: alpha_from_roughness(r.roughness()),
                abbe: if r.is_dispersive() {
                    r.abbe()
                } else {
                    f32::INFINITY
                },
            })
            .collect();
        let spectral = lighting.map(|lighting| Spectral {
            table: uplift_tables().table(),
            lighting,
        });
        Self {
            scene,
            settings,
            media,
            rough: scene.has_roughness(),
            spectral,
        }
    }

    /// Whether this tracer renders spectrally (the scene has dispersive glass).
    pub fn is_spectral(&self) -> bool {
        self.spectral.is_some()
    }

    /// GGX `α` of a surface (0: smooth).
    fn alpha(&self, surface: Surface) -> f32 {
        match surface {
            Surface::Refractor(i) => self.media[i].alpha,
            Surface::Object(k) => alpha_from_roughness(self.scene.objects[k].roughness()),
        }
    }

    /// The absorption of the medium a ray is in (`None`: air or a clear medium).
    fn absorption(&self, medium: Option<usize>) -> Option<Vec3> {
        medium
            .and_then(|m| self.media.get(m))
            .and_then(|m| m.absorption)
    }

    /// The medium a ray is in after crossing an interface of refractor `refractor`.
    fn medium_after(&self, refractor: usize, entering: bool) -> Option<usize> {
        if entering {
            Some(refractor)
        } else {
            self.media[refractor].within
        }
    }

    /// The interface of refractor `refractor` at `hit`, for a path carrying `wavelengths`
    /// (`None`: RGB): where either side is dispersive, the secondary wavelengths are
    /// terminated and both indices are the hero's.
    fn interface(
        &self,
        refractor: usize,
        dir: Vec3,
        hit: &Hit,
        wavelengths: Option<&mut Wavelengths>,
    ) -> Interface {
        let m = &self.media[refractor];
        let outside = m.within.map(|w| &self.media[w]);
        let dispersive = m.abbe.is_finite() || outside.is_some_and(|o| o.abbe.is_finite());
        let (ior, outside_ior) = match wavelengths {
            Some(w) if dispersive => {
                w.terminate_secondary();
                let lambda = w.hero();
                (m.ior_at(lambda), outside.map_or(1.0, |o| o.ior_at(lambda)))
            }
            _ => (m.ior, m.outside_ior),
        };
        Interface::at(dir, hit, ior, outside_ior, self.settings.interface)
    }

    /// Radiance arriving along `dir` from the environment: in RGB, or for a spectral path the
    /// linear sRGB of its wavelengths' spectral radiance.
    fn environment(&self, dir: Vec3, sampler: Option<PathSampler>) -> Vec3 {
        match (&self.spectral, sampler.and_then(|s| s.wavelengths)) {
            (Some(spectral), Some(w)) => w.to_linear_srgb(spectral.lighting.environment::<Exact>(
                &self.scene.environment,
                &spectral.table,
                dir,
                &w.lambda,
            )),
            _ => self.scene.environment.radiance_exact(dir),
        }
    }

    fn closest_hit(&self, ray: &Ray, rays: &mut u64) -> Option<(Surface, Hit)> {
        *rays += 1;
        let mut best: Option<(Surface, Hit)> = None;
        for (i, refractor) in self.scene.refractors().enumerate() {
            let t_max = best.map_or(f32::INFINITY, |(_, h)| h.t);
            if let Some(h) = refractor.bvh().closest_hit(ray, 0.0, t_max) {
                best = Some((Surface::Refractor(i), h));
            }
        }
        for (i, object) in self.scene.objects.iter().enumerate() {
            let t_max = best.map_or(f32::INFINITY, |(_, h)| h.t);
            if let Some(h) = object.bvh().closest_hit(ray, 0.0, t_max) {
                best = Some((Surface::Object(i), h));
            }
        }
        best
    }

    /// The next ray from a surface point, pushed off to the side `dir` goes to.
    fn continue_ray(&self, ray: &Ray, hit: &Hit, dir: Vec3) -> Ray {
        let side = if dir.dot(hit.geometric_normal) >= 0.0 {
            1.0
        } else {
            -1.0
        };
        let p = ray.at(hit.t);
        let offset = OFFSET * (1.0 + p.abs().max_element());
        Ray {
            origin: p + side * offset * hit.geometric_normal,
            dir,
        }
    }

    /// The conductor at a hit, if the surface is one.
    fn conductor(&self, surface: Surface) -> Option<Conductor> {
        match surface {
            Surface::Refractor(i) => self.scene.refractor_at(i).and_then(|r| r.conductor()),
            Surface::Object(k) => self.scene.objects[k].conductor(),
        }
    }

    /// Reflection at a conductor: about the shading normal turned toward the ray, or, on a rough
    /// one (`alpha > 0` and a sampler), about a visible microfacet normal of it; the direction
    /// and the weight per channel (the exact reflectance at the normal's angle, times the
    /// masking `G1(wo, m)` on a rough one, which is 0 where `wo` goes below the surface).
    fn conductor_bounce(
        ray: &Ray,
        hit: &Hit,
        conductor: &Conductor,
        rough: Option<(PathSampler, u32, f32)>,
    ) -> (Vec3, Vec3) {
        let facing = face_forward_shading_normal(
            if ray.dir.dot(hit.geometric_normal) < 0.0 {
                hit.shading_normal
            } else {
                -hit.shading_normal
            },
            ray.dir,
        );
        if let Some((sampler, depth, alpha)) = rough {
            // Only the reflected lobe of the sample is used (η 1: no refraction to compute
            // anything from).
            let s = sampler.rough(depth, ray.dir, facing, 1.0, alpha);
            let weight = conductor.reflectance(-ray.dir.dot(s.m)) * s.reflected_masking;
            return (s.reflected, weight);
        }
        let dir = reflect(ray.dir, facing).normalize();
        (dir, conductor.reflectance(-ray.dir.dot(facing)))
    }

    /// `(sampler, depth, α)` when the surface is rough and the path is sampled.
    fn rough_at(
        &self,
        surface: Surface,
        sampler: Option<PathSampler>,
        depth: u32,
    ) -> Option<(PathSampler, u32, f32)> {
        let alpha = self.alpha(surface);
        sampler.filter(|_| alpha > 0.0).map(|s| (s, depth, alpha))
    }

    /// Radiance leaving opaque object `index` at `hit` toward the ray: in RGB, or for a
    /// spectral path the linear sRGB of its wavelengths' ([`SpectralLighting::diffuse`]).
    fn shade_object(
        &self,
        index: usize,
        ray: &Ray,
        hit: &Hit,
        sampler: Option<PathSampler>,
    ) -> Vec3 {
        let object = &self.scene.objects[index];
        let uv = object.uv_at(hit.triangle, hit.barycentrics, ray.at(hit.t));
        match (
            &self.spectral,
            sampler.and_then(|s| s.wavelengths),
            &object.material,
        ) {
            (Some(spectral), Some(w), Material::Diffuse(albedo)) => {
                let light = &self.scene.light;
                let cos = hit.shading_normal.dot(light.direction).abs();
                let values =
                    spectral
                        .lighting
                        .diffuse(&spectral.table, albedo.at(uv), cos, &w.lambda);
                w.to_linear_srgb(values)
            }
            _ => object.shade(&self.scene.light, uv, hit.shading_normal),
        }
    }

    /// Follows the refracted path of `ray` (TIR reflects) through the surfaces as if they were
    /// smooth, recording the ground truth of [`PathRecord`]; returns the radiance and the
    /// record. The camera is in air. This is the pixel-centre path of the AOV layers: on rough
    /// surfaces it is the path through the macro surface, the one roughness scatters about.
    pub fn transmission_path(&self, ray: Ray, rays: &mut u64) -> (Vec3, PathRecord) {
        self.refracted_path(ray, None, rays)
    }

    /// [`Self::transmission_path`] with rough surfaces sampled by `sampler`: at a rough glass
    /// interface the ray refracts through one visible microfacet normal `m` with weight
    /// `G1(wo, m)` times the radiance factor `η²` (reflects about `m`, weight `G1`, under TIR
    /// about `m`): the rough counterpart of the transmission mode's "refract where Snell allows".
    pub fn transmission_sample(&self, ray: Ray, sampler: PathSampler, rays: &mut u64) -> Vec3 {
        self.refracted_path(ray, Some(sampler), rays).0
    }

    fn refracted_path(
        &self,
        ray: Ray,
        mut sampler: Option<PathSampler>,
        rays: &mut u64,
    ) -> (Vec3, PathRecord) {
        let mut aov = PathRecord::EMPTY;
        let mut ray = ray;
        let mut depth = 0;
        let mut scale = Vec3::ONE;
        let mut medium: Option<usize> = None;
        loop {
            let hit = self.closest_hit(&ray, rays);
            if let Some(sigma) = self.absorption(medium) {
                scale *= beer_lambert(sigma, hit.map_or(f32::INFINITY, |(_, h)| h.t));
            }
            let Some((surface, hit)) = hit else {
                if aov.covers_refractor() {
                    aov.t_out = ray.dir;
                }
                return (scale * self.environment(ray.dir, sampler), aov);
            };
            let p = ray.at(hit.t);
            if let Some(conductor) = self.conductor(surface) {
                if depth == self.settings.max_depth {
                    return (Vec3::ZERO, aov);
                }
                let rough = self.rough_at(surface, sampler, depth);
                depth += 1;
                let (next, reflectance) = Self::conductor_bounce(&ray, &hit, &conductor, rough);
                scale *= reflectance;
                sampler = sampler.map(|s| s.child(REFLECTED));
                if let Surface::Refractor(i) = surface {
                    aov.refractors_met |= refractor_bit(i);
                    if !aov.covers_refractor() {
                        aov.p1 = p;
                        aov.n1 = hit.shading_normal;
                        aov.t1 = next;
                    }
                }
                if rough.is_some() && scale == Vec3::ZERO {
                    return (Vec3::ZERO, aov);
                }
                ray = self.continue_ray(&ray, &hit, next);
                continue;
            }
            let refractor = match surface {
                Surface::Refractor(i) => i,
                Surface::Object(index) => {
                    if aov.covers_refractor() {
                        aov.t_out = ray.dir;
                        aov.p_geom = p;
                    }
                    return (scale * self.shade_object(index, &ray, &hit, sampler), aov);
                }
            };
            if depth == self.settings.max_depth {
                return (Vec3::ZERO, aov);
            }
            let wavelengths = sampler.as_mut().and_then(|s| s.wavelengths.as_mut());
            let interface = self.interface(refractor, ray.dir, &hit, wavelengths);
            let (next, tir) = match self.rough_at(surface, sampler, depth) {
                Some((s, depth, alpha)) => {
                    let m = s.rough(depth, ray.dir, interface.facing, interface.eta, alpha);
                    let tir = m.refracted == Vec3::ZERO;
                    let (next, weight, branch) = if tir {
                        (m.reflected, m.reflected_masking, REFLECTED)
                    } else {
                        (m.refracted, m.refracted_masking, TRANSMITTED)
                    };
                    if weight == 0.0 {
                        return (Vec3::ZERO, aov);
                    }
                    scale *= weight;
                    sampler = Some(s.child(branch));
                    (next, tir)
                }
                None => {
                    let refracted = refract(ray.dir, interface.facing, interface.eta);
                    let tir = refracted == Vec3::ZERO;
                    let next = if tir {
                        reflect(ray.dir, interface.facing)
                    } else {
                        refracted
                    };
                    (next.normalize(), tir)
                }
            };
            depth += 1;
            if !tir {
                scale *= interface.transmitted_radiance;
                medium = self.medium_after(refractor, interface.entering);
            }
            if !aov.covers_refractor() {
                aov.p1 = p;
                aov.n1 = hit.shading_normal;
                aov.t1 = next;
            } else if aov.p2.is_nan() && !interface.entering {
                aov.p2 = p;
                aov.n2 = hit.shading_normal;
                aov.t2 = next;
                aov.tir_first_exit = tir;
            }
            aov.refractors_met |= refractor_bit(refractor);
            aov.tir |= tir;
            aov.interfaces += u32::from(!tir);
            ray = self.continue_ray(&ray, &hit, next);
        }
    }

    /// Radiance along `ray`, which travels in `medium` (`None`: air), with Fresnel splitting
    /// at every refractor interface ([`TraceMode::Full`]): on a smooth one into the specular
    /// reflection and refraction, on a rough one into the reflection and the refraction about
    /// one visible microfacet normal drawn at `sampler`'s node, weighted `F G1(wo_r, m)` and
    /// `(1 − F) G1(wo_t, m) η²` (an unbiased estimate of both lobes of Walter et al.'s BSDF).
    pub fn full_radiance(
        &self,
        ray: Ray,
        medium: Option<usize>,
        depth: u32,
        throughput: f32,
        sampler: PathSampler,
        rays: &mut u64,
    ) -> Vec3 {
        let hit = self.closest_hit(&ray, rays);
        let absorbed = self
            .absorption(medium)
            .map(|sigma| beer_lambert(sigma, hit.map_or(f32::INFINITY, |(_, h)| h.t)));
        let radiance = self.full_radiance_after(
            &ray,
            hit,
            Branch {
                medium,
                depth,
                throughput,
                sampler,
            },
            rays,
        );
        absorbed.map_or(radiance, |a| a * radiance)
    }

    /// [`Self::full_radiance`] from the closest hit `hit` of `ray` on, before the absorption
    /// along `ray`.
    fn full_radiance_after(
        &self,
        ray: &Ray,
        hit: Option<(Surface, Hit)>,
        branch: Branch,
        rays: &mut u64,
    ) -> Vec3 {
        let Branch {
            medium,
            depth,
            throughput,
            mut sampler,
        } = branch;
        let Some((surface, hit)) = hit else {
            return self.environment(ray.dir, Some(sampler));
        };
        if let Some(conductor) = self.conductor(surface) {
            if depth >= self.settings.max_depth {
                return Vec3::ZERO;
            }
            let rough = self.rough_at(surface, Some(sampler), depth);
            let (dir, reflectance) = Self::conductor_bounce(ray, &hit, &conductor, rough);
            let next = self.continue_ray(ray, &hit, dir);
            let weight = throughput * reflectance.max_element();
            if weight <= self.settings.throughput_cutoff {
                return Vec3::ZERO;
            }
            return reflectance
                * self.full_radiance(
                    next,
                    medium,
                    depth + 1,
                    weight,
                    sampler.child(REFLECTED),
                    rays,
                );
        }
        let refractor = match surface {
            Surface::Refractor(i) => i,
            Surface::Object(index) => return self.shade_object(index, ray, &hit, Some(sampler)),
        };
        if depth >= self.settings.max_depth {
            return Vec3::ZERO;
        }
        let interface = self.interface(refractor, ray.dir, &hit, sampler.wavelengths.as_mut());
        // The two lobes: direction and weight of each (a direction of weight 0 is not traced).
        let (reflected, reflectance, refracted, transmittance) =
            match self.rough_at(surface, Some(sampler), depth) {
                Some((s, depth, alpha)) => {
                    let m = s.rough(depth, ray.dir, interface.facing, interface.eta, alpha);
                    (
                        m.reflected,
                        m.fresnel * m.reflected_masking,
                        m.refracted,
                        (1.0 - m.fresnel) * m.refracted_masking,
                    )
                }
                None => {
                    let reflectance =
                        fresnel_dielectric(-ray.dir.dot(interface.facing), interface.eta);
                    let refracted = refract(ray.dir, interface.facing, interface.eta);
                    let tir = refracted == Vec3::ZERO;
                    let reflectance = if tir { 1.0 } else { reflectance };
                    (
                        reflect(ray.dir, interface.facing).normalize(),
                        reflectance,
                        if tir {
                            refracted
                        } else {
                            refracted.normalize()
                        },
                        1.0 - reflectance,
                    )
                }
            };
        let cutoff = self.settings.throughput_cutoff;
        let mut radiance = Vec3::ZERO;
        if reflectance * throughput > cutoff {
            let next = self.continue_ray(ray, &hit, reflected);
            radiance += reflectance
                * self.full_radiance(
                    next,
                    medium,
                    depth + 1,
                    throughput * reflectance,
                    sampler.child(REFLECTED),
                    rays,
                );
        }
        if transmittance * throughput > cutoff {
            let next = self.continue_ray(ray, &hit, refracted);
            let inside = self.medium_after(refractor, interface.entering);
            radiance += transmittance
                * interface.transmitted_radiance
                * self.full_radiance(
                    next,
                    inside,
                    depth + 1,
                    throughput * transmittance,
                    sampler.child(TRANSMITTED),
                    rays,
                );
        }
        radiance
    }

    /// Radiance of one camera ray in the configured mode, its rough surfaces sampled by
    /// `sampler`.
    pub fn sample_radiance(&self, ray: Ray, sampler: PathSampler, rays: &mut u64) -> Vec3 {
        match self.settings.mode {
            TraceMode::Transmission => self.transmission_sample(ray, sampler, rays),
            TraceMode::Full => self.full_radiance(ray, None, 0, 1.0, sampler, rays),
        }
    }

    /// Pixel `(x, y)`: radiance averaged over the pixel's samples, and the ground truth of the
    /// transmission path through the pixel centre.
    pub fn pixel(&self, camera: &Camera, x: u32, y: u32, rays: &mut u64) -> (Vec3, PathRecord) {
        let centre = camera.pixel_ray(Camera::pixel_center(x, y));
        let (centre_radiance, aov) = self.transmission_path(centre, rays);
        let spp = self.settings.spp.max(1);
        let spectral = self.is_spectral();
        if spp == 1 && self.settings.mode == TraceMode::Transmission && !self.rough && !spectral {
            return (centre_radiance, aov);
        }
        let sum: Vec3 = (0..spp)
            .map(|i| {
                let offset = pixel_sample(x, y, i, spp);
                let ray = camera.pixel_ray(Vec2::new(x as f32, y as f32) + offset);
                let sampler = if spectral {
                    PathSampler::spectral(x, y, i, spp)
                } else {
                    PathSampler::new(x, y, i)
                };
                self.sample_radiance(ray, sampler, rays)
            })
            .sum();
        (sum / spp as f32, aov)
    }
}

/// Renders the whole frame, rows in parallel (rayon); the result does not depend on the
/// thread count (every pixel is computed independently from its own coordinates). The frame has
/// every reference AOV layer (see the registry row of `reference`).
pub fn render(scene: &Scene, camera: &Camera, settings: &TraceSettings) -> Frame {
    let mut frame = Frame::default();
    render_into(scene, camera, settings, &mut frame);
    frame
}

/// [`render`] into an existing frame.
pub fn render_into(scene: &Scene, camera: &Camera, settings: &TraceSettings, frame: &mut Frame) {
    render_with(&Tracer::new(scene, *settings), camera, frame);
}

/// [`render_into`] with `tracer`.
pub fn render_with(tracer: &Tracer<'_>, camera: &Camera, frame: &mut Frame) {
    let (width, height) = (camera.width() as usize, camera.height() as usize);
    let n = width * height;
    frame.reset(camera.width(), camera.height());
    let mut layers = RecordLayers::new(n);
    // One row of every output per task, written in place: no serial copy of the records.
    let rows: Vec<RowOut<'_>> = frame
        .color
        .chunks_mut(width)
        .zip(layers.rows(width))
        .map(|(color, layers)| RowOut { color, layers })
        .collect();
    let rays: u64 = rows
        .into_par_iter()
        .enumerate()
        .map(|(y, mut row)| {
            let mut rays = 0;
            for x in 0..width {
                let (radiance, record) = tracer.pixel(camera, x as u32, y as u32, &mut rays);
                row.color[x] = radiance;
                row.layers.write(x, &record);
            }
            rays
        })
        .sum();
    frame.rays = rays;
    layers.into_frame(frame);
}

/// The reference's AOV layers (the `reference` row of the registry), filled row by row.
struct RecordLayers {
    vectors: [(Aov, Vec<Vec3>); 8],
    flags: [(Aov, Vec<bool>); 3],
    interfaces: Vec<u32>,
    refractors_met: Vec<u32>,
}

/// One row of [`RecordLayers`].
struct RecordRow<'a> {
    vectors: [&'a mut [Vec3]; 8],
    flags: [&'a mut [bool]; 3],
    interfaces: &'a mut [u32],
    refractors_met: &'a mut [u32],
}

struct RowOut<'a> {
    color: &'a mut [Vec3],
    layers: RecordRow<'a>,
}

impl RecordLayers {
    fn new(n: usize) -> Self {
        let v = |aov| (aov, vec![Vec3::NAN; n]);
        let f = |aov| (aov, vec![false; n]);
        Self {
            vectors: [
                v(Aov::P1),
                v(Aov::N1),
                v(Aov::T1),
                v(Aov::P2),
                v(Aov::N2),
                v(Aov::T2),
                v(Aov::TOut),
                v(Aov::PGeom),
            ],
            flags: [f(Aov::Covered), f(Aov::Tir), f(Aov::TirFirstExit)],
            interfaces: vec![0; n],
            refractors_met: vec![0; n],
        }
    }

    /// The layers split into rows of `width`.
    fn rows(&mut self, width: usize) -> impl Iterator<Item = RecordRow<'_>> {
        let mut vectors: Vec<_> = self
            .vectors
            .iter_mut()
            .map(|(_, v)| v.chunks_mut(width))
            .collect();
        let mut flags: Vec<_> = self
            .flags
            .iter_mut()
            .map(|(_, v)| v.chunks_mut(width))
            .collect();
        self.interfaces
            .chunks_mut(width)
            .zip(self.refractors_met.chunks_mut(width))
            .map(move |(interfaces, refractors_met)| RecordRow {
                vectors: core::array::from_fn(|k| vectors[k].next().unwrap_or_default()),
                flags: core::array::from_fn(|k| flags[k].next().unwrap_or_default()),
                interfaces,
                refractors_met,
            })
    }

    fn into_frame(self, frame: &mut Frame) {
        for (aov, values) in self.vectors {
            frame.insert_layer(aov, Layer::Vec3(values));
        }
        for (aov, values) in self.flags {
            frame.insert_layer(aov, Layer::Flag(values));
        }
        frame.insert_layer(Aov::Interfaces, Layer::Count(self.interfaces));
        frame.insert_layer(Aov::RefractorsMet, Layer::Count(self.refractors_met));
    }
}

impl RecordRow<'_> {
    /// Pixel `x` of the row; the order is [`RecordLayers::new`]'s.
    fn write(&mut self, x: usize, r: &PathRecord) {
        let vectors = [r.p1, r.n1, r.t1, r.p2, r.n2, r.t2, r.t_out, r.p_geom];
        for (layer, v) in self.vectors.iter_mut().zip(vectors) {
            layer[x] = v;
        }
        let flags = [r.covers_refractor(), r.tir, r.tir_first_exit];
        for (layer, f) in self.flags.iter_mut().zip(flags) {
            layer[x] = f;
        }
        self.interfaces[x] = r.interfaces;
        self.refractors_met[x] = r.refractors_met;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A hit where the geometric and the shading side disagree (a smooth normal tilted past the
    /// ray): the geometric rule says "entering", Mitsuba's shading rule says "leaving", with the
    /// index ratio and radiance factor of its side.
    #[test]
    fn interface_rules_decide_the_side_differently_where_normals_disagree() {
        let hit = Hit {
            t: 1.0,
            triangle: 0,
            barycentrics: Vec2::ZERO,
            geometric_normal: Vec3::Z,
            shading_normal: Vec3::new(1.0, 0.0, 0.2).normalize(),
        };
        let dir = Vec3::new(0.8, 0.0, -0.6);
        assert!(-dir.dot(hit.geometric_normal) > 0.0 && -dir.dot(hit.shading_normal) < 0.0);
        let ior = 1.5;
        let geometric = Interface::at(dir, &hit, ior, 1.0, InterfaceRule::GeometricNormal);
        assert!(geometric.entering);
        assert_eq!(
            (geometric.eta, geometric.transmitted_radiance),
            (1.0 / ior, 1.0)
        );
        let shading = Interface::at(dir, &hit, ior, 1.0, InterfaceRule::ShadingNormal);
        assert!(!shading.entering);
        assert_eq!(
            (shading.eta, shading.transmitted_radiance),
            (ior, ior * ior)
        );
        assert!(
            shading.facing.dot(-dir) > 0.0,
            "the oriented normal faces the ray"
        );
        // Where they agree, the shading rule scales a refraction into glass by 1/n².
        let head_on = Interface::at(Vec3::NEG_Z, &hit, ior, 1.0, InterfaceRule::ShadingNormal);
        assert!(
            head_on.entering && (head_on.transmitted_radiance - 1.0 / (ior * ior)).abs() < 1e-7
        );
    }

    /// A prism scene: refractor 0 is the built-in 60° prism (axis `y`, unit-sphere scale),
    /// IOR 1.5 and Abbe number 30, turned by `turn_deg` about `y`, in the procedural sky.
    fn prism_scene(turn_deg: f32) -> Scene {
        let mut mesh = refract_geometry::builtin::mesh("prism").expect("prism");
        mesh.transform(&glam::Affine3A::from_rotation_y(turn_deg.to_radians()));
        let mut prism = refract_scene::Refractor::new(mesh, 1.5).expect("refractor");
        prism.set_abbe(30.0).expect("abbe");
        Scene::new("prism", prism, refract_scene::Environment::Procedural)
    }

    /// A prism's deviation per wavelength against Snell: a horizontal ray through the two side
    /// faces that meet at the apex leaves turned by `δ = θ₁ + asin(n sin(A − asin(sin θ₁ / n))) − A`
    /// with `A = 60°` and `n = n(λ)` of `KHR_materials_dispersion`, to 1e-4 rad at 400, 550 and
    /// 700 nm (the three deviations differ by 0.02-0.05 rad: one index for all wavelengths
    /// fails). The path terminates the secondary wavelengths; a path that misses the prism
    /// keeps them.
    #[test]
    fn prism_deviation_per_wavelength_follows_snell() {
        // The entry face of the default orientation faces 30° from +z toward +x (its normal
        // (sin 30°, 0, cos 30°)): a ray along −z meets it at θ₁ = 30° + turn.
        let turn = 18.6f32;
        let scene = prism_scene(turn);
        let tracer = Tracer::new(&scene, TraceSettings::default());
        let theta1 = (30.0 + turn).to_radians();
        let apex = 60f32.to_radians();
        // Aim at the entry face's centre: its outward normal times the inradius (half the
        // built-in's circumradius 0.45).
        let normal = Vec3::new(theta1.sin(), 0.0, theta1.cos());
        let target = normal * 0.45 * 0.5;
        let ray = Ray {
            origin: target + Vec3::Z * 5.0,
            dir: Vec3::NEG_Z,
        };
        let mut deviations = Vec::new();
        for lambda in [400.0f32, 550.0, 700.0] {
            let n = refract_core::spectral::dispersive_ior(1.5, 30.0, lambda);
            let inside = (theta1.sin() / n).asin();
            let expected = theta1 + (n * (apex - inside).sin()).asin() - apex;
            let mut w = Wavelengths::sample(0.3);
            w.lambda[0] = lambda;
            let sampler = PathSampler {
                wavelengths: Some(w),
                ..PathSampler::new(0, 0, 0)
            };
            let mut rays = 0;
            let (_, record) = tracer.refracted_path(ray, Some(sampler), &mut rays);
            assert_eq!(record.interfaces, 2, "{lambda} nm: in and out");
            let deviation = record.t_out.angle_between(Vec3::NEG_Z);
            assert!(
                (deviation - expected).abs() < 1e-4,
                "{lambda} nm: deviation {deviation} vs Snell {expected}"
            );
            deviations.push(deviation);
        }
        assert!(deviations[0] > deviations[1] + 0.01 && deviations[1] > deviations[2] + 0.005);

        // Termination happens at the dispersive interface, not before.
        let mut w = Wavelengths::sample(0.3);
        let hit = tracer.closest_hit(&ray, &mut 0).expect("hits the prism").1;
        let interface = tracer.interface(0, ray.dir, &hit, Some(&mut w));
        assert!(w.is_terminated() && interface.entering);
        let mut untouched = Wavelengths::sample(0.3);
        let _ = tracer.interface(0, ray.dir, &hit, None);
        assert!(!untouched.is_terminated());
        untouched.terminate_secondary();
        assert_eq!(untouched.weight[0], w.weight[0]);
    }
}
