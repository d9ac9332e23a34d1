//! `hprt.reference_composite`: the path-traced true composite of a scene's virtual objects
//! into its backplate (CONVENTIONS.md, "Compositing"): the scene rendered with and without
//! them, the backplate times their ratio on the proxies.

use crate::camera::{Camera, resolve};
use crate::maps::{image_array, map_argument};
use crate::progress::with_progress;
use crate::reference::path_settings;
use crate::scene::{Scene, map_rotation};
use ::reference::EnvironmentLight;
use ::reference::composite::{Composite as CompositeData, PixelKind, try_render_composite};
use foundation::scene::{Backplate, load_backplate_image};
use numpy::ndarray::{Array2, Array3};
use numpy::{IntoPyArray, PyArray2, PyArray3};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use std::sync::Arc;

/// A composite and the layers a compositor redoes it from.
#[pyclass(module = "hprt", frozen)]
pub(crate) struct Composite {
    image: Array3<f32>,
    objects: Array3<f32>,
    ratio: Array3<f32>,
    kinds: Array2<u8>,
    changed: Array2<bool>,
}

#[pymethods]
impl Composite {
    /// The composite, `(height, width, 3)`, linear.
    #[getter]
    fn image<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray3<f32>> {
        self.image.clone().into_pyarray(py)
    }

    /// The rendered radiance on object pixels, zero elsewhere.
    #[getter]
    fn objects<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray3<f32>> {
        self.objects.clone().into_pyarray(py)
    }

    /// The shadow ratio `L(with) / L(without)` on proxy pixels, one elsewhere.
    #[getter]
    fn ratio<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray3<f32>> {
        self.ratio.clone().into_pyarray(py)
    }

    /// Per pixel: 0 a virtual object, 1 a proxy, 2 the backplate alone.
    #[getter]
    fn kinds<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<u8>> {
        self.kinds.clone().into_pyarray(py)
    }

    /// Proxy pixels whose luminance the objects change by more than 2%.
    #[getter]
    fn changed<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<bool>> {
        self.changed.clone().into_pyarray(py)
    }
}

/// Path-traces the composite of `scene` (which must have a `[backplate]` and proxies) under
/// `map`, as `hprt reference` does for such a scene: the same settings as [`crate::reference`].
#[pyfunction]
#[pyo3(signature = (scene, map, spp = 64, bounces = 4, seed = 0, rotation_deg = None, width = None, height = None, camera = None, progress = None))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn reference_composite(
    py: Python<'_>,
    scene: &Scene,
    map: &Bound<'_, PyAny>,
    spp: u32,
    bounces: u32,
    seed: u64,
    rotation_deg: Option<f32>,
    width: Option<u32>,
    height: Option<u32>,
    camera: Option<Camera>,
    progress: Option<Bound<'_, PyAny>>,
) -> PyResult<Composite> {
    let data = Arc::clone(&scene.data);
    let Some(backplate) = &data.backplate else {
        return Err(PyValueError::new_err(format!(
            "{}: no [backplate] to composite into",
            data.path.display()
        )));
    };
    let settings = path_settings(spp, bounces, seed)?;
    let rotation_deg = map_rotation(&data, rotation_deg);
    let camera = resolve(&data.camera, camera.as_ref(), width, height)?;
    let plate = match backplate {
        Backplate::Image(path) => Some(
            load_backplate_image(path, camera.width, camera.height)
                .map_err(crate::errors::hprt_error)?,
        ),
        Backplate::Environment => None,
    };
    let map = map_argument(map)?;
    let rendered = with_progress(py, progress.as_ref(), "composite", |progress| {
        let light = EnvironmentLight::new(&map, rotation_deg);
        try_render_composite(
            &data.geometry,
            &light,
            &camera,
            &settings,
            plate.as_ref(),
            progress,
        )
    })?
    .map_err(crate::errors::hprt_error)?;
    Ok(layers(&rendered.composite))
}

/// A composite's image and layers as numpy arrays.
pub(crate) fn layers(c: &CompositeData) -> Composite {
    let (w, h) = (c.image.width, c.image.height);
    let kind = |k: &PixelKind| match k {
        PixelKind::Object => 0u8,
        PixelKind::Proxy => 1,
        PixelKind::Background => 2,
    };
    Composite {
        image: image_array(&c.image),
        objects: image_array(&c.objects),
        ratio: image_array(&c.ratio),
        kinds: Array2::from_shape_vec((h, w), c.kinds.iter().map(kind).collect())
            .expect("one kind per pixel"),
        changed: Array2::from_shape_vec((h, w), c.changed.clone()).expect("one flag per pixel"),
    }
}
