//! The row and parameters of Kakimoto et al. 2007's per-vertex reflection and refraction:
//! `pvrr`.

use super::{
    CPU_AND_GPU, Family, FamilyParams, MemoryModel, MethodId, MethodInfo, MethodParams, ParamKind,
    ParamSpec, ParamValue, choice_names, lookup, name_of,
};
use crate::frame::Aov;

/// The longest map side `pvrr` accepts (`res`).
pub const PVRR_RESOLUTION: (u32, u32) = (16, 4096);
/// The deepest reflection stack of `pvrr` (`depth`).
pub const MAX_PVRR_DEPTH: u32 = 4;
/// The largest index step between channels of `pvrr` (`dispersion`, in thousandths).
pub const MAX_PVRR_DISPERSION: u32 = 100;

const UPDATE_TABLE: [(&str, bool); 2] = [("every-frame", false), ("on-change", true)];
const UPDATE_CHOICES: [&str; 2] = choice_names(&UPDATE_TABLE);

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
        doc: "texels of a map's longer side (the other follows the view volume's aspect)",
        kind: ParamKind::Integer {
            min: PVRR_RESOLUTION.0,
            max: PVRR_RESOLUTION.1,
        },
        default: "1024",
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
];

const PVRR_AOVS: &[Aov] = &[Aov::Covered, Aov::Zoom];

/// Parameters of `pvrr` (Kakimoto et al. 2007).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct PvrrParams {
    /// Levels of the reflection stack (1..=[`MAX_PVRR_DEPTH`]).
    pub depth: u32,
    /// Texels of a map's longer side.
    pub resolution: u32,
    /// Index step between channels, thousandths (0..=[`MAX_PVRR_DISPERSION`]).
    pub dispersion: u32,
    /// Keep the per-vertex work while the camera is unchanged.
    pub update_on_change: bool,
}

impl PvrrParams {
    /// Three levels, 1024-texel maps, no dispersion, the plan made every frame.
    pub const DEFAULT: Self = Self {
        depth: 3,
        resolution: 1024,
        dispersion: 0,
        update_on_change: false,
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

    fn apply(&mut self, name: &str, value: ParamValue) -> bool {
        match (name, value) {
            ("depth", ParamValue::Integer(v)) => self.depth = v,
            ("res", ParamValue::Integer(v)) => self.resolution = v,
            ("dispersion", ParamValue::Integer(v)) => self.dispersion = v,
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
            "dispersion" => ParamValue::Integer(self.dispersion),
            "update" => ParamValue::Choice(name_of(&UPDATE_TABLE, &self.update_on_change)),
            _ => return None,
        })
    }
}
