//! The row and parameters of Kakimoto et al. 2007's per-vertex reflection and refraction:
//! `pvrr`.

use super::{
    CPU_AND_GPU, DispersionWavelengths, Family, FamilyParams, MemoryModel, MethodId, MethodInfo,
    MethodParams, ParamKind, ParamSpec, ParamValue, WAVELENGTHS_PARAM, choice_names, lookup,
    name_of,
};
use crate::frame::Aov;

/// The longest map side `pvrr` accepts (`res`).
pub const PVRR_RESOLUTION: (u32, u32) = (16, 4096);
/// The deepest reflection stack of `pvrr` (`depth`).
pub const MAX_PVRR_DEPTH: u32 = 4;
/// The largest index step between channels of `pvrr` (`dispersion`, in thousandths).
pub const MAX_PVRR_DISPERSION: u32 = 100;

/// Map texels per pixel of the reflector's footprint under `sizing=footprint`
/// ([`refract_core::pvrr::footprint_resolution`]): the smallest of 1, 2, 4 and 8 whose error
/// against the reference stays within 2 % relative FLIP of the fixed 1024-texel maps on every
/// scene of `pvrr`'s claims (`docs/claims.md`, B4). The reference samples each pixel at one
/// point; a bilinear lookup blurs over a texel, so the maps must be much finer than the pixels
/// (at 256², convex mirror: FLIP 0.0707, 0.0542, 0.0453, 0.0430 at 1, 2, 4, 8 against 0.0427
/// with 1024 texels; `docs/performance.md`).
pub const FOOTPRINT_TEXELS_PER_PIXEL: f32 = 8.0;

const UPDATE_TABLE: [(&str, bool); 2] = [("every-frame", false), ("on-change", true)];
const UPDATE_CHOICES: [&str; 2] = choice_names(&UPDATE_TABLE);

/// How a map's size is chosen.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum MapSizing {
    /// From the reflector's screen footprint in the view that looks the map up, at most `res`.
    Footprint,
    /// `res` texels on the longer side, whatever the reflector covers (the fixed size of
    /// previous versions and of the bench's paper rows).
    Fixed,
}

const SIZING_TABLE: [(&str, MapSizing); 2] = [
    ("footprint", MapSizing::Footprint),
    ("fixed", MapSizing::Fixed),
];
const SIZING_CHOICES: [&str; 2] = choice_names(&SIZING_TABLE);

const PVRR_PARAMS: &[ParamSpec] = &[
    ParamSpec {
        name: "depth",
        doc: "levels of the reflection stack (§4.4), the specular interactions of a path as the reference's depth counts them (a lens is one): 1 draws reflectors black inside a map, 2 gives each its own map from this map's virtual viewpoint, ...",
        kind: ParamKind::Integer {
            min: 1,
            max: MAX_PVRR_DEPTH,
        },
        default: "3",
    },
    ParamSpec {
        name: "res",
        doc: "texels of a map's longer side (the other follows the view volume's aspect): the size under sizing=fixed, the largest under sizing=footprint",
        kind: ParamKind::Integer {
            min: PVRR_RESOLUTION.0,
            max: PVRR_RESOLUTION.1,
        },
        default: "1024",
    },
    ParamSpec {
        name: "sizing",
        doc: "how a map's longer side is chosen: footprint (as many texels as the reflector covers pixels in the view that draws it, at most res, at least 16) or fixed (res texels)",
        kind: ParamKind::Choice(&SIZING_CHOICES),
        default: "footprint",
    },
    ParamSpec {
        name: "dispersion",
        doc: "chromatic aberration (§4.5, Fig. 15): R, G, B refract with ior - d/1000, ior, ior + d/1000 and share one map (10 at ior 1.61: the paper's 1.60/1.61/1.62); 0: one ray per vertex",
        kind: ParamKind::Integer {
            min: 0,
            max: MAX_PVRR_DISPERSION,
        },
        default: "0",
    },
    ParamSpec {
        name: "update",
        doc: "per-vertex rays, viewpoints and texture coordinates: every-frame, or on-change (kept while the camera is unchanged: the lens fixed to the eye, §5)",
        kind: ParamKind::Choice(&UPDATE_CHOICES),
        default: "every-frame",
    },
    WAVELENGTHS_PARAM,
];

