//! Wyman 2005b refraction of nearby geometry on the CPU (methods `kay-greenberg`, `ray-plane`,
//! `iterative`, `iterative-seeded`): the three passes of §5 — the refractor's back faces, the
//! nearby opaque objects from the eye into the NG texture (surface + colour per texel), and the
//! front faces — then per pixel the two-interface kernel of Wyman 2005a and
//! [`refract_core::nearby_geometry::find_nearby`], both eight refractor pixels at a time
//! ([`two_interface_lanes`], [`find_nearby_x8`]).
//!
//! Every pixel is one of: the refractor in front of the objects (the refraction), an object
//! seen directly (its NG texel), or the environment.

use std::sync::Arc;

use glam::{UVec2, Vec2, Vec3};
use rayon::prelude::*;
use refract_core::Camera;
use refract_core::exit::ExitNormalSource;
use refract_core::gpu::exit_normal_source_code;
use refract_core::kernel::ImageSpaceParams;
use refract_core::kernel_x8::{FrontLanes, two_interface_lanes};
use refract_core::lanes::{LANES, Vec2x8, mask_from_lanes};
use refract_core::nearby_geometry::{NearbyLookup, Plane, guard_band_camera, view_depth};
use refract_core::nearby_geometry_x8::find_nearby_x8;
use refract_scene::{Aov, Frame, LayerValue, NearbyParams, PixelLayers, RenderError, Scene};

use crate::buffers::{BackFaces, front_faces_into};
use crate::family::{CpuFamily, FrameCx};
use crate::object_surfaces::{NearbyMeshes, NearbyTexture};
use crate::pixel_group::PixelGroup;
use crate::raster::{Attribute, SurfaceBuffer};
use crate::scene_meshes::SceneMeshes;

/// Per-pixel outputs beside the colour; NaN / 0 / false where they do not apply.
#[derive(Clone, Copy, Debug, PartialEq)]
struct NearbyAov {
    covered: bool,
    p2: Vec3,
    t2: Vec3,
    n2: Vec3,
    n2_source: Option<ExitNormalSource>,
    tir: bool,
    p_geom: Vec3,
    ng_texel: Vec3,
    iterations: u32,
    converged: bool,
}

impl PixelLayers for NearbyAov {
    fn value(&self, aov: Aov) -> Option<LayerValue> {
        Some(match aov {
            Aov::Covered => LayerValue::Flag(self.covered),
            Aov::Tir => LayerValue::Flag(self.tir),
            Aov::Converged => LayerValue::Flag(self.converged),
            Aov::P2 => LayerValue::Vec3(self.p2),
            Aov::N2 => LayerValue::Vec3(self.n2),
            Aov::T2 => LayerValue::Vec3(self.t2),
            Aov::PGeom => LayerValue::Vec3(self.p_geom),
            Aov::NgTexel => LayerValue::Vec3(self.ng_texel),
            Aov::Iterations => LayerValue::Count(self.iterations),
            Aov::ExitNormalSource => {
                LayerValue::Count(self.n2_source.map_or(0, exit_normal_source_code))
            }
            _ => return None,
        })
    }
}

impl NearbyAov {
    const NONE: Self = Self {
        covered: false,
        p2: Vec3::NAN,
        t2: Vec3::NAN,
        n2: Vec3::NAN,
        n2_source: None,
        tir: false,
        p_geom: Vec3::NAN,
        ng_texel: Vec3::NAN,
        iterations: 0,
        converged: false,
    };
}

/// The passes of the nearby-geometry methods, with their memory kept between frames.
#[derive(Default)]
pub struct NearbyPasses {
    meshes: NearbyMeshes,
    front: SurfaceBuffer,
    back: BackFaces,
    nearby: NearbyTexture,
    aovs: Vec<NearbyAov>,
}

impl NearbyPasses {
    /// The NG texture of the last frame.
    pub fn nearby_texture(&self) -> &NearbyTexture {
        &self.nearby
    }
}

impl CpuFamily for NearbyPasses {
    type Params = NearbyParams;

    /// Prepares the passes for `scene` (its objects as one mesh).
    fn prepare(&mut self, scene: &Arc<Scene>) {
        self.meshes = SceneMeshes::objects(scene);
    }

