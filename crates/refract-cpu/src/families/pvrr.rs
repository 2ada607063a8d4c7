//! Kakimoto et al. 2007 on the CPU, method `pvrr`: the plan of the frame
//! ([`refract_scene::pvrr`]: per-vertex rays by BVH, virtual viewpoints, view volumes, texture
//! coordinates), then every view rendered with the shared rasteriser, deepest first: a map is
//! the scene from its virtual viewpoint without its own reflector, the eye view is the frame.
//! In each view the diffuse objects are shaded, empty pixels show the environment, and a
//! reflector's pixel interpolates its vertices' map positions (perspective-correct
//! barycentrics) and reads its map bilinearly (§3.1 step 4).
//!
//! Before any view is rendered, each view's reflector triangles mark the texels of their maps
//! that a lookup can read (`demand`); a map view then shades only those texels, so a frame's
//! colours are those of shading every texel, bit for bit, for less work.

mod demand;

use std::sync::Arc;

use glam::{Vec2, Vec3, Vec4};
use rayon::prelude::*;
use refract_core::lanes::{F32x8, LANES, Mask, Vec2x8, Vec3x8, mask_from_lanes, mask_lanes};
use refract_core::pvrr::PvrrVertex;
use refract_core::pvrr::{MapTexels, lookup, lookup_x8, mirror_tint};
use refract_core::real::Vector3;
use refract_scene::pvrr::{PvrrPlan, PvrrPlanner, PvrrView, ReflectorKind};
use refract_scene::{
    Aov, Frame, FrameOutputs, LayerValue, PixelLayers, PvrrParams, RenderError, Scene, SceneMesh,
};

use crate::family::{CpuFamily, FrameCx};
use crate::pixel_group::PixelGroup;
use crate::prefetch::prefetch;
use crate::raster::{
    Attribute, DepthTest, Faces, SurfaceBuffer, Texel, TexelLanes, at_most_three, rasterize_into,
};
use crate::scene_meshes::SceneMeshes;
use crate::shade::ViewRow;
use crate::surfaces::{surface_material, surface_rgb_x8};
use demand::Demand;

/// A rendered view's radiance, row-major from the top. A map holds the texels the frame's
/// lookups read; the others keep unspecified values.
#[derive(Default)]
pub struct Image {
    /// Width in texels.
    pub width: u32,
    /// Height in texels.
    pub height: u32,
    /// Radiance per texel.
    pub texels: Vec<Vec3>,
}

impl MapTexels for Image {
    fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    #[inline]
    fn texel(&self, x: u32, y: u32) -> Vec3 {
        self.texels[(y * self.width + x) as usize]
    }

    /// Prefetches the texel's cache line: the eye view's lookups read a map of megabytes
    /// along curves the hardware prefetchers do not follow.
    #[inline]
    fn prefetch(&self, x: u32, y: u32) {
        if let Some(texel) = self.texels.get((y * self.width + x) as usize) {
            prefetch(texel);
        }
    }
}

/// What one pixel of a view shows beside its colour.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct PvrrAov {
    covered: bool,
    zoom: bool,
}

impl PixelLayers for PvrrAov {
    fn value(&self, aov: Aov) -> Option<LayerValue> {
        match aov {
            Aov::Covered => Some(LayerValue::Flag(self.covered)),
            Aov::Zoom => Some(LayerValue::Flag(self.zoom)),
            _ => None,
        }
    }
}

/// The CPU passes of `pvrr`; the plan and every buffer are kept between frames.
#[derive(Default)]
pub struct PvrrPasses {
    planner: PvrrPlanner,
    /// Every mesh of the scene; and every mesh but reflector `k`, for `k`'s maps.
    everything: SceneMeshes,
    without: Vec<SceneMeshes>,
    buffers: Vec<SurfaceBuffer>,
    /// Per view, the texels the frame shows (the eye: all) or reads (a map).
    demand: Vec<Demand>,
    images: Vec<Image>,
    aovs: Vec<PvrrAov>,
}

impl CpuFamily for PvrrPasses {
    type Params = PvrrParams;

