//! The row and parameters of Umenhoffer et al. 2007's layered distance maps: `distance-map`.

use refract_core::distance_map::{DielectricFresnel, MAX_LAYERS, PathParams, SearchParams};

use super::{
    CPU_AND_GPU, DispersionWavelengths, Family, FamilyParams, MemoryModel, MethodId, MethodInfo,
    MethodParams, ParamKind, ParamSpec, ParamValue, WAVELENGTHS_PARAM, choice_names, lookup,
    name_of,
};
use crate::frame::Aov;

/// The largest linear-step count of the distance-map search.
pub const MAX_LINEAR_STEPS: u32 = 1024;
/// The largest secant-step count.
pub const MAX_SECANT_STEPS: u32 = 64;
/// The largest path depth of the distance-map method.
pub const MAX_PATH_DEPTH: u32 = 16;
/// The smallest and largest distance-map face resolution.
pub const DISTANCE_MAP_RESOLUTION: (u32, u32) = (8, 2048);

const ON_OFF_TABLE: [(&str, bool); 2] = [("on", true), ("off", false)];
const ON_OFF: [&str; 2] = choice_names(&ON_OFF_TABLE);
const FRESNEL_TABLE: [(&str, DielectricFresnel); 3] = [
    ("none", DielectricFresnel::Ignore),
    ("schlick", DielectricFresnel::Schlick),
    ("split", DielectricFresnel::Split),
];
const FRESNEL_CHOICES: [&str; 3] = choice_names(&FRESNEL_TABLE);

const DISTANCE_MAP_PARAMS: &[ParamSpec] = &[
    ParamSpec {
        name: "min-steps",
        doc: "fewest linear-search steps per layer (a short segment s → e), §17.2.1",
        kind: ParamKind::Integer {
            min: 1,
            max: MAX_LINEAR_STEPS,
        },
        default: "15",
    },
    ParamSpec {
        name: "max-steps",
        doc: "most linear-search steps per layer (a segment spanning 180° seen from the reference point)",
        kind: ParamKind::Integer {
            min: 1,
            max: MAX_LINEAR_STEPS,
        },
        default: "80",
    },
    ParamSpec {
        name: "secant",
        doc: "secant refinement steps at most (Listing 17-2's NITER; 0: the linear search's overshooting sample)",
        kind: ParamKind::Integer {
            min: 0,
            max: MAX_SECANT_STEPS,
        },
        default: "5",
    },
    ParamSpec {
        name: "depth",
        doc: "specular interactions per path, the visible surface included (Listing 17-5's MAXDEPTH); a path that needs more is black",
        kind: ParamKind::Integer {
            min: 1,
            max: MAX_PATH_DEPTH,
        },
        default: "2",
    },
    ParamSpec {
        name: "layers",
        doc: "distance-map layers: the specular object's front and back faces, then the other geometry in layers-2 depth-peeled layers (3: the chapter's implementation)",
        kind: ParamKind::Integer {
            min: 3,
            max: MAX_LAYERS as u32,
        },
        default: "3",
    },
    ParamSpec {
        name: "res",
        doc: "texels per cube-map face edge (the chapter: 512)",
        kind: ParamKind::Integer {
            min: DISTANCE_MAP_RESOLUTION.0,
            max: DISTANCE_MAP_RESOLUTION.1,
        },
        default: "512",
    },
    ParamSpec {
        name: "minmax",
        doc: "min-max acceleration (Figure 17-4): search each layer only between the spheres of its smallest and largest distance",
        kind: ParamKind::Choice(&ON_OFF),
        default: "on",
    },
    ParamSpec {
        name: "fresnel",
        doc: "glass: none (the refracted path, as the reference's transmission mode), schlick (Listing 17-5's 1 − F), split (also the F-weighted reflection at the first interface, Figure 17-9; compare with mode=full)",
        kind: ParamKind::Choice(&FRESNEL_CHOICES),
        default: "none",
    },
    WAVELENGTHS_PARAM,
];

const DISTANCE_MAP_AOVS: &[Aov] = &[
    Aov::Covered,
    Aov::HitLayer,
    Aov::LinearSteps,
    Aov::SecantSteps,
    Aov::Bounces,
    Aov::Miss,
    Aov::Tir,
];

