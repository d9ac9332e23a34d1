//! `hprt render`: the hybrid (or plain PRT) image of a baked scene, on the GPU.

use super::decompose::DecomposeOptions;
use super::{EnvironmentArgs, ImageSizeArgs, default_exposure, load_scene};
use anyhow::Context;
use clap::{Args, ValueEnum};
use precompute::atomic_file::AtomicOutput;
use precompute::bake::Transfer;
use precompute::bakefile;
use precompute::image_io::{RgbImageF32, exr_bytes, png_bytes, to_display_rgb8};
use precompute::scene::Scene;
use runtime::render::{Backend, FrameLighting, GpuContext, RenderMode, Renderer, ShadowSettings};
use runtime::{CubeSource, DecomposeMode, DecomposeSettings, Decomposer, Decomposition};
use std::path::{Path, PathBuf};

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Switch {
    On,
    Off,
}

#[derive(Args, Clone, Debug)]
pub struct RenderOptions {
    /// prt: the SH projection of the whole map (the thesis' baseline); hybrid: SH part +
    /// shadow-mapped lights; lights / unshadowed: debug views.
    #[arg(long, default_value = "hybrid")]
    pub mode: RenderMode,
    /// Shadow-map resolution.
    #[arg(long, default_value_t = 2048)]
    pub shadow_res: u32,
    /// PCF taps per side (odd).
    #[arg(long, default_value_t = 3)]
    pub pcf: u32,
    /// Size each light's PCF kernel from its angular radius and the occluder distance
    /// (off: a fixed kernel of --pcf taps one texel apart).
    #[arg(long, value_enum, default_value = "on")]
    pub pcf_from_radius: Switch,
    /// Send the lights through the bake's indirect transfer too (their bounce light);
    /// default: on in consistent mode, off in thesis mode.
    #[arg(long, value_enum)]
    pub lights_indirect: Option<Switch>,
    /// Graphics backend: auto, vulkan or gl.
    #[arg(long, default_value = "auto")]
    pub backend: Backend,
}

impl RenderOptions {
    pub fn shadow_settings(&self) -> ShadowSettings {
        ShadowSettings {
            resolution: self.shadow_res,
            pcf_taps: self.pcf,
            from_angular_radius: self.pcf_from_radius == Switch::On,
        }
    }

    pub fn lights_indirect(&self, mode: DecomposeMode) -> bool {
        match self.lights_indirect {
            Some(s) => s == Switch::On,
            None => mode == DecomposeMode::Consistent,
        }
    }
}

#[derive(Args)]
pub struct RenderArgs {
    /// Scene file (TOML).
    pub scene: PathBuf,
    /// Bake of the scene (from `hprt bake`).
    #[arg(long)]
    pub bake: PathBuf,
    #[command(flatten)]
    pub environment: EnvironmentArgs,
    #[command(flatten)]
    pub render: RenderOptions,
    /// How the decomposition forms lights (thesis or consistent).
    #[arg(long, default_value = "consistent")]
    pub decompose_mode: DecomposeMode,
    #[command(flatten)]
    pub decompose: DecomposeOptions,
    #[command(flatten)]
    pub size: ImageSizeArgs,
    /// Camera position "x,y,z" (default: the scene's).
    #[arg(long, value_parser = parse_vec3_arg, allow_hyphen_values = true)]
    pub camera_position: Option<glam::Vec3>,
    /// Camera target "x,y,z" (default: the scene's).
    #[arg(long, value_parser = parse_vec3_arg, allow_hyphen_values = true)]
    pub camera_target: Option<glam::Vec3>,
    /// Vertical field of view in degrees (default: the scene's).
    #[arg(long)]
    pub fov: Option<f32>,
    /// Tone-mapping exposure (default: 0.5 / the map's mean luminance).
    #[arg(long)]
    pub exposure: Option<f32>,
    /// Output PNG (tone-mapped).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Also write the linear image as OpenEXR.
    #[arg(long)]
    pub exr: Option<PathBuf>,
}

fn parse_vec3_arg(text: &str) -> Result<glam::Vec3, String> {
    parse_vec3(text)
}

/// A vector written "x,y,z".
pub fn parse_vec3(text: &str) -> Result<glam::Vec3, String> {
    let parts: Vec<f32> = text
        .split(',')
        .map(|p| p.trim().parse::<f32>())
        .collect::<Result<_, _>>()
        .map_err(|_| format!("expected \"x,y,z\", got {text:?}"))?;
    match parts[..] {
        [x, y, z] => Ok(glam::Vec3::new(x, y, z)),
        _ => Err(format!("expected three numbers \"x,y,z\", got {text:?}")),
    }
}

