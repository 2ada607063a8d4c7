//! `refract.Tracer`: the exact reference's closest-hit query on one mesh, callable on any rays,
//! so that the tracer can be measured against another ray tracer on the same triangles and the
//! same rays in one process (`python/benchmarks/embree.py`, `docs/performance.md`).

use std::path::PathBuf;

use glam::Vec3;
use numpy::{PyArray1, PyArray2, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::prelude::*;
use refract_core::Ray;
use refract_geometry::MeshBvh;

use crate::errors::{detached, to_py, value_error};

/// What [`Tracer::closest_hits`] returns: each ray's `t` and triangle index.
type Hits<'py> = (Bound<'py, PyArray1<f32>>, Bound<'py, PyArray1<i64>>);

/// The BVH the reference traces (`refract_geometry::MeshBvh`: obvhs's CWBVH, `medium_build`)
/// over one mesh as `refract` loads it (centred and scaled into the unit bounding sphere).
#[pyclass(module = "refract._refract", frozen)]
pub struct Tracer {
    bvh: MeshBvh,
    positions: Vec<Vec3>,
    triangles: Vec<[u32; 3]>,
}

/// `array` as rays' `name` (origins or directions): an `(n, 3)` float32 array.
fn points(name: &str, array: &PyReadonlyArray2<'_, f32>) -> PyResult<Vec<Vec3>> {
    let shape = array.shape();
    if shape[1] != 3 {
        return Err(value_error(format!(
            "{name}: expected an (n, 3) float32 array, got shape {shape:?}"
        )));
    }
    Ok(array
        .as_array()
        .rows()
        .into_iter()
        .map(|r| Vec3::new(r[0], r[1], r[2]))
        .collect())
}

#[pymethods]
impl Tracer {
    /// Loads a mesh file (as `refract render` reads them) and builds the reference's BVH over
    /// it; the time of the build is not part of `closest_hits`. Errors as every call's
    /// (`FileNotFoundError` for a missing file).
    #[staticmethod]
    fn load(py: Python<'_>, path: PathBuf) -> PyResult<Self> {
        let loaded = refract_eval::mesh_files::load_mesh(
            &path,
            &refract_eval::mesh_files::LoadOptions::default(),
        )
        .map_err(|e| to_py(e.into()))?;
        let mesh = loaded.mesh;
        let bvh = py
            .detach(|| MeshBvh::try_build(&mesh))
            .map_err(|e| to_py(e.into()))?;
        Ok(Self {
            bvh,
            positions: mesh.positions,
            triangles: mesh.triangles,
        })
    }

    /// The vertex positions the BVH holds, `(n, 3)` float32.
    #[getter]
    fn vertices<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f32>> {
        let rows: Vec<Vec<f32>> = self
            .positions
            .iter()
            .map(|p| p.to_array().to_vec())
            .collect();
        PyArray2::from_vec2(py, &rows).expect("rows of three")
    }

    /// The triangles, `(m, 3)` uint32 vertex indices (counter-clockwise seen from outside).
    #[getter]
    fn triangles<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<u32>> {
        let rows: Vec<Vec<u32>> = self.triangles.iter().map(|t| t.to_vec()).collect();
        PyArray2::from_vec2(py, &rows).expect("rows of three")
    }

    /// The closest hit of each ray with `t` in `[t_min, inf)`, on one thread with the GIL
    /// released: `(t, triangle)`, float32 and int64 arrays of `n`; a miss is `t = inf` and
    /// `triangle = -1`. `directions` need not be unit length: `t` is in their units.
    #[pyo3(signature = (origins, directions, t_min = 0.0))]
    fn closest_hits<'py>(
        &self,
        py: Python<'py>,
        origins: PyReadonlyArray2<'py, f32>,
        directions: PyReadonlyArray2<'py, f32>,
        t_min: f32,
    ) -> PyResult<Hits<'py>> {
        let (o, d) = (
            points("origins", &origins)?,
            points("directions", &directions)?,
        );
        if o.len() != d.len() {
            return Err(value_error(format!(
                "origins and directions: {} and {} rays",
                o.len(),
                d.len()
            )));
        }
        if !(t_min.is_finite() && t_min >= 0.0) {
            return Err(value_error(format!(
                "t_min: expected a finite distance >= 0, got {t_min}"
            )));
        }
        let (t, triangle): (Vec<f32>, Vec<i64>) = detached(py, || {
            Ok(o.iter()
                .zip(&d)
                .map(|(&origin, &direction)| {
                    // The BVH takes unit directions; t is scaled back to the caller's units.
                    let length = direction.length();
                    if !(length.is_finite() && length > 0.0) {
                        return (f32::INFINITY, -1);
                    }
                    let ray = Ray {
                        origin,
                        dir: direction / length,
                    };
                    match self.bvh.closest_hit(&ray, t_min * length, f32::INFINITY) {
                        Some(hit) => (hit.t / length, i64::from(hit.triangle)),
                        None => (f32::INFINITY, -1),
                    }
                })
                .unzip())
        })?;
        Ok((PyArray1::from_vec(py, t), PyArray1::from_vec(py, triangle)))
    }

    fn __repr__(&self) -> String {
        format!(
            "Tracer({} vertices, {} triangles)",
            self.positions.len(),
            self.triangles.len()
        )
    }
}