    fn render(
        &mut self,
        cx: &FrameCx<'_>,
        method: &NearbyParams,
        frame: &mut Frame,
    ) -> Result<(), RenderError> {
        let FrameCx { scene, camera, .. } = *cx;
        let refractor = &scene.refractor;
        let kernel = &method.two.kernel(cx.ior(refractor))?;
        let planes = &scene.nearby_planes(camera.look_dir());
        let (ng_desc, pad) = guard_band_camera(camera.desc(), method.guard_band_percent);
        let ng_camera =
            Camera::new(ng_desc).map_err(|err| RenderError::Parameter(err.to_string()))?;
        self.back.render_into(refractor, camera, method.two.back);
        self.nearby.render_into(scene, &self.meshes, &ng_camera);
        front_faces_into(refractor, camera, &mut self.front);

        let (width, height) = (camera.width(), camera.height());
        let n = (width * height) as usize;
        frame.resize_for_overwrite(width, height);
        let pixels = PixelContext {
            scene,
            planes,
            camera,
            ng_camera: &ng_camera,
            pad,
            kernel,
            lookup: method.lookup,
            front: &self.front,
            back: &self.back,
            nearby: &self.nearby,
        };
        let rows = frame.color.par_chunks_mut(width as usize).enumerate();
        if cx.with_aovs() {
            self.aovs.clear();
            self.aovs.resize(n, NearbyAov::NONE);
            rows.zip(self.aovs.par_chunks_mut(width as usize))
                .for_each(|((y, colors), aovs)| pixels.row(y as u32, colors, Some(aovs)));
        } else {
            // Colour only, as displayed: no per-pixel AOV memory is touched.
            rows.for_each(|(y, colors)| pixels.row(y as u32, colors, None));
        }
        if cx.with_aovs() {
            frame.write_row_layers(cx.method, &self.aovs[..n])?;
        }
        Ok(())
    }
}

/// What the per-pixel work reads.
struct PixelContext<'a> {
    scene: &'a Scene,
    planes: &'a [Plane],
    camera: &'a Camera,
    ng_camera: &'a Camera,
    pad: UVec2,
    kernel: &'a ImageSpaceParams,
    lookup: NearbyLookup,
    front: &'a SurfaceBuffer,
    back: &'a BackFaces,
    nearby: &'a NearbyTexture,
}

