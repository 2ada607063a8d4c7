//! What every renderer consumes: a camera, one or more refractors (mesh, BVH, `d_N`, IOR,
//! absorption), nearby opaque objects (mesh, BVH, material), a directional light and a distant
//! environment. Built once, with one BVH per mesh; shared by the backends and the reference
//! through `Arc<Scene>`.
//!
//! Media (issue 49). Every refractor is a closed surface filled with its own medium (index
//! [`Refractor::ior`], absorption [`Refractor::attenuation`]); a refractor that lies inside
//! another is immersed in it ([`Refractor::within`]), every other one in air (index 1, no
//! absorption). An interface of refractor `r` therefore separates `r`'s medium from the medium
//! of [`Scene::outside_ior`]`(r)`: exactly Mitsuba 3's `dielectric` with `int_ior = ior` and
//! `ext_ior` the enclosing medium's index, and its `homogeneous` interior medium with
//! `sigma_t = ` [`Attenuation::coefficient`] and albedo 0. Surfaces never touch: water in a
//! glass is a water surface inside the glass's, not one shared wall.

use glam::{Vec2, Vec3};
use refract_core::CameraDesc;
use refract_core::distance_map::TexelMaterial;
pub use refract_core::fresnel::Conductor;
use refract_core::lanes::{Vec2x8, Vec3x8};
use refract_core::nearby_geometry::{MAX_PLANES, Plane};
use refract_core::real::{Real, Vector3};
pub use refract_core::shading::{Albedo, COLOR_CHART, DirectionalLight};
use refract_geometry::{Mesh, MeshBvh, NormalDistances, normal_distances};

use crate::environment::Environment;
use crate::error::SceneError;

/// The dielectric object every method refracts through: its mesh, the mesh's BVH (built once),
/// the per-vertex `d_N` of Wyman 2005a §3.1 (computed once with that BVH) and its index of
/// refraction.
#[derive(Clone, Debug)]
pub struct Refractor {
    mesh: Mesh,
    bvh: MeshBvh,
    normal_distances: NormalDistances,
    ior: f32,
    conductor: Option<Conductor>,
    volume_thickness: Option<f32>,
    attenuation: Option<Attenuation>,
    within: Option<usize>,
    roughness: f32,
    abbe: f32,
}

/// The most refractors a scene holds (the GPU reference keeps one bit per refractor met).
pub const MAX_REFRACTORS: usize = 32;

/// Beer-Lambert absorption of a refractor's medium, as glTF `KHR_materials_volume` defines
/// it: white light that travels [`Self::distance`] through the medium keeps [`Self::color`] of
/// itself, so radiance after a segment of length `s` is scaled by
/// `exp(−σ s)`, `σ = −ln(color) / distance` per channel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Attenuation {
    /// `attenuationColor`: the fraction per channel left after [`Self::distance`], each in
    /// `(0, 1]` ([`ATTENUATION_COLOR_EXPECTED`]).
    pub color: Vec3,
    /// `attenuationDistance` in world units, finite and > 0.
    pub distance: f32,
}

/// The range of [`Attenuation::color`]'s components, as an error message says it.
pub const ATTENUATION_COLOR_EXPECTED: &str =
    "fractions in (0, 1] (1: that channel is not absorbed)";
/// The range of [`Attenuation::distance`], as an error message says it.
pub const ATTENUATION_DISTANCE_EXPECTED: &str = "a finite distance > 0 in world units";

impl Attenuation {
    /// An absorption, or an error naming the field out of range.
    pub fn new(color: Vec3, distance: f32) -> Result<Self, SceneError> {
        if !color.cmpgt(Vec3::ZERO).all() || !color.cmple(Vec3::ONE).all() {
            return Err(SceneError::field(
                "refractor",
                "attenuation_color",
                color,
                ATTENUATION_COLOR_EXPECTED,
            ));
        }
        if !(distance.is_finite() && distance > 0.0) {
            return Err(SceneError::field(
                "refractor",
                "attenuation_distance",
                distance,
                ATTENUATION_DISTANCE_EXPECTED,
            ));
        }
        Ok(Self { color, distance })
    }

    /// The absorption coefficient per channel, `σ = −ln(color) / distance` (per world unit).
    pub fn coefficient(&self) -> Vec3 {
        Vec3::new(-self.color.x.ln(), -self.color.y.ln(), -self.color.z.ln()) / self.distance
    }

    /// The fraction of radiance left after `length` world units: `exp(−σ length)`.
    pub fn transmittance(&self, length: f32) -> Vec3 {
        let sigma = self.coefficient();
        Vec3::new(
            (-sigma.x * length).exp(),
            (-sigma.y * length).exp(),
            (-sigma.z * length).exp(),
        )
    }
}

pub use refract_core::microfacet::{ROUGHNESS_EXPECTED, ROUGHNESS_RANGE, roughness_in_range};
pub use refract_core::spectral::ABBE_MIN;

