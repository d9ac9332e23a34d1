//! `hprt view`: the real-time viewer (winit + egui). The lighting is decomposed again every
//! frame it changes, as in the thesis' dynamic-lighting case.
//!
//! The [`App`] is split by concern: the bake ([`BakeState`]), the environment's lighting
//! ([`LightingState`]), the window and its GPU ([`WindowState`]), mouse input
//! ([`InputState`]), the panel ([`ui::PanelState`]) and a script ([`ScriptState`]); the panel
//! edits only the [`ViewSettings`].

mod orbit;
mod script;
mod settings;
mod ui;
mod window;

use crate::bake_cache;
use crate::environment::{default_exposure, maps_beside, scene_rotation};
use crate::sequence::Sequence;
use crate::support::{load_scene, median};
use anyhow::Context;
use clap::Args;
use foundation::infra::progress::SharedProgress;
use foundation::scene::Scene;
use orbit::Orbit;
use precompute::bake::Transfer;
use runtime::lighting::lights_indirect_default;
use runtime::render::{Backend, RenderMode, Renderer, ShadowSettings};
use runtime::{DecomposeMode, DecomposeSettings, Decomposition, EnvironmentLighting};
use settings::ViewSettings;
use std::collections::VecDeque;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;
use ui::{BakeStatus, PanelAction, PanelInfo, PanelState};
use window::WindowGpu;
use winit::application::ApplicationHandler;
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, EventLoop};
use winit::window::{Window, WindowId};

#[derive(Args)]
pub struct ViewArgs {
    /// Scene file (TOML), or a model (glTF, OBJ, PLY, BPT) placed in a default scene (`hprt
    /// scene init` writes that scene out for editing).
    pub scene: PathBuf,
    /// Bake of the scene (default: the cached bake of the scene's [bake] settings, or offer
    /// to make one).
    #[arg(long)]
    pub bake: Option<PathBuf>,
    /// Environment map (default: the scene's); it gets the scene's rotation_deg.
    #[arg(long)]
    pub env: Option<PathBuf>,
    /// Play an environment sequence (a folder of maps or a sequence file, see
    /// scenes/README.md): one sequence frame per drawn frame, looping, the lights tracked.
    #[arg(long, conflicts_with = "env")]
    pub env_sequence: Option<PathBuf>,
    /// Graphics backend: auto, vulkan or gl.
    #[arg(long, default_value = "auto")]
    pub backend: Backend,
    /// Window size.
    #[arg(long, default_value_t = 1280)]
    pub width: u32,
    #[arg(long, default_value_t = 720)]
    pub height: u32,
    /// Drive the viewer from a script of commands (see src/view/script.rs).
    #[arg(long)]
    pub script: Option<PathBuf>,
}

/// The scene's bake: loaded, being made in the background, or missing.
struct BakeState {
    path: PathBuf,
    transfer: Option<Arc<Transfer>>,
    job: Option<BakeJob>,
}

/// A bake running in the background.
struct BakeJob {
    progress: Arc<SharedProgress>,
    result: std::sync::mpsc::Receiver<anyhow::Result<Transfer>>,
}

/// The environment map as lighting, and the settings it was last turned into lighting for.
#[derive(Default)]
struct LightingState {
    environment: Option<EnvironmentLighting>,
    lit_for: Option<ViewSettings>,
    decomposition: Option<Decomposition>,
    decomposition_ms: f64,
    /// A sequence being played, and the frame shown.
    sequence: Option<(Sequence, usize)>,
}

/// The window, its GPU and what is drawn in it.
struct WindowState {
    backend: Backend,
    /// Requested, then current, window size in pixels.
    size: (u32, u32),
    window: Option<Arc<Window>>,
    gpu: Option<WindowGpu>,
    renderer: Option<Renderer>,
    egui_ctx: egui::Context,
    egui_state: Option<egui_winit::State>,
}

/// The camera and the mouse.
struct InputState {
    orbit: Orbit,
    initial_orbit: Orbit,
    drag: Option<(MouseButton, (f64, f64))>,
    cursor: (f64, f64),
}

/// Commands of `--script` still to run.
#[derive(Default)]
struct ScriptState {
    commands: VecDeque<script::Command>,
    /// Frames to wait before the next command.
    wait: u32,
}

