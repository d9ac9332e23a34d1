//! Scenes and their bakes: `hprt.load_scene`, `hprt.bake`, `hprt.load_bake`, and the bake's
//! transfer as arrays.

use crate::errors::hprt_error;
use crate::progress::with_progress;
use foundation::bake_settings::BakeSettings;
use foundation::bvh::SceneBvh;
use foundation::scene::{ObjectRole, Scene as SceneData, SceneMesh};
use numpy::ndarray::{Array3, ArrayView3};
use numpy::{IntoPyArray, PyArray3};
use precompute::bake::{Transfer, TransferVectors};
use precompute::cache::{self, CacheError};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::IntoPyDict;
use std::path::PathBuf;
use std::sync::Arc;

/// A scene: a scene file (TOML) or a model (glTF, OBJ, PLY, BPT) placed in a default scene.
#[pyclass(module = "hprt", frozen)]
pub(crate) struct Scene {
    pub(crate) data: Arc<SceneData>,
}

#[pymethods]
impl Scene {
    #[getter]
    fn name(&self) -> String {
        self.data.name.clone()
    }

    /// The file it was loaded from.
    #[getter]
    fn path(&self) -> PathBuf {
        self.data.path.clone()
    }

    /// Its objects, in order, with their materials.
    #[getter]
    fn objects(&self) -> Vec<SceneObject> {
        self.data
            .geometry
            .objects
            .iter()
            .map(|o| SceneObject::of(o, &self.data.geometry))
            .collect()
    }

    #[getter]
    fn vertex_count(&self) -> usize {
        self.data.geometry.mesh.positions.len()
    }

    #[getter]
    fn triangle_count(&self) -> usize {
        self.data.geometry.mesh.triangles.len()
    }

    /// The scene's camera (its image size is a render's own).
    #[getter]
    fn camera(&self) -> crate::camera::Camera {
        crate::camera::Camera::from(&self.data.camera)
    }

    /// The scene camera's image size, (width, height).
    #[getter]
    fn image_size(&self) -> (u32, u32) {
        (self.data.camera.width, self.data.camera.height)
    }

    /// The rotation of its map about +Y, degrees: what renders and references use when
    /// given none (decompose a map with it to light the scene as they do).
    #[getter]
    fn rotation_deg(&self) -> f32 {
        map_rotation(&self.data, None)
    }

    /// The environment map the scene names, if any.
    #[getter]
    fn environment(&self) -> Option<PathBuf> {
        self.data.environment.as_ref().map(|e| e.map.clone())
    }

    fn __repr__(&self) -> String {
        format!(
            "Scene({:?}, objects={}, triangles={})",
            self.data.name,
            self.data.geometry.objects.len(),
            self.triangle_count()
        )
    }
}

/// One object of a scene: its part of the mesh, its role and its material (a diffuse albedo,
/// or texture factor, plus a Phong lobe or glTF's metallic-roughness layer).
#[pyclass(module = "hprt", frozen, get_all)]
#[derive(Clone)]
pub(crate) struct SceneObject {
    name: String,
    /// "object" (a virtual object) or "proxy" (a stand-in for a real surface).
    role: &'static str,
    /// Diffuse albedo `k_d`, or for a textured object the factor its texture is multiplied by.
    albedo: [f32; 3],
    textured: bool,
    /// Phong `k_s` per channel (zero: diffuse) and exponent.
    specular: [f32; 3],
    shininess: f32,
    /// The metallic-roughness layer's factors (`None` without one; the albedo is then the
    /// base colour).
    metallic: Option<f32>,
    roughness: Option<f32>,
    /// The scale of its tangent-space normal map (`None` without one).
    normal_map_scale: Option<f32>,
    /// The radiance it emits (glTF's emissive factor times strength; `None` for none).
    emission: Option<[f32; 3]>,
    vertex_count: u32,
    triangle_count: u32,
}

