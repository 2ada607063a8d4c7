//! The rows and parameters of the engine family: the refraction that Godot, three.js, Bevy,
//! Unity HDRP and Filament ship (`screen-offset`, `volume-thickness`, `proxy-sphere`,
//! `proxy-box`, `proxy-thin`; `../shared/engine-methods.md`, [`refract_core::engine`]).

use refract_core::engine::{EngineModel, ProxyLookup, ProxyShape};

use super::{
    CPU_AND_GPU, Family, FamilyParams, MemoryModel, MethodId, MethodInfo, MethodParams, ParamKind,
    ParamSpec, ParamValue, choice_names, lookup, name_of,
};
use crate::frame::Aov;
use crate::scene::Refractor;

/// Which engine method, with its fixed choices.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum EngineMethod {
    /// `screen-offset` (Godot).
    ScreenOffset,
    /// `volume-thickness` (three.js, Bevy).
    VolumeThickness,
    /// `proxy-sphere` (Unity HDRP sphere, Filament solid).
    ProxySphere,
    /// `proxy-box` (Unity HDRP box).
    ProxyBox,
    /// `proxy-thin` (Unity HDRP thin).
    ProxyThin,
}

impl EngineMethod {
    /// Its model's code in the WGSL twin (`refract_core::engine::ENGINE_*`).
    pub fn model_code(self) -> u32 {
        use refract_core::engine::*;
        match self {
            EngineMethod::ScreenOffset => ENGINE_SCREEN_OFFSET,
            EngineMethod::VolumeThickness => ENGINE_VOLUME_THICKNESS,
            EngineMethod::ProxySphere => ENGINE_PROXY_SPHERE,
            EngineMethod::ProxyBox => ENGINE_PROXY_BOX,
            EngineMethod::ProxyThin => ENGINE_PROXY_THIN,
        }
    }
}

/// Where a method's thickness `d` comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ThicknessSource {
    /// The refractor's glTF `KHR_materials_volume` thickness (scaled as the engines scale it)
    /// when it has one, else the mean of its `d_N` (the engines' own default of three.js and
    /// Bevy, 0, means no refraction at all).
    Auto,
    /// The engine's default value ([`EngineParams::engine_thickness`]).
    Engine,
    /// [`EngineParams::thickness_milli`] thousandths of a scene unit.
    Custom,
}

/// Parameters of an engine method.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct EngineParams {
    /// The method.
    pub method: EngineMethod,
    /// Godot's `refraction_scale` in thousandths (`screen-offset`; 50 = Godot's 0.05).
    pub scale_milli: u32,
    /// Godot's depth guard (`screen-offset`) or Bevy's depth rejection (`volume-thickness`).
    pub depth_test: bool,
    /// Where the thickness comes from (`volume-thickness`, `proxy-sphere`, `proxy-box`).
    pub thickness: ThicknessSource,
    /// The thickness with [`ThicknessSource::Custom`], thousandths of a scene unit.
    pub thickness_milli: u32,
    /// The proxies' lookup (HDRP's or Filament's).
    pub lookup: ProxyLookup,
}

/// The largest `scale` (thousandths): 1 moves the sample by the whole screen.
pub const MAX_SCALE_MILLI: u32 = 1000;
/// The largest `thickness-milli`: 100 scene units (the refractor is normalised to the unit
/// sphere in the built-in scenes).
pub const MAX_THICKNESS_MILLI: u32 = 100_000;

impl EngineParams {
    fn of(method: EngineMethod) -> Self {
        Self {
            method,
            scale_milli: 50,
            depth_test: method == EngineMethod::ScreenOffset,
            thickness: ThicknessSource::Auto,
            thickness_milli: 1000,
            lookup: ProxyLookup::Hdrp,
        }
    }

    /// The engine's own default thickness: three.js and Bevy 0 (no offset), Unity HDRP 1.0
    /// (`_Thickness` in `Lit.shader`; Filament's `solid` default is 0.5), the thin model 5 mm.
    pub fn engine_thickness(&self) -> f32 {
        match self.method {
            EngineMethod::VolumeThickness | EngineMethod::ScreenOffset => 0.0,
            EngineMethod::ProxySphere | EngineMethod::ProxyBox => 1.0,
            EngineMethod::ProxyThin => refract_core::engine::THIN_THICKNESS,
        }
    }