/// What an error about an Abbe number says was expected.
pub const ABBE_EXPECTED: &str = "an Abbe number of 1 or more (glass: 20-90), or inf for none";

/// `abbe` (an Abbe number `V_d`) at least [`ABBE_MIN`] or `+inf` (no dispersion), or an error
/// naming `origin`'s `abbe`.
pub fn check_abbe(origin: &str, abbe: f32) -> Result<(), SceneError> {
    if abbe >= ABBE_MIN {
        Ok(())
    } else {
        Err(SceneError::field(origin, "abbe", abbe, ABBE_EXPECTED))
    }
}
pub use refract_core::optics::{IOR_EXPECTED, IOR_RANGE, MAX_IOR, MIN_IOR, ior_in_range};

/// `roughness` in [`ROUGHNESS_RANGE`], or an error naming `origin`'s `roughness`.
pub fn check_roughness(origin: &str, roughness: f32) -> Result<(), SceneError> {
    if roughness_in_range(roughness) {
        Ok(())
    } else {
        Err(SceneError::field(
            origin,
            "roughness",
            roughness,
            ROUGHNESS_EXPECTED,
        ))
    }
}

impl Refractor {
    /// A refractor of index `ior` (the outside is 1): builds the BVH and `d_N` (Wyman 2005a §3.1,
    /// one BVH ray per vertex along `−N`).
    pub fn new(mesh: Mesh, ior: f32) -> Result<Self, SceneError> {
        check_ior(ior)?;
        let bvh = try_bvh(&mesh)?;
        let normal_distances = normal_distances(&mesh, &bvh);
        Ok(Self {
            mesh,
            bvh,
            normal_distances,
            ior,
            conductor: None,
            volume_thickness: None,
            attenuation: None,
            within: None,
            roughness: 0.0,
            abbe: f32::INFINITY,
        })
    }

    /// A refractor with `d_N` computed elsewhere: one value per vertex, finite and ≥ 0.
    pub fn with_normal_distances(
        mesh: Mesh,
        normal_distances: NormalDistances,
        ior: f32,
    ) -> Result<Self, SceneError> {
        check_ior(ior)?;
        let values = &normal_distances.values;
        if values.len() != mesh.positions.len() {
            return Err(SceneError::field(
                "refractor",
                "d_N",
                format!("{} values", values.len()),
                format!("one value per vertex ({})", mesh.positions.len()),
            ));
        }
        if let Some(bad) = values.iter().find(|d| !(d.is_finite() && **d >= 0.0)) {
            return Err(SceneError::field(
                "refractor",
                "d_N",
                bad,
                "finite distances ≥ 0",
            ));
        }
        let bvh = try_bvh(&mesh)?;
        Ok(Self {
            mesh,
            bvh,
            normal_distances,
            ior,
            conductor: None,
            volume_thickness: None,
            attenuation: None,
            within: None,
            roughness: 0.0,
            abbe: f32::INFINITY,
        })
    }

    /// The thickness its glTF material gives (`KHR_materials_volume`'s `thicknessFactor` in
    /// world units: scaled by the node's and the scene's transforms), the default thickness of
    /// the engine methods; `None` when the file gave none.
    pub fn volume_thickness(&self) -> Option<f32> {
        self.volume_thickness
    }

    /// Sets [`Self::volume_thickness`] (finite and ≥ 0, or `None`; other values are dropped).
    pub fn set_volume_thickness(&mut self, thickness: Option<f32>) {
        self.volume_thickness = thickness.filter(|d| d.is_finite() && *d >= 0.0);
    }

    /// The thickness the engine methods read by default (`thickness=auto`) and the glTF export
    /// writes: [`Self::volume_thickness`], else [`Self::mean_d_n`].
    pub fn auto_thickness(&self) -> f32 {
        self.volume_thickness.unwrap_or_else(|| self.mean_d_n())
    }

    /// The mean of `d_N` over the vertices (0 for no vertex): the scene-derived default
    /// thickness of the engine methods.
    pub fn mean_d_n(&self) -> f32 {
        let values = &self.normal_distances.values;
        if values.is_empty() {
            return 0.0;
        }
        let sum: f64 = values.iter().map(|&d| f64::from(d)).sum();
        (sum / values.len() as f64) as f32
    }

    /// Its mesh (outward winding and normals).
    pub fn mesh(&self) -> &Mesh {
        &self.mesh
    }

    /// Its BVH.
    pub fn bvh(&self) -> &MeshBvh {
        &self.bvh
    }

    /// `d_N` per vertex, one per mesh vertex.
    pub fn d_n(&self) -> &[f32] {
        &self.normal_distances.values
    }

    /// `d_N` with how many vertices missed (open meshes) and the value they use.
    pub fn normal_distances(&self) -> &NormalDistances {
        &self.normal_distances
    }