impl SceneObject {
    fn of(o: &foundation::scene::SceneObject, geometry: &SceneMesh) -> Self {
        Self {
            name: o.name.clone(),
            role: match o.role {
                ObjectRole::Object => "object",
                ObjectRole::Proxy => "proxy",
            },
            albedo: o.albedo.to_array(),
            textured: o.texture.is_some(),
            specular: o.material.specular.to_array(),
            shininess: o.material.shininess,
            metallic: o.material.layer.map(|l| l.metallic),
            roughness: o.material.layer.map(|l| l.roughness),
            normal_map_scale: o.normal_map.map(|m| geometry.normal_maps[m].scale),
            emission: o.emission.map(|e| geometry.emissions[e].factor.to_array()),
            vertex_count: o.vertices.end - o.vertices.start,
            triangle_count: o.triangles.end - o.triangles.start,
        }
    }
}

#[pymethods]
impl SceneObject {
    fn __repr__(&self) -> String {
        format!(
            "SceneObject({:?}, role={}, albedo={:?}, triangles={})",
            self.name, self.role, self.albedo, self.triangle_count
        )
    }
}

/// The rotation of the map about +Y: the one asked for, else the scene's (CONVENTIONS.md,
/// "Environment rotation").
pub(crate) fn map_rotation(scene: &SceneData, requested_deg: Option<f32>) -> f32 {
    runtime::map_rotation(
        scene.environment.as_ref().map(|e| e.rotation_deg),
        requested_deg,
    )
}

/// Loads a scene file or a model.
#[pyfunction]
pub(crate) fn load_scene(path: PathBuf) -> PyResult<Scene> {
    crate::errors::existing(&path)?;
    let data = SceneData::open(&path).map_err(hprt_error)?;
    Ok(Scene {
        data: Arc::new(data),
    })
}

/// A scene's bake: per-vertex SH transfer, direct and interreflected.
#[pyclass(module = "hprt", frozen)]
pub(crate) struct Bake {
    pub(crate) transfer: Arc<Transfer>,
    mesh_hash: [u8; 32],
}

#[pymethods]
impl Bake {
    #[getter]
    fn order(&self) -> usize {
        self.transfer.settings.order
    }

    #[getter]
    fn samples(&self) -> u32 {
        self.transfer.settings.samples
    }

    #[getter]
    fn bounces(&self) -> u32 {
        self.transfer.settings.bounces
    }

    /// Direct (shadowed) transfer, `(vertices, 3, order²)`: row `[v, c]` dotted with channel
    /// `c` of a map's SH coefficients is vertex `v`'s outgoing radiance. A read-only view of
    /// the bake's own memory (no copy), which it keeps alive.
    #[getter]
    fn direct<'py>(this: Bound<'py, Self>) -> PyResult<Bound<'py, PyArray3<f32>>> {
        let transfer = Arc::clone(&this.get().transfer);
        shared_view(&transfer.direct, this.into_any())
    }

    /// Interreflected transfer (the bounces), same layout and also a read-only view.
    #[getter]
    fn indirect<'py>(this: Bound<'py, Self>) -> PyResult<Bound<'py, PyArray3<f32>>> {
        let transfer = Arc::clone(&this.get().transfer);
        shared_view(&transfer.indirect, this.into_any())
    }

    /// Direct plus interreflected.
    #[getter]
    fn transfer<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray3<f32>> {
        vectors_array(&self.transfer.full()).into_pyarray(py)
    }

    /// Writes the bake as a `.bake` file (`hprt render --bake` reads it).
    fn save(&self, path: PathBuf) -> PyResult<()> {
        precompute::bakefile::write(&path, &self.transfer, &self.mesh_hash).map_err(hprt_error)
    }

    fn __repr__(&self) -> String {
        let s = &self.transfer.settings;
        format!(
            "Bake(order={}, samples={}, bounces={}, vertices={})",
            s.order,
            s.samples,
            s.bounces,
            self.transfer.direct.vertex_count()
        )
    }
}