    /// The thickness `d` in scene units for `refractor`.
    pub fn thickness_for(&self, refractor: &Refractor) -> f32 {
        match self.thickness {
            ThicknessSource::Auto => refractor.auto_thickness(),
            ThicknessSource::Engine => self.engine_thickness(),
            ThicknessSource::Custom => self.thickness_milli as f32 * 1e-3,
        }
    }

    /// The core model these parameters run on `refractor` (its code is
    /// [`EngineMethod::model_code`], tested).
    pub fn model(&self, refractor: &Refractor) -> EngineModel {
        let thickness = self.thickness_for(refractor);
        let proxy = |shape| EngineModel::Proxy {
            shape,
            thickness,
            lookup: self.lookup,
        };
        match self.method {
            EngineMethod::ScreenOffset => EngineModel::ScreenOffset {
                scale: self.scale_milli as f32 * 1e-3,
                depth_guard: self.depth_test,
            },
            EngineMethod::VolumeThickness => EngineModel::VolumeThickness {
                thickness,
                reject_nearer: self.depth_test,
            },
            EngineMethod::ProxySphere => proxy(ProxyShape::Sphere),
            EngineMethod::ProxyBox => proxy(ProxyShape::Box),
            EngineMethod::ProxyThin => proxy(ProxyShape::Thin),
        }
    }
}

const ON_OFF: [(&str, bool); 2] = [("on", true), ("off", false)];
const ON_OFF_CHOICES: [&str; 2] = choice_names(&ON_OFF);
const DEPTH_TEST: [(&str, bool); 2] = [("none", false), ("reject", true)];
const DEPTH_TEST_CHOICES: [&str; 2] = choice_names(&DEPTH_TEST);
const THICKNESS: [(&str, ThicknessSource); 3] = [
    ("auto", ThicknessSource::Auto),
    ("engine", ThicknessSource::Engine),
    ("custom", ThicknessSource::Custom),
];
const THICKNESS_CHOICES: [&str; 3] = choice_names(&THICKNESS);
const LOOKUP: [(&str, ProxyLookup); 2] = [
    ("hdrp", ProxyLookup::Hdrp),
    ("filament", ProxyLookup::Filament),
];
const LOOKUP_CHOICES: [&str; 2] = choice_names(&LOOKUP);

const SCALE_PARAM: ParamSpec = ParamSpec {
    name: "scale",
    doc: "Godot's refraction_scale in thousandths (50 = the engine's default 0.05): the screen UV moves by -n_view.xy times it",
    kind: ParamKind::Integer {
        min: 0,
        max: MAX_SCALE_MILLI,
    },
    default: "50",
};
const GUARD_PARAM: ParamSpec = ParamSpec {
    name: "depth-guard",
    doc: "Godot 4.x's depth guard: the offset fades back to the pixel's own UV where the sampled surface is less than one unit behind the glass",
    kind: ParamKind::Choice(&ON_OFF_CHOICES),
    default: "on",
};
const DEPTH_TEST_PARAM: ParamSpec = ParamSpec {
    name: "depth-test",
    doc: "none: three.js (samples in front of the glass show through; dispersive glass refracts each RGB channel with its own index); reject: Bevy (such samples become the environment along normalize(I + d T))",
    kind: ParamKind::Choice(&DEPTH_TEST_CHOICES),
    default: "none",
};
const THICKNESS_PARAM: ParamSpec = ParamSpec {
    name: "thickness",
    doc: "auto: the glTF KHR_materials_volume thickness (scaled with the object) or else the refractor's mean d_N; engine: the engine's default (three.js/Bevy 0, HDRP 1.0); custom: thickness-milli",
    kind: ParamKind::Choice(&THICKNESS_CHOICES),
    default: "auto",
};
const THICKNESS_MILLI_PARAM: ParamSpec = ParamSpec {
    name: "thickness-milli",
    doc: "the thickness with thickness=custom, thousandths of a scene unit",
    kind: ParamKind::Integer {
        min: 0,
        max: MAX_THICKNESS_MILLI,
    },
    default: "1000",
};
const LOOKUP_PARAM: ParamSpec = ParamSpec {
    name: "lookup",
    doc: "hdrp: the ray P1 + t R2 to the sky (65504) projected, faded at the screen's edges to the environment, the own texel where the hit is in front; filament: proj(P1) clamped, no depth test",
    kind: ParamKind::Choice(&LOOKUP_CHOICES),
    default: "hdrp",
};