    /// The conductor (metal, mirror) the object is made of instead of glass, if it is: it then
    /// reflects only ([`Conductor`]); `None` for a dielectric of index [`Self::ior`].
    pub fn conductor(&self) -> Option<Conductor> {
        self.conductor
    }

    /// Makes the object a conductor (`Some`) or a dielectric again (`None`).
    pub fn set_conductor(&mut self, conductor: Option<Conductor>) {
        self.conductor = conductor;
    }

    /// Its material as a distance-map texel stores it (Umenhoffer et al. 2007 §17.3, the sign
    /// code): a conductor `ior = −1` with `F_p` per channel, glass its index with
    /// `F0 = ((n − 1)/(n + 1))²`.
    pub fn texel_material(&self) -> TexelMaterial {
        self.texel_material_at(None)
    }

    /// [`Self::texel_material`] at wavelength `lambda_nm` ([`Self::ior_at`]).
    pub fn texel_material_at(&self, lambda_nm: Option<f32>) -> TexelMaterial {
        let ior = self.ior_at(lambda_nm);
        match self.conductor {
            Some(c) => TexelMaterial {
                rgb: c.f0(),
                ior: -1.0,
            },
            None => TexelMaterial {
                rgb: Vec3::splat(refract_core::fresnel::f0_dielectric(1.0 / ior)),
                ior,
            },
        }
    }

    /// Whether it is glass (a dielectric), as the image-space methods require.
    pub fn is_dielectric(&self) -> bool {
        self.conductor.is_none()
    }

    /// Index of refraction.
    pub fn ior(&self) -> f32 {
        self.ior
    }

    /// The index of refraction at wavelength `lambda_nm` (nm): `None` is the d line, where it is
    /// [`Self::ior`] exactly; otherwise [`refract_core::spectral::dispersive_ior`] of
    /// [`Self::abbe`] (the same index at every wavelength without dispersion). An approximate
    /// method traces a dispersive frame at several wavelengths through its kernel
    /// ([`refract_core::spectral::WavelengthBins`]).
    pub fn ior_at(&self, lambda_nm: Option<f32>) -> f32 {
        match lambda_nm {
            Some(lambda) => refract_core::spectral::dispersive_ior(self.ior, self.abbe, lambda),
            None => self.ior,
        }
    }

    /// Changes the index of refraction (the BVH and `d_N` do not depend on it).
    pub fn set_ior(&mut self, ior: f32) -> Result<(), SceneError> {
        check_ior(ior)?;
        self.ior = ior;
        Ok(())
    }

    /// The roughness of its surface in [`ROUGHNESS_RANGE`] (glTF's `roughnessFactor`; GGX
    /// `α = roughness²`, see [`refract_core::microfacet`]): 0, the default, is smooth glass or
    /// a mirror-smooth conductor. The reference traces it; the approximate methods do not.
    pub fn roughness(&self) -> f32 {
        self.roughness
    }

    /// Sets [`Self::roughness`] (an error outside [`ROUGHNESS_RANGE`]).
    pub fn set_roughness(&mut self, roughness: f32) -> Result<(), SceneError> {
        check_roughness("refractor", roughness)?;
        self.roughness = roughness;
        Ok(())
    }

    /// Its glass's Abbe number `V_d` (`+inf`, the default: no dispersion): the index at
    /// wavelength `λ` is [`refract_core::spectral::dispersive_ior`]`(ior, abbe, λ)`, glTF's
    /// `KHR_materials_dispersion` with `dispersion = 20 / V_d`. The reference renders
    /// dispersion spectrally; the approximate methods at a few wavelengths
    /// ([`Self::ior_at`]).
    pub fn abbe(&self) -> f32 {
        self.abbe
    }

    /// Whether its index depends on the wavelength (a finite Abbe number, on glass).
    pub fn is_dispersive(&self) -> bool {
        self.abbe.is_finite() && self.is_dielectric()
    }

    /// Sets [`Self::abbe`] (an error below [`ABBE_MIN`] or for NaN).
    pub fn set_abbe(&mut self, abbe: f32) -> Result<(), SceneError> {
        check_abbe("refractor", abbe)?;
        self.abbe = abbe;
        Ok(())
    }

    /// The absorption of its medium (`None`: clear).
    pub fn attenuation(&self) -> Option<Attenuation> {
        self.attenuation
    }

    /// Sets [`Self::attenuation`].
    pub fn set_attenuation(&mut self, attenuation: Option<Attenuation>) {
        self.attenuation = attenuation;
    }

    /// The refractor (its index in [`Scene::refractors`]) whose medium surrounds this one, or
    /// `None` for air; set by [`Scene::nest_refractors`].
    pub fn within(&self) -> Option<usize> {
        self.within
    }

    /// The diameter of the mesh's bounding sphere (the unit of the `|P~2 − P2|` metric).
    pub fn diameter(&self) -> f32 {
        2.0 * self.mesh.bounding_sphere().radius
    }
}

