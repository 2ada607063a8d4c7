//! The method registry: one table of every method (id, paper and section, family, parameters
//! with defaults and ranges, AOVs it writes, backends that run it), and [`MethodParams`], the
//! parameters of one run. The CLI, the report, the metrics and the tests iterate [`REGISTRY`].
//!
//! Each family has its own module here with its rows and its parameter type, which implements
//! [`FamilyParams`] (parameters set and read by name, checked against the rows' [`ParamSpec`]s:
//! names, ranges and choices are written once). Adding a family is its module, its methods'
//! [`MethodId`] variants and one line of `method_families!` (which declares its [`Family`] and
//! [`MethodParams`] variants and puts its `ROWS` in [`REGISTRY`]); every backend's exhaustive
//! `match` over [`MethodParams`] then has to handle or decline it.

use core::fmt;

use crate::error::SceneError;
use crate::frame::Aov;

mod depth_peel;
mod distance_map;
mod engine;
mod image_space;
mod nearby_geometry;
mod pvrr;
mod reference;
mod wavelengths;

pub use depth_peel::{
    DepthPeelParams, MAX_PEEL_INTERFACES, MAX_PEEL_STEPS, MAX_PEEL_THICKNESS_MILLI,
};
pub use distance_map::{
    DISTANCE_MAP_RESOLUTION, DistanceMapParams, MAX_LINEAR_STEPS, MAX_PATH_DEPTH, MAX_SECANT_STEPS,
};
pub use engine::{
    EngineMethod, EngineParams, MAX_SCALE_MILLI, MAX_THICKNESS_MILLI, ThicknessSource,
};
pub use image_space::{ImageSpaceMethod, TwoInterfaceParams};
pub use nearby_geometry::{MAX_GUARD_BAND_PERCENT, NearbyParams, seed_spacing};
pub use pvrr::{
    FOOTPRINT_TEXELS_PER_PIXEL, MAX_PVRR_DEPTH, MAX_PVRR_DISPERSION, MapSizing, PVRR_RESOLUTION,
    PvrrParams,
};
pub use reference::{InterfaceRule, MAX_SPP, ROUGH_MIN_SPP, TraceMode, TraceSettings};
pub use wavelengths::DispersionWavelengths;
use wavelengths::WAVELENGTHS_PARAM;

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
    /// `kay-greenberg`: Wyman 2005b §4.1, `P~2` projected into the NG texture.
    KayGreenberg,
    /// `ray-plane`: Wyman 2005b §4.2, the nearest plane hit projected into the NG texture.
    RayPlane,
    /// `iterative`: Wyman 2005b §4.3 (Ohbuchi), the plane hit refined with the NG depth.
    Iterative,
    /// `iterative-seeded`: Wyman 2005b §4.3, the best of `K` seeds refined with the NG depth.
    IterativeSeeded,
    /// `distance-map`: Umenhoffer et al. 2007, rays traced in layered distance cube maps.
    DistanceMap,
    /// `pvrr`: Kakimoto et al. 2007, per-vertex exact rays warping one map per reflector.
    Pvrr,
    /// `screen-offset`: Godot 4's refraction, the screen UV shifted by the view-space normal.
    ScreenOffset,
    /// `volume-thickness`: three.js / Bevy, `P + d T` projected into the screen texture.
    VolumeThickness,
    /// `proxy-sphere`: Unity HDRP's sphere model (Filament's `solid`).
    ProxySphere,
    /// `proxy-box`: Unity HDRP's box model.
    ProxyBox,
    /// `proxy-thin`: Unity HDRP's thin model (a 5 mm slab).
    ProxyThin,
    /// `depth-peel`: every refractor's surfaces depth-peeled, each ray followed through them.
    DepthPeel,
}