const SCREEN_OFFSET_PARAMS: &[ParamSpec] = &[SCALE_PARAM, GUARD_PARAM];
const VOLUME_PARAMS: &[ParamSpec] = &[THICKNESS_PARAM, THICKNESS_MILLI_PARAM, DEPTH_TEST_PARAM];
const PROXY_PARAMS: &[ParamSpec] = &[THICKNESS_PARAM, THICKNESS_MILLI_PARAM, LOOKUP_PARAM];
const THIN_PARAMS: &[ParamSpec] = &[LOOKUP_PARAM];

const ENGINE_AOVS: &[Aov] = &[
    Aov::Covered,
    Aov::P2,
    Aov::T2,
    Aov::PGeom,
    Aov::NgTexel,
    Aov::OffScreen,
];

/// The opaque objects' surface pass at the frame's size (the nearby-geometry family's, 40
/// bytes a texel), for rough glass its colours mip-mapped (12 bytes a texel, 4/3 of the
/// frame's texels: 16 a pixel, counted for every scene), and the refractor's front faces; the
/// per-pixel figures are the nearby-geometry family's, whose passes these are a subset of (not
/// measured separately: an upper bound).
const ENGINE_MEMORY: MemoryModel = MemoryModel {
    color_bytes_per_pixel: 47,
    layers_bytes_per_pixel: 275,
    texels: |_, width, height| u64::from(width) * u64::from(height),
    bytes_per_texel: 56,
};

/// The engines that ship `screen-offset`.
const GODOT: &str = "scene/resources/material.cpp (BaseMaterial3D refraction); Unreal's IOR offset mode has the same shape";

/// The rows of the family.
pub(super) const ROWS: &[MethodInfo] = &[
    MethodInfo {
        id: MethodId::ScreenOffset,
        name: "screen-offset",
        paper: "engine: Godot 4",
        section: GODOT,
        family: Family::Engine,
        summary: "the screen UV shifted by -n_view.xy x refraction_scale; Godot 4.x's depth guard; no IOR, thickness or exit",
        params: SCREEN_OFFSET_PARAMS,
        aovs: ENGINE_AOVS,
        defaults: || MethodParams::Engine(EngineParams::of(EngineMethod::ScreenOffset)),
        renders_conductors: false,
        memory: ENGINE_MEMORY,
        backends: CPU_AND_GPU,
    },
    MethodInfo {
        id: MethodId::VolumeThickness,
        name: "volume-thickness",
        paper: "engine: three.js, Bevy",
        section: "three.js transmission_pars_fragment.glsl.js; Bevy pbr_transmission.wgsl (glTF KHR_materials_volume)",
        family: Family::Engine,
        summary: "refract once, walk thickness d along T, project P + d T into the opaque scene's screen texture; Bevy's depth rejection optional",
        params: VOLUME_PARAMS,
        aovs: ENGINE_AOVS,
        defaults: || MethodParams::Engine(EngineParams::of(EngineMethod::VolumeThickness)),
        renders_conductors: false,
        memory: ENGINE_MEMORY,
        backends: CPU_AND_GPU,
    },
    MethodInfo {
        id: MethodId::ProxySphere,
        name: "proxy-sphere",
        paper: "engine: Unity HDRP, Filament",
        section: "HDRP Refraction.hlsl RefractionModelSphere, Lit.hlsl; Filament surface_light_indirect.fs refractionSolidSphere",
        family: Family::Engine,
        summary: "exit from a tangent sphere of diameter d (P + T d cos θt, refracted there), then HDRP's proxy ray to the sky or Filament's proj(P1)",
        params: PROXY_PARAMS,
        aovs: ENGINE_AOVS,
        defaults: || MethodParams::Engine(EngineParams::of(EngineMethod::ProxySphere)),
        renders_conductors: false,
        memory: ENGINE_MEMORY,
        backends: CPU_AND_GPU,
    },
    MethodInfo {
        id: MethodId::ProxyBox,
        name: "proxy-box",
        paper: "engine: Unity HDRP",
        section: "Refraction.hlsl RefractionModelBox (_REFRACTION_PLANE), Lit.hlsl",
        family: Family::Engine,
        summary: "exit from a slab of thickness d (P + T d / cos θt, direction unchanged), then HDRP's proxy ray to the sky",
        params: PROXY_PARAMS,
        aovs: ENGINE_AOVS,
        defaults: || MethodParams::Engine(EngineParams::of(EngineMethod::ProxyBox)),
        renders_conductors: false,
        memory: ENGINE_MEMORY,
        backends: CPU_AND_GPU,
    },
    MethodInfo {
        id: MethodId::ProxyThin,
        name: "proxy-thin",
        paper: "engine: Unity HDRP",
        section: "Refraction.hlsl (REFRACTION_MODEL_THIN, 5 mm), Lit.hlsl",
        family: Family::Engine,
        summary: "the box model with a 5 mm slab: the direction unchanged, the exit nearly at the entry",
        params: THIN_PARAMS,
        aovs: ENGINE_AOVS,
        defaults: || MethodParams::Engine(EngineParams::of(EngineMethod::ProxyThin)),
        renders_conductors: false,
        memory: ENGINE_MEMORY,
        backends: CPU_AND_GPU,
    },
];