    /// Prepares the meshes of `scene`.
    fn prepare(&mut self, scene: &Arc<Scene>) {
        self.planner.prepare(scene);
        let all: Vec<SceneMesh> = core::iter::once(SceneMesh::Refractor)
            .chain((0..scene.objects.len()).map(SceneMesh::Object))
            .collect();
        self.everything = SceneMeshes::of(scene, all.iter().copied());
        self.without = refract_scene::pvrr::reflectors(scene)
            .iter()
            .map(|r| SceneMeshes::of(scene, all.iter().copied().filter(|m| *m != r.mesh)))
            .collect();
    }

    /// One frame.
    fn render(
        &mut self,
        cx: &FrameCx<'_>,
        params: &PvrrParams,
        frame: &mut Frame,
    ) -> Result<(), RenderError> {
        let FrameCx {
            scene,
            camera,
            outputs,
            ..
        } = *cx;
        let plan = self.planner.plan_at(scene, camera, params, cx.lambda_nm)?;
        let views = plan.views.len();
        self.buffers.resize_with(views, SurfaceBuffer::new);
        self.demand.resize_with(views, Demand::default);
        self.images.resize_with(views, Image::default);
        for (index, view) in plan.views.iter().enumerate() {
            let (width, height) = (view.camera.width(), view.camera.height());
            match index {
                0 => self.demand[0].fill(width, height),
                _ => self.demand[index].clear(height),
            }
        }
        for view in &plan.views {
            mark_map_reads(scene, plan, view, &self.demand);
        }
        for index in (1..views).rev() {
            let (done, rest) = self.images.split_at_mut(index + 1);
            let image = &mut done[index];
            let view = &plan.views[index];
            image.width = view.camera.width();
            image.height = view.camera.height();
            image
                .texels
                .resize((image.width * image.height) as usize, Vec3::ZERO);
            let meshes = match view.excluded {
                Some(k) => &self.without[k],
                None => &self.everything,
            };
            let children = ChildMaps {
                first: index + 1,
                images: rest,
            };
            let pass = ViewPass {
                scene,
                plan,
                view,
                meshes,
                children: &children,
            };
            let demand = &self.demand[index];
            let buffer = &mut self.buffers[index];
            render_view(&pass, buffer, demand, &mut image.texels, None);
        }
        let (width, height) = (camera.width(), camera.height());
        frame.resize_for_overwrite(width, height);
        let with_aovs = outputs == FrameOutputs::ColorAndAovs;
        self.aovs.resize(
            if with_aovs {
                (width * height) as usize
            } else {
                0
            },
            PvrrAov::default(),
        );
        let children = ChildMaps {
            first: 1,
            images: self.images.get(1..).unwrap_or_default(),
        };
        let eye = ViewPass {
            scene,
            plan,
            view: &plan.views[0],
            meshes: &self.everything,
            children: &children,
        };
        render_view(
            &eye,
            &mut self.buffers[0],
            &self.demand[0],
            &mut frame.color,
            with_aovs.then_some(&mut self.aovs[..]),
        );
        if with_aovs {
            frame.write_row_layers(cx.method, &self.aovs)?;
        }
        Ok(())
    }
}

impl PvrrPasses {
    /// The plan of the last frame.
    pub fn last_plan(&self) -> &PvrrPlan {
        self.planner.last()
    }

    /// The map of view `view` (≥ 1) of the last frame: shaded where the frame's lookups could
    /// read it (see [`Image`]), unspecified elsewhere.
    pub fn map(&self, view: usize) -> Option<&Image> {
        (view >= 1).then(|| self.images.get(view)).flatten()
    }

    /// The mesh map `view` of the last frame shows at map position `st`, `None` where it shows
    /// the environment (Kakimoto et al. §6: what the occlusion inconsistency compares).
    pub fn map_mesh_at(&self, view: usize, st: Vec2) -> Option<SceneMesh> {
        let plan = self.planner.last();
        let v = plan.views.get(view)?;
        let buffer = self.buffers.get(view)?;
        let (w, h) = (v.camera.width(), v.camera.height());
        let (x, y) = (st.x.floor(), st.y.floor());
        if !(x >= 0.0 && y >= 0.0 && x < w as f32 && y < h as f32) {
            return None;
        }
        let meshes = match v.excluded {
            Some(k) => &self.without[k],
            None => &self.everything,
        };
        let texel = buffer.texel((y as u32 * w + x as u32) as usize)?;
        Some(meshes.source(texel.triangle).0)
    }
}

