//! The row and parameters of the layered image-space family: `depth-peel`, refraction through
//! any number of interfaces in the depth-peeled surfaces of every refractor
//! ([`refract_core::depth_peel`]).

use glam::{Vec3, Vec4};
use refract_core::depth_peel::{MAX_PEEL_LAYERS, PeelMedium, PeelSettings};

use super::{
    CPU_AND_GPU, DispersionWavelengths, Family, FamilyParams, MemoryModel, MethodId, MethodInfo,
    MethodParams, ParamKind, ParamSpec, ParamValue, WAVELENGTHS_PARAM,
};
use crate::frame::Aov;
use crate::scene::Scene;

/// The most interactions a `depth-peel` path may have (`max-interfaces`).
pub const MAX_PEEL_INTERFACES: u32 = 64;
/// The most samples per marched segment (`steps`).
pub const MAX_PEEL_STEPS: u32 = 1024;
/// The largest `thickness` (thousandths of the refractors' bounding radius).
pub const MAX_PEEL_THICKNESS_MILLI: u32 = 1000;

/// Parameters of `depth-peel`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct DepthPeelParams {
    /// Layers peeled, `1..=`[`MAX_PEEL_LAYERS`].
    pub layers: u32,
    /// Interactions (refractions and total internal reflections) per path,
    /// `1..=`[`MAX_PEEL_INTERFACES`].
    pub max_interfaces: u32,
    /// Samples per marched segment, `1..=`[`MAX_PEEL_STEPS`].
    pub steps: u32,
    /// The largest depth gap of an accepted crossing, in thousandths of the radius of the
    /// sphere holding every refractor, `1..=`[`MAX_PEEL_THICKNESS_MILLI`].
    pub thickness_milli: u32,
    /// Wavelengths traced through dispersive refractors.
    pub wavelengths: DispersionWavelengths,
}

impl DepthPeelParams {
    /// The defaults: 4 layers (two glass objects, or a vessel's four walls), 8 interactions
    /// (the reference's depth), 48 steps, thickness 5 % of the refractors' radius.
    pub const DEFAULT: Self = Self {
        layers: 4,
        max_interfaces: 8,
        steps: 48,
        thickness_milli: 50,
        wavelengths: DispersionWavelengths::DEFAULT,
    };

    /// The media of `scene`'s refractors as the march reads them (refractor `k` in entry
    /// `k`): its IOR at wavelength `lambda_nm` ([`crate::Refractor::ior_at`]), the IOR around
    /// it ([`Scene::outside_ior_at`]), the medium around it and its Beer-Lambert coefficient.
    pub fn media(&self, scene: &Scene, lambda_nm: Option<f32>) -> Vec<PeelMedium> {
        scene
            .refractors()
            .enumerate()
            .map(|(k, r)| PeelMedium {
                ior: r.ior_at(lambda_nm),
                outside_ior: scene.outside_ior_at(k, lambda_nm),
                within: r.within().map_or(0, |w| w as u32 + 1),
                _padding: 0,
                sigma: r
                    .attenuation()
                    .map_or([0.0; 4], |a| a.coefficient().extend(0.0).to_array()),
            })
            .collect()
    }

    /// The march settings of these parameters on `scene`: the spheres around the refractors
    /// and around everything (none without opaque objects), each the box-centred sphere over
    /// the meshes' bounding spheres widened by 1 %, and the thickness in scene units.
    pub fn settings(&self, scene: &Scene) -> PeelSettings {
        let sphere = |mesh: &refract_geometry::Mesh| {
            let s = mesh.bounding_sphere();
            (s.center, s.radius)
        };
        let refractors: Vec<(Vec3, f32)> = scene.refractors().map(|r| sphere(r.mesh())).collect();
        let refractor_bound = enclosing_sphere(&refractors);
        let scene_bound = if scene.objects.is_empty() {
            Vec4::ZERO
        } else {
            let mut all = refractors.clone();
            all.extend(scene.objects.iter().map(|o| sphere(o.mesh())));
            enclosing_sphere(&all)
        };
        PeelSettings {
            layers: self.layers,
            max_interfaces: self.max_interfaces,
            steps: self.steps,
            thickness: self.thickness_milli as f32 * 1e-3 * refractor_bound.w,
            refractor_bound,
            scene_bound,
        }
    }
}