impl FamilyParams for EngineParams {
    fn id(&self) -> MethodId {
        match self.method {
            EngineMethod::ScreenOffset => MethodId::ScreenOffset,
            EngineMethod::VolumeThickness => MethodId::VolumeThickness,
            EngineMethod::ProxySphere => MethodId::ProxySphere,
            EngineMethod::ProxyBox => MethodId::ProxyBox,
            EngineMethod::ProxyThin => MethodId::ProxyThin,
        }
    }

    fn apply(&mut self, name: &str, value: ParamValue) -> bool {
        use EngineMethod::*;
        let thick = matches!(self.method, VolumeThickness | ProxySphere | ProxyBox);
        let proxy = matches!(self.method, ProxySphere | ProxyBox | ProxyThin);
        match (name, value) {
            ("scale", ParamValue::Integer(v)) if self.method == ScreenOffset => {
                self.scale_milli = v;
                true
            }
            ("depth-guard", ParamValue::Choice(v)) if self.method == ScreenOffset => {
                lookup(&ON_OFF, v).map(|b| self.depth_test = b).is_some()
            }
            ("depth-test", ParamValue::Choice(v)) if self.method == VolumeThickness => {
                lookup(&DEPTH_TEST, v)
                    .map(|b| self.depth_test = b)
                    .is_some()
            }
            ("thickness", ParamValue::Choice(v)) if thick => {
                lookup(&THICKNESS, v).map(|t| self.thickness = t).is_some()
            }
            ("thickness-milli", ParamValue::Integer(v)) if thick => {
                self.thickness_milli = v;
                true
            }
            ("lookup", ParamValue::Choice(v)) if proxy => {
                lookup(&LOOKUP, v).map(|l| self.lookup = l).is_some()
            }
            _ => false,
        }
    }

    fn get(&self, name: &str) -> Option<ParamValue> {
        use EngineMethod::*;
        let thick = matches!(self.method, VolumeThickness | ProxySphere | ProxyBox);
        let proxy = matches!(self.method, ProxySphere | ProxyBox | ProxyThin);
        Some(match name {
            "scale" if self.method == ScreenOffset => ParamValue::Integer(self.scale_milli),
            "depth-guard" if self.method == ScreenOffset => {
                ParamValue::Choice(name_of(&ON_OFF, &self.depth_test))
            }
            "depth-test" if self.method == VolumeThickness => {
                ParamValue::Choice(name_of(&DEPTH_TEST, &self.depth_test))
            }
            "thickness" if thick => ParamValue::Choice(name_of(&THICKNESS, &self.thickness)),
            "thickness-milli" if thick => ParamValue::Integer(self.thickness_milli),
            "lookup" if proxy => ParamValue::Choice(name_of(&LOOKUP, &self.lookup)),
            _ => return None,
        })
    }

    fn unread_unless(&self, name: &str) -> Option<&'static str> {
        (name == "thickness-milli" && self.thickness != ThicknessSource::Custom)
            .then_some("thickness=custom")
    }
}
