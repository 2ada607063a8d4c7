//! Kakimoto et al. 2007, per-vertex reflection and refraction (`pvrr`): the per-frame plan
//! both backends draw.
//!
//! The per-vertex work runs here, on the CPU with the scene's BVHs, for both backends (as the
//! paper does, §3.4 and §5): for every reflector seen in a view, each vertex's exact ray
//! (§3.1 step 3.1: the reflection of the ray from the view's eye at the vertex, or for a lens
//! the refraction at the front-face vertex, a BVH hit on the back surface and a second
//! refraction), the virtual viewpoint (§3.2), the view volume (§3.3) and the texture
//! coordinates (§3.4) come from [`refract_core::pvrr`]. A map may itself show reflectors:
//! each gets its own map from that map's virtual viewpoint, down to `depth` levels (the stack
//! of §4.4). The backends then render every view, deepest first: the diffuse objects shaded,
//! the environment behind them, and each reflector drawn with its vertices' coordinates
//! interpolated into its map.

use glam::Vec3;
use rayon::prelude::*;
use refract_core::optics::{face_forward_shading_normal, reflect, refract};
use refract_core::pvrr::{
    MAX_INTERNAL_BOUNCES, PvrrVertex, RayEnd, STATE_DEPTH, STATE_TRAPPED, STATE_ZOOM, SceneBounds,
    VertexRay, ViewVolume, footprint_resolution, mean_direction, parallel_viewpoint, texcoord,
    view_volume, virtual_viewpoint,
};
use refract_core::{Camera, CameraDesc, Ray};

use crate::registry::{FOOTPRINT_TEXELS_PER_PIXEL, MapSizing, PVRR_RESOLUTION, PvrrParams};
use crate::{RenderError, Scene, SceneMesh};

/// What a reflector does to the rays that meet it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ReflectorKind {
    /// A conductor: reflection, tinted by Schlick's approximation from `f0`
    /// ([`refract_core::pvrr::mirror_tint`]).
    Mirror {
        /// Normal-incidence reflectance per channel.
        f0: Vec3,
    },
    /// The glass refractor: refraction in at the front face, out at the back (§4.5).
    Lens {
        /// Index of refraction.
        ior: f32,
    },
}

/// A reflector of the scene: a mesh with its own vertices and one map per view that sees it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Reflector {
    /// Its mesh.
    pub mesh: SceneMesh,
    /// Mirror or lens.
    pub kind: ReflectorKind,
}

/// The reflectors of `scene`: the specular object (a mirror when it is a conductor, a lens when
/// it is glass), then every conductor object.
pub fn reflectors(scene: &Scene) -> Vec<Reflector> {
    reflectors_at(scene, None)
}

/// [`reflectors`] with the lens's index at wavelength `lambda_nm`
/// ([`crate::Refractor::ior_at`]).
pub fn reflectors_at(scene: &Scene, lambda_nm: Option<f32>) -> Vec<Reflector> {
    let first = Reflector {
        mesh: SceneMesh::Refractor,
        kind: match scene.refractor.conductor() {
            Some(c) => ReflectorKind::Mirror { f0: c.f0() },
            None => ReflectorKind::Lens {
                ior: scene.refractor.ior_at(lambda_nm),
            },
        },
    };
    core::iter::once(first)
        .chain(scene.objects.iter().enumerate().filter_map(|(k, o)| {
            o.conductor().map(|c| Reflector {
                mesh: SceneMesh::Object(k),
                kind: ReflectorKind::Mirror { f0: c.f0() },
            })
        }))
        .collect()
}

/// One reflector drawn in one view.
#[derive(Clone, Debug, PartialEq)]
pub struct PvrrDraw {
    /// Index into [`PvrrPlan::reflectors`].
    pub reflector: usize,
    /// The view holding its map; `None` past the last level ([`STATE_DEPTH`]).
    pub map: Option<usize>,
    /// One entry per vertex of the reflector's mesh.
    pub vertices: Vec<PvrrVertex>,
    /// The per-vertex rays traced for this draw (vertices of triangles facing the view).
    pub rays: usize,
}