/// What the pixels on one triangle of a view share: a diffuse object's triangle, or a
/// reflector's (its corners' map positions and states, `None` for a mesh the scene lacks; the
/// map it reads, `None` past the last level).
enum TriangleSurface<'a> {
    Diffuse {
        mesh: SceneMesh,
        triangle: u32,
    },
    Reflector {
        corners: Option<[PvrrVertex; 3]>,
        map: Option<&'a Image>,
        kind: ReflectorKind,
    },
}

/// The rendered maps of views `first..`.
struct ChildMaps<'a> {
    first: usize,
    images: &'a [Image],
}

impl ChildMaps<'_> {
    fn get(&self, view: usize) -> Option<&Image> {
        view.checked_sub(self.first)
            .and_then(|i| self.images.get(i))
    }
}

/// One view of a frame's plan and what it is drawn with.
#[derive(Clone, Copy)]
struct ViewPass<'a> {
    scene: &'a Scene,
    plan: &'a PvrrPlan,
    view: &'a PvrrView,
    /// The scene's meshes the view sees (all but its own reflector's, for a map).
    meshes: &'a SceneMeshes,
    /// The maps of the views this view's reflectors look up.
    children: &'a ChildMaps<'a>,
}

/// Renders `pass`'s view and shades its demanded pixels into `out` (one radiance per pixel)
/// and, for the eye, its AOVs.
fn render_view(
    pass: &ViewPass<'_>,
    buffer: &mut SurfaceBuffer,
    demand: &Demand,
    out: &mut [Vec3],
    aovs: Option<&mut [PvrrAov]>,
) {
    let camera = &pass.view.camera;
    let raster = pass.meshes.raster();
    rasterize_into(&raster, camera, Faces::Both, DepthTest::Nearest, buffer);
    let width = camera.width() as usize;
    let rows = ViewRows {
        pass,
        buffer,
        demand,
    };
    match aovs {
        Some(aovs) => out
            .par_chunks_mut(width)
            .zip(aovs.par_chunks_mut(width))
            .enumerate()
            .for_each(|(y, (colors, aovs))| rows.row(y as u32, colors, Some(aovs))),
        None => out
            .par_chunks_mut(width)
            .enumerate()
            .for_each(|(y, colors)| rows.row(y as u32, colors, None)),
    }
}

/// One rasterised view, shaded row by row: the pixels that see the environment and those that
/// see a surface each gathered eight at a time (camera rays and sky on lanes, texels resolved
/// on lanes: [`SurfaceBuffer::attribute_lanes`], the scalar resolve's bits), the surfaces then shaded
/// one by one.
struct ViewRows<'a> {
    pass: &'a ViewPass<'a>,
    buffer: &'a SurfaceBuffer,
    /// The pixels to shade.
    demand: &'a Demand,
}

