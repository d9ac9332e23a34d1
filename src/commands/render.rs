//! `hprt render`: the hybrid (or plain PRT) image of a baked scene, on the GPU.

use crate::bake_cache::load_bake;
use crate::cli::{
    DecomposeOptions, EnvironmentArgs, ImageSizeArgs, RenderOptions, parse_positive, parse_vec3,
};
use crate::maps::{default_exposure, scene_rotation};
use crate::outputs::{check_outputs, open_outputs, scene_inputs, write_outputs};
use crate::support::{TerminalObserver, open_scene};
use anyhow::Context;
use clap::Args;
use foundation::image_io::{RgbImageF32, check_finite, exr_bytes, png_bytes, to_display_rgb8};
use reference::composite::PixelKind;
use report::env_sequence::{Sequence, lighting_at_frame};
use report::gpu_composite;
use runtime::render::{GpuContext, Renderer};
use runtime::{DecomposeMode, EnvironmentLighting};
use std::path::PathBuf;

#[derive(Args)]
pub struct RenderArgs {
    /// Scene file (TOML), or a model (glTF, OBJ, PLY, BPT) placed in a default scene (`hprt
    /// scene init` writes that scene out for editing).
    pub scene: PathBuf,
    /// Bake of the scene (from `hprt bake`).
    #[arg(long)]
    pub bake: PathBuf,
    #[command(flatten)]
    pub environment: EnvironmentArgs,
    /// An environment sequence (a folder of maps or a sequence file, see scenes/README.md):
    /// renders its frame --frame, the lights tracked from its first frame.
    #[arg(long, conflicts_with = "env")]
    pub env_sequence: Option<PathBuf>,
    /// Frame of --env-sequence to render (from 0).
    #[arg(long, default_value_t = 0, requires = "env_sequence")]
    pub frame: usize,
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
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    pub camera_position: Option<glam::Vec3>,
    /// Camera target "x,y,z" (default: the scene's).
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    pub camera_target: Option<glam::Vec3>,
    /// Vertical field of view in degrees (default: the scene's).
    #[arg(long, value_parser = parse_positive)]
    pub fov: Option<f32>,
    /// Tone-mapping exposure (default: 0.5 / the map's mean luminance).
    #[arg(long, value_parser = parse_positive)]
    pub exposure: Option<f32>,
    /// Output PNG (tone-mapped).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Also write the linear image as OpenEXR.
    #[arg(long)]
    pub exr: Option<PathBuf>,
    /// For a scene with a [backplate]: also write the layers a compositor redoes the composite
    /// from into this folder (`objects.exr`, `ratio.exr`, and the object, proxy and changed
    /// masks as EXR).
    #[arg(long)]
    pub layers: Option<PathBuf>,
    /// For a scene with a [backplate]: how the objects change the proxies. differential: the
    /// ratio with and without the objects (the truth's form); occlusion: the mobile-AR paper's
    /// peer, the backplate times the proxies' ambient occlusion by the objects; live: the
    /// differential form as the viewer draws it, on the GPU in the frame.
    #[arg(long, value_enum, default_value_t)]
    pub composite: gpu_composite::CompositeForm,
    /// For a model: composite it into "environment" (the map as the camera sees it) or an
    /// image seen through the camera, its ground slab the proxy (as `hprt view --backplate`).
    #[arg(long)]
    pub backplate: Option<PathBuf>,
    /// Move the virtual objects (not the proxies) by x,y,z, as the viewer's panel does (the
    /// bake must be of the moved scene).
    #[arg(long, value_parser = crate::cli::parse_vec3)]
    pub move_objects: Option<glam::Vec3>,
}

/// The files `--layers DIR` writes.
const LAYERS: [&str; 5] = [
    "objects.exr",
    "ratio.exr",
    "object_mask.exr",
    "proxy_mask.exr",
    "changed_mask.exr",
];

pub fn run(args: RenderArgs) -> anyhow::Result<()> {
    let mut scene = open_scene(&args.scene, args.backplate.as_deref())?;
    if let Some(offset) = args.move_objects {
        scene.geometry.move_objects(offset);
    }
    let transfer = load_bake(&scene, &args.bake, args.decompose.order)?;
    let rotation_deg = scene_rotation(&scene, args.environment.rotate);
    let mut camera = args.size.camera(&scene)?;
    camera.position = args.camera_position.unwrap_or(camera.position);
    camera.target = args.camera_target.unwrap_or(camera.target);
    camera.fov_y_deg = args.fov.unwrap_or(camera.fov_y_deg);
    camera.validate()?;
    let inputs = scene_inputs(&scene, &[Some(&args.bake), args.environment.env.as_deref()]);
    let layers = layer_files(&args, &scene)?;
    let mut outputs = vec![
        ("-o", Some(args.output.as_path())),
        ("--exr", args.exr.as_deref()),
    ];
    outputs.extend(layers.iter().map(|p| ("--layers", Some(p.as_path()))));
    check_outputs(&inputs, &outputs)?;
    if let Some(dir) = &args.layers {
        crate::support::create_folder(dir)?;
    }
    let files = open_outputs(&outputs)?;
    let settings = args
        .decompose
        .settings(args.decompose_mode, transfer.settings.order);
    let mut lighting = environment_lighting(&args, &scene, settings, rotation_deg)?;
    let frame = lighting.frame(args.render.mode, args.render.lights_indirect());
    let gpu = GpuContext::headless(args.render.backend)?;
    println!("adapter: {}", gpu.description());
    let (image, composite) = draw(
        &gpu,
        &args,
        &scene,
        &transfer,
        &camera,
        (lighting.map(), rotation_deg),
        &frame.lighting,
    )?;
    warn_if_clipped(&args, &image);
    let exposure = args
        .exposure
        .unwrap_or_else(|| default_exposure(lighting.map()));
    let bytes = output_bytes(&args, &image, composite.as_ref(), exposure)?;
    write_outputs(files, bytes)?;
    println!(
        "{} mode, {} light(s), {} {:.2} ms; wrote {}",
        args.render.mode.name(),
        frame.lighting.lights.len(),
        if args.render.mode.uses_lights() {
            "decomposition"
        } else {
            "projection"
        },
        frame.ms,
        args.output.display()
    );
    Ok(())
}

