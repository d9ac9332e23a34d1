//! `hprt view`: the real-time viewer (winit + egui). The lighting is decomposed again every
//! frame it changes, as in the thesis' dynamic-lighting case.
//!
//! The [`App`] is split by concern: the bake ([`BakeState`]), the environment's lighting
//! ([`LightingState`]), the window and its GPU ([`WindowState`]), mouse input
//! ([`InputState`]), the panel ([`ui::PanelState`]) and a script ([`ScriptState`]); the panel
//! edits only the [`ViewSettings`].

mod events;
mod jobs;
mod lighting;
mod panel_io;
mod room;
mod room_state;
mod state;
mod ui;
mod window;

use crate::bake_cache;
use crate::maps::{maps_beside, scene_rotation};
use anyhow::Context;
use clap::Args;
use foundation::scene::Scene;
use report::env_sequence::Sequence;
use runtime::lights_indirect_default;
use runtime::render::{Backend, RenderMode, ShadowSettings};
use runtime::viewer::ViewSettings;
use runtime::viewer::{Orbit, script};
use runtime::{DecomposeMode, DecomposeSettings};
use state::{BakeState, InputState, Jobs, LightingState, ScriptState, Stats, WindowState};
use std::collections::VecDeque;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use ui::PanelState;
use winit::event_loop::{ActiveEventLoop, EventLoop};

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
    /// Drive the viewer from a script of commands (see runtime/src/viewer/script.rs).
    #[arg(long)]
    pub script: Option<PathBuf>,
    /// For a model: composite it into a backplate, "environment" (the map as the camera sees
    /// it) or an image seen through the scene's camera; its ground slab becomes the proxy its
    /// shadow falls on. A scene file names its own [backplate].
    #[arg(long)]
    pub backplate: Option<PathBuf>,
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
    /// The room the model moves through, when the scene has probes.
    room: Option<room_state::RoomState>,
    /// Background work besides the scene's bake.
    jobs: Jobs,
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

/// The scene's bake: the one given, the cached one, or none yet (offered in the window, with
/// progress).
fn open_bake(scene: &Scene, path: Option<&Path>) -> anyhow::Result<BakeState> {
    let bake_settings = scene.bake;
    Ok(match path {
        Some(path) => BakeState {
            transfer: Some(Arc::new(bake_cache::load_bake(scene, path, None)?)),
            path: path.to_owned(),
            job: None,
            proxies: None,
        },
        None => match bake_cache::load_cached(scene, &bake_settings) {
            Some((path, transfer)) => BakeState {
                path,
                transfer: Some(Arc::new(transfer)),
                job: None,
                proxies: None,
            },
            None => BakeState {
                path: bake_cache::bake_path(scene, &bake_settings),
                transfer: None,
                job: None,
                proxies: None,
            },
        },
    })
}

/// The commands of a `--script` file (none without one).
fn read_script(path: Option<&Path>) -> anyhow::Result<VecDeque<script::Command>> {
    Ok(match path {
        Some(path) => {
            let text = foundation::infra::limits::read_text_file(path)
                .with_context(|| format!("cannot read {}", path.display()))?;
            script::parse(path, &text)?.into()
        }
        None => VecDeque::new(),
    })
}

/// What the viewer opens with: the hybrid in consistent mode under `env`, at the bake's order.
fn initial_settings(
    scene: &Scene,
    env: &Path,
    order: usize,
    backplate: Option<&Path>,
) -> ViewSettings {
    let decompose_mode = DecomposeMode::Consistent;
    ViewSettings {
        env: env.to_owned(),
        rotation_deg: scene_rotation(scene, None),
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
        composite: scene.backplate.is_some() || !scene.probes.is_empty(),
        play_path: !scene.probes.is_empty() && scene.model_path.is_some(),
        soft_shadow: true,
        wireframe: false,
        backplate: backplate.map(Path::to_owned),
        object_offset: glam::Vec3::ZERO,
    }
}

pub fn run(args: ViewArgs) -> anyhow::Result<()> {
    check_display()?;
    let scene = crate::support::open_scene(&args.scene, args.backplate.as_deref())?;
    let bake = open_bake(&scene, args.bake.as_deref())?;
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
    let commands = read_script(args.script.as_deref())?;
    let order = bake
        .transfer
        .as_ref()
        .map_or(scene.bake.order, |t| t.settings.order);
    let orbit = Orbit::from_camera(&scene.camera);
    let settings = initial_settings(&scene, &env, order, args.backplate.as_deref());
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
        room: None,
        jobs: Jobs::default(),
        error: None,
    };
    app.load_environment();
    if let Some(map) = (app.lighting.environment.as_ref()).map(|e| e.map().clone()) {
        app.open_room(&map);
    }
    // A scene opened for the first time bakes at once, with its progress in the panel, into
    // the cache the next opening reads (a room bakes its parts as it opens).
    if app.bake.transfer.is_none() && app.jobs.room.is_none() {
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
    pub(super) fn reset_view(&mut self) {
        self.input.orbit = self.input.initial_orbit;
    }

    pub(super) fn run_script(&mut self, event_loop: &ActiveEventLoop) -> anyhow::Result<()> {
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
                    if self.busy() {
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
                C::Move(offset) if self.room.is_some() => self.move_model(offset),
                C::Move(offset) => self.move_objects(offset),
                C::Turn(degrees) => {
                    anyhow::ensure!(
                        self.room.is_some(),
                        "turn: the scene has no room (no [[probe]] entries)"
                    );
                    self.turn_model(degrees);
                }
                C::Place(centre) => {
                    anyhow::ensure!(
                        self.room.is_some(),
                        "place: the scene has no room (no [[probe]] entries); use move"
                    );
                    self.place_model(centre);
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

    pub(super) fn current_camera(&self) -> foundation::camera::Camera {
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
            .map(|w| runtime::viewer::shell_quote(w))
            .collect::<Vec<_>>()
            .join(" ")
    }

    pub(super) fn save_screenshot(&mut self, path: &Path) -> anyhow::Result<()> {
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

    pub(super) fn save_window_screenshot(&mut self, path: &Path) -> anyhow::Result<()> {
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

    pub(super) fn state_json(&self) -> serde_json::Value {
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
            "object_offset": self.settings.object_offset.to_array(),
            "compositing": self
                .window
                .renderer
                .as_ref()
                .is_some_and(|r| r.is_compositing()),
            "rotation_deg": self.settings.rotation_deg,
            "room": self.room_json(),
            "window": [camera.width, camera.height],
            "command": self.command_line(Path::new("render.png")),
            "materials": self
                .settings
                .materials
                .iter()
                .map(|m| match m.layer {
                    Some(l) => serde_json::json!({ "metallic": l.metallic, "roughness": l.roughness }),
                    None => serde_json::json!([m.specular.x, m.specular.y, m.specular.z, m.shininess]),
                })
                .collect::<Vec<_>>(),
        })
    }
}
