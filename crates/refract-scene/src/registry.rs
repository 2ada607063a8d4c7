//! The method registry: one table of every method (id, paper and section, family, parameters
//! with defaults and ranges, AOVs it writes, backends that run it), and [`MethodParams`], the
//! parameters of one run. The CLI, the report, the metrics and the tests iterate [`REGISTRY`];
//! adding a method is a row here and a [`MethodParams`] variant, which every backend's
//! exhaustive `match` then has to handle or decline.

use core::fmt;

use refract_core::kernel::ImageSpaceParams;
use refract_core::{BackSurface, DistanceMode, TirPolicy};

use crate::error::SceneError;
use crate::frame::Aov;
use crate::renderer::RenderError;

/// Every method, by its design.md id.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum MethodId {
    /// `reference`: the exact ray tracer.
    Reference,
    /// `single`: Wyman 2005a Table 1 "1-sided".
    Single,
    /// `wyman`: Wyman 2005a two interfaces, `d~` interpolated.
    Wyman,
    /// `wyman-dv`: the ablation `d~ = d_V`.
    WymanDv,
    /// `wyman-dn`: the ablation `d~ = d_N`.
    WymanDn,
}

/// A family of methods: the methods of one family share their passes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Family {
    /// Exact ray tracing (the ground truth).
    Reference,
    /// Wyman 2005a image-space refraction (front/back-face buffers, one kernel per pixel).
    ImageSpace,
}

/// A renderer implementation.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum BackendId {
    /// refract-cpu.
    Cpu,
    /// refract-gpu (wgpu/WGSL).
    Gpu,
    /// refract-trace, the exact reference.
    Trace,
}

impl BackendId {
    /// The id in file names, metrics and on the command line.
    pub const fn id(self) -> &'static str {
        match self {
            BackendId::Cpu => "cpu",
            BackendId::Gpu => "gpu",
            BackendId::Trace => "trace",
        }
    }
}

impl fmt::Display for BackendId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.id())
    }
}

/// The values a parameter takes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ParamKind {
    /// One of a list of names.
    Choice(&'static [&'static str]),
    /// An integer in `min..=max`.
    Integer {
        /// Smallest value.
        min: u32,
        /// Largest value.
        max: u32,
    },
}

/// One parameter of a method, as the CLI (`--param name=value`) and the report show it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ParamSpec {
    /// Its name.
    pub name: &'static str,
    /// What it does.
    pub doc: &'static str,
    /// Its values.
    pub kind: ParamKind,
    /// Its default, as text.
    pub default: &'static str,
}

/// One row of the registry.
#[derive(Clone, Copy, Debug)]
pub struct MethodInfo {
    /// The method.
    pub id: MethodId,
    /// Its design.md id (CLI, metrics, file names).
    pub name: &'static str,
    /// The paper.
    pub paper: &'static str,
    /// The section the implementation follows.
    pub section: &'static str,
    /// Its family.
    pub family: Family,
    /// One line on what it computes.
    pub summary: &'static str,
    /// Its parameters.
    pub params: &'static [ParamSpec],
    /// The AOV layers it writes beside the colour (with [`crate::FrameOutputs::ColorAndAovs`]).
    pub aovs: &'static [Aov],
    /// The backends that run it.
    pub backends: &'static [BackendId],
}

const TIR_CHOICES: &[&str] = &["clamp", "reflect", "black"];
const BACK_CHOICES: &[&str] = &["furthest", "second"];
const MODE_CHOICES: &[&str] = &["transmission", "full"];
const INTERFACE_CHOICES: &[&str] = &["shading", "geometric"];

const TWO_INTERFACE_PARAMS: &[ParamSpec] = &[
    ParamSpec {
        name: "back",
        doc: "back surface rasterised: the furthest (depth Greater) or the second (nearest back face), §3.2",
        kind: ParamKind::Choice(BACK_CHOICES),
        default: "furthest",
    },
    ParamSpec {
        name: "tir",
        doc: "total internal reflection at the exit: clamp to the critical angle (§3.3), reflect once, or black",
        kind: ParamKind::Choice(TIR_CHOICES),
        default: "clamp",
    },
];