/// The one list of families: each line declares a [`Family`] variant (its name in lists and
/// the Python package), the [`MethodParams`] variant holding the family's parameter type, the
/// conversion `TryFrom<MethodParams>` for that type, the dispatch to its [`FamilyParams`] and
/// its registry rows in [`REGISTRY`]. A backend's exhaustive `match` over [`MethodParams`] then
/// fails to compile until it handles or declines the new family.
macro_rules! method_families {
    ($($(#[doc = $doc:literal])* $variant:ident($params:ty) = $name:literal, rows: $rows:path;)*) => {
        /// A family of methods: the methods of one family share their passes.
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
        pub enum Family {
            $($(#[doc = $doc])* $variant,)*
        }

        impl Family {
            /// Every family, in registry order.
            pub const ALL: &[Family] = &[$(Family::$variant),*];

            /// Its id in lists and the Python package (`image-space`, `nearby-geometry`, ...).
            pub const fn name(self) -> &'static str {
                match self {
                    $(Family::$variant => $name,)*
                }
            }
        }

        /// The parameters of one run of one method: one variant per family, so a backend's
        /// exhaustive `match` decides, at compile time, what it does with every family.
        #[derive(Clone, Copy, Debug, PartialEq)]
        pub enum MethodParams {
            $($(#[doc = $doc])* $variant($params),)*
        }

        // `TryFrom<MethodParams>` for each family's parameter type: its parameters, or the
        // parameters of another family back (the GPU builds one pipeline per row that converts).
        $(impl TryFrom<MethodParams> for $params {
            type Error = MethodParams;

            fn try_from(params: MethodParams) -> Result<Self, MethodParams> {
                match params {
                    MethodParams::$variant(p) => Ok(p),
                    other => Err(other),
                }
            }
        })*

        impl MethodParams {
            /// The family's parameter type behind these parameters.
            fn family(&self) -> &dyn FamilyParams {
                match self {
                    $(MethodParams::$variant(p) => p,)*
                }
            }

            fn family_mut(&mut self) -> &mut dyn FamilyParams {
                match self {
                    $(MethodParams::$variant(p) => p,)*
                }
            }

            /// The wavelengths a frame of a dispersive scene traces through the method's
            /// kernel ([`FamilyParams::wavelengths`]).
            pub fn wavelengths(&self) -> Option<DispersionWavelengths> {
                self.family().wavelengths()
            }

            /// The family these parameters belong to.
            pub fn family_id(&self) -> Family {
                match self {
                    $(MethodParams::$variant(_) => Family::$variant,)*
                }
            }
        }

        /// Every family's registry rows, in order.
        const FAMILY_ROWS: &[&[MethodInfo]] = &[$($rows),*];
    };
}

method_families! {
    /// Exact ray tracing (the ground truth): `reference`.
    Reference(TraceSettings) = "reference", rows: reference::ROWS;
    /// Wyman 2005a image-space refraction (front/back-face buffers, one kernel per pixel):
    /// `single`, `wyman`, `wyman-dv`, `wyman-dn`.
    ImageSpace(ImageSpaceMethod) = "image-space", rows: image_space::ROWS;
    /// Wyman 2005b: the two-interface kernel, then a lookup in the nearby-geometry (NG)
    /// texture rendered from the eye: `kay-greenberg`, `ray-plane`, `iterative`,
    /// `iterative-seeded`.
    NearbyGeometry(NearbyParams) = "nearby-geometry", rows: nearby_geometry::ROWS;
    /// Umenhoffer et al. 2007: layered distance cube maps around a reference point, searched
    /// per secondary ray (mirrors, metals, glass, several bounces): `distance-map`.
    DistanceMap(DistanceMapParams) = "distance-map", rows: distance_map::ROWS;
    /// Kakimoto et al. 2007: per-vertex exact rays (BVH), one map per reflector rendered from
    /// its virtual viewpoint, texture coordinates per vertex (mirrors, lenses, stacks): `pvrr`.
    Pvrr(PvrrParams) = "pvrr", rows: pvrr::ROWS;
    /// Today's engines (Godot, three.js, Bevy, Unity HDRP, Filament): one interface or a
    /// proxy shape, then a lookup in the screen texture of the opaque objects:
    /// `screen-offset`, `volume-thickness`, `proxy-sphere`, `proxy-box`, `proxy-thin`.
    Engine(EngineParams) = "engine", rows: engine::ROWS;
    /// Screen-space refraction through any number of interfaces: every refractor's surfaces
    /// depth-peeled into layers, each eye ray refracted at every layer it crosses:
    /// `depth-peel`.
    DepthPeel(DepthPeelParams) = "depth-peel", rows: depth_peel::ROWS;
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
    /// Its default parameters.
    pub defaults: fn() -> MethodParams,
    /// Whether it renders conductors (mirrors, metals) as the specular object or among the
    /// other objects; methods that do not refract through glass among diffuse objects only.
    pub renders_conductors: bool,
    /// What a frame of it holds in host memory (for refusing jobs that cannot fit).
    pub memory: MemoryModel,
    /// The backends that run it.
    pub backends: &'static [BackendId],
}

/// What a frame of a method holds in host memory, measured (peak resident memory, the slope
/// between two resolutions and two parameter values; `docs/performance.md`): bytes per pixel
/// of the frame, plus bytes per texel of the textures its parameters size (the NG texture,
/// distance maps, PVRR maps).
#[derive(Clone, Copy, Debug)]
pub struct MemoryModel {
    /// Bytes per pixel of a colour-only frame.
    pub color_bytes_per_pixel: u32,
    /// Bytes per pixel of a frame with its AOV layers.
    pub layers_bytes_per_pixel: u32,
    /// Texels of the textures `params` size for a `width × height` frame.
    pub texels: fn(&MethodParams, u32, u32) -> u64,
    /// Bytes per such texel.
    pub bytes_per_texel: u32,
}

impl MemoryModel {
    /// No textures beyond the frame's buffers.
    pub(crate) const fn per_pixel(color: u32, layers: u32) -> Self {
        Self {
            color_bytes_per_pixel: color,
            layers_bytes_per_pixel: layers,
            texels: |_, _, _| 0,
            bytes_per_texel: 0,
        }
    }

    /// The bytes of the textures `params` size for a `width × height` frame.
    pub fn texture_bytes(&self, params: &MethodParams, width: u32, height: u32) -> u64 {
        (self.texels)(params, width, height).saturating_mul(u64::from(self.bytes_per_texel))
    }

    /// The bytes of a `width × height` frame of `params`, with or without its layers.
    pub fn bytes(&self, params: &MethodParams, width: u32, height: u32, layers: bool) -> u64 {
        let per_pixel = if layers {
            self.layers_bytes_per_pixel
        } else {
            self.color_bytes_per_pixel
        };
        let pixels = u64::from(width) * u64::from(height);
        pixels
            .saturating_mul(u64::from(per_pixel))
            .saturating_add(self.texture_bytes(params, width, height))
    }
}

/// A parameter's value, checked against its [`ParamSpec`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ParamValue {
    /// One of the spec's choices.
    Choice(&'static str),
    /// An integer in the spec's range.
    Integer(u32),
}

impl fmt::Display for ParamValue {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ParamValue::Choice(name) => f.write_str(name),
            ParamValue::Integer(v) => write!(f, "{v}"),
        }
    }
}

impl ParamSpec {
    /// `text` as a value of this parameter: one of its choices or an integer in its range;
    /// `origin` names where the value came from in the error.
    pub fn parse(&self, text: &str, origin: &str) -> Result<ParamValue, SceneError> {
        match self.kind {
            ParamKind::Choice(choices) => choices
                .iter()
                .find(|c| **c == text)
                .map(|c| ParamValue::Choice(c))
                .ok_or_else(|| {
                    SceneError::field(
                        origin,
                        self.name,
                        text,
                        format!("one of {}", choices.join(", ")),
                    )
                }),
            ParamKind::Integer { min, max } => text
                .trim()
                .parse::<u32>()
                .ok()
                .filter(|v| (min..=max).contains(v))
                .map(ParamValue::Integer)
                .ok_or_else(|| {
                    SceneError::field(
                        origin,
                        self.name,
                        text,
                        format!("an integer from {min} to {max}"),
                    )
                }),
        }
    }
}

/// The parameter type of a family: its methods' parameters set and read by name. Values come
/// checked against the row's [`ParamSpec`] (so ranges and choices are written once, in the
/// specs); a test holds every row's specs and its family's type to each other.
pub trait FamilyParams {
    /// The method these parameters run.
    fn id(&self) -> MethodId;
    /// Sets parameter `name` to `value`; `false` for a name or value the method does not
    /// have (never for one of its row's specs: tested).
    fn apply(&mut self, name: &str, value: ParamValue) -> bool;
    /// The value of parameter `name`, `None` for a name the method does not have.
    fn get(&self, name: &str) -> Option<ParamValue>;
    /// What another parameter must be for `name` to be read (`"thickness=custom"`), `None`
    /// where `name` is read as the parameters stand: a value set for a parameter that is not
    /// read is refused by [`MethodParams::set_all`] rather than ignored.
    fn unread_unless(&self, name: &str) -> Option<&'static str> {
        let _ = name;
        None
    }
    /// The wavelengths a frame of a dispersive scene traces through the method's kernel,
    /// `None` for a method that disperses its own way or not at all (the engines, the
    /// reference).
    fn wavelengths(&self) -> Option<DispersionWavelengths> {
        None
    }
}

/// The names of a choice table, in its order (`const`, so that a [`ParamKind::Choice`] and the
/// table it is parsed with are one list).
pub(crate) const fn choice_names<T, const N: usize>(
    table: &[(&'static str, T); N],
) -> [&'static str; N] {
    let mut names = [""; N];
    let mut i = 0;
    while i < N {
        names[i] = table[i].0;
        i += 1;
    }
    names
}

/// The value of choice `name` in `table`.
pub(crate) fn lookup<T: Copy>(table: &[(&'static str, T)], name: &str) -> Option<T> {
    table.iter().find(|(n, _)| *n == name).map(|(_, v)| *v)
}

/// The name of `value` in `table`.
pub(crate) fn name_of<T: PartialEq>(table: &[(&'static str, T)], value: &T) -> &'static str {
    table
        .iter()
        .find(|(_, v)| v == value)
        .map_or("?", |(n, _)| n)
}

/// The backends of every method but the reference.
pub(crate) const CPU_AND_GPU: &[BackendId] = &[BackendId::Cpu, BackendId::Gpu];

const fn concat<const N: usize>(parts: &[&[MethodInfo]]) -> [MethodInfo; N] {
    let mut rows = [parts[0][0]; N];
    let (mut k, mut p) = (0, 0);
    while p < parts.len() {
        let mut i = 0;
        while i < parts[p].len() {
            rows[k] = parts[p][i];
            k += 1;
            i += 1;
        }
        p += 1;
    }
    assert!(k == N, "REGISTRY's length is the sum of the families' rows");
    rows
}

const fn row_count(parts: &[&[MethodInfo]]) -> usize {
    let (mut n, mut p) = (0, 0);
    while p < parts.len() {
        n += parts[p].len();
        p += 1;
    }
    n
}

/// Every method, in report order (the reference first): the families' rows in [`MethodId`]
/// order (tested).
pub const REGISTRY: [MethodInfo; row_count(FAMILY_ROWS)] = concat(FAMILY_ROWS);

/// Whether `method` can render `scene`, and why not: a row that does not render conductors
/// (the image-space and nearby-geometry families) refracts through glass among diffuse objects
/// only (the engine family and `depth-peel` draw every refractor, so all of them must be glass); the others (the reference, `distance-map`, `pvrr`) render mirrors and metals too.
pub fn scene_support(method: MethodId, scene: &crate::Scene) -> Result<(), String> {
    if method.info().renders_conductors {
        Ok(())
    } else if let Some(c) = scene.refractor.conductor() {
        Err(format!(
            "method `{method}` refracts through glass; the specular object of scene `{}` is a conductor ({})",
            scene.name,
            crate::scene::conductor_name(&c)
        ))
    } else if let Some(k) = matches!(method.info().family, Family::Engine | Family::DepthPeel)
        .then(|| scene.refractors().position(|r| r.conductor().is_some()))
        .flatten()
    {
        // The engine methods and depth-peel draw every refractor as glass.
        Err(format!(
            "method `{method}` draws every refractor as glass; refractor {k} of scene `{}` is a conductor",
            scene.name
        ))
    } else if let Some(k) = scene.objects.iter().position(|o| o.conductor().is_some()) {
        Err(format!(
            "method `{method}` shades opaque objects as diffuse; object {k} of scene `{}` is a conductor",
            scene.name
        ))
    } else {
        Ok(())
    }
}

/// An unknown method id.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("unknown method `{0}`; expected one of: {names}", names = method_names())]
pub struct UnknownMethod(pub String);

/// The ids of the registry, comma-separated.
pub fn method_names() -> String {
    REGISTRY
        .iter()
        .map(|m| m.name)
        .collect::<Vec<_>>()
        .join(", ")
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

impl MethodParams {
    /// The default parameters of `id` (its registry row's).
    pub fn defaults(id: MethodId) -> Self {
        (id.info().defaults)()
    }

    /// The method these parameters run.
    pub fn id(&self) -> MethodId {
        self.family().id()
    }

    /// Sets parameter `name` (of the registry row) from text, checked against the row's spec;
    /// `origin` names where the value came from in the error.
    pub fn set(&mut self, name: &str, value: &str, origin: &str) -> Result<(), SceneError> {
        let id = self.id();
        let unknown = || {
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
        let spec = id
            .info()
            .params
            .iter()
            .find(|p| p.name == name)
            .ok_or_else(unknown)?;
        let value = spec.parse(value, origin)?;
        if self.family_mut().apply(name, value) {
            Ok(())
        } else {
            Err(unknown())
        }
    }

    /// Sets every `(name, value)` of `assignments` as [`Self::set`] does, then refuses a
    /// parameter that the others leave unread (`thickness-milli` without `thickness=custom`),
    /// naming it and what it needs.
    pub fn set_all<'a>(
        &mut self,
        assignments: impl IntoIterator<Item = (&'a str, &'a str)> + Clone,
        origin: &str,
    ) -> Result<(), SceneError> {
        for (name, value) in assignments.clone() {
            self.set(name, value, origin)?;
        }
        for (name, value) in assignments {
            if let Some(needs) = self.family().unread_unless(name) {
                return Err(SceneError::field(
                    origin,
                    format!("{} parameter {name}", self.id()),
                    value,
                    format!("it is read only with {needs}; set that too"),
                ));
            }
        }
        Ok(())
    }

    /// The value of parameter `name` as text, `None` for a name the method does not have.
    pub fn get(&self, name: &str) -> Option<String> {
        self.family().get(name).map(|v| v.to_string())
    }

    /// Sets the exit TIR policy (the parameter `tir`) where the method has one (no effect
    /// elsewhere).
    pub fn with_tir_policy(mut self, tir: refract_core::TirPolicy) -> Self {
        if self.id().info().params.iter().any(|p| p.name == "tir") {
            let name = name_of(&image_space::TIR_TABLE, &tir);
            // A name of the table the `tir` spec's choices are made of: cannot fail.
            let _ = self.set("tir", name, "with_tir_policy");
        }
        self
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

    /// Issue 54 #22: `thickness-milli` without `thickness=custom` is refused by `set_all`
    /// (before, it was set and never read); with it, in either order, it is read.
    #[test]
    fn a_parameter_left_unread_is_refused() {
        let mut params = MethodParams::defaults(MethodId::VolumeThickness);
        let err = params
            .set_all([("thickness-milli", "500")], "--param")
            .expect_err("unread");
        assert!(
            err.to_string()
                .contains("thickness-milli = 500: it is read only with thickness=custom"),
            "{err}"
        );
        for order in [
            [("thickness-milli", "500"), ("thickness", "custom")],
            [("thickness", "custom"), ("thickness-milli", "500")],
        ] {
            let mut params = MethodParams::defaults(MethodId::VolumeThickness);
            params.set_all(order, "--param").expect("read");
            assert_eq!(params.get("thickness-milli").as_deref(), Some("500"));
        }
    }
}