/// The mesh's BVH, or an error for coordinates too large for it.
fn try_bvh(mesh: &Mesh) -> Result<MeshBvh, SceneError> {
    MeshBvh::try_build(mesh).map_err(|source| SceneError::Geometry {
        origin: format!("mesh {}", mesh.name),
        source,
    })
}

/// `ior` in [`IOR_RANGE`].
pub fn check_ior(ior: f32) -> Result<(), SceneError> {
    if ior_in_range(ior) {
        Ok(())
    } else {
        Err(SceneError::field("refractor", "ior", ior, IOR_EXPECTED))
    }
}

/// What an opaque object's surface does with light.
#[derive(Clone, Debug, PartialEq)]
pub enum Material {
    /// View-independent diffuse shading under the scene's [`DirectionalLight`].
    Diffuse(Albedo),
    /// A conductor: a mirror or a metal, reflecting with its Fresnel reflectance (traced by
    /// the reference and the distance-map method; the image-space methods decline scenes with
    /// one, see [`crate::registry::scene_support`]).
    Conductor(Conductor),
}

/// The named conductors of scene files: `mirror` ([`Conductor::MIRROR`]), `gold`, `silver`,
/// `copper`, `aluminium`.
pub const CONDUCTORS: [(&str, Conductor); 5] = [
    ("mirror", Conductor::MIRROR),
    ("gold", Conductor::GOLD),
    ("silver", Conductor::SILVER),
    ("copper", Conductor::COPPER),
    ("aluminium", Conductor::ALUMINIUM),
];

/// The name of a conductor of [`CONDUCTORS`], or `conductor` for another.
pub fn conductor_name(conductor: &Conductor) -> &'static str {
    CONDUCTORS
        .iter()
        .find(|(_, c)| c == conductor)
        .map_or("conductor", |(n, _)| n)
}

/// An opaque object near the refractor (Wyman 2005b's "nearby geometry").
#[derive(Clone, Debug)]
pub struct Object {
    mesh: Mesh,
    bvh: MeshBvh,
    own_plane: Option<Plane>,
    center: Vec3,
    /// Its surface.
    pub material: Material,
    roughness: f32,
}

impl Object {
    /// An object of `mesh`; builds its BVH (an error for coordinates too large for it).
    pub fn new(mesh: Mesh, material: Material) -> Result<Self, SceneError> {
        let bvh = try_bvh(&mesh)?;
        let sphere = mesh.bounding_sphere();
        Ok(Self {
            own_plane: planar(&mesh, 2e-4 * sphere.radius),
            center: sphere.center,
            mesh,
            bvh,
            material,
            roughness: 0.0,
        })
    }

    /// Its mesh.
    pub fn mesh(&self) -> &Mesh {
        &self.mesh
    }

    /// Its BVH.
    pub fn bvh(&self) -> &MeshBvh {
        &self.bvh
    }

    /// The texture coordinates at a point `p_ws` of triangle `triangle`: the mesh's uvs
    /// interpolated barycentrically, or world `(x, z)` for meshes without uvs.
    pub fn uv_at(&self, triangle: u32, barycentrics: Vec2, p_ws: Vec3) -> Vec2 {
        let (u, v) = self.uv_at_lanes(triangle, (barycentrics.x, barycentrics.y), p_ws);
        Vec2::new(u, v)
    }

    /// [`Self::uv_at`] at eight points of triangle `triangle`: lane `i` is
    /// `uv_at(triangle, barycentrics_i, p_ws_i)`, bit for bit.
    pub fn uv_at_x8(&self, triangle: u32, barycentrics: Vec2x8, p_ws: Vec3x8) -> Vec2x8 {
        let (x, y) = self.uv_at_lanes(triangle, (barycentrics.x, barycentrics.y), p_ws);
        Vec2x8 { x, y }
    }

    /// [`Self::uv_at`] for one point or eight: `(1 − b₁ − b₂) uv_a + b₁ uv_b + b₂ uv_c`.
    fn uv_at_lanes<V: Vector3>(
        &self,
        triangle: u32,
        (b1, b2): (V::Real, V::Real),
        p_ws: V,
    ) -> (V::Real, V::Real) {
        if self.mesh.uvs.is_empty() {
            return (p_ws.x(), p_ws.z());
        }
        let [a, b, c] = self.mesh.triangles[triangle as usize].map(|i| self.mesh.uvs[i as usize]);
        let w0 = V::Real::ONE - b1 - b2;
        let at = |a: f32, b: f32, c: f32| {
            w0 * V::Real::splat(a) + b1 * V::Real::splat(b) + b2 * V::Real::splat(c)
        };
        (at(a.x, b.x, c.x), at(a.y, b.y, c.y))
    }

    /// [`Self::shade`] at eight points: lane `i` is `shade(light, uv_i, n_i)`, bit for bit.
    pub fn shade_x8(&self, light: &DirectionalLight, uv: Vec2x8, n: Vec3x8) -> Vec3x8 {
        match &self.material {
            Material::Diffuse(albedo) => light.shade(albedo.at_x8(uv), n),
            Material::Conductor(_) => Vec3x8::ZERO,
        }
    }