/// One view of the plan: the eye (view 0) or a reflector's map.
#[derive(Clone, Debug, PartialEq)]
pub struct PvrrView {
    /// The camera (the frame's for view 0, a map camera otherwise).
    pub camera: Camera,
    /// The reflector whose map this is (it is not drawn in it); `None` for the eye.
    pub excluded: Option<usize>,
    /// The view's level: 0 the eye, 1 a map seen from the eye, ...
    pub level: u32,
    /// The reflectors drawn in this view.
    pub draws: Vec<PvrrDraw>,
    /// The near plane of a map's view volume (0 for the eye).
    pub near: f32,
}

/// Every view of one frame, parents before children: render them in reverse order.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PvrrPlan {
    /// The reflectors (see [`reflectors`]).
    pub reflectors: Vec<Reflector>,
    /// View 0 is the eye.
    pub views: Vec<PvrrView>,
}

impl PvrrPlan {
    /// Per-vertex rays traced for the whole plan.
    pub fn rays(&self) -> usize {
        self.views
            .iter()
            .flat_map(|v| &v.draws)
            .map(|d| d.rays)
            .sum()
    }
}

/// Builds the plan of each frame and keeps it while nothing it depends on changed, when asked
/// to (`update=on-change`: the lens fixed to the eye, §5).
#[derive(Default)]
pub struct PvrrPlanner {
    bounds: Option<SceneBounds>,
    plan: PvrrPlan,
    key: Option<(CameraDesc, PvrrParams, Option<u32>)>,
    builds: u64,
}

/// The smallest ray distance of a per-vertex ray, relative to the scene radius.
const RAY_EPSILON: f32 = 1e-4;

impl PvrrPlanner {
    /// The scene's bounds (after [`Self::prepare`]).
    pub fn bounds(&self) -> Option<SceneBounds> {
        self.bounds
    }

    /// Forgets everything about the previous scene.
    pub fn prepare(&mut self, scene: &Scene) {
        let (mut min, mut max) = scene.refractor.mesh().bounds();
        for o in &scene.objects {
            let (a, b) = o.mesh().bounds();
            min = min.min(a);
            max = max.max(b);
        }
        self.bounds = Some(SceneBounds { min, max });
        self.key = None;
        self.plan = PvrrPlan::default();
    }

    /// The plan of a frame of `scene` seen by `camera`.
    pub fn plan(
        &mut self,
        scene: &Scene,
        camera: &Camera,
        params: &PvrrParams,
    ) -> Result<&PvrrPlan, RenderError> {
        self.plan_at(scene, camera, params, None)
    }

    /// [`Self::plan`] with the lens's index at wavelength `lambda_nm`
    /// ([`crate::Refractor::ior_at`]).
    pub fn plan_at(
        &mut self,
        scene: &Scene,
        camera: &Camera,
        params: &PvrrParams,
        lambda_nm: Option<f32>,
    ) -> Result<&PvrrPlan, RenderError> {
        let bounds = match self.bounds {
            Some(b) => b,
            None => {
                self.prepare(scene);
                self.bounds.unwrap_or(SceneBounds {
                    min: Vec3::ZERO,
                    max: Vec3::ZERO,
                })
            }
        };
        let key = (*camera.desc(), *params, lambda_nm.map(f32::to_bits));
        if params.update_on_change && self.key == Some(key) {
            return Ok(&self.plan);
        }
        self.plan = build_plan(scene, camera, params, bounds, lambda_nm)?;
        self.key = Some(key);
        self.builds += 1;
        Ok(&self.plan)
    }

    /// The last plan (empty before the first frame).
    pub fn last(&self) -> &PvrrPlan {
        &self.plan
    }

    /// How many plans were built (not reused) since this planner was made.
    pub fn builds(&self) -> u64 {
        self.builds
    }
}