const REFERENCE_PARAMS: &[ParamSpec] = &[
    ParamSpec {
        name: "mode",
        doc: "transmission: the refracted path only (TIR reflects); full: Fresnel splitting at every interface",
        kind: ParamKind::Choice(MODE_CHOICES),
        default: "transmission",
    },
    ParamSpec {
        name: "depth",
        doc: "refractor interactions per path; a path that needs more is black",
        kind: ParamKind::Integer { min: 1, max: 64 },
        default: "8",
    },
    ParamSpec {
        name: "interface",
        doc: "which side of an interface a ray is on: shading (Mitsuba 3: from the shading normal, radiance × η² per refraction) or geometric (from the geometric normal, no η²)",
        kind: ParamKind::Choice(INTERFACE_CHOICES),
        default: "shading",
    },
    ParamSpec {
        name: "spp",
        doc: "samples per pixel (1 = the pixel centre; more: stratified, box filter)",
        kind: ParamKind::Integer { min: 1, max: 4096 },
        default: "1",
    },
];

const TWO_INTERFACE_AOVS: &[Aov] = &[
    Aov::Covered,
    Aov::P2,
    Aov::N2,
    Aov::T2,
    Aov::ExitNormalSource,
    Aov::Tir,
];
const IMAGE_SPACE_BACKENDS: &[BackendId] = &[BackendId::Cpu, BackendId::Gpu];

/// Every method, in report order (the reference first).
pub const REGISTRY: [MethodInfo; 5] = [
    MethodInfo {
        id: MethodId::Reference,
        name: "reference",
        paper: "ground truth",
        section: "(docs/reference.md)",
        family: Family::Reference,
        summary: "exact recursive ray tracing through the mesh (BVH), the same shading normals",
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
            Aov::Tir,
            Aov::TirFirstExit,
        ],
        backends: &[BackendId::Trace],
    },
    MethodInfo {
        id: MethodId::Single,
        name: "single",
        paper: "Wyman 2005a",
        section: "Table 1 \"1-sided\"",
        family: Family::ImageSpace,
        summary: "refract once at P1, look T1 up in the environment",
        params: &[],
        aovs: &[Aov::Covered, Aov::T2, Aov::Tir],
        backends: IMAGE_SPACE_BACKENDS,
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
        backends: IMAGE_SPACE_BACKENDS,
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
        backends: IMAGE_SPACE_BACKENDS,
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
        backends: IMAGE_SPACE_BACKENDS,
    },
];

/// An unknown method id.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("unknown method `{0}`; expected one of: {names}", names = method_names())]
pub struct UnknownMethod(pub String);

/// The ids of the registry, comma-separated.
pub fn method_names() -> String {
    REGISTRY.map(|m| m.name).join(", ")
}

impl MethodId {
    /// Its registry row.
    pub fn info(self) -> &'static MethodInfo {
        // The registry is in enum order (tested).
        &REGISTRY[self as usize]
    }

    /// Its design.md id.
    pub fn name(self) -> &'static str {
        self.info().name
    }

    /// Every approximate method (all but the reference), in report order.
    pub fn approximations() -> impl Iterator<Item = MethodId> {
        REGISTRY
            .iter()
            .map(|m| m.id)
            .filter(|id| *id != MethodId::Reference)
    }
}

impl fmt::Display for MethodId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl core::str::FromStr for MethodId {
    type Err = UnknownMethod;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        REGISTRY
            .iter()
            .find(|m| m.name == s)
            .map(|m| m.id)
            .ok_or_else(|| UnknownMethod(s.to_owned()))
    }
}

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

impl Default for TraceSettings {
    fn default() -> Self {
        Self {
            mode: TraceMode::Transmission,
            max_depth: 8,
            spp: 1,
            throughput_cutoff: 1e-4,
            interface: InterfaceRule::ShadingNormal,
        }
    }
}

/// Parameters of the two-interface methods (`wyman`, `wyman-dv`, `wyman-dn`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct TwoInterfaceParams {
    /// How `d~` is approximated (fixed by the method id).
    pub distance: DistanceMode,
    /// Which back surface is rasterised.
    pub back: BackSurface,
    /// Total internal reflection at the exit.
    pub tir: TirPolicy,
}

/// The parameters of one run of one method: one variant per parameter set, so a backend's
/// exhaustive `match` decides, at compile time, what it does with every method.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum MethodParams {
    /// `reference`.
    Reference(TraceSettings),
    /// `single` (no parameters).
    Single,
    /// `wyman`, `wyman-dv`, `wyman-dn`.
    TwoInterface(TwoInterfaceParams),
}