/// The lighting the image is drawn under: the sequence's frame or the chosen map, turned by
/// `rotation_deg`, with the render options' lights and, for glossy objects, reflections.
fn environment_lighting(
    args: &RenderArgs,
    scene: &foundation::scene::Scene,
    settings: runtime::DecomposeSettings,
    rotation_deg: f32,
) -> anyhow::Result<EnvironmentLighting> {
    let mut lighting = match &args.env_sequence {
        Some(path) => {
            let sequence = Sequence::load(path)?;
            lighting_at_frame(&sequence, settings, rotation_deg, args.frame)?
        }
        None => {
            let env = args.environment.choose(scene)?;
            let mut lighting = EnvironmentLighting::new(&env.loaded.map, settings)?;
            lighting.set_rotation(rotation_deg);
            lighting
        }
    };
    lighting.set_median_cut_lights(args.render.lights)?;
    if scene.geometry.is_glossy() {
        lighting.enable_reflections(Some(runtime::render::DEFAULT_REFLECTION_SIZE));
    }
    Ok(lighting)
}

/// Warns when `--exr` will hold pixels clipped at the half-float target's largest value.
fn warn_if_clipped(args: &RenderArgs, image: &RgbImageF32) {
    // The renderer's target is half float: radiance above its largest value is clipped.
    let clipped = image
        .pixels
        .iter()
        .filter(|p| p.max_element() >= 65504.0)
        .count();
    if clipped > 0 && args.exr.is_some() {
        log::warn!(
            "{clipped} pixel(s) reached 65504, the largest value of the renderer's half-float \
             target: the EXR holds them clipped"
        );
    }
}

/// The files `--layers DIR` will write (none without it); refused for a scene that does not
/// composite.
fn layer_files(
    args: &RenderArgs,
    scene: &foundation::scene::Scene,
) -> anyhow::Result<Vec<PathBuf>> {
    anyhow::ensure!(
        args.layers.is_none() || scene.backplate.is_some(),
        "--layers: {} has no [backplate] to composite into",
        scene.path.display()
    );
    anyhow::ensure!(
        args.layers.is_none() || args.composite != gpu_composite::CompositeForm::Live,
        "--layers: the live composite keeps its layers on the GPU; use --composite differential"
    );
    Ok(args
        .layers
        .iter()
        .flat_map(|dir| LAYERS.map(|name| dir.join(name)))
        .collect())
}

/// The PNG, then the EXR and the layers when asked, in the order of the outputs.
fn output_bytes(
    args: &RenderArgs,
    image: &RgbImageF32,
    composite: Option<&reference::composite::Composite>,
    exposure: f32,
) -> anyhow::Result<Vec<Vec<u8>>> {
    check_finite(image, "PNG").context("the render failed")?;
    let png = png_bytes(&to_display_rgb8(image, exposure), image.width, image.height)?;
    let mut bytes = vec![png];
    if args.exr.is_some() {
        bytes.push(exr_bytes(image)?);
    }
    if let Some(c) = composite.filter(|_| args.layers.is_some()) {
        let grey = |values: Vec<f32>| {
            exr_bytes(&RgbImageF32::from_grey(image.width, image.height, &values))
        };
        bytes.extend([
            exr_bytes(&c.objects)?,
            exr_bytes(&c.ratio)?,
            grey(c.mask(PixelKind::Object))?,
            grey(c.mask(PixelKind::Proxy))?,
            grey(c.changed_mask())?,
        ]);
    }
    Ok(bytes)
}

/// Draws `frame` of `scene`: composited into its backplate when it has one.
fn draw(
    gpu: &GpuContext,
    args: &RenderArgs,
    scene: &foundation::scene::Scene,
    transfer: &precompute::bake::Transfer,
    camera: &foundation::camera::Camera,
    (map, rotation_deg): (&foundation::envmap::EnvMap, f32),
    frame: &runtime::FrameLighting,
) -> anyhow::Result<(RgbImageF32, Option<reference::composite::Composite>)> {
    let mut renderer = Renderer::new(
        gpu,
        &scene.geometry,
        transfer,
        camera,
        args.render.shadow_settings(),
    )?;
    if scene.backplate.is_none() {
        renderer.set_environment(map, rotation_deg);
        renderer.set_lighting(frame)?;
        renderer.render()?;
        return Ok((renderer.read_back()?, None));
    }
    let inputs = gpu_composite::CompositeInputs {
        scene,
        camera,
        map,
        rotation_deg,
        shadow: args.render.shadow_settings(),
        form: args.composite,
    };
    if args.composite == gpu_composite::CompositeForm::Live {
        let image = gpu_composite::live_composite_frame(
            &mut renderer,
            transfer,
            frame,
            &inputs,
            &TerminalObserver,
        )?;
        return Ok((image, None));
    }
    let c = gpu_composite::composite_frame(
        gpu,
        &mut renderer,
        transfer,
        frame,
        &inputs,
        &TerminalObserver,
    )?;
    Ok((c.image.clone(), Some(c)))
}