/// Timings and messages the panel and the scripted state report.
#[derive(Default)]
struct Stats {
    frame_ms: VecDeque<f64>,
    adapter: String,
    message: String,
    frames: u64,
    last_frame: Option<Instant>,
}

impl Stats {
    fn median_frame_ms(&self) -> Option<f64> {
        (!self.frame_ms.is_empty()).then(|| median(self.frame_ms.iter().copied().collect()))
    }
}

pub struct App {
    scene: Scene,
    settings: ViewSettings,
    env_choices: Vec<PathBuf>,
    bake: BakeState,
    lighting: LightingState,
    window: WindowState,
    input: InputState,
    panel: PanelState,
    script: ScriptState,
    stats: Stats,
    error: Option<anyhow::Error>,
}

/// Fails clearly when there is no display to open a window on.
fn check_display() -> anyhow::Result<()> {
    let has = |name: &str| std::env::var_os(name).is_some_and(|v| !v.is_empty());
    if !has("DISPLAY") && !has("WAYLAND_DISPLAY") {
        anyhow::bail!(
            "no display: hprt view needs a window (set DISPLAY or WAYLAND_DISPLAY, or run it under \
             `xvfb-run`); to draw an image without a window use `hprt render SCENE --bake BAKE -o out.png`"
        );
    }
    Ok(())
}

pub fn run(args: ViewArgs) -> anyhow::Result<()> {
    check_display()?;
    let scene = load_scene(&args.scene)?;
    let bake_settings = scene.bake;
    let bake = match &args.bake {
        Some(path) => BakeState {
            transfer: Some(Arc::new(bake_cache::load_bake(&scene, path, None)?)),
            path: path.clone(),
            job: None,
        },
        None => match bake_cache::load_cached(&scene, &bake_settings) {
            Some((path, transfer)) => BakeState {
                path,
                transfer: Some(Arc::new(transfer)),
                job: None,
            },
            // Offered in the window, with progress.
            None => BakeState {
                path: bake_cache::bake_path(&scene, &bake_settings),
                transfer: None,
                job: None,
            },
        },
    };
    let env = match (&args.env, &scene.environment) {
        (Some(p), _) => p.clone(),
        (None, Some(spec)) => spec.map.clone(),
        (None, None) => anyhow::bail!(
            "{} names no [environment]; pass --env MAP",
            scene.path.display()
        ),
    };
    let sequence = match &args.env_sequence {
        Some(path) => Some((Sequence::load(path)?, 0)),
        None => None,
    };
    let commands = match &args.script {
        Some(path) => {
            let text = std::fs::read_to_string(path)
                .with_context(|| format!("cannot read {}", path.display()))?;
            script::parse(path, &text)?.into()
        }
        None => VecDeque::new(),
    };
    let order = bake
        .transfer
        .as_ref()
        .map_or(bake_settings.order, |t| t.settings.order);
    let orbit = Orbit::from_camera(&scene.camera);
    let decompose_mode = DecomposeMode::Consistent;
    let settings = ViewSettings {
        env: env.clone(),
        rotation_deg: scene_rotation(&scene, None),
        animate: false,
        animate_speed: 20.0,
        mode: RenderMode::Hybrid,
        decompose_mode,
        threshold: DecomposeSettings::default().threshold,
        order,
        shadow: ShadowSettings::default(),
        lights_indirect: lights_indirect_default(decompose_mode),
        median_cut_lights: 8,
        exposure: 1.0,
        materials: scene.geometry.objects.iter().map(|o| o.material).collect(),
    };
    let event_loop = EventLoop::new().map_err(|e| {
        anyhow::anyhow!(
            "cannot open a window ({e}); to draw an image without a window use `hprt render`"
        )
    })?;
    let mut app = App {
        env_choices: maps_beside(&env),
        panel: PanelState::new(&env),
        scene,
        settings,
        bake,
        lighting: LightingState {
            sequence,
            ..Default::default()
        },
        window: WindowState {
            backend: args.backend,
            size: (args.width, args.height),
            window: None,
            gpu: None,
            renderer: None,
            egui_ctx: egui::Context::default(),
            egui_state: None,
        },
        input: InputState {
            orbit,
            initial_orbit: orbit,
            drag: None,
            cursor: (0.0, 0.0),
        },
        script: ScriptState { commands, wait: 0 },
        stats: Stats::default(),
        error: None,
    };
    app.load_environment();
    // A scene opened for the first time bakes at once, with its progress in the panel, into
    // the cache the next opening reads.
    if app.bake.transfer.is_none() {
        app.start_bake();
    }
    event_loop
        .run_app(&mut app)
        .context("the window's event loop failed")?;
    match app.error {
        Some(error) => Err(error),
        None => Ok(()),
    }
}

