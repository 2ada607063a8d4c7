//! The method registry: one table of every method (id, paper and section, family, parameters
//! with defaults and ranges, AOVs it writes, backends that run it), and [`MethodParams`], the
//! parameters of one run. The CLI, the report, the metrics and the tests iterate [`REGISTRY`];
//! adding a method is a row here and a [`MethodParams`] variant, which every backend's
//! exhaustive `match` then has to handle or decline.

use core::fmt;

use refract_core::distance_map::{DielectricFresnel, MAX_LAYERS, PathParams, SearchParams};
use refract_core::kernel::ImageSpaceParams;
use refract_core::nearby_geometry::{MAX_ITERATIONS, MAX_SEEDS, NearbyLookup, SeedSpacing};
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
}

/// A family of methods: the methods of one family share their passes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Family {
    /// Exact ray tracing (the ground truth).
    Reference,
    /// Wyman 2005a image-space refraction (front/back-face buffers, one kernel per pixel).
    ImageSpace,
    /// Wyman 2005b: the two-interface kernel, then a lookup in the nearby-geometry (NG)
    /// texture rendered from the eye.
    NearbyGeometry,
    /// Umenhoffer et al. 2007: layered distance cube maps around a reference point, searched
    /// per secondary ray (mirrors, metals, glass, several bounces).
    DistanceMap,
    /// Kakimoto et al. 2007: per-vertex exact rays (BVH), one map per reflector rendered from
    /// its virtual viewpoint, texture coordinates per vertex (mirrors, lenses, stacks).
    Pvrr,
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
const SPACING_CHOICES: &[&str] = &["screen", "world"];
const ON_OFF: &[&str] = &["on", "off"];
const FRESNEL_CHOICES: &[&str] = &["none", "schlick", "split"];

/// The largest linear-step count of the distance-map search.
pub const MAX_LINEAR_STEPS: u32 = 1024;
/// The largest secant-step count.
pub const MAX_SECANT_STEPS: u32 = 64;
/// The largest path depth of the distance-map method.
pub const MAX_PATH_DEPTH: u32 = 16;
/// The smallest and largest distance-map face resolution.
pub const DISTANCE_MAP_RESOLUTION: (u32, u32) = (8, 2048);

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
        kind: ParamKind::Choice(ON_OFF),
        default: "on",
    },
    ParamSpec {
        name: "fresnel",
        doc: "glass: none (the refracted path, as the reference's transmission mode), schlick (Listing 17-5's 1 − F), split (also the F-weighted reflection at the first interface, Figure 17-9; compare with mode=full)",
        kind: ParamKind::Choice(FRESNEL_CHOICES),
        default: "none",
    },
];

/// The longest map side `pvrr` accepts (`res`).
pub const PVRR_RESOLUTION: (u32, u32) = (16, 4096);
/// The deepest reflection stack of `pvrr` (`depth`).
pub const MAX_PVRR_DEPTH: u32 = 4;
/// The largest index step between channels of `pvrr` (`dispersion`, in thousandths).
pub const MAX_PVRR_DISPERSION: u32 = 100;

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
        kind: ParamKind::Choice(UPDATE_CHOICES),
        default: "every-frame",
    },
];

const UPDATE_CHOICES: &[&str] = &["every-frame", "on-change"];

const PVRR_AOVS: &[Aov] = &[Aov::Covered, Aov::Zoom];

const DISTANCE_MAP_AOVS: &[Aov] = &[
    Aov::Covered,
    Aov::HitLayer,
    Aov::LinearSteps,
    Aov::SecantSteps,
    Aov::Bounces,
    Aov::Miss,
    Aov::Tir,
];

/// The largest guard band, in percent of the image size added on each side.
pub const MAX_GUARD_BAND_PERCENT: u32 = 100;

const BACK_PARAM: ParamSpec = ParamSpec {
    name: "back",
    doc: "back surface rasterised: the furthest (depth Greater) or the second (nearest back face), §3.2",
    kind: ParamKind::Choice(BACK_CHOICES),
    default: "furthest",
};
const TIR_PARAM: ParamSpec = ParamSpec {
    name: "tir",
    doc: "total internal reflection at the exit: clamp to the critical angle (§3.3), reflect once, or black",
    kind: ParamKind::Choice(TIR_CHOICES),
    default: "clamp",
};
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
    kind: ParamKind::Choice(SPACING_CHOICES),
    default: "screen",
};