    /// The plane that stands for this object in the ray-plane and iterative lookups of
    /// Wyman 2005b §4.2–4.3 (the paper leaves the choice to the user): the object's own plane
    /// when it is planar ([`Self::own_plane`]), otherwise the plane through its bounding-sphere
    /// centre facing `look_dir` (the camera's).
    pub fn stand_in_plane(&self, look_dir: Vec3) -> Plane {
        self.own_plane
            .unwrap_or_else(|| Plane::through(self.center, -look_dir))
    }

    /// The object's plane when every vertex lies within `10⁻⁴` of its bounding-sphere diameter
    /// from the plane of its first non-degenerate triangle.
    pub fn own_plane(&self) -> Option<Plane> {
        self.own_plane
    }

    /// Whether the mesh has texture coordinates (otherwise [`Self::uv_at`] uses world `x, z`).
    pub fn has_uvs(&self) -> bool {
        !self.mesh.uvs.is_empty()
    }

    /// Outgoing radiance at a point with texture coordinates `uv` and unit normal `n` of a
    /// diffuse object; 0 for a conductor (it emits nothing: what it shows is traced).
    pub fn shade(&self, light: &DirectionalLight, uv: Vec2, n: Vec3) -> Vec3 {
        match &self.material {
            Material::Diffuse(albedo) => light.shade(albedo.at(uv), n),
            Material::Conductor(_) => Vec3::ZERO,
        }
    }

    /// The roughness of a conductor's surface in [`ROUGHNESS_RANGE`] (0, the default: a
    /// mirror-smooth one; a diffuse surface ignores it).
    pub fn roughness(&self) -> f32 {
        self.roughness
    }

    /// Sets [`Self::roughness`] (an error outside [`ROUGHNESS_RANGE`]).
    pub fn set_roughness(&mut self, roughness: f32) -> Result<(), SceneError> {
        check_roughness("object", roughness)?;
        self.roughness = roughness;
        Ok(())
    }

    /// The conductor the object is made of, `None` for a diffuse object.
    pub fn conductor(&self) -> Option<Conductor> {
        match self.material {
            Material::Conductor(c) => Some(c),
            Material::Diffuse(_) => None,
        }
    }
}

/// The plane of the first non-degenerate triangle of `mesh` when every vertex lies within
/// `tolerance` of it.
fn planar(mesh: &Mesh, tolerance: f32) -> Option<Plane> {
    let (a, n) = (0..mesh.triangles.len()).find_map(|i| {
        let [a, b, c] = mesh.triangle_positions(i);
        Some((a, (b - a).cross(c - a).try_normalize()?))
    })?;
    let flat = mesh
        .positions
        .iter()
        .all(|p| (*p - a).dot(n).abs() <= tolerance);
    flat.then(|| Plane::through(a, n))
}

/// Where the probed vertices of one mesh lie with respect to a closed refractor.
enum Containment {
    Outside,
    Inside,
    Crossing,
}

/// How many vertices [`containment`] probes.
const CONTAINMENT_PROBES: usize = 16;

/// Ray parity at up to [`CONTAINMENT_PROBES`] vertices of `mesh` spread over its vertex list,
/// along a fixed direction no axis-aligned mesh is parallel to.
fn containment(mesh: &Mesh, other: &Refractor) -> Containment {
    let dir = Vec3::new(0.284_169, 0.876_221, 0.389_284).normalize();
    let n = mesh.positions.len();
    let step = (n / CONTAINMENT_PROBES).max(1);
    let mut hits = Vec::new();
    let (mut inside, mut outside) = (0, 0);
    for p in mesh.positions.iter().step_by(step).take(CONTAINMENT_PROBES) {
        hits.clear();
        let ray = refract_core::Ray { origin: *p, dir };
        other.bvh().all_hits(&ray, 0.0, f32::INFINITY, &mut hits);
        if hits.len() % 2 == 1 {
            inside += 1;
        } else {
            outside += 1;
        }
    }
    match (inside, outside) {
        (0, _) => Containment::Outside,
        (_, 0) => Containment::Inside,
        _ => Containment::Crossing,
    }
}

/// Which mesh of a scene.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum SceneMesh {
    /// The refractor.
    Refractor,
    /// Opaque object `k` of [`Scene::objects`].
    Object(usize),
}

impl SceneMesh {
    /// The object id raster passes write: 0 for the refractor, `1 + k` for object `k`.
    pub fn object_id(self) -> u32 {
        match self {
            SceneMesh::Refractor => 0,
            SceneMesh::Object(k) => 1 + k as u32,
        }
    }
}