impl App {
    fn load_environment(&mut self) {
        // The map, and how many of its texels were invalid and set to 0.
        let loaded = match &self.lighting.sequence {
            Some((sequence, _)) => sequence.frame(0).map(|map| (map, 0)),
            None => crate::environment::load_map(&self.settings.env, None)
                .map(|loaded| (loaded.map, loaded.sanitized)),
        };
        let (map, sanitized) = match loaded {
            Ok(loaded) => loaded,
            Err(e) => {
                self.stats.message = format!("cannot load the map: {e:#}");
                return;
            }
        };
        let mut lighting = match EnvironmentLighting::new(&map, self.settings.decompose_settings())
        {
            Ok(lighting) => lighting,
            Err(e) => {
                self.stats.message = format!("cannot light the scene with the map: {e}");
                return;
            }
        };
        if self.settings.exposure == 1.0 && self.lighting.environment.is_none() {
            self.settings.exposure = default_exposure(&map);
        }
        self.lighting.lit_for = None;
        self.panel.environment_changed();
        self.stats.message = if sanitized > 0 {
            format!("{sanitized} texels with negative or invalid radiance set to 0")
        } else {
            String::new()
        };
        if self.lighting.sequence.is_some()
            && let Err(e) = lighting.enable_tracking(Some(runtime::TrackingSettings::default()))
        {
            self.stats.message = format!("cannot track the lights: {e}");
        }
        if let Some(r) = self.window.renderer.as_mut() {
            r.set_environment(lighting.map(), self.settings.rotation_deg);
            if let Some(gpu) = self.window.gpu.as_mut() {
                gpu.renderer_changed();
            }
        }
        self.lighting.environment = Some(lighting);
    }

    fn start_bake(&mut self) {
        let scene = self.scene.clone();
        let progress = Arc::new(SharedProgress::default());
        let shared = progress.clone();
        let (sender, receiver) = std::sync::mpsc::channel();
        std::thread::spawn(move || {
            let result = bake_cache::bake_into_cache(&scene, &scene.bake, shared.as_ref())
                .map(|(_, transfer, _)| transfer);
            let _ = sender.send(result);
        });
        self.bake.job = Some(BakeJob {
            progress,
            result: receiver,
        });
    }

    fn poll_bake(&mut self) {
        let Some(job) = &self.bake.job else { return };
        match job.result.try_recv() {
            Ok(Ok(transfer)) => {
                self.settings.order = transfer.settings.order;
                self.bake.transfer = Some(Arc::new(transfer));
                self.bake.job = None;
                self.stats.message = format!("baked into {}", self.bake.path.display());
            }
            Ok(Err(e)) => {
                self.stats.message = format!("the bake failed: {e:#}");
                self.bake.job = None;
            }
            Err(_) => {}
        }
    }

    /// Shows the next frame of the sequence being played.
    fn advance_sequence(&mut self) -> anyhow::Result<()> {
        let (Some((sequence, frame)), Some(env)) = (
            self.lighting.sequence.as_mut(),
            self.lighting.environment.as_mut(),
        ) else {
            return Ok(());
        };
        *frame = (*frame + 1) % sequence.len();
        if *frame == 0 {
            // Looping: start the tracking afresh, as on the first frame.
            env.enable_tracking(Some(runtime::TrackingSettings::default()))?;
        }
        env.set_map(sequence.frame(*frame)?);
        if let Some(renderer) = self.window.renderer.as_mut() {
            renderer.set_environment(env.map(), self.settings.rotation_deg);
            if let Some(gpu) = self.window.gpu.as_mut() {
                gpu.renderer_changed();
            }
        }
        self.lighting.lit_for = None;
        self.panel.environment_changed();
        Ok(())
    }