const KAY_GREENBERG_PARAMS: &[ParamSpec] = &[BACK_PARAM, TIR_PARAM, GUARD_PARAM];
const ITERATIVE_PARAMS: &[ParamSpec] = &[BACK_PARAM, TIR_PARAM, GUARD_PARAM, ITERATIONS_PARAM];
const SEEDED_PARAMS: &[ParamSpec] = &[
    BACK_PARAM,
    TIR_PARAM,
    GUARD_PARAM,
    SEEDED_ITERATIONS_PARAM,
    SEEDS_PARAM,
    SPACING_PARAM,
];

const TWO_INTERFACE_PARAMS: &[ParamSpec] = &[BACK_PARAM, TIR_PARAM];

const REFERENCE_PARAMS: &[ParamSpec] = &[
    ParamSpec {
        name: "mode",
        doc: "transmission: the refracted path only (TIR reflects); full: Fresnel splitting at every interface",
        kind: ParamKind::Choice(MODE_CHOICES),
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

/// Every method, in report order (the reference first).
pub const REGISTRY: [MethodInfo; 11] = [
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
    MethodInfo {
        id: MethodId::KayGreenberg,
        name: "kay-greenberg",
        paper: "Wyman 2005b",
        section: "§4.1",
        family: Family::NearbyGeometry,
        summary: "wyman's P~2 projected into the nearby-geometry (NG) texture; the environment along T~2 where it is empty",
        params: KAY_GREENBERG_PARAMS,
        aovs: NEARBY_AOVS,
        backends: IMAGE_SPACE_BACKENDS,
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
        backends: IMAGE_SPACE_BACKENDS,
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
        backends: IMAGE_SPACE_BACKENDS,
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
        backends: IMAGE_SPACE_BACKENDS,
    },
    MethodInfo {
        id: MethodId::DistanceMap,
        name: "distance-map",
        paper: "Umenhoffer et al. 2007",
        section: "GPU Gems 3 §17.2-17.3",
        family: Family::DistanceMap,
        summary: "layered distance cube maps around the specular object's centre; linear search uniform in texture space + secant refinement; multiple reflection/refraction; Schlick Fresnel incl. metals",
        params: DISTANCE_MAP_PARAMS,
        aovs: DISTANCE_MAP_AOVS,
        backends: IMAGE_SPACE_BACKENDS,
    },
    MethodInfo {
        id: MethodId::Pvrr,
        name: "pvrr",
        paper: "Kakimoto et al. 2007",
        section: "§3-4",
        family: Family::Pvrr,
        summary: "per-vertex exact rays (BVH) of each mirror or lens; one map per reflector from the least-squares virtual viewpoint; per-vertex texture coordinates; stacks, chromatic aberration",
        params: PVRR_PARAMS,
        aovs: PVRR_AOVS,
        backends: IMAGE_SPACE_BACKENDS,
    },
];

/// Whether `method` can render `scene`, and why not: the image-space and nearby-geometry
/// families refract through glass among diffuse objects only; the reference and the
/// distance-map method render conductors (mirrors, metals) too.
pub fn scene_support(method: MethodId, scene: &crate::Scene) -> Result<(), String> {
    match method.info().family {
        Family::Reference | Family::DistanceMap | Family::Pvrr => Ok(()),
        Family::ImageSpace | Family::NearbyGeometry => {
            if let Some(c) = scene.refractor.conductor() {
                Err(format!(
                    "method `{method}` refracts through glass; the specular object of scene `{}` is a conductor ({})",
                    scene.name,
                    crate::scene::conductor_name(&c)
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
    }
}

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

impl TwoInterfaceParams {
    /// The parameters of refract-core's two-interface kernel for a refractor of index `ior`
    /// (an index out of range is [`RenderError::Parameter`]).
    pub fn kernel(&self, ior: f32) -> Result<ImageSpaceParams, RenderError> {
        ImageSpaceParams::new(ior, self.distance, self.tir)
            .map_err(|err| RenderError::Parameter(err.to_string()))
    }
}

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

/// Parameters of `distance-map` (Umenhoffer et al. 2007).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct DistanceMapParams {
    /// The search and the bounce loop.
    pub path: PathParams,
    /// Layers: 2 for the specular object, `layers − 2` depth-peeled for the rest (3..=8).
    pub layers: u32,
    /// Texels per face edge.
    pub resolution: u32,
}

impl Default for DistanceMapParams {
    /// The chapter's setting (§17.4): 3 layers of 6 × 512², depth 2, with min-max.
    fn default() -> Self {
        Self {
            path: PathParams::default(),
            layers: 3,
            resolution: 512,
        }
    }
}

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

impl Default for PvrrParams {
    fn default() -> Self {
        Self {
            depth: 3,
            resolution: 1024,
            dispersion: 0,
            update_on_change: false,
        }
    }
}

impl PvrrParams {
    /// The indices of refraction of the R, G and B rays through a lens of index `ior`.
    pub fn channel_iors(&self, ior: f32) -> [f32; 3] {
        let d = self.dispersion as f32 * 1e-3;
        [ior - d, ior, ior + d]
    }
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
    /// `kay-greenberg`, `ray-plane`, `iterative`, `iterative-seeded`.
    NearbyGeometry(NearbyParams),
    /// `distance-map`.
    DistanceMap(DistanceMapParams),
    /// `pvrr`.
    Pvrr(PvrrParams),
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
const SPACING_TABLE: [(&str, SeedSpacing); 2] = [
    ("screen", SeedSpacing::Screen),
    ("world", SeedSpacing::World),
];
const ON_OFF_TABLE: [(&str, bool); 2] = [("on", true), ("off", false)];
const FRESNEL_TABLE: [(&str, DielectricFresnel); 3] = [
    ("none", DielectricFresnel::Ignore),
    ("schlick", DielectricFresnel::Schlick),
    ("split", DielectricFresnel::Split),
];
const UPDATE_TABLE: [(&str, bool); 2] = [("every-frame", false), ("on-change", true)];
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
        let nearby = |lookup| {
            MethodParams::NearbyGeometry(NearbyParams {
                two: TwoInterfaceParams::default(),
                lookup,
                guard_band_percent: 0,
            })
        };
        match id {
            MethodId::Reference => MethodParams::Reference(TraceSettings::default()),
            MethodId::Single => MethodParams::Single,
            MethodId::Wyman => two(DistanceMode::Interpolated),
            MethodId::WymanDv => two(DistanceMode::ViewOnly),
            MethodId::WymanDn => two(DistanceMode::NormalOnly),
            MethodId::KayGreenberg => nearby(NearbyLookup::KayGreenberg),
            MethodId::RayPlane => nearby(NearbyLookup::RayPlane),
            MethodId::Iterative => nearby(NearbyLookup::Iterative { iterations: 5 }),
            MethodId::IterativeSeeded => nearby(NearbyLookup::Seeded {
                iterations: 5,
                seeds: 7,
                spacing: SeedSpacing::Screen,
            }),
            MethodId::DistanceMap => MethodParams::DistanceMap(DistanceMapParams::default()),
            MethodId::Pvrr => MethodParams::Pvrr(PvrrParams::default()),
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
            MethodParams::NearbyGeometry(p) => match p.lookup {
                NearbyLookup::KayGreenberg => MethodId::KayGreenberg,
                NearbyLookup::RayPlane => MethodId::RayPlane,
                NearbyLookup::Iterative { .. } => MethodId::Iterative,
                NearbyLookup::Seeded { .. } => MethodId::IterativeSeeded,
            },
            MethodParams::DistanceMap(_) => MethodId::DistanceMap,
            MethodParams::Pvrr(_) => MethodId::Pvrr,
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
            MethodParams::NearbyGeometry(p) => match (name, &mut p.lookup) {
                ("back", _) => p.two.back = choice(name, value, &BACK_TABLE, origin)?,
                ("tir", _) => p.two.tir = choice(name, value, &TIR_TABLE, origin)?,
                ("guard", _) => {
                    p.guard_band_percent = integer(name, value, 0, MAX_GUARD_BAND_PERCENT, origin)?;
                }
                ("iterations", NearbyLookup::Iterative { iterations }) => {
                    *iterations = integer(name, value, 1, MAX_ITERATIONS, origin)?;
                }
                ("iterations", NearbyLookup::Seeded { iterations, .. }) => {
                    *iterations = integer(name, value, 0, MAX_ITERATIONS, origin)?;
                }
                ("seeds", NearbyLookup::Seeded { seeds, .. }) => {
                    *seeds = integer(name, value, 1, MAX_SEEDS, origin)?;
                }
                ("spacing", NearbyLookup::Seeded { spacing, .. }) => {
                    *spacing = choice(name, value, &SPACING_TABLE, origin)?;
                }
                _ => return Err(unknown(id)),
            },
            MethodParams::DistanceMap(p) => {
                let search: &mut SearchParams = &mut p.path.search;
                match name {
                    "min-steps" => {
                        search.min_steps = integer(name, value, 1, MAX_LINEAR_STEPS, origin)?;
                    }
                    "max-steps" => {
                        search.max_steps = integer(name, value, 1, MAX_LINEAR_STEPS, origin)?;
                    }
                    "secant" => {
                        search.secant_steps = integer(name, value, 0, MAX_SECANT_STEPS, origin)?;
                    }
                    "minmax" => search.min_max = choice(name, value, &ON_OFF_TABLE, origin)?,
                    "depth" => p.path.max_depth = integer(name, value, 1, MAX_PATH_DEPTH, origin)?,
                    "layers" => p.layers = integer(name, value, 3, MAX_LAYERS as u32, origin)?,
                    "res" => {
                        let (lo, hi) = DISTANCE_MAP_RESOLUTION;
                        p.resolution = integer(name, value, lo, hi, origin)?;
                    }
                    "fresnel" => p.path.fresnel = choice(name, value, &FRESNEL_TABLE, origin)?,
                    _ => return Err(unknown(id)),
                }
            }
            MethodParams::Pvrr(p) => match name {
                "depth" => p.depth = integer(name, value, 1, MAX_PVRR_DEPTH, origin)?,
                "res" => {
                    let (lo, hi) = PVRR_RESOLUTION;
                    p.resolution = integer(name, value, lo, hi, origin)?;
                }
                "dispersion" => {
                    p.dispersion = integer(name, value, 0, MAX_PVRR_DISPERSION, origin)?;
                }
                "update" => p.update_on_change = choice(name, value, &UPDATE_TABLE, origin)?,
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
            (MethodParams::NearbyGeometry(p), _) => match (name, p.lookup) {
                ("back", _) => Some(name_of(&BACK_TABLE, &p.two.back).into()),
                ("tir", _) => Some(name_of(&TIR_TABLE, &p.two.tir).into()),
                ("guard", _) => Some(p.guard_band_percent.to_string()),
                ("iterations", NearbyLookup::Iterative { iterations })
                | ("iterations", NearbyLookup::Seeded { iterations, .. }) => {
                    Some(iterations.to_string())
                }
                ("seeds", NearbyLookup::Seeded { seeds, .. }) => Some(seeds.to_string()),
                ("spacing", NearbyLookup::Seeded { spacing, .. }) => {
                    Some(name_of(&SPACING_TABLE, &spacing).into())
                }
                _ => None,
            },
            (MethodParams::DistanceMap(p), _) => match name {
                "min-steps" => Some(p.path.search.min_steps.to_string()),
                "max-steps" => Some(p.path.search.max_steps.to_string()),
                "secant" => Some(p.path.search.secant_steps.to_string()),
                "minmax" => Some(name_of(&ON_OFF_TABLE, &p.path.search.min_max).into()),
                "depth" => Some(p.path.max_depth.to_string()),
                "layers" => Some(p.layers.to_string()),
                "res" => Some(p.resolution.to_string()),
                "fresnel" => Some(name_of(&FRESNEL_TABLE, &p.path.fresnel).into()),
                _ => None,
            },
            (MethodParams::Pvrr(p), _) => match name {
                "depth" => Some(p.depth.to_string()),
                "res" => Some(p.resolution.to_string()),
                "dispersion" => Some(p.dispersion.to_string()),
                "update" => Some(name_of(&UPDATE_TABLE, &p.update_on_change).into()),
                _ => None,
            },
            _ => None,
        }
    }

    /// Sets the exit TIR policy where the method has one (no effect elsewhere).
    pub fn with_tir_policy(mut self, tir: TirPolicy) -> Self {
        match &mut self {
            MethodParams::TwoInterface(p) => p.tir = tir,
            MethodParams::NearbyGeometry(p) => p.two.tir = tir,
            MethodParams::Reference(_)
            | MethodParams::Single
            | MethodParams::DistanceMap(_)
            | MethodParams::Pvrr(_) => {}
        }
        self
    }

    /// The parameters of refract-core's image-space kernels for a refractor of index `ior`
    /// (`single` ignores the distance mode and exit policy), `None` for other methods.
    pub fn image_space_kernel(&self, ior: f32) -> Option<Result<ImageSpaceParams, RenderError>> {
        let (distance, tir) = match self {
            MethodParams::Single => (DistanceMode::Interpolated, TirPolicy::default()),
            MethodParams::TwoInterface(p) => (p.distance, p.tir),
            MethodParams::NearbyGeometry(p) => (p.two.distance, p.two.tir),
            MethodParams::Reference(_) | MethodParams::DistanceMap(_) | MethodParams::Pvrr(_) => {
                return None;
            }
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
            MethodParams::NearbyGeometry(p) => Some(p.two.back),
            MethodParams::Single
            | MethodParams::Reference(_)
            | MethodParams::DistanceMap(_)
            | MethodParams::Pvrr(_) => None,
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