/// Reads the scene's bake, refusing one of another mesh, or one whose SH order is below the
/// lighting order asked (a lower lighting order than the bake's just drops bands).
pub fn load_bake(scene: &Scene, path: &Path, order: Option<usize>) -> anyhow::Result<Transfer> {
    let transfer = bakefile::read_for_mesh(path, &scene.geometry.content_hash())
        .context("cannot use the bake")?;
    if let Some(order) = order.filter(|o| *o > transfer.settings.order || *o == 0) {
        anyhow::bail!(
            "{} was baked at SH order {}, but order {order} was asked; re-bake with \
             `hprt bake {} --order {order}` or ask for an order from 1 to {}",
            path.display(),
            transfer.settings.order,
            scene.path.display(),
            transfer.settings.order
        );
    }
    Ok(transfer)
}

/// The lighting of `mode` for a map: its decomposition and its plain projection.
pub struct MapLighting {
    pub decomposition: Decomposition,
    pub projection: precompute::sh::ShCoeffs<precompute::Rgb>,
    pub decomposition_ms: f64,
}

pub fn decompose_map(
    map: &precompute::envmap::EnvMap,
    rotation_deg: f32,
    settings: DecomposeSettings,
) -> anyhow::Result<MapLighting> {
    let mut decomposer = Decomposer::new(settings.clone())
        .map_err(|m| anyhow::anyhow!("invalid decomposition settings: {m}"))?;
    let cube = CubeSource::new(map, settings.face_size).cube(rotation_deg.to_radians());
    let start = std::time::Instant::now();
    let decomposition = decomposer.decompose(&cube);
    let decomposition_ms = start.elapsed().as_secs_f64() * 1e3;
    let projection = decomposer.project(&cube);
    Ok(MapLighting {
        decomposition,
        projection,
        decomposition_ms,
    })
}

pub fn run(args: RenderArgs) -> anyhow::Result<()> {
    let scene = load_scene(&args.scene)?;
    let transfer = load_bake(&scene, &args.bake, args.decompose.order)?;
    let env = args.environment.choose(&scene)?;
    let mut camera = args.size.camera(&scene)?;
    camera.position = args.camera_position.unwrap_or(camera.position);
    camera.target = args.camera_target.unwrap_or(camera.target);
    camera.fov_y_deg = args.fov.unwrap_or(camera.fov_y_deg);
    camera
        .validate()
        .map_err(|m| anyhow::anyhow!("invalid camera or image size: {m}"))?;
    let output = AtomicOutput::create(&args.output)
        .with_context(|| format!("cannot write {}", args.output.display()))?;
    let exr_output = match &args.exr {
        Some(p) => {
            Some(AtomicOutput::create(p).with_context(|| format!("cannot write {}", p.display()))?)
        }
        None => None,
    };
    let settings = args
        .decompose
        .settings(args.decompose_mode, transfer.settings.order);
    let lighting = decompose_map(&env.loaded.map, env.rotation_deg, settings)?;
    let frame = FrameLighting::for_mode(
        args.render.mode,
        &lighting.projection,
        &lighting.decomposition,
        args.render.lights_indirect(args.decompose_mode),
    );
    let gpu = GpuContext::headless(args.render.backend)?;
    println!("adapter: {}", gpu.description());
    let mut renderer = Renderer::new(
        &gpu,
        &scene.geometry,
        &transfer,
        &camera,
        args.render.shadow_settings(),
    )?;
    renderer.set_environment(&env.loaded.map, env.rotation_deg);
    renderer.set_lighting(&frame)?;
    renderer.render()?;
    let image: RgbImageF32 = renderer.read_back()?;
    let exposure = args
        .exposure
        .unwrap_or_else(|| default_exposure(&env.loaded.map));
    let png = png_bytes(
        &to_display_rgb8(&image, exposure),
        image.width,
        image.height,
    )
    .map_err(|m| anyhow::anyhow!("cannot encode the PNG: {m}"))?;
    output
        .commit(&png)
        .with_context(|| format!("cannot write {}", args.output.display()))?;
    if let Some(exr) = exr_output {
        let bytes = exr_bytes(&image).map_err(|m| anyhow::anyhow!("cannot encode the EXR: {m}"))?;
        exr.commit(&bytes).context("cannot write the EXR")?;
    }
    println!(
        "{} mode, {} light(s), decomposition {:.2} ms; wrote {}",
        args.render.mode.name(),
        frame.lights.len(),
        lighting.decomposition_ms,
        args.output.display()
    );
    Ok(())
}
