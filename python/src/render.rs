//! `hprt.Renderer`: the real-time renderer (PRT pass plus shadow-mapped lights) on a headless
//! GPU, made once per scene and bake and reused across frames.

use crate::camera::{Camera, resolve};
use crate::decompose::{Decomposition, settings};
use crate::maps::{image_array, map_argument};
use crate::scene::{Bake, Scene};
use foundation::Rgb;
use foundation::envmap::EnvMap;
use numpy::{IntoPyArray, PyArray3};
use precompute::bake::Transfer;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use runtime::render::{Backend, GpuContext, Renderer as GpuRenderer, ShadowSettings};
use runtime::{
    DecomposeMode, EnvironmentLighting, FrameLighting, ReflectedEnvironment, RenderMode,
    lights_indirect_default,
};
use std::sync::Arc;

/// The scene's renderer: its GPU buffers and pipelines, kept between `render` calls.
#[pyclass(module = "hprt", unsendable)]
pub(crate) struct Renderer {
    renderer: GpuRenderer,
    scene: Arc<foundation::scene::Scene>,
    /// The whole scene's bake (the composite's proxies are baked with its settings).
    transfer: Arc<Transfer>,
    order: usize,
    /// The image size, fixed when made.
    size: (u32, u32),
    adapter: String,
    // Declared last: the device outlives the renderer's resources.
    gpu: GpuContext,
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
            transfer: Arc::clone(&bake.transfer),
            order: bake.transfer.settings.order,
            size: (camera.width, camera.height),
            adapter: gpu.description().to_string(),
            gpu,
        })
    }

    /// The graphics adapter it draws with.
    #[getter]
    fn adapter(&self) -> String {
        self.adapter.clone()
    }

    /// Renders the scene lit by `lighting`, turned by `rotation_deg` about +Y (the scene's
    /// `rotation_deg` when not given, as on the command line; a `Decomposition` is already
    /// turned, and only its background is), seen by
    /// `camera` (the scene's when not given). `lighting` is a map (a path or an `(H, W, 3)
    /// float32` array), decomposed here, or a `Decomposition` (one of `hprt.decompose`'s, or
    /// SH and lights of your own, drawn over `background`, a map, black when not given).
    /// `mode`: "hybrid" (SH part plus shadow-mapped lights), "prt" (the whole map through
    /// the transfer), "unshadowed", "lights", or a peer ("median-cut", "sh-sun", "ibl"; a map only).
    /// Returns the linear radiance image, `(height, width, 3) float32`.
    #[pyo3(signature = (lighting, mode = "hybrid", rotation_deg = None, decompose_mode = "consistent", camera = None, background = None))]
    #[allow(clippy::too_many_arguments)]
    fn render<'py>(
        &mut self,
        py: Python<'py>,
        lighting: &Bound<'py, PyAny>,
        mode: &str,
        rotation_deg: Option<f32>,
        decompose_mode: &str,
        camera: Option<Camera>,
        background: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyArray3<f32>>> {
        let rotation_deg = crate::scene::map_rotation(&self.scene, rotation_deg);
        self.set_view(camera.as_ref())?;
        let (frame, environment) =
            self.frame_lighting(lighting, (mode, decompose_mode), rotation_deg, background)?;
        self.renderer.set_environment(&environment, rotation_deg);
        self.renderer
            .set_lighting(&frame)
            .map_err(crate::errors::hprt_error)?;
        self.renderer.render().map_err(crate::errors::hprt_error)?;
        let image = self
            .renderer
            .read_back()
            .map_err(crate::errors::hprt_error)?;
        Ok(image_array(&image).into_pyarray(py))
    }
}

impl Renderer {
    /// Points the renderer at `camera` (the scene's when not given), at its image size.
    pub(crate) fn set_view(
        &mut self,
        camera: Option<&Camera>,
    ) -> PyResult<foundation::camera::Camera> {
        let (width, height) = self.size;
        let view = resolve(&self.scene.camera, camera, Some(width), Some(height))?;
        self.renderer
            .set_camera(&view)
            .map_err(crate::errors::hprt_error)?;
        Ok(view)
    }

    /// A frame's lighting from `lighting` (a map, decomposed here, or a `Decomposition`) in
    /// `mode`, and the map the background shows.
    pub(crate) fn frame_lighting(
        &self,
        lighting: &Bound<'_, PyAny>,
        (mode, decompose_mode): (&str, &str),
        rotation_deg: f32,
        background: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<(FrameLighting, EnvMap)> {
        let mode: RenderMode = crate::errors::parse_choice("mode", mode)?;
        let decompose_mode: DecomposeMode =
            crate::errors::parse_choice("decompose_mode", decompose_mode)?;
        Ok(match lighting.cast::<Decomposition>() {
            Ok(given) => {
                let frame = self.given_lighting(&given.borrow(), mode, decompose_mode)?;
                let environment = match background {
                    Some(map) => map_argument(map)?,
                    None => EnvMap::uniform(2, 1, Rgb::ZERO),
                };
                (frame, environment)
            }
            Err(_) => {
                let map = map_argument(lighting)?;
                let mut decomposer = EnvironmentLighting::new(
                    &map,
                    settings(decompose_mode, None, Some(self.order)),
                )
                .map_err(crate::errors::hprt_error)?;
                decomposer.set_rotation(rotation_deg);
                if self.scene.geometry.is_glossy() {
                    decomposer.enable_reflections(Some(runtime::render::DEFAULT_REFLECTION_SIZE));
                }
                (decomposer.frame(mode, None).lighting, map)
            }
        })
    }

    /// The scene it draws.
    pub(crate) fn scene(&self) -> &foundation::scene::Scene {
        &self.scene
    }

    /// What the GPU composite draws with: the device, the whole scene's renderer and bake,
    /// and the scene.
    pub(crate) fn composite_parts(
        &mut self,
    ) -> (
        &GpuContext,
        &mut GpuRenderer,
        &Transfer,
        &foundation::scene::Scene,
    ) {
        (&self.gpu, &mut self.renderer, &self.transfer, &self.scene)
    }

    /// A frame of given SH and lights, in the modes that draw a decomposition as it is.
    fn given_lighting(
        &self,
        given: &Decomposition,
        mode: RenderMode,
        decompose_mode: DecomposeMode,
    ) -> PyResult<FrameLighting> {
        let (sh, lights) = given.parts(self.order)?;
        let indirect = lights_indirect_default(decompose_mode);
        let mut frame = match mode {
            RenderMode::Hybrid | RenderMode::Unshadowed | RenderMode::Lights => {
                let decomposition = runtime::Decomposition {
                    total_power: Rgb::ZERO,
                    candidates: lights.len(),
                    sh: sh.clone(),
                    lights,
                };
                FrameLighting::for_mode(mode, &sh, &decomposition, indirect)
            }
            _ => {
                return Err(PyValueError::new_err(format!(
                    "mode {mode}: a Decomposition is drawn in hybrid, unshadowed or lights mode \
                     (prt and the peers start from a map)"
                )));
            }
        };
        // Glossy surfaces reflect the SH part where no map is decomposed here.
        frame.reflections = ReflectedEnvironment::Sh(frame.sh.clone());
        Ok(frame)
    }
}