/// Builds the plan of one frame (no reuse).
pub fn build_plan(
    scene: &Scene,
    camera: &Camera,
    params: &PvrrParams,
    bounds: SceneBounds,
    lambda_nm: Option<f32>,
) -> Result<PvrrPlan, RenderError> {
    let mut plan = PvrrPlan {
        reflectors: reflectors_at(scene, lambda_nm),
        views: vec![PvrrView {
            camera: *camera,
            excluded: None,
            level: 0,
            draws: Vec::new(),
            near: 0.0,
        }],
    };
    let context = Context {
        scene,
        params,
        bounds,
        epsilon: RAY_EPSILON * bounds.radius().max(1e-6),
    };
    let mut next = 0;
    while next < plan.views.len() {
        let (eye_camera, excluded, level) = {
            let v = &plan.views[next];
            (v.camera, v.excluded, v.level)
        };
        let mut draws = Vec::new();
        for (index, reflector) in plan.reflectors.iter().enumerate() {
            if Some(index) == excluded {
                continue;
            }
            let mesh = scene.mesh(reflector.mesh).ok_or_else(|| {
                RenderError::Parameter(format!("pvrr: reflector mesh {:?} missing", reflector.mesh))
            })?;
            // Past the last level, or outside the view: drawn black, no map.
            if level >= params.depth || !seen(scene, reflector.mesh, &eye_camera) {
                draws.push(PvrrDraw {
                    reflector: index,
                    map: None,
                    vertices: vec![PvrrVertex::unmapped(STATE_DEPTH); mesh.positions.len()],
                    rays: 0,
                });
                continue;
            }
            let Some(map) = context.map_of(reflector, &eye_camera) else {
                draws.push(PvrrDraw {
                    reflector: index,
                    map: None,
                    vertices: vec![PvrrVertex::unmapped(STATE_ZOOM); mesh.positions.len()],
                    rays: 0,
                });
                continue;
            };
            let child = plan.views.len();
            plan.views.push(PvrrView {
                camera: map.volume.camera,
                excluded: Some(index),
                level: level + 1,
                draws: Vec::new(),
                near: map.volume.near,
            });
            draws.push(PvrrDraw {
                reflector: index,
                map: Some(child),
                vertices: map.vertices,
                rays: map.rays,
            });
        }
        plan.views[next].draws = draws;
        next += 1;
    }
    Ok(plan)
}

/// Whether any vertex of `mesh` projects inside `camera`'s image widened by its own size on
/// each side (a cheap view-frustum test: a reflector outside gets no map).
fn seen(scene: &Scene, mesh: SceneMesh, camera: &Camera) -> bool {
    let Some(mesh) = scene.mesh(mesh) else {
        return false;
    };
    let (w, h) = (camera.width() as f32, camera.height() as f32);
    mesh.positions.iter().any(|p| {
        camera.world_to_pixel(*p).is_some_and(|px| {
            px.x >= -w && px.x <= 2.0 * w && px.y >= -h && px.y <= 2.0 * h && px.z <= 1.0
        })
    })
}

struct Context<'a> {
    scene: &'a Scene,
    params: &'a PvrrParams,
    bounds: SceneBounds,
    epsilon: f32,
}

/// A reflector's map seen from one eye: its view volume and its vertices' coordinates.
struct MapPlan {
    volume: ViewVolume,
    vertices: Vec<PvrrVertex>,
    rays: usize,
}

