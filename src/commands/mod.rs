//! One module per subcommand; each parses its arguments and calls into the libraries.

pub mod bake;
pub mod bench;
pub mod decompose;
pub mod demo;
pub mod export;
pub mod reference;
pub mod render;
pub mod report;

use anyhow::Context;
use indicatif::{ProgressBar, ProgressStyle};
use precompute::scene::Scene;
use std::path::Path;

/// Loads a scene file, with the path in any error.
pub fn load_scene(path: &Path) -> anyhow::Result<Scene> {
    Scene::load(path).with_context(|| "cannot load the scene".to_string())
}

/// Runs `f` on a rayon pool of `threads` threads (all cores when `None`).
pub fn with_threads<T: Send>(
    threads: Option<usize>,
    f: impl FnOnce() -> T + Send,
) -> anyhow::Result<T> {
    match threads {
        None => Ok(f()),
        Some(0) => anyhow::bail!("--threads must be at least 1"),
        Some(n) => Ok(rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()
            .context("cannot start the thread pool")?
            .install(f)),
    }
}

/// A progress bar with ETA on a terminal; draws nothing when stderr is not a terminal.
pub fn progress_bar(length: u64, what: &str) -> ProgressBar {
    let bar = ProgressBar::new(length);
    bar.set_style(
        ProgressStyle::with_template(&format!(
            "{what} [{{bar:40}}] {{pos}}/{{len}} {{msg}} ({{elapsed}} elapsed, ETA {{eta}})"
        ))
        .unwrap_or_else(|_| ProgressStyle::default_bar())
        .progress_chars("=> "),
    );
    bar
}

/// `--env`, `--layout`, `--rotate`: the map a command lights the scene with.
#[derive(clap::Args, Clone, Debug)]
pub struct EnvironmentArgs {
    /// Environment map (default: the scene's).
    #[arg(long)]
    pub env: Option<std::path::PathBuf>,
    /// Layout of the map (default: from the aspect ratio).
    #[arg(long)]
    pub layout: Option<precompute::envmap::Layout>,
    /// Rotation of the map about +Y in degrees (default: the scene's).
    #[arg(long, allow_negative_numbers = true)]
    pub rotate: Option<f32>,
}

impl EnvironmentArgs {
    pub fn choose(&self, scene: &Scene) -> anyhow::Result<ChosenEnvironment> {
        choose_environment(scene, self.env.as_deref(), self.layout, self.rotate)
    }
}

/// `--width`, `--height`: the image size, by default the scene camera's.
#[derive(clap::Args, Clone, Debug, Default)]
pub struct ImageSizeArgs {
    /// Image width (default: the scene camera's).
    #[arg(long)]
    pub width: Option<u32>,
    /// Image height (default: the scene camera's).
    #[arg(long)]
    pub height: Option<u32>,
}

impl ImageSizeArgs {
    /// The scene's camera at this size.
    pub fn camera(&self, scene: &Scene) -> anyhow::Result<precompute::camera::Camera> {
        let camera = scene.camera.with_size(
            self.width.unwrap_or(scene.camera.width),
            self.height.unwrap_or(scene.camera.height),
        );
        camera
            .validate()
            .map_err(|m| anyhow::anyhow!("invalid image size: {m}"))?;
        Ok(camera)
    }
}

/// The environment a command lights a scene with: `--env` or the scene's default map, and
/// `--rotate` or the scene's rotation.
pub struct ChosenEnvironment {
    pub path: std::path::PathBuf,
    pub loaded: precompute::envmap::LoadedEnvMap,
    pub rotation_deg: f32,
}

pub fn choose_environment(
    scene: &Scene,
    env: Option<&Path>,
    layout: Option<precompute::envmap::Layout>,
    rotate: Option<f32>,
) -> anyhow::Result<ChosenEnvironment> {
    let (path, scene_rotation) = match (env, &scene.environment) {
        (Some(path), _) => (path.to_owned(), 0.0),
        (None, Some(spec)) => (spec.map.clone(), spec.rotation_deg),
        (None, None) => anyhow::bail!(
            "{} names no [environment]; pass --env MAP",
            scene.path.display()
        ),
    };
    let loaded = decompose::load_map(&path, layout)?;
    Ok(ChosenEnvironment {
        path,
        loaded,
        rotation_deg: rotate.unwrap_or(scene_rotation),
    })
}

/// The default tone-mapping exposure for a map: a white Lambertian surface seeing the whole
/// environment (radiance = the map's mean luminance) maps to `1 - e^(-1/2)` (about 0.39
/// linear, 0.66 after sRGB encoding), leaving headroom for sunlit surfaces.
pub fn default_exposure(map: &precompute::envmap::EnvMap) -> f32 {
    0.5 / map.mean_luminance().max(1e-6)
}

/// The maps next to `map` (its folder's `.exr` and `.hdr` files), sorted: the choices the
/// viewer offers and the maps a report covers by default.
pub fn maps_beside(map: &Path) -> Vec<std::path::PathBuf> {
    let dir = match map.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let mut maps: Vec<std::path::PathBuf> = std::fs::read_dir(dir)
        .map(|entries| {
            entries
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| p.extension().is_some_and(|x| x == "exr" || x == "hdr"))
                .collect()
        })
        .unwrap_or_default();
    maps.sort();
    maps
}
