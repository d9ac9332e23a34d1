//! hprt in a page: a scene exported by `hprt export web` ([`runtime::bundle`]), drawn by the
//! runtime's renderer with the same WGSL as the native program, its map decomposed in the page
//! each time it turns. `index.html` (beside this crate) is the page: it fetches the scene,
//! opens a [`Viewer`] on its canvas and drives it; what differs from the native viewer (files,
//! threads, the event loop) stays there and in [`canvas`].
#![cfg(target_arch = "wasm32")]

mod canvas;

use canvas::{CanvasGpu, WebBackend};
use runtime::bundle::{BundledMap, SceneBundle};
use runtime::render::{DisplayPass, Renderer, ShadowSettings};
use runtime::viewer::Orbit;
use runtime::{EnvironmentLighting, RenderMode};
use wasm_bindgen::prelude::*;
use web_sys::HtmlCanvasElement;

/// What the page shows behind nothing: the viewer's grey.
const BACKGROUND: wgpu::Color = wgpu::Color {
    r: 0.05,
    g: 0.05,
    b: 0.06,
    a: 1.0,
};

/// Lights of the median-cut peer (`hprt render`'s default `--lights`).
const MEDIAN_CUT_LIGHTS: usize = 8;

fn js_error(e: impl std::fmt::Display) -> JsError {
    JsError::new(&e.to_string())
}

/// Panics (a bug) reach the browser's console with their message.
#[wasm_bindgen(start)]
fn start() {
    console_error_panic_hook::set_once();
}

/// A scene drawn into a canvas.
#[wasm_bindgen]
pub struct Viewer {
    canvas: CanvasGpu,
    renderer: Renderer,
    display: DisplayPass,
    lighting: EnvironmentLighting,
    maps: Vec<BundledMap>,
    map: usize,
    rotation_deg: f32,
    mode: RenderMode,
    orbit: Orbit,
    /// The exported camera, drawn exactly until the user moves it (then [`Self::orbit`]'s).
    camera: Option<foundation::camera::Camera>,
    /// The decomposition (or projection) is stale: the map, its rotation or the mode changed.
    lighting_stale: bool,
    /// What the last [`Viewer::frame`] spent on the lighting (ms).
    lighting_ms: f64,
    light_count: usize,
    /// Decompositions (or projections) made so far.
    decompositions: u32,
}

#[wasm_bindgen]
impl Viewer {
    /// Opens `canvas` on `backend` ("webgpu", "webgl2", or "" for the first that works) and
    /// uploads the scene of `scene` (the bytes of an exported `scene.bin`).
    pub async fn open(
        canvas: HtmlCanvasElement,
        scene: Vec<u8>,
        backend: String,
    ) -> Result<Viewer, JsError> {
        let bundle = SceneBundle::from_bytes("scene.bin", &scene).map_err(js_error)?;
        drop(scene);
        let wanted = match backend.as_str() {
            "webgpu" => Some(WebBackend::WebGpu),
            "webgl2" => Some(WebBackend::WebGl2),
            "" => None,
            other => return Err(js_error(format!("unknown backend {other:?}"))),
        };
        canvas.set_width(bundle.camera.width);
        canvas.set_height(bundle.camera.height);
        let opened = canvas::open(&canvas, wanted).await.map_err(js_error)?;
        Self::with_gpu(opened, bundle)
    }

    fn with_gpu(canvas: CanvasGpu, bundle: SceneBundle) -> Result<Viewer, JsError> {
        let SceneBundle {
            camera,
            geometry,
            transfer,
            decompose,
            maps,
            ..
        } = bundle;
        let first = &maps[0];
        let mut lighting = EnvironmentLighting::new(&first.map, decompose).map_err(js_error)?;
        lighting.set_rotation(first.rotation_deg);
        lighting
            .set_median_cut_lights(MEDIAN_CUT_LIGHTS)
            .map_err(js_error)?;
        if geometry.is_glossy() {
            lighting.enable_reflections(Some(runtime::render::DEFAULT_REFLECTION_SIZE));
        }
        let renderer = Renderer::new(
            &canvas.gpu,
            &geometry,
            &transfer,
            &camera,
            ShadowSettings::default(),
        )
        .map_err(js_error)?;
        let display = DisplayPass::new(&canvas.gpu.device, canvas.config.format);
        let mut viewer = Viewer {
            rotation_deg: first.rotation_deg,
            orbit: Orbit::from_camera(&camera),
            camera: Some(camera),
            canvas,
            renderer,
            display,
            lighting,
            maps,
            map: 0,
            mode: RenderMode::Hybrid,
            lighting_stale: true,
            lighting_ms: 0.0,
            light_count: 0,
            decompositions: 0,
        };
        viewer.set_environment();
        Ok(viewer)
    }

    /// "WebGPU" or "WebGL2".
    pub fn backend(&self) -> String {
        self.canvas.backend.name().into()
    }

    /// The adapter, as the native program prints it.
    pub fn adapter(&self) -> String {
        self.canvas.gpu.description().to_string()
    }

    /// The maps the page can choose among, in order.
    pub fn map_names(&self) -> Vec<String> {
        self.maps.iter().map(|m| m.name.clone()).collect()
    }

    pub fn set_map(&mut self, index: usize) -> Result<(), JsError> {
        let map = self
            .maps
            .get(index)
            .ok_or_else(|| js_error(format!("no map {index}")))?;
        self.map = index;
        self.rotation_deg = map.rotation_deg;
        self.lighting.set_map(map.map.clone());
        self.set_environment();
        Ok(())
    }