impl ViewRows<'_> {
    fn row(&self, y: u32, colors: &mut [Vec3], aovs: Option<&mut [PvrrAov]>) {
        let view = ViewRow {
            camera: &self.pass.view.camera,
            environment: &self.pass.scene.environment,
            buffer: self.buffer,
        };
        view.shade(
            y,
            self.demand.span(y),
            colors,
            aovs,
            |group, colors, aovs| self.surfaces(group, y, colors, aovs),
        );
    }

    /// Eight pixels that see a surface, shaded on lanes ([`Self::shade_lanes`]).
    fn surfaces(
        &self,
        group: &PixelGroup,
        y: u32,
        colors: &mut [Vec3],
        aovs: Option<&mut [PvrrAov]>,
    ) {
        // Position, normal and barycentrics: what the shading reads.
        let texels = self
            .buffer
            .attribute_lanes::<{ Attribute::BARYCENTRICS }>(&group.x, y);
        let (color, aov) = self.shade_lanes(&texels);
        let color = color.to_lanes();
        for (&x, color) in group.x.iter().zip(color).take(group.len) {
            colors[x as usize] = color;
        }
        if let Some(aovs) = aovs {
            for (&x, aov) in group.x.iter().zip(aov).take(group.len) {
                aovs[x as usize] = aov;
            }
        }
    }

    /// The colours and AOVs of eight surface texels, lane `i` bit for bit
    /// [`Self::surface`]'s for texel `i`. Neighbouring pixels mostly see the same triangle:
    /// each of the group's triangles (at most three; with more, lane by lane) is looked up
    /// once ([`Self::triangle_surface`]) and shaded on all eight lanes, each lane keeping its
    /// own triangle's values.
    fn shade_lanes(&self, texels: &TexelLanes) -> (Vec3x8, [PvrrAov; LANES]) {
        let Some((distinct, count)) = at_most_three(&texels.triangle) else {
            let texels = texels.to_texels();
            let (mut colors, mut aovs) = ([Vec3::ZERO; LANES], [PvrrAov::default(); LANES]);
            for (i, t) in texels.iter().enumerate() {
                (colors[i], aovs[i]) = self.surface(t, &self.triangle_surface(t.triangle));
            }
            return (Vec3x8::from_lanes(&colors), aovs);
        };
        let (mut color, mut covered, mut zoom) =
            self.triangle_lanes(texels, &self.triangle_surface(distinct[0]));
        for &other in &distinct[1..count] {
            let mut on_other = [false; LANES];
            for (on, &t) in on_other.iter_mut().zip(&texels.triangle) {
                *on = t == other;
            }
            let on_other = mask_from_lanes(on_other);
            let (c, v, z) = self.triangle_lanes(texels, &self.triangle_surface(other));
            color = Vec3x8::select(on_other, c, color);
            (covered, zoom) = (on_other.select(v, covered), on_other.select(z, zoom));
        }
        let (covered, zoom) = (mask_lanes(covered), mask_lanes(zoom));
        let mut aovs = [PvrrAov::default(); LANES];
        for (i, aov) in aovs.iter_mut().enumerate() {
            *aov = PvrrAov {
                covered: covered[i],
                zoom: zoom[i],
            };
        }
        (color, aovs)
    }

    /// [`Self::surface`] on all eight lanes as if each were on `triangle`: the colours and the
    /// lanes' `covered` and `zoom` AOVs as masks.
    fn triangle_lanes(
        &self,
        t: &TexelLanes,
        triangle: &TriangleSurface<'_>,
    ) -> (Vec3x8, Mask, Mask) {
        let (none, all) = (
            mask_from_lanes([false; LANES]),
            mask_from_lanes([true; LANES]),
        );
        let (corners, map, kind) = match *triangle {
            TriangleSurface::Diffuse { mesh, triangle } => {
                let rgb = surface_rgb_x8(
                    self.pass.scene,
                    mesh,
                    triangle,
                    t.barycentrics,
                    t.p_ws,
                    t.n_ws,
                );
                return (rgb, none, none);
            }
            TriangleSurface::Reflector { corners, map, kind } => (corners, map, kind),
        };
        let (Some(corners), Some(map)) = (corners, map) else {
            return (Vec3x8::ZERO, all, all);
        };
        let w = [t.barycentrics.x, t.barycentrics.y, t.barycentrics.z];
        // As the scalar sums: the state from the first term, the positions from zero.
        let state = w[0] * F32x8::splat(corners[0].state)
            + w[1] * F32x8::splat(corners[1].state)
            + w[2] * F32x8::splat(corners[2].state);
        let looked_up = state.simd_le(F32x8::ZERO);
        if looked_up.none() {
            return (Vec3x8::ZERO, all, all);
        }
        // (Loops, not `array::map`: its closures are not always inlined.)
        let mut st = [Vec2x8::splat(Vec2::ZERO); 3];
        for (c, st) in st.iter_mut().enumerate() {
            for (k, w) in w.iter().enumerate() {
                let [x, y] = corners[k].st[c];
                *st = Vec2x8 {
                    x: st.x + *w * F32x8::splat(x),
                    y: st.y + *w * F32x8::splat(y),
                };
            }
        }
        let tint = match kind {
            ReflectorKind::Mirror { f0 } => {
                let to_texel = t.p_ws - Vec3x8::splat(self.pass.view.camera.eye());
                let view = to_texel * (F32x8::ONE / to_texel.length());
                mirror_tint(f0, t.n_ws, view)
            }
            ReflectorKind::Lens { .. } => Vec3x8::splat(Vec3::ONE),
        };
        let color = lookup_x8(map, st, tint);
        (
            Vec3x8::select(looked_up, color, Vec3x8::ZERO),
            all,
            !looked_up,
        )
    }

    /// What shading needs of combined triangle `triangle` of this view's meshes.
    fn triangle_surface(&self, triangle: u32) -> TriangleSurface<'_> {
        let ViewPass {
            scene,
            plan,
            view,
            meshes,
            children,
        } = *self.pass;
        let (mesh, triangle) = meshes.source(triangle);
        let Some(draw) = view
            .draws
            .iter()
            .find(|d| plan.reflectors[d.reflector].mesh == mesh)
        else {
            return TriangleSurface::Diffuse { mesh, triangle };
        };
        TriangleSurface::Reflector {
            corners: scene
                .mesh(mesh)
                .map(|m| m.triangles[triangle as usize].map(|v| draw.vertices[v as usize])),
            map: draw.map.and_then(|m| children.get(m)),
            kind: plan.reflectors[draw.reflector].kind,
        }
    }

    /// The colour of a surface texel on `triangle`: a diffuse object shaded, or a reflector's
    /// map looked up at its vertices' interpolated coordinates (black where they are not all
    /// mapped).
    fn surface(&self, t: &Texel, triangle: &TriangleSurface<'_>) -> (Vec3, PvrrAov) {
        let w = t.barycentrics;
        let (corners, map, kind) = match *triangle {
            TriangleSurface::Diffuse { mesh, triangle } => {
                let scene = self.pass.scene;
                let material = surface_material(scene, None, mesh, triangle, w, t.p_ws, t.n_ws);
                return (material.rgb, PvrrAov::default());
            }
            TriangleSurface::Reflector { corners, map, kind } => (corners, map, kind),
        };
        let covered = PvrrAov {
            covered: true,
            zoom: true,
        };
        let Some(corners) = corners else {
            return (Vec3::ZERO, covered);
        };
        let state: f32 = (0..3).map(|k| w[k] * corners[k].state).sum();
        let (Some(map), true) = (map, state <= 0.0) else {
            return (Vec3::ZERO, covered);
        };
        let st = [0, 1, 2].map(|c| {
            (0..3)
                .map(|k| w[k] * Vec2::from_array(corners[k].st[c]))
                .sum::<Vec2>()
        });
        let tint = match kind {
            ReflectorKind::Mirror { f0 } => mirror_tint(
                f0,
                t.n_ws,
                (t.p_ws - self.pass.view.camera.eye()).normalize(),
            ),
            ReflectorKind::Lens { .. } => Vec3::ONE,
        };
        (
            lookup(map, st, tint),
            PvrrAov {
                covered: true,
                zoom: false,
            },
        )
    }
}