/// The nearest front surface of one mesh at one pixel centre, as a raster pass of any mesh from
/// any camera sees it (both backends produce these, so they can be compared).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceTexel {
    /// Perspective-correct interpolated world position.
    pub p_ws: Vec3,
    /// Interpolated vertex normal, normalised.
    pub n_ws: Vec3,
    /// Interpolated texture coordinates (0 for meshes without).
    pub uv: Vec2,
    /// [`SceneMesh::object_id`] of the mesh.
    pub object: u32,
}

/// Everything a renderer renders.
#[derive(Clone, Debug)]
pub struct Scene {
    /// Built-in name or file stem.
    pub name: String,
    /// The scene's camera; each run sets its resolution (`width`, `height`).
    pub camera: CameraDesc,
    /// The first refractor: the one the one-refractor methods (every family but the
    /// reference) refract through; refractor 0 of [`Self::refractors`].
    pub refractor: Refractor,
    /// The refractors after the first: entry `k` is refractor `k + 1` of [`Self::refractors`].
    /// [`Self::nest_refractors`] must run after it changes.
    pub other_refractors: Vec<Refractor>,
    /// Opaque objects near it.
    pub objects: Vec<Object>,
    /// Distant lighting.
    pub environment: Environment,
    /// The file the lat-long environment was loaded from, when it was (for exporters).
    pub environment_file: Option<std::path::PathBuf>,
    /// The light of the opaque objects.
    pub light: DirectionalLight,
}

impl Scene {
    /// A refractor alone in an environment, seen by the default camera.
    pub fn new(name: impl Into<String>, refractor: Refractor, environment: Environment) -> Self {
        Self {
            name: name.into(),
            camera: CameraDesc::default(),
            refractor,
            other_refractors: Vec::new(),
            objects: Vec::new(),
            environment,
            environment_file: None,
            light: DirectionalLight::default(),
        }
    }

    /// Several refractors in an environment, seen by the default camera, nested by
    /// [`Self::nest_refractors`]; an error for no refractor, more than [`MAX_REFRACTORS`] or
    /// surfaces that cross.
    pub fn with_refractors(
        name: impl Into<String>,
        refractors: Vec<Refractor>,
        environment: Environment,
    ) -> Result<Self, SceneError> {
        let name = name.into();
        let mut refractors = refractors.into_iter();
        let Some(first) = refractors.next() else {
            return Err(SceneError::field(
                format!("scene {name}"),
                "refractors",
                0,
                "at least one refractor",
            ));
        };
        let mut scene = Self::new(name, first, environment);
        scene.other_refractors = refractors.collect();
        scene.nest_refractors()?;
        Ok(scene)
    }

    /// Every refractor, the first ([`Self::refractor`]) first.
    pub fn refractors(&self) -> impl Iterator<Item = &Refractor> + Clone {
        core::iter::once(&self.refractor).chain(&self.other_refractors)
    }

    /// How many refractors the scene has (at least 1).
    pub fn refractor_count(&self) -> usize {
        1 + self.other_refractors.len()
    }

    /// Refractor `index` of [`Self::refractors`], or `None` out of range.
    pub fn refractor_at(&self, index: usize) -> Option<&Refractor> {
        match index {
            0 => Some(&self.refractor),
            k => self.other_refractors.get(k - 1),
        }
    }

    /// The index of the medium that surrounds refractor `index`: the index of the refractor it
    /// lies within, or 1 (air) for one in air or an index out of range.
    pub fn outside_ior(&self, index: usize) -> f32 {
        self.outside_ior_at(index, None)
    }

    /// [`Self::outside_ior`] at wavelength `lambda_nm` ([`Refractor::ior_at`]).
    pub fn outside_ior_at(&self, index: usize, lambda_nm: Option<f32>) -> f32 {
        self.refractor_at(index)
            .and_then(Refractor::within)
            .and_then(|outer| self.refractor_at(outer))
            .map_or(1.0, |outer| outer.ior_at(lambda_nm))
    }

    /// Finds which refractor each glass refractor lies within (the innermost one that contains
    /// it; conductors hold no medium and are skipped) and stores it ([`Refractor::within`]).
    /// Containment is decided by ray parity from a few vertices spread over the mesh: a vertex is
    /// inside a closed mesh when a ray from it crosses the mesh an odd number of times.
    /// Errors: more than [`MAX_REFRACTORS`] refractors, or two refractors whose surfaces cross
    /// (some of the probed vertices inside the other, some outside), which no medium
    /// assignment describes. A scene with one refractor is left as it is.
    pub fn nest_refractors(&mut self) -> Result<(), SceneError> {
        let count = self.refractor_count();
        if count > MAX_REFRACTORS {
            return Err(SceneError::field(
                format!("scene {}", self.name),
                "refractors",
                count,
                format!("at most {MAX_REFRACTORS} refractors"),
            ));
        }
        let mut within = vec![None; count];
        if count > 1 {
            let refractors: Vec<&Refractor> = self.refractors().collect();
            for (inner, refractor) in refractors.iter().enumerate() {
                if !refractor.is_dielectric() {
                    continue;
                }
                let mut best: Option<(usize, f32)> = None;
                for (outer, other) in refractors.iter().enumerate() {
                    if outer == inner || !other.is_dielectric() {
                        continue;
                    }
                    match containment(refractor.mesh(), other) {
                        Containment::Outside => {}
                        Containment::Inside => {
                            let radius = other.mesh().bounding_sphere().radius;
                            if best.is_none_or(|(_, r)| radius < r) {
                                best = Some((outer, radius));
                            }
                        }
                        Containment::Crossing => {
                            return Err(SceneError::field(
                                format!("scene {}", self.name),
                                format!("refractor {inner}"),
                                format!("a surface crossing refractor {outer}'s"),
                                "refractors that do not intersect: one inside another (immersed in it) or apart",
                            ));
                        }
                    }
                }
                within[inner] = best.map(|(outer, _)| outer);
            }
        }
        self.refractor.within = within[0];
        for (refractor, within) in self.other_refractors.iter_mut().zip(&within[1..]) {
            refractor.within = *within;
        }
        Ok(())
    }