    /// The decomposition (and the renderer's lighting) when anything it depends on changed.
    fn update_lighting(&mut self) -> anyhow::Result<()> {
        let (Some(env), Some(renderer)) = (
            self.lighting.environment.as_mut(),
            self.window.renderer.as_mut(),
        ) else {
            return Ok(());
        };
        renderer.set_shadow_settings(self.settings.shadow)?;
        let materials_changed = self
            .lighting
            .lit_for
            .as_ref()
            .is_none_or(|previous| previous.materials != self.settings.materials);
        if materials_changed {
            // Kept within energy conservation: k_s at most 1 − k_d per channel.
            for (m, o) in self
                .settings
                .materials
                .iter_mut()
                .zip(&self.scene.geometry.objects)
            {
                m.specular = m
                    .specular
                    .min(foundation::Rgb::ONE - o.albedo)
                    .max(foundation::Rgb::ZERO);
            }
            renderer.set_materials(&self.settings.materials)?;
            if renderer.is_glossy() {
                env.enable_reflections(Some(runtime::render::DEFAULT_REFLECTION_SIZE));
            }
        }
        let needs = match &self.lighting.lit_for {
            Some(previous) => {
                materials_changed
                    || previous.rotation_deg != self.settings.rotation_deg
                    || previous.decompose_settings() != self.settings.decompose_settings()
                    || previous.mode != self.settings.mode
                    || previous.lights_indirect != self.settings.lights_indirect
                    || previous.median_cut_lights != self.settings.median_cut_lights
                    || previous.env != self.settings.env
            }
            None => true,
        };
        if !needs {
            return Ok(());
        }
        env.set_settings(self.settings.decompose_settings())?;
        env.set_rotation(self.settings.rotation_deg);
        env.set_median_cut_lights(self.settings.median_cut_lights)?;
        let frame = env.frame(self.settings.mode, Some(self.settings.lights_indirect));
        // The panel shows the lights in every mode, plain PRT included.
        let decomposition = match frame.decomposition {
            Some(d) => d,
            None => env.decompose(),
        };
        renderer.set_lighting(&frame.lighting)?;
        renderer.set_environment_rotation(self.settings.rotation_deg);
        self.lighting.decomposition = Some(decomposition);
        self.lighting.decomposition_ms = frame.ms;
        self.lighting.lit_for = Some(self.settings.clone());
        Ok(())
    }

    fn ensure_renderer(&mut self) -> anyhow::Result<()> {
        if self.window.renderer.is_some() {
            return Ok(());
        }
        let (Some(gpu), Some(transfer)) = (self.window.gpu.as_mut(), self.bake.transfer.as_ref())
        else {
            return Ok(());
        };
        let camera = self.input.orbit.camera(gpu.config.width, gpu.config.height);
        let mut renderer = Renderer::new(
            &gpu.gpu,
            &self.scene.geometry,
            transfer,
            &camera,
            self.settings.shadow,
        )?;
        if let Some(env) = &self.lighting.environment {
            renderer.set_environment(env.map(), self.settings.rotation_deg);
        }
        gpu.renderer_changed();
        self.window.renderer = Some(renderer);
        self.lighting.lit_for = None;
        Ok(())
    }

    fn reset_view(&mut self) {
        self.input.orbit = self.input.initial_orbit;
    }

    fn run_script(&mut self, event_loop: &ActiveEventLoop) -> anyhow::Result<()> {
        if self.script.wait > 0 {
            self.script.wait -= 1;
            return Ok(());
        }
        while let Some(command) = self.script.commands.pop_front() {
            use script::Command as C;
            match command {
                C::Wait(n) => {
                    self.script.wait = n;
                    return Ok(());
                }
                C::WaitBake => {
                    if self.bake.job.is_some() {
                        self.script.commands.push_front(C::WaitBake);
                        return Ok(());
                    }
                    anyhow::ensure!(
                        self.bake.transfer.is_some(),
                        "wait-bake: there is no bake ({})",
                        self.stats.message
                    );
                }
                C::Orbit(dx, dy) => self.input.orbit.rotate(dx, dy),
                C::Pan(dx, dy) => self.input.orbit.pan(dx, dy, self.window.size.1),
                C::Zoom(steps) => self.input.orbit.zoom(steps),
                C::Reset => self.reset_view(),
                C::Set(name, value) => {
                    self.settings.set(&name, &value)?;
                    if name == "env" {
                        self.load_environment();
                    }
                }
                C::Screenshot(path) => self.save_screenshot(&path)?,
                C::WindowScreenshot(path) => self.save_window_screenshot(&path)?,
                C::SaveRenderLine(path) => {
                    let line = self.command_line(&PathBuf::from("render.png"));
                    foundation::infra::atomic_file::write_atomic(
                        &path,
                        format!("{line}\n").as_bytes(),
                    )?;
                }
                C::State(path) => {
                    let json = serde_json::to_string_pretty(&self.state_json())?;
                    foundation::infra::atomic_file::write_atomic(&path, json.as_bytes())?;
                }
                C::Quit => {
                    event_loop.exit();
                    return Ok(());
                }
            }
        }
        Ok(())
    }