impl Context<'_> {
    /// The end of `ray`: its nearest hit on any mesh but `exclude`, or its escape direction.
    fn trace(&self, ray: &Ray, exclude: SceneMesh) -> RayEnd {
        match self.scene.closest_hit(ray, self.epsilon, Some(exclude)) {
            Some((_, hit)) => RayEnd::Hit(ray.at(hit.t)),
            None => RayEnd::Escape(ray.dir),
        }
    }

    /// The exact ray of vertex `(v, n)` of `reflector` seen from `eye` through a lens of index
    /// `ior` (ignored for mirrors): `None` when it is trapped in the lens.
    fn vertex_ray(
        &self,
        reflector: &Reflector,
        eye: Vec3,
        v: Vec3,
        n: Vec3,
        ior: f32,
    ) -> Option<Ray> {
        let incident = (v - eye).normalize();
        let n = face_forward_shading_normal(n, incident);
        match reflector.kind {
            ReflectorKind::Mirror { .. } => Some(Ray {
                origin: v,
                dir: reflect(incident, n),
            }),
            ReflectorKind::Lens { .. } => {
                let mut dir = refract(incident, n, 1.0 / ior).try_normalize()?;
                let mut origin = v;
                let bvh = self.scene.refractor.bvh();
                for _ in 0..=MAX_INTERNAL_BOUNCES {
                    let inside = Ray { origin, dir };
                    let hit = bvh.closest_hit(&inside, self.epsilon, f32::INFINITY)?;
                    origin = inside.at(hit.t);
                    // The exit: the normal facing the ray inside is −N (outward N).
                    let facing = face_forward_shading_normal(-hit.shading_normal, dir);
                    let out = refract(dir, facing, ior);
                    match out.try_normalize() {
                        Some(out) => return Some(Ray { origin, dir: out }),
                        None => dir = reflect(dir, facing),
                    }
                }
                None
            }
        }
    }

    /// The map of `reflector` seen by `view` (the eye, or the map that draws it), `None` when
    /// no ray ends inside any map.
    fn map_of(&self, reflector: &Reflector, view: &Camera) -> Option<MapPlan> {
        let eye = view.eye();
        let mesh = self.scene.mesh(reflector.mesh)?;
        let iors = match reflector.kind {
            ReflectorKind::Mirror { .. } => [1.0; 3],
            ReflectorKind::Lens { ior } => self.params.channel_iors(ior),
        };
        let channels = if iors[0] == iors[2] { 1 } else { 3 };
        // Which vertices issue rays: every vertex of a two-sided mirror; a lens's vertices on
        // faces turned toward the eye (the faces drawn).
        let mut issuing = vec![false; mesh.positions.len()];
        for t in &mesh.triangles {
            let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
            let toward = (b - a).cross(c - a).dot(a - eye) < 0.0;
            if toward || matches!(reflector.kind, ReflectorKind::Mirror { .. }) {
                for &i in t {
                    issuing[i as usize] = true;
                }
            }
        }
        // Per vertex and channel: the exit ray and where it ends.
        let rays: Vec<[Option<VertexRay>; 3]> = (0..mesh.positions.len())
            .into_par_iter()
            .map(|i| {
                let mut out = [None; 3];
                if !issuing[i] {
                    return out;
                }
                let (v, n) = (mesh.positions[i], mesh.normals[i]);
                for (k, slot) in out.iter_mut().enumerate().take(channels) {
                    *slot = self
                        .vertex_ray(reflector, eye, v, n, iors[k])
                        .map(|ray| VertexRay {
                            origin: ray.origin,
                            dir: ray.dir,
                            end: self.trace(&ray, reflector.mesh),
                        });
                }
                if channels == 1 {
                    out[1] = out[0];
                    out[2] = out[0];
                }
                out
            })
            .collect();
        // §3.2 from the green rays (the middle index), §3.3 over every channel's ends.
        let green: Vec<VertexRay> = rays.iter().filter_map(|r| r[1]).collect();
        let c = match virtual_viewpoint(green.iter().map(|r| (r.origin, r.dir))) {
            Some(c) => c,
            None => parallel_viewpoint(&green, self.bounds.radius())?,
        };
        let direction = mean_direction(&green)?;
        let ends: Vec<RayEnd> = rays.iter().flatten().flatten().map(|r| r.end).collect();
        let issued: Vec<Vec3> = (0..mesh.positions.len())
            .filter(|&i| issuing[i])
            .map(|i| mesh.positions[i])
            .collect();
        let resolution = match self.params.sizing {
            MapSizing::Fixed => self.params.resolution,
            MapSizing::Footprint => footprint_resolution(
                view,
                &issued,
                FOOTPRINT_TEXELS_PER_PIXEL,
                (PVRR_RESOLUTION.0, self.params.resolution),
            ),
        };
        let volume = view_volume(c, direction, &issued, &ends, self.bounds, resolution).ok()?;
        let vertices = rays
            .iter()
            .map(|r| {
                let st = r.map(|ray| ray.and_then(|ray| texcoord(&volume, ray.end)));
                match st {
                    [Some(a), Some(b), Some(c)] => PvrrVertex::mapped([a, b, c]),
                    _ if r[1].is_none() => PvrrVertex::unmapped(STATE_TRAPPED),
                    _ => PvrrVertex::unmapped(STATE_ZOOM),
                }
            })
            .collect();
        Some(MapPlan {
            volume,
            vertices,
            rays: green.len() * channels,
        })
    }
}