    /// The mesh `which`, or `None` for an object index out of range.
    pub fn mesh(&self, which: SceneMesh) -> Option<&Mesh> {
        match which {
            SceneMesh::Refractor => Some(self.refractor.mesh()),
            SceneMesh::Object(k) => self.objects.get(k).map(Object::mesh),
        }
    }

    /// The nearest hit of `ray` beyond `t_min` on any mesh of the scene but `exclude`, with the
    /// mesh it is on (BVH queries, the refractor first, ties to the earlier mesh).
    pub fn closest_hit(
        &self,
        ray: &refract_core::Ray,
        t_min: f32,
        exclude: Option<SceneMesh>,
    ) -> Option<(SceneMesh, refract_geometry::Hit)> {
        let mut best: Option<(SceneMesh, refract_geometry::Hit)> = None;
        let meshes = core::iter::once((SceneMesh::Refractor, self.refractor.bvh())).chain(
            self.objects
                .iter()
                .enumerate()
                .map(|(k, o)| (SceneMesh::Object(k), o.bvh())),
        );
        for (mesh, bvh) in meshes.filter(|(m, _)| Some(*m) != exclude) {
            let t_max = best.as_ref().map_or(f32::INFINITY, |(_, h)| h.t);
            if let Some(hit) = bvh.closest_hit(ray, t_min, t_max) {
                best = Some((mesh, hit));
            }
        }
        best
    }

    /// Whether any surface is rough: a refractor (glass or conductor) or a conductor object
    /// with roughness above 0. Only the reference traces roughness.
    pub fn has_roughness(&self) -> bool {
        self.refractors().any(|r| r.roughness() > 0.0)
            || self
                .objects
                .iter()
                .any(|o| o.conductor().is_some() && o.roughness() > 0.0)
    }

    /// Whether any refractor is dispersive ([`Refractor::is_dispersive`]): the reference then
    /// renders spectrally.
    pub fn has_dispersion(&self) -> bool {
        self.refractors().any(Refractor::is_dispersive)
    }

    /// Whether every surface is glass or diffuse (what the image-space and nearby-geometry
    /// methods can render): no conductor refractor and no conductor object.
    pub fn is_dielectric_and_diffuse(&self) -> bool {
        self.refractor.is_dielectric() && self.objects.iter().all(|o| o.conductor().is_none())
    }

    /// The near and far planes of cube-map face cameras at `center` (the distance-map layers):
    /// a thousandth of the refractor's bounding radius, and twice the distance of the farthest
    /// vertex of any mesh plus one.
    pub fn cube_map_clip_planes(&self, center: Vec3) -> (f32, f32) {
        let radius = self.refractor.mesh().bounding_sphere().radius;
        let far = core::iter::once(self.refractor.mesh())
            .chain(self.objects.iter().map(Object::mesh))
            .flat_map(|m| m.positions.iter())
            .fold(0.0f32, |far, p| far.max((*p - center).length()));
        (1e-3 * radius.max(1e-6), 2.0 * far + 1.0)
    }

    /// The planes standing for the opaque objects in the ray-plane and iterative lookups
    /// (Wyman 2005b §4.2) for a camera looking along `look_dir`, one per object
    /// ([`Object::stand_in_plane`]), at most
    /// [`MAX_PLANES`] (the first ones).
    pub fn nearby_planes(&self, look_dir: Vec3) -> Vec<Plane> {
        self.objects
            .iter()
            .take(MAX_PLANES)
            .map(|o| o.stand_in_plane(look_dir))
            .collect()
    }