fn choice<T: Copy>(
    name: &str,
    value: &str,
    table: &[(&str, T)],
    origin: &str,
) -> Result<T, SceneError> {
    table
        .iter()
        .find(|(n, _)| *n == value)
        .map(|(_, v)| *v)
        .ok_or_else(|| {
            let names: Vec<&str> = table.iter().map(|(n, _)| *n).collect();
            SceneError::field(origin, name, value, format!("one of {}", names.join(", ")))
        })
}

fn integer(name: &str, value: &str, min: u32, max: u32, origin: &str) -> Result<u32, SceneError> {
    value
        .trim()
        .parse::<u32>()
        .ok()
        .filter(|v| (min..=max).contains(v))
        .ok_or_else(|| {
            SceneError::field(
                origin,
                name,
                value,
                format!("an integer from {min} to {max}"),
            )
        })
}

const TIR_TABLE: [(&str, TirPolicy); 3] = [
    ("clamp", TirPolicy::ClampToCritical),
    ("reflect", TirPolicy::ReflectOnce),
    ("black", TirPolicy::Black),
];
const BACK_TABLE: [(&str, BackSurface); 2] = [
    ("furthest", BackSurface::Furthest),
    ("second", BackSurface::Second),
];
const INTERFACE_TABLE: [(&str, InterfaceRule); 2] = [
    ("shading", InterfaceRule::ShadingNormal),
    ("geometric", InterfaceRule::GeometricNormal),
];
const MODE_TABLE: [(&str, TraceMode); 2] = [
    ("transmission", TraceMode::Transmission),
    ("full", TraceMode::Full),
];

