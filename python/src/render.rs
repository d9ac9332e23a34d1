//! `hprt.Renderer`: the real-time renderer (PRT pass plus shadow-mapped lights) on a headless
//! GPU, made once per scene and bake and reused across frames.

use crate::camera::{Camera, resolve};
use crate::decompose::settings;
use crate::maps::{image_array, map_argument};
use crate::scene::{Bake, Scene};
use numpy::{IntoPyArray, PyArray3};
use pyo3::prelude::*;
use runtime::render::{Backend, GpuContext, Renderer as GpuRenderer, ShadowSettings};
use runtime::{DecomposeMode, EnvironmentLighting, RenderMode};
use std::sync::Arc;

/// The scene's renderer: its GPU buffers and pipelines, kept between `render` calls.
#[pyclass(module = "hprt", unsendable)]
pub(crate) struct Renderer {
    renderer: GpuRenderer,
    scene: Arc<foundation::scene::Scene>,
    order: usize,
    /// The image size, fixed when made.
    size: (u32, u32),
    adapter: String,
    // Declared last: the device outlives the renderer's resources.
    _gpu: GpuContext,
}

#[pymethods]
impl Renderer {
    /// `backend`: "auto" (Vulkan, else OpenGL), "vulkan" or "gl". The image is `width` ×
    /// `height` (the scene camera's size when not given).
    #[new]
    #[pyo3(signature = (scene, bake, backend = "auto", width = None, height = None))]
    fn new(
        scene: &Scene,
        bake: &Bake,
        backend: &str,
        width: Option<u32>,
        height: Option<u32>,
    ) -> PyResult<Self> {
        let backend: Backend = crate::errors::parse_choice("backend", backend)?;
        let data = Arc::clone(&scene.data);
        let camera = resolve(&data.camera, None, width, height)?;
        let gpu = GpuContext::headless(backend).map_err(crate::errors::hprt_error)?;
        let renderer = GpuRenderer::new(
            &gpu,
            &data.geometry,
            &bake.transfer,
            &camera,
            ShadowSettings::default(),
        )
        .map_err(crate::errors::hprt_error)?;
        Ok(Self {
            renderer,
            scene: data,
            order: bake.transfer.settings.order,
            size: (camera.width, camera.height),
            adapter: gpu.description().to_string(),
            _gpu: gpu,
        })
    }

    /// The graphics adapter it draws with.
    #[getter]
    fn adapter(&self) -> String {
        self.adapter.clone()
    }

    /// Renders the scene lit by `map` (a path or an `(H, W, 3) float32` array) turned by
    /// `rotation_deg` about +Y: `mode` "hybrid" (SH part plus shadow-mapped lights), "prt"
    /// (the whole map through the transfer), or a peer ("median-cut", "sh-sun"). Returns the
    /// linear radiance image, `(height, width, 3) float32`, seen by `camera` (the scene's
    /// when not given).
    #[pyo3(signature = (map, mode = "hybrid", rotation_deg = 0.0, decompose_mode = "consistent", camera = None))]
    fn render<'py>(
        &mut self,
        py: Python<'py>,
        map: &Bound<'py, PyAny>,
        mode: &str,
        rotation_deg: f32,
        decompose_mode: &str,
        camera: Option<Camera>,
    ) -> PyResult<Bound<'py, PyArray3<f32>>> {
        let (width, height) = self.size;
        let view = resolve(
            &self.scene.camera,
            camera.as_ref(),
            Some(width),
            Some(height),
        )?;
        self.renderer
            .set_camera(&view)
            .map_err(crate::errors::hprt_error)?;
        let mode: RenderMode = crate::errors::parse_choice("mode", mode)?;
        let decompose_mode: DecomposeMode =
            crate::errors::parse_choice("decompose_mode", decompose_mode)?;
        let map = map_argument(map)?;
        let mut lighting =
            EnvironmentLighting::new(&map, settings(decompose_mode, None, Some(self.order)))
                .map_err(crate::errors::hprt_error)?;
        lighting.set_rotation(rotation_deg);
        if self.scene.geometry.is_glossy() {
            lighting.enable_reflections(Some(runtime::render::DEFAULT_REFLECTION_SIZE));
        }
        let frame = lighting.frame(mode, None);
        self.renderer.set_environment(lighting.map(), rotation_deg);
        self.renderer
            .set_lighting(&frame.lighting)
            .map_err(crate::errors::hprt_error)?;
        self.renderer.render().map_err(crate::errors::hprt_error)?;
        let image = self
            .renderer
            .read_back()
            .map_err(crate::errors::hprt_error)?;
        Ok(image_array(&image).into_pyarray(py))
    }
}
