//! `hprt.reference`: the CPU path-traced truth of a scene under a map.

use crate::maps::{image_array, map_argument};
use crate::scene::Scene;
use ::reference::{EnvironmentLight, ReferenceSettings};
use foundation::bvh::SceneBvh;
use foundation::infra::progress::NoProgress;
use numpy::{IntoPyArray, PyArray3};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use std::sync::Arc;

/// Path-traces `scene` under `map` (a path or an `(H, W, 3) float32` array) turned by
/// `rotation_deg`: `spp` samples per pixel, `bounces` interreflections, `seed`. The image is
/// `width` × `height` (the scene camera's size when not given); the same bits whatever the
/// thread count.
#[pyfunction]
#[pyo3(signature = (scene, map, spp = 64, bounces = 4, seed = 0, rotation_deg = 0.0, width = None, height = None))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn reference<'py>(
    py: Python<'py>,
    scene: &Scene,
    map: &Bound<'py, PyAny>,
    spp: u32,
    bounces: u32,
    seed: u64,
    rotation_deg: f32,
    width: Option<u32>,
    height: Option<u32>,
) -> PyResult<Bound<'py, PyArray3<f32>>> {
    let settings = ReferenceSettings::new(spp, bounces, seed);
    settings
        .validate()
        .map_err(|e| PyValueError::new_err(format!("spp: {e}")))?;
    let data = Arc::clone(&scene.data);
    let camera = data.camera.with_size(
        width.unwrap_or(data.camera.width),
        height.unwrap_or(data.camera.height),
    );
    camera
        .validate()
        .map_err(|e| PyValueError::new_err(format!("width, height: {e}")))?;
    let map = map_argument(map)?;
    let image = py.detach(|| {
        let bvh = SceneBvh::build(&data.geometry.mesh);
        let light = EnvironmentLight::new(&map, rotation_deg);
        ::reference::render(
            &data.geometry,
            &bvh,
            &light,
            &camera,
            &settings,
            &NoProgress,
        )
    });
    Ok(image_array(&image.radiance).into_pyarray(py))
}
