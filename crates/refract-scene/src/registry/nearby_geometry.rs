//! The rows and parameters of Wyman 2005b's nearby-geometry methods: `kay-greenberg`,
//! `ray-plane`, `iterative`, `iterative-seeded`.

use refract_core::nearby_geometry::{MAX_ITERATIONS, MAX_SEEDS, NearbyLookup, SeedSpacing};

use super::image_space::{BACK_PARAM, TIR_PARAM, TwoInterfaceParams};
use super::{
    CPU_AND_GPU, DispersionWavelengths, Family, FamilyParams, MemoryModel, MethodId, MethodInfo,
    MethodParams, ParamKind, ParamSpec, ParamValue, WAVELENGTHS_PARAM, choice_names, lookup,
    name_of,
};
use crate::frame::Aov;

/// Parameters of the nearby-geometry methods (`kay-greenberg`, `ray-plane`, `iterative`,
/// `iterative-seeded`): the two-interface kernel (`d~` interpolated, as in Wyman 2005b §3) and
/// the lookup in the NG texture.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct NearbyParams {
    /// The two-interface kernel's back surface and exit TIR policy (`distance` is `Interpolated`).
    pub two: TwoInterfaceParams,
    /// The lookup (fixed by the method id; its counts are parameters).
    pub lookup: NearbyLookup,
    /// Guard band of the NG texture, percent of the image size added on each side (0..=100).
    pub guard_band_percent: u32,
}

impl NearbyParams {
    /// The defaults of a method with `lookup`: `d~` interpolated, the furthest back surface,
    /// clamped TIR, no guard band.
    fn of(lookup: NearbyLookup) -> Self {
        Self {
            two: TwoInterfaceParams::default(),
            lookup,
            guard_band_percent: 0,
        }
    }
}

/// The largest guard band, in percent of the image size added on each side.
pub const MAX_GUARD_BAND_PERCENT: u32 = 100;

const SPACING_TABLE: [(&str, SeedSpacing); 2] = [
    ("screen", SeedSpacing::Screen),
    ("world", SeedSpacing::World),
];
const SPACING_CHOICES: [&str; 2] = choice_names(&SPACING_TABLE);

/// The seed spacing a `spacing` parameter value names (`screen`, `world`).
pub fn seed_spacing(name: &str) -> Option<SeedSpacing> {
    lookup(&SPACING_TABLE, name)
}

const GUARD_PARAM: ParamSpec = ParamSpec {
    name: "guard",
    doc: "NG guard band: percent of the image width/height added on each side of the NG texture (same texel size, wider view; 0 = the screen, as in the paper)",
    kind: ParamKind::Integer {
        min: 0,
        max: MAX_GUARD_BAND_PERCENT,
    },
    default: "0",
};
const ITERATIONS_PARAM: ParamSpec = ParamSpec {
    name: "iterations",
    doc: "distance updates at most (§4.3: \"typically fewer than five\"); stops early when the texel repeats",
    kind: ParamKind::Integer {
        min: 1,
        max: MAX_ITERATIONS,
    },
    default: "5",
};
const SEEDED_ITERATIONS_PARAM: ParamSpec = ParamSpec {
    name: "iterations",
    doc: "distance updates after seeding at most (0: the best seed's texel)",
    kind: ParamKind::Integer {
        min: 0,
        max: MAX_ITERATIONS,
    },
    default: "5",
};
const SEEDS_PARAM: ParamSpec = ParamSpec {
    name: "seeds",
    doc: "K, samples P~2 + α T~2 along the part of the ray inside the NG view (§4.3: 7)",
    kind: ParamKind::Integer {
        min: 1,
        max: MAX_SEEDS,
    },
    default: "7",
};
const SPACING_PARAM: ParamSpec = ParamSpec {
    name: "spacing",
    doc: "where the K seeds go: evenly on screen (in 1/depth, Fig. 9's assumption) or evenly in world distance α",
    kind: ParamKind::Choice(&SPACING_CHOICES),
    default: "screen",
};

const KAY_GREENBERG_PARAMS: &[ParamSpec] = &[BACK_PARAM, TIR_PARAM, GUARD_PARAM, WAVELENGTHS_PARAM];
const ITERATIVE_PARAMS: &[ParamSpec] = &[
    BACK_PARAM,
    TIR_PARAM,
    GUARD_PARAM,
    ITERATIONS_PARAM,
    WAVELENGTHS_PARAM,
];
const SEEDED_PARAMS: &[ParamSpec] = &[
    BACK_PARAM,
    TIR_PARAM,
    GUARD_PARAM,
    SEEDED_ITERATIONS_PARAM,
    SEEDS_PARAM,
    SPACING_PARAM,
    WAVELENGTHS_PARAM,
];

const NEARBY_AOVS: &[Aov] = &[
    Aov::Covered,
    Aov::P2,
    Aov::N2,
    Aov::T2,
    Aov::ExitNormalSource,
    Aov::Tir,
    Aov::PGeom,
    Aov::NgTexel,
];
const ITERATIVE_AOVS: &[Aov] = &[
    Aov::Covered,
    Aov::P2,
    Aov::N2,
    Aov::T2,
    Aov::ExitNormalSource,
    Aov::Tir,
    Aov::PGeom,
    Aov::NgTexel,
    Aov::Iterations,
    Aov::Converged,
];