/// Marks in `maps` (one [`Demand`] per view of the plan) every texel that `view`'s lookups
/// can read. A pixel of a reflector's triangle looks its map up only where every corner it
/// weighs is mapped (its interpolated state is 0, the others' are positive), at a convex
/// combination of those corners' map positions (§3.1 step 4, each channel's for dispersion,
/// §4.5); so each triangle marks the rectangle around its mapped corners' positions, widened
/// by a texel on each side for the bilinear footprint and the rounding of the interpolation.
/// A triangle whose corners all lie outside one side of the view's frustum covers no pixel
/// and marks nothing.
fn mark_map_reads(scene: &Scene, plan: &PvrrPlan, view: &PvrrView, maps: &[Demand]) {
    let world_to_clip = view.camera.world_to_clip();
    for draw in &view.draws {
        let Some(map) = draw.map else {
            continue;
        };
        let Some(mesh) = scene.mesh(plan.reflectors[draw.reflector].mesh) else {
            continue;
        };
        let camera = &plan.views[map].camera;
        let (width, height) = (camera.width(), camera.height());
        let demand = &maps[map];
        for triangle in &mesh.triangles {
            let clip = triangle.map(|v| world_to_clip * mesh.positions[v as usize].extend(1.0));
            if outside_one_plane(&clip) {
                continue;
            }
            let corners = triangle.map(|v| draw.vertices[v as usize]);
            let mapped = corners.iter().filter(|c| c.state <= 0.0);
            let positions = mapped.flat_map(|c| c.st.map(Vec2::from_array));
            let Some((lo, hi)) = positions.fold(None, |bounds, st| {
                let (lo, hi) = bounds.unwrap_or((st, st));
                Some((lo.min(st), hi.max(st)))
            }) else {
                continue;
            };
            if !(lo.is_finite() && hi.is_finite()) {
                // (`min`/`max` drop a NaN: any non-finite position is caught here.)
                demand.mark([0, width - 1], [0, height - 1]);
                continue;
            }
            let texel = |v: f32, margin: f32, size: u32| {
                ((v - 0.5).floor() + margin).clamp(0.0, (size - 1) as f32) as u32
            };
            demand.mark(
                [texel(lo.x, -1.0, width), texel(hi.x, 2.0, width)],
                [texel(lo.y, -1.0, height), texel(hi.y, 2.0, height)],
            );
        }
    }
}