    fn current_camera(&self) -> foundation::camera::Camera {
        let (w, h) = self
            .window
            .gpu
            .as_ref()
            .map_or(self.window.size, |g| (g.config.width, g.config.height));
        self.input
            .orbit
            .camera(w.saturating_sub(self.panel.width_px).max(16), h)
    }

    pub fn command_line(&self, output: &Path) -> String {
        self.settings
            .render_command(
                &self.scene.path,
                &self.bake.path,
                &self.current_camera(),
                output,
            )
            .iter()
            .map(|w| settings::shell_quote(w))
            .collect::<Vec<_>>()
            .join(" ")
    }

    fn save_screenshot(&mut self, path: &Path) -> anyhow::Result<()> {
        let renderer = self
            .window
            .renderer
            .as_ref()
            .context("nothing rendered yet (no bake)")?;
        let image = renderer.read_back()?;
        let rgb = foundation::image_io::to_display_rgb8(&image, self.settings.exposure);
        foundation::image_io::write_png_rgb8(path, image.width, image.height, &rgb)?;
        self.stats.message = format!("saved {}", path.display());
        Ok(())
    }

    fn save_window_screenshot(&mut self, path: &Path) -> anyhow::Result<()> {
        let window = self.window.window.clone().context("no window")?;
        let (paint, screen) = self.run_ui(&window);
        let gpu = self.window.gpu.as_mut().context("no window")?;
        let (w, h, rgb) = gpu.capture(
            self.window.renderer.as_ref(),
            self.settings.exposure,
            &paint,
            &screen,
        )?;
        foundation::image_io::write_png_rgb8(path, w as usize, h as usize, &rgb)?;
        Ok(())
    }

    fn state_json(&self) -> serde_json::Value {
        let frame_ms = self.stats.median_frame_ms().unwrap_or(0.0);
        let lights: Vec<f32> = self
            .lighting
            .decomposition
            .as_ref()
            .map(|d| d.lights.iter().map(|l| l.share).collect())
            .unwrap_or_default();
        let camera = self.current_camera();
        serde_json::json!({
            "adapter": self.stats.adapter,
            "frames": self.stats.frames,
            "frame_ms": frame_ms,
            "fps": if frame_ms > 0.0 { 1000.0 / frame_ms } else { 0.0 },
            "decomposition_ms": self.lighting.decomposition_ms,
            "light_shares": lights,
            "panels": self.panel.headings,
            "mode": self.settings.mode.name(),
            "rotation_deg": self.settings.rotation_deg,
            "window": [camera.width, camera.height],
            "command": self.command_line(Path::new("render.png")),
            "materials": self
                .settings
                .materials
                .iter()
                .map(|m| [m.specular.x, m.specular.y, m.specular.z, m.shininess])
                .collect::<Vec<_>>(),
        })
    }

