//! The eye pass of `distance-map`: every pixel of the rasterised eye view shaded, row by row.
//! The pixels that see the environment and those that see a surface are gathered eight at a
//! time: rays and sky on lanes, the texels resolved on lanes, diffuse surfaces shaded on lanes
//! (each of a group's triangles, at most three, on all eight lanes); a pixel on the specular
//! object or a conductor starts its path ([`trace_path`], §17.3) alone. Every pixel gets the
//! bits of shading it alone ([`EyePass::pixel`]).

use glam::Vec3;
use refract_core::Camera;
use refract_core::distance_map::{PathStart, trace_path};
use refract_core::lanes::{LANES, Vec3x8, mask_from_lanes};
use refract_core::real::Vector3;
use refract_scene::{Scene, SceneMesh};

use super::{DistanceAov, MapScene, start_layer};
use crate::pixel_group::PixelGroup;
use crate::raster::{Attribute, SurfaceBuffer, Texel, TexelLanes, at_most_three};
use crate::scene_meshes::SceneMeshes;
use crate::shade::ViewRow;
use crate::surfaces::{surface_material, surface_rgb_x8};

/// What the eye pass of one frame reads.
pub(super) struct EyePass<'a> {
    pub scene: &'a Scene,
    pub camera: &'a Camera,
    /// The eye view rasterised.
    pub buffer: &'a SurfaceBuffer,
    /// The meshes `buffer` was rasterised from.
    pub everything: &'a SceneMeshes,
    /// The frame's distance map with the scene it samples.
    pub map: &'a MapScene<'a>,
    pub path: &'a refract_core::distance_map::PathParams,
}

impl EyePass<'_> {
    /// Row `y`: its colours and, for an AOV frame, its AOVs.
    pub fn row(&self, y: u32, colors: &mut [Vec3], aovs: Option<&mut [DistanceAov]>) {
        let view = ViewRow {
            camera: self.camera,
            environment: &self.scene.environment,
            buffer: self.buffer,
        };
        let width = colors.len() as u32;
        view.shade(y, 0..width, colors, aovs, |group, colors, aovs| {
            self.surfaces(group, y, colors, aovs)
        });
    }

    /// Eight pixels that see a surface: the diffuse ones shaded on lanes per triangle, the
    /// others (and every pixel of a group on more than three triangles) one by one.
    fn surfaces(
        &self,
        group: &PixelGroup,
        y: u32,
        colors: &mut [Vec3],
        mut aovs: Option<&mut [DistanceAov]>,
    ) {
        let lanes = self
            .buffer
            .attribute_lanes::<{ Attribute::BARYCENTRICS }>(&group.x, y);
        let mut diffuse = [false; LANES];
        let mut color = Vec3x8::ZERO;
        if let Some((distinct, count)) = at_most_three(&lanes.triangle) {
            for &triangle in &distinct[..count] {
                if let Some(rgb) = self.diffuse_lanes(&lanes, triangle) {
                    let mut on = [false; LANES];
                    for (i, on) in on.iter_mut().enumerate() {
                        *on = lanes.triangle[i] == triangle;
                        diffuse[i] |= *on;
                    }
                    color = Vec3x8::select(mask_from_lanes(on), rgb, color);
                }
            }
        }
        let color = color.to_lanes();
        // The texels one by one only when a pixel starts a path.
        let mut texels = None;
        for i in 0..group.len {
            let x = group.x[i];
            let (c, aov) = match diffuse[i] {
                true => (color[i], DistanceAov::default()),
                false => {
                    let texels = texels.get_or_insert_with(|| lanes.to_texels());
                    self.pixel(x, y, Some(&texels[i]))
                }
            };
            colors[x as usize] = c;
            if let Some(aovs) = aovs.as_deref_mut() {
                aovs[x as usize] = aov;
            }
        }
    }

    /// The radiance of a diffuse object's `triangle` at all eight lanes as if each were on
    /// it, `None` when the triangle is not a diffuse object's.
    fn diffuse_lanes(&self, t: &TexelLanes, triangle: u32) -> Option<Vec3x8> {
        let (mesh, triangle) = self.everything.source(triangle);
        let SceneMesh::Object(k) = mesh else {
            return None;
        };
        if self.scene.objects[k].conductor().is_some() {
            return None;
        }
        Some(surface_rgb_x8(
            self.scene,
            mesh,
            triangle,
            t.barycentrics,
            t.p_ws,
            t.n_ws,
        ))
    }

    /// One pixel shaded alone: the environment where `texel` is `None`, a diffuse surface's
    /// radiance, or the path a specular surface starts.
    pub fn pixel(&self, x: u32, y: u32, texel: Option<&Texel>) -> (Vec3, DistanceAov) {
        let Some(t) = texel else {
            let dir = self.camera.pixel_ray(Camera::pixel_center(x, y)).dir;
            return (self.scene.environment.radiance(dir), DistanceAov::default());
        };
        let (mesh, triangle) = self.everything.source(t.triangle);
        let w = t.barycentrics;
        let material = surface_material(
            self.scene,
            self.map.lambda_nm,
            mesh,
            triangle,
            w,
            t.p_ws,
            t.n_ws,
        );
        if material.ior == 0.0 {
            return (material.rgb, DistanceAov::default());
        }
        let center = self.map.map.center;
        let start = PathStart {
            x: t.p_ws - center,
            v: (t.p_ws - self.camera.eye()).normalize(),
            n: t.n_ws,
            material,
            layer: Some(start_layer(mesh, t.p_ws, t.n_ws, center)),
        };
        let result = trace_path(self.map, &start, self.path);
        (result.radiance, DistanceAov::of(&result))
    }
}

