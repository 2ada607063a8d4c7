//! The reference's row and parameters: the exact ray tracer (`docs/reference.md`).

use super::{
    BackendId, Family, FamilyParams, MemoryModel, MethodId, MethodInfo, MethodParams, ParamKind,
    ParamSpec, ParamValue, choice_names, lookup, name_of,
};
use crate::frame::Aov;

/// Which light paths the reference follows.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum TraceMode {
    /// Only the refracted path (total internal reflection reflects): the apples-to-apples
    /// reference for image-space methods, which ignore Fresnel reflection.
    #[default]
    Transmission,
    /// Every interface splits by the exact Fresnel reflectance into a reflected and a refracted
    /// branch (deterministic splitting, no random walk).
    Full,
}

/// How the reference decides which side of a refractor interface a ray is on.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum InterfaceRule {
    /// Mitsuba 3's dielectric: the side from the interpolated shading normal
    /// (`cos θi = −d·N_s ≥ 0`: outside), Snell about that normal, and radiance scaled by
    /// `η² = (n_i/n_t)²` per refraction. With smooth normals the shading side can disagree with
    /// the geometric one on concave meshes, and there the `η²` factors do not cancel. The
    /// default, so the reference can be checked against Mitsuba.
    #[default]
    ShadingNormal,
    /// The side from the geometric normal, the shading normal flipped to it and turned past
    /// grazing if needed; no radiance scaling (it cancels for closed objects entered and left
    /// once).
    GeometricNormal,
}

/// Parameters of the reference tracer.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TraceSettings {
    /// Which paths are followed.
    pub mode: TraceMode,
    /// Refractor interactions allowed per path (1..=64); a path that needs more is black.
    pub max_depth: u32,
    /// Samples per pixel (1..=4096; 1 = the pixel centre).
    pub spp: u32,
    /// `Full` mode drops branches whose throughput falls below this.
    pub throughput_cutoff: f32,
    /// Which side of an interface a ray is on.
    pub interface: InterfaceRule,
}

impl TraceSettings {
    /// 1 sample per pixel at its centre, transmission, depth 8, Mitsuba's interface rule.
    pub const DEFAULT: Self = Self {
        mode: TraceMode::Transmission,
        max_depth: 8,
        spp: 1,
        throughput_cutoff: 1e-4,
        interface: InterfaceRule::ShadingNormal,
    };
}

/// The fewest samples per pixel the reference takes on a scene with rough surfaces in the
/// comparisons (`compare`, the default job, sweeps): its colour there is a Monte Carlo
/// estimate over microfacet normals (or, in a dispersive scene, over wavelengths), and one
/// sample is noise.
pub const ROUGH_MIN_SPP: u32 = 64;

impl TraceSettings {
    /// These settings for `scene`: the samples raised to [`ROUGH_MIN_SPP`] when the scene has
    /// a rough surface ([`crate::Scene::has_roughness`]) or dispersive glass
    /// ([`crate::Scene::has_dispersion`]).
    pub fn for_scene(self, scene: &crate::Scene) -> Self {
        if scene.has_roughness() || scene.has_dispersion() {
            Self {
                spp: self.spp.max(ROUGH_MIN_SPP),
                ..self
            }
        } else {
            self
        }
    }
}

impl Default for TraceSettings {
    fn default() -> Self {
        Self::DEFAULT
    }
}

const MODE_TABLE: [(&str, TraceMode); 2] = [
    ("transmission", TraceMode::Transmission),
    ("full", TraceMode::Full),
];
const MODE_CHOICES: [&str; 2] = choice_names(&MODE_TABLE);
const INTERFACE_TABLE: [(&str, InterfaceRule); 2] = [
    ("shading", InterfaceRule::ShadingNormal),
    ("geometric", InterfaceRule::GeometricNormal),
];
const INTERFACE_CHOICES: [&str; 2] = choice_names(&INTERFACE_TABLE);

const REFERENCE_PARAMS: &[ParamSpec] = &[
    ParamSpec {
        name: "mode",
        doc: "transmission: the refracted path only (TIR reflects); full: Fresnel splitting at every interface",
        kind: ParamKind::Choice(&MODE_CHOICES),
        default: "transmission",
    },
    ParamSpec {
        name: "depth",
        doc: "specular interactions per path (refractor interfaces, conductor reflections); a path that needs more is black",
        kind: ParamKind::Integer { min: 1, max: 64 },
        default: "8",
    },
    ParamSpec {
        name: "interface",
        doc: "which side of an interface a ray is on: shading (Mitsuba 3: from the shading normal, radiance × η² per refraction) or geometric (from the geometric normal, no η²)",
        kind: ParamKind::Choice(&INTERFACE_CHOICES),
        default: "shading",
    },
    ParamSpec {
        name: "spp",
        doc: "samples per pixel (1 = the pixel centre; more: stratified, box filter); comparisons raise it to 64 on scenes with rough surfaces",
        kind: ParamKind::Integer {
            min: 1,
            max: MAX_SPP,
        },
        default: "1",
    },
];

/// The reference's row.
pub(super) const ROWS: &[MethodInfo] = &[MethodInfo {
    id: MethodId::Reference,
    name: "reference",
    paper: "ground truth",
    section: "(docs/reference.md)",
    family: Family::Reference,
    summary: "exact recursive ray tracing through every refractor (BVH), nested media, absorption, the same shading normals",
    params: REFERENCE_PARAMS,
    aovs: &[
        Aov::Covered,
        Aov::P1,
        Aov::N1,
        Aov::T1,
        Aov::P2,
        Aov::N2,
        Aov::T2,
        Aov::TOut,
        Aov::PGeom,
        Aov::Interfaces,
        Aov::RefractorsMet,
        Aov::Tir,
        Aov::TirFirstExit,
    ],
    defaults: || MethodParams::Reference(TraceSettings::DEFAULT),
    renders_conductors: true,
    memory: MemoryModel::per_pixel(118, 243),
    // The GPU traces both modes at any sample count (refract_gpu::reference).
    backends: &[BackendId::Trace, BackendId::Gpu],
}];

impl FamilyParams for TraceSettings {
    fn id(&self) -> MethodId {
        MethodId::Reference
    }

    fn apply(&mut self, name: &str, value: ParamValue) -> bool {
        match (name, value) {
            ("mode", ParamValue::Choice(v)) => {
                lookup(&MODE_TABLE, v).map(|m| self.mode = m).is_some()
            }
            ("depth", ParamValue::Integer(v)) => {
                self.max_depth = v;
                true
            }
            ("interface", ParamValue::Choice(v)) => lookup(&INTERFACE_TABLE, v)
                .map(|i| self.interface = i)
                .is_some(),
            ("spp", ParamValue::Integer(v)) => {
                self.spp = v;
                true
            }
            _ => false,
        }
    }

    fn get(&self, name: &str) -> Option<ParamValue> {
        match name {
            "mode" => Some(ParamValue::Choice(name_of(&MODE_TABLE, &self.mode))),
            "depth" => Some(ParamValue::Integer(self.max_depth)),
            "interface" => Some(ParamValue::Choice(name_of(
                &INTERFACE_TABLE,
                &self.interface,
            ))),
            "spp" => Some(ParamValue::Integer(self.spp)),
            _ => None,
        }
    }
}

/// The most reference samples per pixel (`spp`): the bound the registry row, the CLI and sweep
/// files check.
pub const MAX_SPP: u32 = 4096;
