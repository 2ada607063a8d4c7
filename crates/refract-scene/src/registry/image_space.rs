//! The rows and parameters of Wyman 2005a's image-space methods: `single`, `wyman` and its
//! ablations `wyman-dv`, `wyman-dn`.

use refract_core::kernel::ImageSpaceParams;
use refract_core::{BackSurface, DistanceMode, TirPolicy};

use super::{
    CPU_AND_GPU, DispersionWavelengths, Family, FamilyParams, MemoryModel, MethodId, MethodInfo,
    MethodParams, ParamKind, ParamSpec, ParamValue, WAVELENGTHS_PARAM, choice_names, lookup,
    name_of,
};
use crate::frame::Aov;
use crate::renderer::RenderError;

/// Parameters of the two-interface methods (`wyman`, `wyman-dv`, `wyman-dn`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct TwoInterfaceParams {
    /// How `d~` is approximated (fixed by the method id).
    pub distance: DistanceMode,
    /// Which back surface is rasterised.
    pub back: BackSurface,
    /// Total internal reflection at the exit.
    pub tir: TirPolicy,
    /// Wavelengths traced through a dispersive refractor.
    pub wavelengths: DispersionWavelengths,
}

impl TwoInterfaceParams {
    /// The parameters of refract-core's two-interface kernel for a refractor of index `ior`
    /// (an index out of range is [`RenderError::Parameter`]).
    pub fn kernel(&self, ior: f32) -> Result<ImageSpaceParams, RenderError> {
        ImageSpaceParams::new(ior, self.distance, self.tir)
            .map_err(|err| RenderError::Parameter(err.to_string()))
    }
}

/// An image-space method run: one interface, or two with their parameters.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ImageSpaceMethod {
    /// `single`: refract once at `P1`, look `T1` up (its only parameter: the wavelengths of a
    /// dispersive refractor).
    Single(DispersionWavelengths),
    /// `wyman`, `wyman-dv`, `wyman-dn`: two interfaces.
    TwoInterface(TwoInterfaceParams),
}

impl ImageSpaceMethod {
    const fn two(distance: DistanceMode) -> Self {
        Self::TwoInterface(TwoInterfaceParams {
            distance,
            back: BackSurface::Furthest,
            tir: TirPolicy::ClampToCritical,
            wavelengths: DispersionWavelengths::DEFAULT,
        })
    }

    /// The back surface rasterised, `None` for one interface.
    pub fn back_surface(&self) -> Option<BackSurface> {
        match self {
            ImageSpaceMethod::Single(_) => None,
            ImageSpaceMethod::TwoInterface(p) => Some(p.back),
        }
    }

    /// The kernel's parameters for a refractor of index `ior` (`single` ignores the distance
    /// mode and the exit policy).
    pub fn kernel(&self, ior: f32) -> Result<ImageSpaceParams, RenderError> {
        match self {
            ImageSpaceMethod::Single(_) => TwoInterfaceParams::default().kernel(ior),
            ImageSpaceMethod::TwoInterface(p) => p.kernel(ior),
        }
    }
}

pub(super) const TIR_TABLE: [(&str, TirPolicy); 3] = [
    ("clamp", TirPolicy::ClampToCritical),
    ("reflect", TirPolicy::ReflectOnce),
    ("black", TirPolicy::Black),
];
const TIR_CHOICES: [&str; 3] = choice_names(&TIR_TABLE);
pub(super) const BACK_TABLE: [(&str, BackSurface); 2] = [
    ("furthest", BackSurface::Furthest),
    ("second", BackSurface::Second),
];
const BACK_CHOICES: [&str; 2] = choice_names(&BACK_TABLE);

pub(super) const BACK_PARAM: ParamSpec = ParamSpec {
    name: "back",
    doc: "back surface rasterised: the furthest (depth Greater) or the second (nearest back face), §3.2",
    kind: ParamKind::Choice(&BACK_CHOICES),
    default: "furthest",
};
pub(super) const TIR_PARAM: ParamSpec = ParamSpec {
    name: "tir",
    doc: "total internal reflection at the exit: clamp to the critical angle (§3.3), reflect once, or black",
    kind: ParamKind::Choice(&TIR_CHOICES),
    default: "clamp",
};

const TWO_INTERFACE_PARAMS: &[ParamSpec] = &[BACK_PARAM, TIR_PARAM, WAVELENGTHS_PARAM];

pub(super) const TWO_INTERFACE_AOVS: &[Aov] = &[
    Aov::Covered,
    Aov::P2,
    Aov::N2,
    Aov::T2,
    Aov::ExitNormalSource,
    Aov::Tir,
];

/// The frame's buffers (measured, `docs/performance.md`) and, in a scene with opaque objects,
/// their pass from the eye at the frame's size (the engine family's screen texture, 40 bytes a
/// texel; counted for every scene: an upper bound where there are none).
const IMAGE_SPACE_MEMORY: MemoryModel = MemoryModel {
    color_bytes_per_pixel: 47,
    layers_bytes_per_pixel: 186,
    texels: |_, width, height| u64::from(width) * u64::from(height),
    bytes_per_texel: 40,
};

