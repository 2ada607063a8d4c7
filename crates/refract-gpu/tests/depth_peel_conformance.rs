//! `depth-peel`'s WGSL (`src/methods/depth_peel.wgsl`) against refract-core's
//! `depth_peel::peel_path`, through the family's conformance module
//! (`src/methods/depth_peel_conformance.wgsl`): whole paths over the same analytic layers (two
//! glass spheres, one partly behind the other, and a wall behind them), for proptest-generated
//! IORs, absorption, layer counts, step counts and interaction budgets.

use glam::{UVec2, Vec3, Vec4};
use proptest::prelude::*;
use refract_core::depth_peel::{
    PeelMedium, PeelSettings, PeelUniforms, PeeledLayers, facing_plane, peel_path,
};
use refract_core::{Camera, CameraDesc};
use refract_gpu::conformance::{FamilyEvaluation, evaluate_family};

#[macro_use]
mod common;
use common::{close, close3, config, context};

const SPHERES: [Vec4; 2] = [
    Vec4::new(0.0, 0.0, 0.0, 1.0),
    Vec4::new(0.3, 0.2, -2.2, 0.6),
];

/// `depth_peel_conformance.wgsl`'s layers: the texel's centre ray against the two spheres,
/// sorted by view depth; the wall z = −4.
struct AnalyticLayers<'a> {
    camera: &'a Camera,
    layers: u32,
}

impl AnalyticLayers<'_> {
    fn hits(&self, texel: UVec2) -> [(f32, Vec3, u32); 4] {
        let ray = self
            .camera
            .pixel_ray(Camera::pixel_center(texel.x, texel.y));
        let mut hits = [(f32::INFINITY, Vec3::Z, 0); 4];
        let mut n = 0;
        for (k, s) in SPHERES.iter().enumerate() {
            let oc = ray.origin - s.truncate();
            let b = oc.dot(ray.dir);
            let disc = b * b - (oc.dot(oc) - s.w * s.w);
            if disc > 0.0 {
                let root = disc.sqrt();
                for t in [-b - root, -b + root] {
                    let p = ray.origin + t * ray.dir;
                    let depth = (p - self.camera.eye()).dot(self.camera.look_dir());
                    hits[n] = (depth, (p - s.truncate()) / s.w, k as u32);
                    n += 1;
                }
            }
        }
        hits.sort_by(|a, b| a.0.total_cmp(&b.0));
        hits
    }
}

impl PeeledLayers for AnalyticLayers<'_> {
    fn layer_plane(&self, texel: UVec2, layer: u32) -> Vec4 {
        if layer >= self.layers.min(4) {
            return Vec4::NAN;
        }
        let (depth, n, k) = self.hits(texel)[layer as usize];
        let s = SPHERES[k as usize];
        if depth.is_finite() {
            facing_plane(s.truncate() + s.w * n, n, self.camera.eye())
        } else {
            Vec4::NAN
        }
    }
    fn layer_normal(&self, texel: UVec2, layer: u32) -> Vec3 {
        self.hits(texel)[layer.min(3) as usize].1
    }
    fn layer_refractor(&self, texel: UVec2, layer: u32) -> u32 {
        self.hits(texel)[layer.min(3) as usize].2
    }
    fn opaque_plane(&self, texel: UVec2) -> Vec4 {
        let ray = self
            .camera
            .pixel_ray(Camera::pixel_center(texel.x, texel.y));
        let t = (-4.0 - ray.origin.z) / ray.dir.z;
        if t > 0.0 {
            facing_plane(ray.origin + t * ray.dir, Vec3::Z, self.camera.eye())
        } else {
            Vec4::NAN
        }
    }
}