/// Parameters of `distance-map` (Umenhoffer et al. 2007).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct DistanceMapParams {
    /// The search and the bounce loop.
    pub path: PathParams,
    /// Layers: 2 for the specular object, `layers − 2` depth-peeled for the rest (3..=8).
    pub layers: u32,
    /// Texels per face edge.
    pub resolution: u32,
    /// Wavelengths traced through a dispersive refractor.
    pub wavelengths: DispersionWavelengths,
}

impl DistanceMapParams {
    /// The chapter's setting (§17.4): 3 layers of 6 × 512², depth 2, 15 to 80 linear and 5
    /// secant steps with min-max, no dielectric Fresnel.
    pub const DEFAULT: Self = Self {
        path: PathParams {
            search: SearchParams {
                min_steps: 15,
                max_steps: 80,
                secant_steps: 5,
                min_max: true,
            },
            max_depth: 2,
            fresnel: DielectricFresnel::Ignore,
        },
        layers: 3,
        resolution: 512,
        wavelengths: DispersionWavelengths::DEFAULT,
    };
}

impl Default for DistanceMapParams {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// The row of the family.
pub(super) const ROWS: &[MethodInfo] = &[MethodInfo {
    id: MethodId::DistanceMap,
    name: "distance-map",
    paper: "Umenhoffer et al. 2007",
    section: "GPU Gems 3 §17.2-17.3",
    family: Family::DistanceMap,
    summary: "layered distance cube maps around the specular object's centre; linear search uniform in texture space + secant refinement; multiple reflection/refraction; Schlick Fresnel incl. metals",
    params: DISTANCE_MAP_PARAMS,
    aovs: DISTANCE_MAP_AOVS,
    defaults: || MethodParams::DistanceMap(DistanceMapParams::DEFAULT),
    renders_conductors: true,
    memory: MemoryModel {
        color_bytes_per_pixel: 23,
        layers_bytes_per_pixel: 99,
        texels: |params, _, _| match params {
            MethodParams::DistanceMap(p) => {
                6 * u64::from(p.layers) * u64::from(p.resolution).pow(2)
            }
            _ => 0,
        },
        bytes_per_texel: 13,
    },
    backends: CPU_AND_GPU,
}];

impl FamilyParams for DistanceMapParams {
    fn wavelengths(&self) -> Option<DispersionWavelengths> {
        Some(self.wavelengths)
    }

    fn id(&self) -> MethodId {
        MethodId::DistanceMap
    }

    fn apply(&mut self, name: &str, value: ParamValue) -> bool {
        let search = &mut self.path.search;
        match (name, value) {
            ("min-steps", ParamValue::Integer(v)) => search.min_steps = v,
            ("max-steps", ParamValue::Integer(v)) => search.max_steps = v,
            ("secant", ParamValue::Integer(v)) => search.secant_steps = v,
            ("minmax", ParamValue::Choice(v)) => {
                return lookup(&ON_OFF_TABLE, v)
                    .map(|m| search.min_max = m)
                    .is_some();
            }
            ("depth", ParamValue::Integer(v)) => self.path.max_depth = v,
            ("layers", ParamValue::Integer(v)) => self.layers = v,
            ("res", ParamValue::Integer(v)) => self.resolution = v,
            ("wavelengths", _) => return self.wavelengths.apply(name, value),
            ("fresnel", ParamValue::Choice(v)) => {
                return lookup(&FRESNEL_TABLE, v)
                    .map(|f| self.path.fresnel = f)
                    .is_some();
            }
            _ => return false,
        }
        true
    }

    fn get(&self, name: &str) -> Option<ParamValue> {
        let search = &self.path.search;
        Some(match name {
            "min-steps" => ParamValue::Integer(search.min_steps),
            "max-steps" => ParamValue::Integer(search.max_steps),
            "secant" => ParamValue::Integer(search.secant_steps),
            "minmax" => ParamValue::Choice(name_of(&ON_OFF_TABLE, &search.min_max)),
            "depth" => ParamValue::Integer(self.path.max_depth),
            "layers" => ParamValue::Integer(self.layers),
            "res" => ParamValue::Integer(self.resolution),
            "wavelengths" => return self.wavelengths.get(name),
            "fresnel" => ParamValue::Choice(name_of(&FRESNEL_TABLE, &self.path.fresnel)),
            _ => return None,
        })
    }
}