#[cfg(test)]
mod tests {
    use std::sync::Arc;

    use refract_scene::{DistanceMapParams, Frame, FrameOutputs, MethodId};

    use super::*;
    use crate::families::distance_map::DistancePasses;
    use crate::family::{CpuFamily, FrameCx};

    /// Every pixel of the eye pass (colour and AOVs) is that pixel shaded alone, bit for bit:
    /// a mirror sphere before a mirror (conductors), a glass sphere that reflects and
    /// refracts, glass behind an opaque ball with the sky around, and a torus (the sky in its
    /// hole); the views hold groups shaded on lanes, pixels traced alone, groups on more than
    /// three triangles and pixels that see the environment inside a row's covered span.
    #[test]
    fn the_pass_shades_every_pixel_as_alone() {
        let (mut on_lanes, mut alone, mut crowded, mut sky) = (0, 0, 0, 0);
        for name in ["mirror-room", "glass-room", "engine-failures", "torus"] {
            let scene = Arc::new(refract_eval::load_scene(name).expect(name).scene);
            let camera = scene.camera(120, 96).expect("camera");
            let params = DistanceMapParams {
                resolution: 48,
                ..DistanceMapParams::DEFAULT
            };
            let mut passes = DistancePasses::default();
            passes.prepare(&scene);
            let cx = FrameCx {
                scene: &scene,
                camera: &camera,
                method: MethodId::DistanceMap,
                outputs: FrameOutputs::ColorAndAovs,
                lambda_nm: None,
                repeat: false,
            };
            let mut frame = Frame::default();
            passes.render(&cx, &params, &mut frame).expect("frame");
            let map = MapScene {
                map: &passes.map,
                scene: &scene,
                lambda_nm: None,
            };
            let eye = EyePass {
                scene: &scene,
                camera: &camera,
                buffer: &passes.camera,
                everything: &passes.everything,
                map: &map,
                path: &params.path,
            };
            let bits = |v: Vec3| v.to_array().map(f32::to_bits);
            for y in 0..camera.height() {
                let row = (y * camera.width()) as usize;
                let span = eye.buffer.covered_span(y);
                let covered: Vec<u32> = span
                    .clone()
                    .filter(|&x| eye.buffer.is_covered(row + x as usize))
                    .collect();
                sky += span.len() - covered.len();
                for chunk in covered.chunks(LANES) {
                    let mut group = PixelGroup::new();
                    chunk.iter().for_each(|&x| _ = group.push(x));
                    group.pad();
                    let lanes = eye
                        .buffer
                        .attribute_lanes::<{ Attribute::BARYCENTRICS }>(&group.x, y);
                    match at_most_three(&lanes.triangle) {
                        None => crowded += 1,
                        Some(_) => on_lanes += 1,
                    }
                }
                for x in 0..camera.width() {
                    let i = row + x as usize;
                    let texel = eye.buffer.texel(i);
                    let (color, aov) = eye.pixel(x, y, texel.as_ref());
                    alone += usize::from(aov.covered);
                    assert_eq!(bits(frame.color[i]), bits(color), "{name} ({x}, {y})");
                    assert_eq!(passes.aovs[i], aov, "{name} ({x}, {y})");
                }
            }
        }
        assert!(
            on_lanes > 0 && alone > 0 && crowded > 0 && sky > 0,
            "{on_lanes} {alone} {crowded} {sky}"
        );
    }
}