/// A sphere `(centre, radius)` holding every sphere of `spheres`: centred on their bounding
/// box, widened by 1 % so that surfaces on it are inside.
fn enclosing_sphere(spheres: &[(Vec3, f32)]) -> Vec4 {
    let (lo, hi) = spheres.iter().fold(
        (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
        |(lo, hi), (c, r)| (lo.min(*c - *r), hi.max(*c + *r)),
    );
    let center = 0.5 * (lo + hi);
    let radius = spheres
        .iter()
        .map(|(c, r)| (*c - center).length() + r)
        .fold(0.0, f32::max);
    center.extend(radius * 1.01)
}

impl Default for DepthPeelParams {
    fn default() -> Self {
        Self::DEFAULT
    }
}

const PARAMS: &[ParamSpec] = &[
    ParamSpec {
        name: "layers",
        doc: "surfaces of every refractor peeled from the eye, nearest first (1: the nearest surface only, as `single`; 2: front and back of one glass, as `wyman`)",
        kind: ParamKind::Integer {
            min: 1,
            max: MAX_PEEL_LAYERS,
        },
        default: "4",
    },
    ParamSpec {
        name: "max-interfaces",
        doc: "refractions and total internal reflections per path; a path that needs more looks up the environment along its last ray",
        kind: ParamKind::Integer {
            min: 1,
            max: MAX_PEEL_INTERFACES,
        },
        default: "8",
    },
    ParamSpec {
        name: "steps",
        doc: "samples of the linear search along each segment, from its start to where it leaves the refractors' bounding sphere (and along the last ray to the scene's); each crossing is then bisected 8 times",
        kind: ParamKind::Integer {
            min: 1,
            max: MAX_PEEL_STEPS,
        },
        default: "48",
    },
    ParamSpec {
        name: "thickness",
        doc: "the largest gap between the ray's view depth and a layer's at an accepted crossing, in thousandths of the refractors' bounding radius (a larger gap is a depth discontinuity the ray passed behind)",
        kind: ParamKind::Integer {
            min: 1,
            max: MAX_PEEL_THICKNESS_MILLI,
        },
        default: "50",
    },
    WAVELENGTHS_PARAM,
];

/// Per layer and pixel: the CPU's visibility buffer (8 bytes) and its unpacked depth, normal
/// and refractor (17 bytes), the GPU's three `Rgba32Float` targets being larger (48); plus the
/// screen texture of the engine family. Computed from the buffers' sizes, not measured.
const MEMORY: MemoryModel = MemoryModel {
    color_bytes_per_pixel: 47,
    layers_bytes_per_pixel: 275,
    texels: |params, width, height| {
        let layers = match params {
            MethodParams::DepthPeel(p) => u64::from(p.layers),
            _ => 0,
        };
        u64::from(width) * u64::from(height) * layers
    },
    bytes_per_texel: 25,
};

/// The row of the family.
pub(super) const ROWS: &[MethodInfo] = &[MethodInfo {
    id: MethodId::DepthPeel,
    name: "depth-peel",
    paper: "Everitt 2001 (depth peeling); Krueger et al. 2006 (layered search)",
    section: "docs/methods.md: depth-peel",
    family: Family::DepthPeel,
    summary: "every refractor's surfaces peeled into K layers; each eye ray refracted or reflected at every layer it crosses (linear search + bisection), then the opaque objects or the environment",
    params: PARAMS,
    aovs: &[
        Aov::Covered,
        Aov::P2,
        Aov::T2,
        Aov::TOut,
        Aov::PGeom,
        Aov::Interfaces,
        Aov::RefractorsMet,
        Aov::Tir,
        Aov::OffScreen,
        Aov::Miss,
    ],
    defaults: || MethodParams::DepthPeel(DepthPeelParams::DEFAULT),
    renders_conductors: false,
    memory: MEMORY,
    backends: CPU_AND_GPU,
}];

impl FamilyParams for DepthPeelParams {
    fn id(&self) -> MethodId {
        MethodId::DepthPeel
    }

    fn wavelengths(&self) -> Option<DispersionWavelengths> {
        Some(self.wavelengths)
    }

    fn apply(&mut self, name: &str, value: ParamValue) -> bool {
        if name == "wavelengths" {
            return self.wavelengths.apply(name, value);
        }
        let ParamValue::Integer(v) = value else {
            return false;
        };
        match name {
            "layers" => self.layers = v,
            "max-interfaces" => self.max_interfaces = v,
            "steps" => self.steps = v,
            "thickness" => self.thickness_milli = v,
            _ => return false,
        }
        true
    }

    fn get(&self, name: &str) -> Option<ParamValue> {
        Some(ParamValue::Integer(match name {
            "layers" => self.layers,
            "max-interfaces" => self.max_interfaces,
            "steps" => self.steps,
            "thickness" => self.thickness_milli,
            "wavelengths" => return self.wavelengths.get(name),
            _ => return None,
        }))
    }
}