    /// The scene's camera at `width × height`.
    pub fn camera(&self, width: u32, height: u32) -> Result<refract_core::Camera, SceneError> {
        refract_core::Camera::new(CameraDesc {
            width,
            height,
            ..self.camera
        })
        .map_err(|err| {
            SceneError::field(
                format!("scene {}", self.name),
                "camera",
                format!("{width}x{height}"),
                err.to_string(),
            )
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use refract_core::lanes::LANES;

    /// Numbers in `[0, 1)` that fill the interval evenly without repeating (the additive
    /// sequence of the golden ratio), enough to spread test inputs; no dependency.
    struct Spread(f64);

    impl Spread {
        fn next(&mut self) -> f32 {
            self.0 = (self.0 + 0.618_033_988_749_895).fract();
            self.0 as f32
        }
        fn range(&mut self, lo: f32, hi: f32) -> f32 {
            lo + (hi - lo) * self.next()
        }
    }

    /// The bits of each component, every NaN as one value (lanes and scalar code may differ in
    /// a NaN's sign and payload only).
    fn bits(v: Vec3) -> [u32; 3] {
        v.to_array()
            .map(|c| if c.is_nan() { u32::MAX } else { c.to_bits() })
    }

    /// Texture coordinates around the uv square, far outside it, on cell and ring edges, and a
    /// few non-finite ones.
    fn coordinates(rng: &mut Spread) -> [Vec2; LANES] {
        core::array::from_fn(|_| match (rng.next() * 20.0) as u32 {
            0 => Vec2::new(rng.range(-1e7, 1e7), rng.range(-1e9, 1e9)),
            1 => Vec2::new(
                (rng.next() * 16.0).floor() / 8.0,
                -(rng.next() * 16.0).floor() / 4.0,
            ),
            2 => Vec2::new(f32::NAN, 0.5),
            3 => Vec2::new(0.5, f32::INFINITY),
            // Inside the unit square (the colour chart's patches), and on its patch edges.
            4..=6 => Vec2::new(rng.next(), rng.next()),
            7 => Vec2::new(
                (rng.next() * 7.0).floor() / 6.0,
                (rng.next() * 5.0).floor() / 4.0,
            ),
            _ => Vec2::new(rng.range(-3.0, 4.0), rng.range(-3.0, 4.0)),
        })
    }

    #[test]
    fn eight_lanes_of_shading_equal_the_scalar_shading_bit_for_bit() {
        let albedos = [
            Albedo::Constant(Vec3::new(0.2, 0.4, 0.6)),
            Albedo::Checker {
                a: Vec3::splat(0.9),
                b: Vec3::new(0.1, 0.2, 0.05),
                squares: 8.0,
            },
            Albedo::ColorChart,
            Albedo::WOOD,
        ];
        let light = DirectionalLight {
            direction: Vec3::new(0.3, 0.8, -0.52).normalize(),
            radiance: Vec3::new(1.0, 0.95, 0.9),
            ambient: Vec3::splat(0.15),
        };
        let mut plane = refract_geometry::shapes::plane(3.0, 4).expect("plane");
        // Stretch the uvs past the unit square, so the lanes see cell edges and rings.
        plane
            .uvs
            .iter_mut()
            .for_each(|uv| *uv = *uv * 5.0 - Vec2::splat(2.0));
        let mut no_uvs = plane.clone();
        no_uvs.uvs.clear();
        let mut rng = Spread(0.3);
        for albedo in &albedos {
            for mesh in [&plane, &no_uvs] {
                let object =
                    Object::new(mesh.clone(), Material::Diffuse(albedo.clone())).expect("object");
                for round in 0..300 {
                    let uv = coordinates(&mut rng);
                    let lanes = albedo.at_x8(Vec2x8::from_lanes(&uv)).to_lanes();
                    for (lane, uv) in lanes.iter().zip(uv) {
                        assert_eq!(bits(*lane), bits(albedo.at(uv)), "{albedo:?} at {uv}");
                    }
                    let triangle = round % mesh.triangles.len() as u32;
                    let w: [Vec2; LANES] = core::array::from_fn(|_| {
                        Vec2::new(rng.range(-0.2, 1.0), rng.range(-0.2, 1.0))
                    });
                    let p: [Vec3; LANES] = core::array::from_fn(|_| {
                        Vec3::new(rng.range(-5.0, 5.0), 0.0, rng.range(-5.0, 5.0))
                    });
                    let n: [Vec3; LANES] = core::array::from_fn(|_| {
                        Vec3::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), 0.3).normalize()
                    });
                    let uv_lanes =
                        object.uv_at_x8(triangle, Vec2x8::from_lanes(&w), Vec3x8::from_lanes(&p));
                    let shaded = object
                        .shade_x8(&light, uv_lanes, Vec3x8::from_lanes(&n))
                        .to_lanes();
                    for i in 0..LANES {
                        let uv = object.uv_at(triangle, w[i], p[i]);
                        let uv_lane = uv_lanes.to_lanes()[i];
                        assert_eq!(
                            uv_lane.to_array().map(f32::to_bits),
                            uv.to_array().map(f32::to_bits)
                        );
                        assert_eq!(bits(shaded[i]), bits(object.shade(&light, uv, n[i])));
                    }
                }
            }
        }
    }
}