const PVRR_AOVS: &[Aov] = &[Aov::Covered, Aov::Zoom];

/// Parameters of `pvrr` (Kakimoto et al. 2007).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct PvrrParams {
    /// Levels of the reflection stack (1..=[`MAX_PVRR_DEPTH`]).
    pub depth: u32,
    /// Texels of a map's longer side: the size under [`MapSizing::Fixed`], the largest under
    /// [`MapSizing::Footprint`].
    pub resolution: u32,
    /// How the map size is chosen.
    pub sizing: MapSizing,
    /// Index step between channels, thousandths (0..=[`MAX_PVRR_DISPERSION`]).
    pub dispersion: u32,
    /// Keep the per-vertex work while the camera is unchanged.
    pub update_on_change: bool,
    /// Wavelengths traced through a dispersive lens (each with [`Self::dispersion`]'s
    /// channels around its index).
    pub wavelengths: DispersionWavelengths,
}

impl PvrrParams {
    /// Three levels, maps sized from the footprint up to 1024 texels, no dispersion, the plan
    /// made every frame.
    pub const DEFAULT: Self = Self {
        depth: 3,
        resolution: 1024,
        sizing: MapSizing::Footprint,
        dispersion: 0,
        update_on_change: false,
        wavelengths: DispersionWavelengths::DEFAULT,
    };

    /// The indices of refraction of the R, G and B rays through a lens of index `ior`.
    pub fn channel_iors(&self, ior: f32) -> [f32; 3] {
        let d = self.dispersion as f32 * 1e-3;
        [ior - d, ior, ior + d]
    }
}

impl Default for PvrrParams {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// The row of the family.
pub(super) const ROWS: &[MethodInfo] = &[MethodInfo {
    id: MethodId::Pvrr,
    name: "pvrr",
    paper: "Kakimoto et al. 2007",
    section: "§3-4",
    family: Family::Pvrr,
    summary: "per-vertex exact rays (BVH) of each mirror or lens; one map per reflector from the least-squares virtual viewpoint; per-vertex texture coordinates; stacks, chromatic aberration",
    params: PVRR_PARAMS,
    aovs: PVRR_AOVS,
    defaults: || MethodParams::Pvrr(PvrrParams::DEFAULT),
    renders_conductors: true,
    memory: MemoryModel {
        color_bytes_per_pixel: 23,
        layers_bytes_per_pixel: 44,
        // One map per level of the stack and one more (scenes with several reflectors have
        // several per level: mirror-stack measured 3.4 maps at depth 3).
        texels: |params, _, _| match params {
            MethodParams::Pvrr(p) => u64::from(p.depth + 1) * u64::from(p.resolution).pow(2),
            _ => 0,
        },
        bytes_per_texel: 18,
    },
    backends: CPU_AND_GPU,
}];

impl FamilyParams for PvrrParams {
    fn id(&self) -> MethodId {
        MethodId::Pvrr
    }

    fn wavelengths(&self) -> Option<DispersionWavelengths> {
        Some(self.wavelengths)
    }

    fn apply(&mut self, name: &str, value: ParamValue) -> bool {
        match (name, value) {
            ("depth", ParamValue::Integer(v)) => self.depth = v,
            ("res", ParamValue::Integer(v)) => self.resolution = v,
            ("sizing", ParamValue::Choice(v)) => {
                return lookup(&SIZING_TABLE, v).map(|s| self.sizing = s).is_some();
            }
            ("dispersion", ParamValue::Integer(v)) => self.dispersion = v,
            ("wavelengths", _) => return self.wavelengths.apply(name, value),
            ("update", ParamValue::Choice(v)) => {
                return lookup(&UPDATE_TABLE, v)
                    .map(|u| self.update_on_change = u)
                    .is_some();
            }
            _ => return false,
        }
        true
    }

    fn get(&self, name: &str) -> Option<ParamValue> {
        Some(match name {
            "depth" => ParamValue::Integer(self.depth),
            "res" => ParamValue::Integer(self.resolution),
            "sizing" => ParamValue::Choice(name_of(&SIZING_TABLE, &self.sizing)),
            "dispersion" => ParamValue::Integer(self.dispersion),
            "wavelengths" => return self.wavelengths.get(name),
            "update" => ParamValue::Choice(name_of(&UPDATE_TABLE, &self.update_on_change)),
            _ => return None,
        })
    }
}