/// Whether clip-space points `clip` all lie outside one of the frustum's side planes
/// (`|x| ≤ w`, `|y| ≤ w`) or behind its near plane (`z ≥ 0`), so that a triangle through them
/// covers no pixel (a conservative test: a triangle across a corner of the frustum passes).
fn outside_one_plane(clip: &[Vec4; 3]) -> bool {
    let all = |outside: fn(&Vec4) -> bool| clip.iter().all(outside);
    all(|c| c.x > c.w)
        || all(|c| c.x < -c.w)
        || all(|c| c.y > c.w)
        || all(|c| c.y < -c.w)
        || all(|c| c.z < 0.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use refract_core::Camera;
    use refract_scene::MethodId;

    /// `name` at 120 × 96 with maps of `resolution` texels and `dispersion`, its passes
    /// prepared.
    fn set_up(
        name: &str,
        resolution: u32,
        dispersion: u32,
    ) -> (Arc<Scene>, Camera, PvrrParams, PvrrPasses) {
        let scene = Arc::new(refract_eval::load_scene(name).expect(name).scene);
        let camera = scene.camera(120, 96).expect("camera");
        let params = PvrrParams {
            resolution,
            dispersion,
            ..PvrrParams::DEFAULT
        };
        let mut passes = PvrrPasses::default();
        passes.prepare(&scene);
        (scene, camera, params, passes)
    }

    /// A colour-only frame of `scene` seen by `camera`.
    fn color_frame<'a>(scene: &'a Scene, camera: &'a Camera) -> FrameCx<'a> {
        FrameCx {
            scene,
            camera,
            method: MethodId::Pvrr,
            outputs: FrameOutputs::Color,
            lambda_nm: None,
            repeat: false,
        }
    }

    /// Every surface pixel of every view (the eye and each map) shaded on lanes is lane by
    /// lane the scalar shading's, bit for bit: a convex mirror with its map, a stack of maps,
    /// and a lens with chromatic aberration (three map positions per vertex), whose views hold
    /// diffuse objects of every albedo, reflectors looked up and not, and groups on one, two,
    /// three and more triangles.
    #[test]
    fn lane_shading_equals_the_scalar_shading_bit_for_bit() {
        let mut groups_by_triangles = [0usize; 5];
        for (name, dispersion) in [
            ("convex-mirror", 0),
            ("mirror-stack", 0),
            ("spectacles", 10),
        ] {
            let (scene, camera, params, mut passes) = set_up(name, 128, dispersion);
            let cx = color_frame(&scene, &camera);
            passes
                .render(&cx, &params, &mut Frame::default())
                .expect("frame");
            let plan = passes.last_plan();
            for (index, view) in plan.views.iter().enumerate() {
                let children = ChildMaps {
                    first: index + 1,
                    images: &passes.images[index + 1..],
                };
                let pass = ViewPass {
                    scene: &scene,
                    plan,
                    view,
                    meshes: match view.excluded {
                        Some(k) => &passes.without[k],
                        None => &passes.everything,
                    },
                    children: &children,
                };
                let buffer = &passes.buffers[index];
                let rows = ViewRows {
                    pass: &pass,
                    buffer,
                    demand: &passes.demand[index],
                };
                for y in 0..view.camera.height() {
                    let row = (y * buffer.width) as usize;
                    let covered: Vec<u32> = buffer
                        .covered_span(y)
                        .filter(|&x| buffer.is_covered(row + x as usize))
                        .collect();
                    for chunk in covered.chunks(LANES) {
                        let mut group = PixelGroup::new();
                        chunk.iter().for_each(|&x| _ = group.push(x));
                        group.pad();
                        let texels =
                            buffer.attribute_lanes::<{ Attribute::BARYCENTRICS }>(&group.x, y);
                        let triangles = (1..=LANES)
                            .filter(|&i| {
                                !texels.triangle[..i - 1].contains(&texels.triangle[i - 1])
                            })
                            .count();
                        groups_by_triangles[triangles.min(4)] += 1;
                        let (colors, aovs) = rows.shade_lanes(&texels);
                        let colors = colors.to_lanes();
                        for (i, t) in texels.to_texels().iter().enumerate() {
                            let (color, aov) = rows.surface(t, &rows.triangle_surface(t.triangle));
                            let bits = |v: Vec3| v.to_array().map(f32::to_bits);
                            assert_eq!(
                                bits(colors[i]),
                                bits(color),
                                "{name}, view {index}, ({}, {y})",
                                group.x[i]
                            );
                            assert_eq!(aovs[i], aov);
                        }
                    }
                }
            }
        }
        // Every path was taken: one, two, three and more triangles per group.
        assert!(
            groups_by_triangles[1..].iter().all(|&n| n > 0),
            "{groups_by_triangles:?}"
        );
    }

    /// Maps shade only what the frame's lookups read, and the frame is the same as shading
    /// everything: every map texel is set to NaN between two renders of the same frame, and
    /// the second frame must equal the first bit for bit (a lookup of a texel the demand
    /// missed would read the NaN); some texels of some map must have stayed NaN (the demand
    /// skipped them). Mirrors, a stack of maps, two mirrors sharing vertices, the lens with
    /// chromatic aberration, and the stack with a map size too small for the view.
    #[test]
    fn maps_shade_what_lookups_read_and_frames_equal_the_fully_shaded_ones() {
        for (name, dispersion, resolution) in [
            ("convex-mirror", 0, 128),
            ("mirror-stack", 0, 128),
            ("mirror-stack", 0, 24),
            ("adjacent-mirrors", 0, 96),
            ("spectacles", 100, 512),
            ("spectacles", 10, 128),
            ("spectacles", 0, 64),
        ] {
            let (scene, camera, params, mut passes) = set_up(name, resolution, dispersion);
            let cx = color_frame(&scene, &camera);
            let (mut first, mut second) = (Frame::default(), Frame::default());
            passes.render(&cx, &params, &mut first).expect("frame");
            for image in &mut passes.images {
                image.texels.fill(Vec3::NAN);
            }
            passes.render(&cx, &params, &mut second).expect("frame");
            let bits = |frame: &Frame| -> Vec<[u32; 3]> {
                frame
                    .color
                    .iter()
                    .map(|c| c.to_array().map(f32::to_bits))
                    .collect()
            };
            assert!(first.color.iter().all(|c| c.is_finite()), "{name}");
            assert_eq!(bits(&first), bits(&second), "{name}, maps of {resolution}");
            let skipped = passes.images[1..]
                .iter()
                .map(|image| image.texels.iter().filter(|t| t.is_nan()).count())
                .sum::<usize>();
            assert!(skipped > 0, "{name}: every map texel was shaded");
        }
    }
}