/// The rows of the family.
pub(super) const ROWS: &[MethodInfo] = &[
    MethodInfo {
        id: MethodId::Single,
        name: "single",
        paper: "Wyman 2005a",
        section: "Table 1 \"1-sided\"",
        family: Family::ImageSpace,
        summary: "refract once at P1, look T1 up in the environment",
        params: &[WAVELENGTHS_PARAM],
        aovs: &[Aov::Covered, Aov::T2, Aov::Tir],
        defaults: || {
            MethodParams::ImageSpace(ImageSpaceMethod::Single(DispersionWavelengths::DEFAULT))
        },
        renders_conductors: false,
        memory: IMAGE_SPACE_MEMORY,
        backends: CPU_AND_GPU,
    },
    MethodInfo {
        id: MethodId::Wyman,
        name: "wyman",
        paper: "Wyman 2005a",
        section: "§3-4",
        family: Family::ImageSpace,
        summary: "two interfaces: d~ = (θt/θi) d_V + (1 − θt/θi) d_N, N2 from the back-face buffer",
        params: TWO_INTERFACE_PARAMS,
        aovs: TWO_INTERFACE_AOVS,
        defaults: || MethodParams::ImageSpace(ImageSpaceMethod::two(DistanceMode::Interpolated)),
        renders_conductors: false,
        memory: IMAGE_SPACE_MEMORY,
        backends: CPU_AND_GPU,
    },
    MethodInfo {
        id: MethodId::WymanDv,
        name: "wyman-dv",
        paper: "Wyman 2005a",
        section: "§3.1 (ablation)",
        family: Family::ImageSpace,
        summary: "two interfaces with d~ = d_V",
        params: TWO_INTERFACE_PARAMS,
        aovs: TWO_INTERFACE_AOVS,
        defaults: || MethodParams::ImageSpace(ImageSpaceMethod::two(DistanceMode::ViewOnly)),
        renders_conductors: false,
        memory: IMAGE_SPACE_MEMORY,
        backends: CPU_AND_GPU,
    },
    MethodInfo {
        id: MethodId::WymanDn,
        name: "wyman-dn",
        paper: "Wyman 2005a",
        section: "§3.1 (ablation)",
        family: Family::ImageSpace,
        summary: "two interfaces with d~ = d_N",
        params: TWO_INTERFACE_PARAMS,
        aovs: TWO_INTERFACE_AOVS,
        defaults: || MethodParams::ImageSpace(ImageSpaceMethod::two(DistanceMode::NormalOnly)),
        renders_conductors: false,
        memory: IMAGE_SPACE_MEMORY,
        backends: CPU_AND_GPU,
    },
];

impl TwoInterfaceParams {
    /// Sets `back`, `tir` or `wavelengths` (shared with the nearby-geometry methods).
    pub(super) fn apply(&mut self, name: &str, value: ParamValue) -> bool {
        match (name, value) {
            ("wavelengths", _) => self.wavelengths.apply(name, value),
            ("back", ParamValue::Choice(v)) => {
                lookup(&BACK_TABLE, v).map(|b| self.back = b).is_some()
            }
            ("tir", ParamValue::Choice(v)) => lookup(&TIR_TABLE, v).map(|t| self.tir = t).is_some(),
            _ => false,
        }
    }

    /// `back`, `tir` or `wavelengths`.
    pub(super) fn get(&self, name: &str) -> Option<ParamValue> {
        match name {
            "wavelengths" => self.wavelengths.get(name),
            "back" => Some(ParamValue::Choice(name_of(&BACK_TABLE, &self.back))),
            "tir" => Some(ParamValue::Choice(name_of(&TIR_TABLE, &self.tir))),
            _ => None,
        }
    }
}

impl FamilyParams for ImageSpaceMethod {
    fn id(&self) -> MethodId {
        match self {
            ImageSpaceMethod::Single(_) => MethodId::Single,
            ImageSpaceMethod::TwoInterface(p) => match p.distance {
                DistanceMode::Interpolated => MethodId::Wyman,
                DistanceMode::ViewOnly => MethodId::WymanDv,
                DistanceMode::NormalOnly => MethodId::WymanDn,
            },
        }
    }

    fn apply(&mut self, name: &str, value: ParamValue) -> bool {
        match self {
            ImageSpaceMethod::Single(w) => w.apply(name, value),
            ImageSpaceMethod::TwoInterface(p) => p.apply(name, value),
        }
    }

    fn get(&self, name: &str) -> Option<ParamValue> {
        match self {
            ImageSpaceMethod::Single(w) => w.get(name),
            ImageSpaceMethod::TwoInterface(p) => p.get(name),
        }
    }

    fn wavelengths(&self) -> Option<DispersionWavelengths> {
        Some(match self {
            ImageSpaceMethod::Single(w) => *w,
            ImageSpaceMethod::TwoInterface(p) => p.wavelengths,
        })
    }
}