    /// What the panel shows.
    fn panel_info(&self, command_line: String) -> PanelInfo<'_> {
        let bake = match (&self.bake.transfer, &self.bake.job) {
            (Some(t), _) => BakeStatus::Ready {
                order: t.settings.order,
            },
            (None, Some(job)) => BakeStatus::Baking(job.progress.fraction()),
            (None, None) => BakeStatus::Missing {
                path: &self.bake.path,
                settings: self.scene.bake,
            },
        };
        PanelInfo {
            bake,
            environment: self.lighting.environment.as_ref().map(|e| e.map()),
            env_choices: &self.env_choices,
            decomposition: self.lighting.decomposition.as_ref(),
            tracked: self
                .lighting
                .environment
                .as_ref()
                .map_or(&[], |e| e.tracked_lights()),
            sequence_frame: self
                .lighting
                .sequence
                .as_ref()
                .map(|(s, frame)| (*frame, s.len())),
            frame_ms: self.stats.median_frame_ms(),
            decomposition_ms: self.lighting.decomposition_ms,
            adapter: &self.stats.adapter,
            message: &self.stats.message,
            command_line,
            objects: self
                .scene
                .geometry
                .objects
                .iter()
                .map(|o| (o.name.as_str(), o.albedo))
                .collect(),
        }
    }

    fn apply(&mut self, action: PanelAction) {
        match action {
            PanelAction::LoadEnvironment(path) => {
                self.settings.env = path;
                self.load_environment();
            }
            PanelAction::StartBake => self.start_bake(),
            PanelAction::ResetView => self.reset_view(),
            PanelAction::SaveScreenshot => {
                let name = format!("hprt-{}-{}.png", self.scene.name, self.stats.frames);
                if let Err(e) = self.save_screenshot(Path::new(&name)) {
                    self.stats.message = format!("screenshot failed: {e:#}");
                }
            }
        }
    }

    fn run_ui(
        &mut self,
        window: &Window,
    ) -> (Vec<egui::ClippedPrimitive>, egui_wgpu::ScreenDescriptor) {
        let state = self
            .window
            .egui_state
            .as_mut()
            .expect("egui is set up with the window");
        let input = state.take_egui_input(window);
        let ctx = self.window.egui_ctx.clone();
        // The panel edits copies of the settings and its own state while it reads the rest.
        let command_line = self.command_line(Path::new("render.png"));
        let mut settings = self.settings.clone();
        let mut panel = std::mem::take(&mut self.panel);
        let info = self.panel_info(command_line);
        let mut actions = Vec::new();
        let mut output = ctx.run_ui(input, |ui| {
            actions = ui::panel(ui, &mut settings, &mut panel, &info);
        });
        drop(info);
        self.settings = settings;
        self.panel = panel;
        for action in actions {
            self.apply(action);
        }
        let state = self
            .window
            .egui_state
            .as_mut()
            .expect("egui is set up with the window");
        state.handle_platform_output(window, output.platform_output);
        let gpu = self.window.gpu.as_mut().expect("a window has its GPU");
        for (id, deltas) in &output.textures_delta.set {
            for delta in deltas {
                gpu.egui
                    .update_texture(&gpu.gpu.device, &gpu.gpu.queue, *id, delta);
            }
        }
        for id in &output.textures_delta.free {
            gpu.egui.free_texture(id);
        }
        // Applied above: tell epaint they were handled.
        output.textures_delta.clear();
        let paint = ctx.tessellate(output.shapes, output.pixels_per_point);
        let screen = egui_wgpu::ScreenDescriptor {
            size_in_pixels: [gpu.config.width, gpu.config.height],
            pixels_per_point: output.pixels_per_point,
        };
        (paint, screen)
    }

    fn frame(&mut self, event_loop: &ActiveEventLoop) -> anyhow::Result<()> {
        let now = Instant::now();
        if let Some(last) = self.stats.last_frame {
            let dt = now.duration_since(last).as_secs_f64();
            self.stats.frame_ms.push_back(dt * 1e3);
            if self.stats.frame_ms.len() > 60 {
                self.stats.frame_ms.pop_front();
            }
            if self.settings.animate {
                self.settings.rotation_deg = (self.settings.rotation_deg
                    + self.settings.animate_speed * dt as f32)
                    .rem_euclid(360.0);
            }
        }
        self.stats.last_frame = Some(now);
        self.poll_bake();
        self.run_script(event_loop)?;
        self.ensure_renderer()?;
        if self.window.renderer.is_some() {
            self.advance_sequence()?;
        }
        self.update_lighting()?;
        let camera = self.current_camera();
        if let Some(renderer) = self.window.renderer.as_mut() {
            if renderer.set_camera(&camera)?
                && let Some(gpu) = self.window.gpu.as_mut()
            {
                gpu.renderer_changed();
            }
            renderer.render()?;
        }
        let window = self.window.window.clone().context("no window")?;
        let (paint, screen) = self.run_ui(&window);
        let gpu = self.window.gpu.as_mut().context("no window")?;
        let frame = match gpu.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(frame)
            | wgpu::CurrentSurfaceTexture::Suboptimal(frame) => frame,
            other => {
                log::warn!("skipping a frame: {other:?}");
                let (w, h) = (gpu.config.width, gpu.config.height);
                gpu.resize(w, h);
                return Ok(());
            }
        };
        let view = frame.texture.create_view(&Default::default());
        let mut encoder = gpu.gpu.device.create_command_encoder(&Default::default());
        gpu.record(
            &mut encoder,
            &view,
            self.window.renderer.as_ref(),
            self.settings.exposure,
            &paint,
            &screen,
        );
        gpu.gpu.queue.submit([encoder.finish()]);
        window.pre_present_notify();
        gpu.gpu.queue.present(frame);
        self.stats.frames += 1;
        window.request_redraw();
        Ok(())
    }

    fn open_window(&mut self, event_loop: &ActiveEventLoop) -> anyhow::Result<()> {
        let (width, height) = self.window.size;
        let attributes = Window::default_attributes()
            .with_title(format!("hprt — {}", self.scene.name))
            .with_inner_size(winit::dpi::PhysicalSize::new(width, height));
        let window = Arc::new(
            event_loop
                .create_window(attributes)
                .context("cannot create a window")?,
        );
        let descriptor = wgpu::InstanceDescriptor::new_with_display_handle(Box::new(
            event_loop.owned_display_handle(),
        ));
        let gpu = WindowGpu::new(window.clone(), self.window.backend, descriptor)?;
        self.stats.adapter = gpu.gpu.description().to_string();
        println!("adapter: {}", self.stats.adapter);
        self.window.egui_state = Some(egui_winit::State::new(
            self.window.egui_ctx.clone(),
            egui::ViewportId::ROOT,
            &window,
            Some(window.scale_factor() as f32),
            None,
            None,
        ));
        self.window.gpu = Some(gpu);
        self.window.window = Some(window.clone());
        window.request_redraw();
        Ok(())
    }

    fn mouse_moved(&mut self, x: f64, y: f64) {
        let previous = self.input.cursor;
        self.input.cursor = (x, y);
        if let Some((button, _)) = self.input.drag {
            let (dx, dy) = ((x - previous.0) as f32, (y - previous.1) as f32);
            match button {
                MouseButton::Left => self.input.orbit.rotate(dx, dy),
                _ => self.input.orbit.pan(dx, dy, self.window.size.1),
            }
        }
    }
}