/// The NG texture: the frame widened by the guard band on each side, 40 bytes a texel
/// (measured: `iterative-seeded` at guard 0 and 100, 315 and 635 bytes a pixel with layers).
const NEARBY_MEMORY: MemoryModel = MemoryModel {
    color_bytes_per_pixel: 47,
    layers_bytes_per_pixel: 275,
    texels: |params, width, height| {
        let guard = match params {
            MethodParams::NearbyGeometry(p) => u64::from(p.guard_band_percent),
            _ => 0,
        };
        let side = |n: u32| u64::from(n) * (100 + 2 * guard) / 100;
        side(width) * side(height)
    },
    bytes_per_texel: 40,
};

/// The rows of the family.
pub(super) const ROWS: &[MethodInfo] = &[
    MethodInfo {
        id: MethodId::KayGreenberg,
        name: "kay-greenberg",
        paper: "Wyman 2005b",
        section: "§4.1",
        family: Family::NearbyGeometry,
        summary: "wyman's P~2 projected into the nearby-geometry (NG) texture; the environment along T~2 where it is empty",
        params: KAY_GREENBERG_PARAMS,
        aovs: NEARBY_AOVS,
        defaults: || MethodParams::NearbyGeometry(NearbyParams::of(NearbyLookup::KayGreenberg)),
        renders_conductors: false,
        memory: NEARBY_MEMORY,
        backends: CPU_AND_GPU,
    },
    MethodInfo {
        id: MethodId::RayPlane,
        name: "ray-plane",
        paper: "Wyman 2005b",
        section: "§4.2",
        family: Family::NearbyGeometry,
        summary: "P~2 + t T~2 meets one plane per object (its own plane, or through its centre facing the camera); the nearest hit projected into NG",
        params: KAY_GREENBERG_PARAMS,
        aovs: NEARBY_AOVS,
        defaults: || MethodParams::NearbyGeometry(NearbyParams::of(NearbyLookup::RayPlane)),
        renders_conductors: false,
        memory: NEARBY_MEMORY,
        backends: CPU_AND_GPU,
    },
    MethodInfo {
        id: MethodId::Iterative,
        name: "iterative",
        paper: "Wyman 2005b",
        section: "§4.3 (Ohbuchi 2003)",
        family: Family::NearbyGeometry,
        summary: "from the plane hit, t <- |S(t) - P~2| with S the NG surface under P~2 + t T~2, until the texel repeats",
        params: ITERATIVE_PARAMS,
        aovs: ITERATIVE_AOVS,
        defaults: || {
            MethodParams::NearbyGeometry(NearbyParams::of(NearbyLookup::Iterative {
                iterations: 5,
            }))
        },
        renders_conductors: false,
        memory: NEARBY_MEMORY,
        backends: CPU_AND_GPU,
    },
    MethodInfo {
        id: MethodId::IterativeSeeded,
        name: "iterative-seeded",
        paper: "Wyman 2005b",
        section: "§4.3",
        family: Family::NearbyGeometry,
        summary: "K seeds along T~2 inside the NG view; the one whose depth best matches NG depth starts the iteration",
        params: SEEDED_PARAMS,
        aovs: ITERATIVE_AOVS,
        defaults: || {
            MethodParams::NearbyGeometry(NearbyParams::of(NearbyLookup::Seeded {
                iterations: 5,
                seeds: 7,
                spacing: SeedSpacing::Screen,
            }))
        },
        renders_conductors: false,
        memory: NEARBY_MEMORY,
        backends: CPU_AND_GPU,
    },
];

impl FamilyParams for NearbyParams {
    fn wavelengths(&self) -> Option<DispersionWavelengths> {
        Some(self.two.wavelengths)
    }

    fn id(&self) -> MethodId {
        match self.lookup {
            NearbyLookup::KayGreenberg => MethodId::KayGreenberg,
            NearbyLookup::RayPlane => MethodId::RayPlane,
            NearbyLookup::Iterative { .. } => MethodId::Iterative,
            NearbyLookup::Seeded { .. } => MethodId::IterativeSeeded,
        }
    }

    fn apply(&mut self, name: &str, value: ParamValue) -> bool {
        match (name, value, &mut self.lookup) {
            ("back" | "tir" | "wavelengths", ..) => self.two.apply(name, value),
            ("guard", ParamValue::Integer(v), _) => {
                self.guard_band_percent = v;
                true
            }
            (
                "iterations",
                ParamValue::Integer(v),
                NearbyLookup::Iterative { iterations } | NearbyLookup::Seeded { iterations, .. },
            ) => {
                *iterations = v;
                true
            }
            ("seeds", ParamValue::Integer(v), NearbyLookup::Seeded { seeds, .. }) => {
                *seeds = v;
                true
            }
            ("spacing", ParamValue::Choice(v), NearbyLookup::Seeded { spacing, .. }) => {
                lookup(&SPACING_TABLE, v).map(|s| *spacing = s).is_some()
            }
            _ => false,
        }
    }

    fn get(&self, name: &str) -> Option<ParamValue> {
        match (name, self.lookup) {
            ("back" | "tir" | "wavelengths", _) => self.two.get(name),
            ("guard", _) => Some(ParamValue::Integer(self.guard_band_percent)),
            (
                "iterations",
                NearbyLookup::Iterative { iterations } | NearbyLookup::Seeded { iterations, .. },
            ) => Some(ParamValue::Integer(iterations)),
            ("seeds", NearbyLookup::Seeded { seeds, .. }) => Some(ParamValue::Integer(seeds)),
            ("spacing", NearbyLookup::Seeded { spacing, .. }) => {
                Some(ParamValue::Choice(name_of(&SPACING_TABLE, &spacing)))
            }
            _ => None,
        }
    }
}