fn name_of<T: PartialEq>(table: &[(&'static str, T)], value: &T) -> &'static str {
    table
        .iter()
        .find(|(_, v)| v == value)
        .map_or("?", |(n, _)| n)
}

impl MethodParams {
    /// The default parameters of `id`.
    pub fn defaults(id: MethodId) -> Self {
        let two = |distance| {
            MethodParams::TwoInterface(TwoInterfaceParams {
                distance,
                ..TwoInterfaceParams::default()
            })
        };
        match id {
            MethodId::Reference => MethodParams::Reference(TraceSettings::default()),
            MethodId::Single => MethodParams::Single,
            MethodId::Wyman => two(DistanceMode::Interpolated),
            MethodId::WymanDv => two(DistanceMode::ViewOnly),
            MethodId::WymanDn => two(DistanceMode::NormalOnly),
        }
    }

    /// The method these parameters run.
    pub fn id(&self) -> MethodId {
        match self {
            MethodParams::Reference(_) => MethodId::Reference,
            MethodParams::Single => MethodId::Single,
            MethodParams::TwoInterface(p) => match p.distance {
                DistanceMode::Interpolated => MethodId::Wyman,
                DistanceMode::ViewOnly => MethodId::WymanDv,
                DistanceMode::NormalOnly => MethodId::WymanDn,
            },
        }
    }

    /// Sets parameter `name` (of the registry row) from text, checking its range; `origin`
    /// names where the value came from in the error.
    pub fn set(&mut self, name: &str, value: &str, origin: &str) -> Result<(), SceneError> {
        let unknown = |id: MethodId| {
            let names: Vec<&str> = id.info().params.iter().map(|p| p.name).collect();
            SceneError::field(
                origin,
                format!("{id} parameter"),
                name,
                if names.is_empty() {
                    "none: this method has no parameters".to_owned()
                } else {
                    format!("one of {}", names.join(", "))
                },
            )
        };
        let id = self.id();
        match self {
            MethodParams::Reference(settings) => match name {
                "mode" => settings.mode = choice(name, value, &MODE_TABLE, origin)?,
                "depth" => settings.max_depth = integer(name, value, 1, 64, origin)?,
                "interface" => settings.interface = choice(name, value, &INTERFACE_TABLE, origin)?,
                "spp" => settings.spp = integer(name, value, 1, 4096, origin)?,
                _ => return Err(unknown(id)),
            },
            MethodParams::Single => return Err(unknown(id)),
            MethodParams::TwoInterface(p) => match name {
                "back" => p.back = choice(name, value, &BACK_TABLE, origin)?,
                "tir" => p.tir = choice(name, value, &TIR_TABLE, origin)?,
                _ => return Err(unknown(id)),
            },
        }
        Ok(())
    }

    /// The value of parameter `name` as text, `None` for a name the method does not have.
    pub fn get(&self, name: &str) -> Option<String> {
        match (self, name) {
            (MethodParams::Reference(s), "mode") => Some(name_of(&MODE_TABLE, &s.mode).into()),
            (MethodParams::Reference(s), "depth") => Some(s.max_depth.to_string()),
            (MethodParams::Reference(s), "spp") => Some(s.spp.to_string()),
            (MethodParams::Reference(s), "interface") => {
                Some(name_of(&INTERFACE_TABLE, &s.interface).into())
            }
            (MethodParams::TwoInterface(p), "back") => Some(name_of(&BACK_TABLE, &p.back).into()),
            (MethodParams::TwoInterface(p), "tir") => Some(name_of(&TIR_TABLE, &p.tir).into()),
            _ => None,
        }
    }

    /// Sets the exit TIR policy where the method has one (no effect elsewhere).
    pub fn with_tir_policy(mut self, tir: TirPolicy) -> Self {
        if let MethodParams::TwoInterface(p) = &mut self {
            p.tir = tir;
        }
        self
    }

    /// The parameters of refract-core's image-space kernels for a refractor of index `ior`
    /// (`single` ignores the distance mode and exit policy), `None` for other methods.
    pub fn image_space_kernel(&self, ior: f32) -> Option<Result<ImageSpaceParams, RenderError>> {
        let (distance, tir) = match self {
            MethodParams::Single => (DistanceMode::Interpolated, TirPolicy::default()),
            MethodParams::TwoInterface(p) => (p.distance, p.tir),
            MethodParams::Reference(_) => return None,
        };
        Some(
            ImageSpaceParams::new(ior, distance, tir)
                .map_err(|err| RenderError::Parameter(err.to_string())),
        )
    }

    /// The back surface the method rasterises, `None` for methods without one.
    pub fn back_surface(&self) -> Option<BackSurface> {
        match self {
            MethodParams::TwoInterface(p) => Some(p.back),
            MethodParams::Single | MethodParams::Reference(_) => None,
        }
    }

    /// `name=value` of every parameter, for reports.
    pub fn describe(&self) -> String {
        self.id()
            .info()
            .params
            .iter()
            .filter_map(|p| self.get(p.name).map(|v| format!("{}={v}", p.name)))
            .collect::<Vec<_>>()
            .join(" ")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn registry_is_in_enum_order_and_ids_round_trip() {
        for (i, row) in REGISTRY.iter().enumerate() {
            assert_eq!(row.id as usize, i);
            assert_eq!(row.name.parse::<MethodId>(), Ok(row.id));
            assert_eq!(MethodParams::defaults(row.id).id(), row.id);
        }
        let err = "wyman-xx".parse::<MethodId>().expect_err("unknown");
        assert!(err.to_string().contains("single, wyman"), "{err}");
    }

    /// Every parameter of a registry row is one `MethodParams` knows, with the row's default,
    /// and every value of its range is accepted; a value outside is an error naming the field.
    #[test]
    fn registry_parameters_match_method_params() {
        for row in &REGISTRY {
            let mut params = MethodParams::defaults(row.id);
            for spec in row.params {
                assert_eq!(
                    params.get(spec.name).as_deref(),
                    Some(spec.default),
                    "{}",
                    row.name
                );
                match spec.kind {
                    ParamKind::Choice(values) => {
                        for v in values {
                            params.set(spec.name, v, "test").expect(v);
                            assert_eq!(params.get(spec.name).as_deref(), Some(*v));
                        }
                        let err = params.set(spec.name, "bogus", "test").expect_err("bogus");
                        assert!(err.to_string().contains(spec.name), "{err}");
                    }
                    ParamKind::Integer { min, max } => {
                        for v in [min, max] {
                            params
                                .set(spec.name, &v.to_string(), "test")
                                .expect("in range");
                        }
                        assert!(params.set(spec.name, &(max + 1).to_string(), "t").is_err());
                        assert!(params.set(spec.name, "-1", "t").is_err());
                    }
                }
                params
                    .set(spec.name, spec.default, "test")
                    .expect("default");
            }
            assert!(params.set("no-such-parameter", "1", "test").is_err());
            assert_eq!(params.id(), row.id, "setting parameters keeps the method");
        }
    }
}