impl PixelContext<'_> {
    /// Shades row `y`: the pixels the refractor covers eight at a time (their front texels
    /// resolved on lanes, then the lane kernel `two_interface_lanes`, bit-identical to the
    /// scalar kernel, and each lane's lookup, or the object where one is nearer), pixels that
    /// see an object directly at once, and the environment eight pixels at a time.
    fn row(&self, y: u32, colors: &mut [Vec3], mut aovs: Option<&mut [NearbyAov]>) {
        let mut group = PixelGroup::new();
        let mut background = PixelGroup::new();
        let row = (y * self.camera.width()) as usize;
        for x in 0..colors.len() as u32 {
            if self.front.is_covered(row + x as usize) {
                if group.push(x) {
                    self.refractor(&group, y, colors, aovs.as_deref_mut());
                    group.len = 0;
                }
            } else if let Some(object) = self.nearby.texel(UVec2::new(x, y) + self.pad) {
                colors[x as usize] = object.color;
                if let Some(aovs) = aovs.as_deref_mut() {
                    aovs[x as usize] = NearbyAov::NONE;
                }
            } else if background.push(x) {
                self.background(&background, y, colors, aovs.as_deref_mut());
                background.len = 0;
            }
        }
        if background.len > 0 {
            background.pad();
            self.background(&background, y, colors, aovs.as_deref_mut());
        }
        if group.len > 0 {
            group.pad();
            self.refractor(&group, y, colors, aovs);
        }
    }

    /// Eight pixels of row `y` that see the environment: eight-lane rays and lookups
    /// (bit-identical to the scalar ones).
    fn background(
        &self,
        group: &PixelGroup,
        y: u32,
        colors: &mut [Vec3],
        mut aovs: Option<&mut [NearbyAov]>,
    ) {
        let uv: [Vec2; LANES] = core::array::from_fn(|i| Camera::pixel_center(group.x[i], y));
        let dirs = self.camera.pixel_ray_dir_x8(Vec2x8::from_lanes(&uv));
        let radiance = self.scene.environment.radiance_x8(dirs).to_lanes();
        for (&x, &color) in group.x.iter().zip(&radiance).take(group.len) {
            colors[x as usize] = color;
            if let Some(aovs) = aovs.as_deref_mut() {
                aovs[x as usize] = NearbyAov::NONE;
            }
        }
    }

    /// Eight pixels of row `y` the refractor covers: the lane kernel, then per lane the object
    /// when one is nearer than the refractor there, else the lookup, the eight lookups on
    /// lanes ([`find_nearby_x8`], bit-identical to the scalar
    /// [`refract_core::nearby_geometry::find_nearby`]).
    fn refractor(
        &self,
        group: &PixelGroup,
        y: u32,
        colors: &mut [Vec3],
        mut aovs: Option<&mut [NearbyAov]>,
    ) {
        let uv: [Vec2; LANES] = core::array::from_fn(|i| Camera::pixel_center(group.x[i], y));
        let texels = self
            .front
            .attribute_lanes::<{ Attribute::SCALAR }>(&group.x, y);
        let front = FrontLanes {
            p1_ws: texels.p_ws,
            n1_ws: texels.n_ws,
            d_n: texels.scalar,
        };
        let paths = two_interface_lanes(self.camera, &uv, &front, self.back, self.kernel);
        let (p1, p2, t2, n2) = (
            texels.p_ws.to_lanes(),
            paths.p2.to_lanes(),
            paths.t2.to_lanes(),
            paths.n2.to_lanes(),
        );
        // Per lane: the object where it is nearer, black for a degenerate input, else the
        // path (a lookup, or black where the TIR policy `black` absorbed it: `T~2 = 0`).
        let mut shown = [Shown::Degenerate; LANES];
        let mut looked_up = [false; LANES];
        for i in 0..group.len {
            // The refractor wins only where it is strictly nearer (NaN: the object).
            let refractor_nearer = |depth: f32| view_depth(self.camera, p1[i]) < depth;
            let object = self
                .nearby
                .texel(UVec2::new(group.x[i], y) + self.pad)
                .filter(|o| !refractor_nearer(o.surface.depth));
            shown[i] = if let Some(object) = object {
                Shown::Object(object.color)
            } else if !paths.ok[i] {
                Shown::Degenerate
            } else {
                looked_up[i] = t2[i] != Vec3::ZERO;
                Shown::Path
            };
        }
        let results = looked_up.contains(&true).then(|| {
            find_nearby_x8(
                self.ng_camera,
                self.nearby,
                self.planes,
                self.lookup,
                &paths.p2,
                &paths.t2,
                mask_from_lanes(looked_up),
            )
        });
        for i in 0..group.len {
            let x = group.x[i] as usize;
            let result = results.as_ref().filter(|_| looked_up[i]).map(|r| r[i]);
            // A hit's surface was read by the lookup: only its colour and object remain.
            let shaded = result
                .and_then(|r| r.hit)
                .and_then(|hit| Some((hit, self.nearby.shading(hit.texel)?)));
            colors[x] = match (shown[i], shaded) {
                (Shown::Object(color), _) => color,
                (Shown::Degenerate, _) => Vec3::ZERO,
                (Shown::Path, Some((_, (color, _)))) => color,
                (Shown::Path, None) if looked_up[i] => self.scene.environment.radiance(t2[i]),
                (Shown::Path, None) => Vec3::ZERO,
            };
            let Some(aovs) = aovs.as_deref_mut() else {
                continue;
            };
            let covered = NearbyAov {
                covered: true,
                ..NearbyAov::NONE
            };
            aovs[x] = match shown[i] {
                Shown::Object(_) => NearbyAov::NONE,
                Shown::Degenerate => covered,
                Shown::Path => {
                    let (p_geom, ng_texel) = shaded.map_or(
                        (NearbyAov::NONE.p_geom, NearbyAov::NONE.ng_texel),
                        |(hit, (_, object))| {
                            let texel = hit.texel.as_vec2();
                            (hit.p_geom, Vec3::new(texel.x, texel.y, object as f32))
                        },
                    );
                    NearbyAov {
                        p2: p2[i],
                        t2: t2[i],
                        n2: n2[i],
                        n2_source: Some(if paths.n2_from_back_face[i] {
                            ExitNormalSource::BackFace
                        } else {
                            ExitNormalSource::SilhouetteFallback
                        }),
                        tir: paths.tir[i],
                        p_geom,
                        ng_texel,
                        iterations: result.map_or(0, |r| r.iterations),
                        converged: result.is_some_and(|r| r.converged),
                        ..covered
                    }
                }
            };
        }
    }
}

/// What a refractor pixel shows before its lookup.
#[derive(Clone, Copy, Debug)]
enum Shown {
    /// An object nearer than the refractor: its NG texel's colour.
    Object(Vec3),
    /// A degenerate input to the kernel: black, no path.
    Degenerate,
    /// The refracted path: the lookup's colour (black where the TIR policy absorbed it).
    Path,
}
