//! `hprt.reference`: the CPU path-traced truth of a scene under a map.

use crate::camera::{Camera, resolve};
use crate::maps::{image_array, map_argument};
use crate::progress::with_progress;
use crate::scene::Scene;
use ::reference::{EnvironmentLight, ReferenceSettings};
use foundation::bvh::SceneBvh;
use numpy::{IntoPyArray, PyArray3};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use std::sync::Arc;

/// Path-traces `scene` under `map` (a path or an `(H, W, 3) float32` array) turned by
/// `rotation_deg` (the scene's when not given, as on the command line): `spp` samples per pixel, `bounces` interreflections, `seed`. The image is
/// `width` × `height` (the scene camera's size when not given), seen by `camera` (the scene's
/// when not given); the same bits whatever the thread count. `progress` (as `hprt.bake`'s)
/// counts image rows; Ctrl-C stops the render within a row.
#[pyfunction]
#[pyo3(signature = (scene, map, spp = 64, bounces = 4, seed = 0, rotation_deg = None, width = None, height = None, camera = None, progress = None))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn reference<'py>(
    py: Python<'py>,
    scene: &Scene,
    map: &Bound<'py, PyAny>,
    spp: u32,
    bounces: u32,
    seed: u64,
    rotation_deg: Option<f32>,
    width: Option<u32>,
    height: Option<u32>,
    camera: Option<Camera>,
    progress: Option<Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyArray3<f32>>> {
    let settings = path_settings(spp, bounces, seed)?;
    let rotation_deg = crate::scene::map_rotation(&scene.data, rotation_deg);
    let data = Arc::clone(&scene.data);
    let camera = resolve(&data.camera, camera.as_ref(), width, height)?;
    let map = map_argument(map)?;
    let image = with_progress(py, progress.as_ref(), "reference", |progress| {
        let bvh = SceneBvh::cached(&data.geometry.mesh);
        let light = EnvironmentLight::new(&map, rotation_deg);
        ::reference::try_render(&data.geometry, &bvh, &light, &camera, &settings, progress)
    })?
    .map_err(crate::errors::hprt_error)?;
    Ok(image_array(&image.radiance).into_pyarray(py))
}

/// The path tracer's settings, checked as the command line checks them.
pub(crate) fn path_settings(spp: u32, bounces: u32, seed: u64) -> PyResult<ReferenceSettings> {
    if spp == 0 {
        return Err(PyValueError::new_err("spp must be at least 1"));
    }
    let settings = ReferenceSettings::new(spp, bounces, seed);
    settings
        .validate()
        .map_err(|e| PyValueError::new_err(format!("spp: {e}")))?;
    Ok(settings)
}