impl ApplicationHandler for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.window.window.is_some() {
            return;
        }
        if let Err(e) = self.open_window(event_loop) {
            self.error = Some(e);
            event_loop.exit();
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        let consumed = match (&mut self.window.egui_state, &self.window.window) {
            (Some(state), Some(window)) => state.on_window_event(window, &event).consumed,
            _ => false,
        };
        match event {
            WindowEvent::CloseRequested => event_loop.exit(),
            WindowEvent::Resized(size) => {
                if let Some(gpu) = self.window.gpu.as_mut() {
                    gpu.resize(size.width, size.height);
                }
                self.window.size = (size.width.max(1), size.height.max(1));
            }
            WindowEvent::RedrawRequested => {
                if let Err(e) = self.frame(event_loop) {
                    self.error = Some(e);
                    event_loop.exit();
                }
            }
            WindowEvent::CursorMoved { position, .. } => self.mouse_moved(position.x, position.y),
            WindowEvent::MouseInput { state, button, .. } if !consumed => match state {
                ElementState::Pressed => self.input.drag = Some((button, self.input.cursor)),
                ElementState::Released => self.input.drag = None,
            },
            WindowEvent::MouseInput {
                state: ElementState::Released,
                ..
            } => self.input.drag = None,
            WindowEvent::MouseWheel { delta, .. } if !consumed => {
                let steps = match delta {
                    MouseScrollDelta::LineDelta(_, y) => y,
                    MouseScrollDelta::PixelDelta(p) => p.y as f32 / 40.0,
                };
                self.input.orbit.zoom(steps);
            }
            WindowEvent::KeyboardInput { event, .. }
                if !consumed
                    && event.state == ElementState::Pressed
                    && event.logical_key == winit::keyboard::Key::Character("r".into()) =>
            {
                self.reset_view();
            }
            _ => {}
        }
    }
}