proptest! {
    #![proptest_config(config())]

    /// Whole paths on every covered pixel of a 48 × 36 frame. A crossing is decided by signs
    /// of depth differences read at texels (floors of projected points), so a row whose sample
    /// lands within rounding of a texel edge or of a layer may take another branch: at most
    /// 3 % of the rows may differ; the others must end the same way, with the same counts,
    /// the last ray's origin and direction, the opaque hit, the transmittance and the first
    /// exit (`P2`, `T2`: whether there is one, and where) within 1e-3.
    #[test]
    fn peel_path_agrees(
        ior0 in prop::sample::select(vec![1.5f32, 1.33, 2.0]),
        ior1 in prop::sample::select(vec![1.5f32, 1.2, 1.8]),
        sigma in 0.0f32..2.0,
        layers in 1u32..=4,
        steps in prop::sample::select(vec![8u32, 24, 48]),
        max_interfaces in 1u32..=8,
        with_wall in any::<bool>(),
    ) {
        let context = gpu_or_skip!();
        let camera = Camera::new(CameraDesc {
            eye: Vec3::new(0.4, 0.3, 4.0),
            target: Vec3::new(0.0, 0.0, -0.5),
            width: 48,
            height: 36,
            ..CameraDesc::default()
        })
        .expect("camera");
        let analytic = AnalyticLayers { camera: &camera, layers };
        let texels: Vec<UVec2> = (0..36)
            .flat_map(|y| (0..48).map(move |x| UVec2::new(x, y)))
            .filter(|t| analytic.hits(*t)[0].0.is_finite())
            .collect();
        prop_assume!(texels.len() > 200);
        let settings = PeelSettings {
            layers,
            max_interfaces,
            steps,
            thickness: 0.06,
            refractor_bound: Vec4::new(0.15, 0.1, -1.1, 2.0),
            scene_bound: if with_wall { Vec4::new(0.0, 0.0, -1.0, 6.0) } else { Vec4::ZERO },
        };
        let mut media = [PeelMedium::default(); refract_scene::MAX_REFRACTORS];
        media[0] = PeelMedium { ior: ior0, outside_ior: 1.0, within: 0, _padding: 0, sigma: [sigma, 0.5 * sigma, 0.0, 0.0] };
        media[1] = PeelMedium { ior: ior1, outside_ior: 1.0, within: 0, _padding: 0, sigma: [0.0, 0.0, sigma, 0.0] };
        let uniforms = PeelUniforms::from(&settings);
        let blocks = [
            (16, bytemuck::bytes_of(&uniforms)),
            (17, bytemuck::cast_slice::<PeelMedium, u8>(&media)),
        ];
        let a: Vec<Vec4> = texels.iter().map(|t| Vec4::new(t.x as f32, t.y as f32, 0.0, 0.0)).collect();
        let eval = |entry| {
            let evaluation = FamilyEvaluation {
                module: "depth-peel-conformance",
                entry,
                camera: &camera,
                ior: ior0,
                uniforms: &blocks,
                constants: &[],
            };
            evaluate_family(context, &evaluation, &a, &a).expect("gpu")
        };
        let (origin, dir, opaque, transmittance) = (
            eval("test_peel_origin"),
            eval("test_peel_dir"),
            eval("test_peel_opaque"),
            eval("test_peel_transmittance"),
        );
        let (p2, t2) = (eval("test_peel_p2"), eval("test_peel_t2"));
        let mut mismatches = Vec::new();
        let mut searched = 0usize;
        for (k, &texel) in texels.iter().enumerate() {
            let (depth, n1, r) = analytic.hits(texel)[0];
            let ray = camera.pixel_ray(Camera::pixel_center(texel.x, texel.y));
            let p1 = ray.origin + ray.dir * (depth / ray.dir.dot(camera.look_dir()));
            let path = peel_path(&camera, &analytic, &media, &settings, p1, n1, r);
            searched += usize::from(path.interfaces + path.reflections >= 2);
            let counts = (path.interfaces + 16 * path.reflections) as f32;
            let hit = path.opaque.map(|(_, p)| p);
            let same = origin[k].w == path.end.code() as f32
                && close3(origin[k], path.origin, 1e-3)
                && dir[k].w == counts
                && close3(dir[k], path.dir, 1e-3)
                && (opaque[k].w > 0.5) == hit.is_some()
                && hit.is_none_or(|p| close3(opaque[k], p, 1e-3))
                && close3(transmittance[k], path.transmittance, 1e-3)
                && close(transmittance[k].w, path.refractors_met as f32, 0.0)
                && (p2[k].w > 0.5) == path.first_exit.is_some()
                && path.first_exit.is_none_or(|(p, t)| close3(p2[k], p, 1e-3) && close3(t2[k], t, 1e-3));
            if !same {
                mismatches.push(k);
            }
        }
        // Where a second interaction is possible, the march must have found one.
        if layers >= 2 && max_interfaces >= 2 {
            prop_assert!(searched * 2 > texels.len(), "{searched} of {} rows crossed a layer", texels.len());
        }
        prop_assert!(
            mismatches.len() * 100 <= texels.len() * 3,
            "{} of {} rows differ; first: texel {:?}, gpu origin {} dir {} opaque {} transmittance {}",
            mismatches.len(),
            texels.len(),
            texels[mismatches[0]],
            origin[mismatches[0]],
            dir[mismatches[0]],
            opaque[mismatches[0]],
            transmittance[mismatches[0]],
        );
    }
}