/// `vectors` as a read-only numpy array over their own memory, `owner` (the `Bake` holding
/// them, immutable) kept alive by the array.
fn shared_view<'py>(
    vectors: &TransferVectors,
    owner: Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyArray3<f32>>> {
    let n = vectors.order() * vectors.order();
    let view = ArrayView3::from_shape((vectors.vertex_count(), 3, n), vectors.as_slice())
        .expect("vertices × 3 × order² coefficients");
    // SAFETY: the memory belongs to the `Transfer` behind the frozen `Bake` `owner`, which
    // never changes it and which the array keeps alive; the array is made read-only below.
    let array = unsafe { PyArray3::borrow_from_array(&view, owner) };
    array.call_method(
        "setflags",
        (),
        Some(&[("write", false)].into_py_dict(array.py())?),
    )?;
    Ok(array)
}

fn vectors_array(vectors: &TransferVectors) -> Array3<f32> {
    let n = vectors.order() * vectors.order();
    Array3::from_shape_vec((vectors.vertex_count(), 3, n), vectors.as_slice().to_vec())
        .expect("vertices × 3 × order² coefficients")
}

/// Most threads a bake may be asked for: each is a real thread of this process.
const MAX_THREADS: usize = 1024;

/// Bakes `scene` (its `[bake]` settings, each overridden where given) on `threads` threads
/// (all cores when `None`); the same bits whatever the thread count. `progress`: a callable
/// `progress(stage, done, total)`, called at most once per percent of each stage, or `"tqdm"`
/// (or `True`) for bars; Ctrl-C stops the bake within a chunk of vertices. With `cache`, the bake is read
/// from the cache the command line and the viewer share (`$HPRT_CACHE`, else
/// `$XDG_CACHE_HOME/hprt`, else `~/.cache/hprt`) when it holds this geometry and these
/// settings, and written there when not.
#[pyfunction]
#[pyo3(signature = (scene, samples = None, bounces = None, order = None, seed = None, threads = None, progress = None, cache = false))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn bake(
    py: Python<'_>,
    scene: &Scene,
    samples: Option<u32>,
    bounces: Option<u32>,
    order: Option<usize>,
    seed: Option<u64>,
    threads: Option<usize>,
    progress: Option<Bound<'_, PyAny>>,
    cache: bool,
) -> PyResult<Bake> {
    let defaults = scene.data.bake;
    let settings = BakeSettings {
        samples: samples.unwrap_or(defaults.samples),
        bounces: bounces.unwrap_or(defaults.bounces),
        order: order.unwrap_or(defaults.order),
        seed: seed.unwrap_or(defaults.seed),
    };
    settings.validate().map_err(hprt_error)?;
    if let Some(n) = threads.filter(|n| !(1..=MAX_THREADS).contains(n)) {
        return Err(PyValueError::new_err(format!(
            "threads {n}: from 1 to {MAX_THREADS}"
        )));
    }
    let mesh_hash = scene.data.geometry.content_hash();
    let data = Arc::clone(&scene.data);
    let transfer = with_progress(py, progress.as_ref(), "bake", |progress| {
        if cache && let Some((_, transfer)) = cache::load_cached(&data, &settings) {
            return Ok(transfer);
        }
        let run = || -> Result<Transfer, CacheError> {
            if cache {
                return Ok(cache::bake_into_cache(&data, &settings, progress)?.1);
            }
            let bvh = SceneBvh::build(&data.geometry.mesh);
            Ok(precompute::bake::bake(&data.geometry, &bvh, &settings, progress)?.0)
        };
        match threads {
            None => run().map_err(hprt_error),
            Some(n) => rayon::ThreadPoolBuilder::new()
                .num_threads(n)
                .build()
                .map_err(hprt_error)?
                .install(run)
                .map_err(hprt_error),
        }
    })??;
    Ok(Bake {
        transfer: Arc::new(transfer),
        mesh_hash,
    })
}

/// Loads a `.bake` file of `scene` (refused if it was baked from other geometry).
#[pyfunction]
pub(crate) fn load_bake(scene: &Scene, path: PathBuf) -> PyResult<Bake> {
    crate::errors::existing(&path)?;
    let mesh_hash = scene.data.geometry.content_hash();
    let transfer = precompute::bakefile::read_for_mesh(&path, &mesh_hash).map_err(hprt_error)?;
    Ok(Bake {
        transfer: Arc::new(transfer),
        mesh_hash,
    })
}