    /// The current map's rotation about +Y (degrees).
    pub fn rotation(&self) -> f32 {
        self.rotation_deg
    }

    /// Turns the map: the next frame decomposes it again.
    pub fn set_rotation(&mut self, degrees: f32) {
        if degrees.is_finite() && degrees != self.rotation_deg {
            self.rotation_deg = degrees;
            self.renderer.set_environment_rotation(degrees);
            self.lighting_stale = true;
        }
    }

    /// "hybrid", "prt", "median-cut", "sh-sun", "ibl" (or any `hprt render --mode`).
    pub fn set_mode(&mut self, mode: &str) -> Result<(), JsError> {
        self.mode = mode.parse().map_err(js_error)?;
        self.lighting_stale = true;
        Ok(())
    }

    /// Orbits the camera by a drag of `dx`, `dy` pixels.
    pub fn orbit(&mut self, dx: f32, dy: f32) {
        self.camera = None;
        self.orbit.rotate(dx, dy);
    }

    /// Moves the camera in (positive) or out by wheel or pinch steps.
    pub fn zoom(&mut self, steps: f32) {
        self.camera = None;
        self.orbit.zoom(steps);
    }

    /// Decomposes the map if it changed, and draws a frame into the canvas.
    pub fn frame(&mut self) -> Result<(), JsError> {
        if self.lighting_stale {
            self.lighting.set_rotation(self.rotation_deg);
            // Every turn is a new decomposition in the page, as a changing map's would be.
            self.lighting.forget_derived();
            let frame = self.lighting.frame(self.mode, None);
            self.lighting_ms = frame.ms;
            self.decompositions += 1;
            self.light_count = frame.lighting.lights.len();
            self.renderer
                .set_lighting(&frame.lighting)
                .map_err(js_error)?;
            self.lighting_stale = false;
        }
        let (width, height) = (self.canvas.config.width, self.canvas.config.height);
        let camera = self
            .camera
            .unwrap_or_else(|| self.orbit.camera(width, height));
        self.renderer.set_camera(&camera).map_err(js_error)?;
        self.renderer.render().map_err(js_error)?;
        self.present()
    }

    fn present(&mut self) -> Result<(), JsError> {
        let output = match self.canvas.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(t)
            | wgpu::CurrentSurfaceTexture::Suboptimal(t) => t,
            // Hidden or resized: configured again, drawn next frame.
            wgpu::CurrentSurfaceTexture::Outdated | wgpu::CurrentSurfaceTexture::Occluded => {
                let c = &self.canvas;
                c.surface.configure(&c.gpu.device, &c.config);
                return Ok(());
            }
            other => return Err(js_error(format!("the canvas cannot be drawn: {other:?}"))),
        };
        let view = output.texture.create_view(&Default::default());
        let gpu = &self.canvas.gpu;
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        let exposure = self.maps[self.map].exposure;
        self.display.record(
            gpu,
            &mut encoder,
            &view,
            BACKGROUND,
            Some((&self.renderer, exposure)),
            |_| {},
        );
        gpu.queue.submit([encoder.finish()]);
        gpu.queue.present(output);
        Ok(())
    }

    /// What the last decomposition (or projection) took, in milliseconds.
    pub fn lighting_ms(&self) -> f64 {
        self.lighting_ms
    }

    /// Decompositions (or projections) made so far: one more for each frame the map turned.
    pub fn decompositions(&self) -> u32 {
        self.decompositions
    }

    /// Directional lights in the current frame.
    pub fn light_count(&self) -> usize {
        self.light_count
    }

    /// The last frame's linear radiance, RGB per pixel, rows from the top: what `hprt render
    /// --exr` writes for the same view.
    pub async fn read_frame(&self) -> Result<js_sys::Float32Array, JsError> {
        let copy = self.renderer.start_read_back();
        let (sender, mut receiver) = futures_channel::oneshot::channel();
        copy.buffer()
            .slice(..)
            .map_async(wgpu::MapMode::Read, move |result| {
                let _ = sender.send(result);
            });
        // WebGPU maps on its own; WebGL2 maps only when polled, once its fence has passed.
        let mapped = loop {
            let _ = self.canvas.gpu.device.poll(wgpu::PollType::Poll);
            match receiver.try_recv() {
                Ok(Some(result)) => break result,
                Ok(None) => next_tick().await?,
                Err(_) => return Err(js_error("the frame's read-back was dropped")),
            }
        };
        mapped.map_err(js_error)?;
        let image = self.renderer.finish_read_back(copy).map_err(js_error)?;
        let values: Vec<f32> = image.pixels.iter().flat_map(|p| p.to_array()).collect();
        Ok(js_sys::Float32Array::from(values.as_slice()))
    }

    /// The frame's width and height.
    pub fn size(&self) -> Vec<u32> {
        vec![self.canvas.config.width, self.canvas.config.height]
    }
}

/// Lets the browser run (a zero-delay timeout) before the caller goes on.
async fn next_tick() -> Result<(), JsError> {
    let promise = js_sys::Promise::new(&mut |resolve, _| {
        if let Some(window) = web_sys::window() {
            let _ = window.set_timeout_with_callback_and_timeout_and_arguments_0(&resolve, 0);
        }
    });
    wasm_bindgen_futures::JsFuture::from(promise)
        .await
        .map(|_| ())
        .map_err(|e| js_error(format!("{e:?}")))
}

impl Viewer {
    fn set_environment(&mut self) {
        let map = &self.maps[self.map];
        self.renderer.set_environment(&map.map, self.rotation_deg);
        self.lighting_stale = true;
    }
}
