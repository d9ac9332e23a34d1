//! `hprt reference`: the CPU path-traced ground truth.

use crate::cli::{EnvironmentArgs, ImageSizeArgs};
use crate::maps::default_exposure;
use crate::outputs::{check_outputs, open_outputs, scene_inputs, write_outputs};
use crate::support::{TerminalProgress, load_scene, with_threads};
use anyhow::Context;
use clap::Args;
use foundation::bvh::SceneBvh;
use foundation::image_io::{RgbImageF32, exr_bytes, png_bytes, to_display_rgb8};
use foundation::scene::{Backplate, load_backplate_image};
use reference::composite::{Composite, PixelKind};
use reference::{self, EnvironmentLight, ReferenceImage, ReferenceSettings, SamplerKind};
use std::path::PathBuf;

#[derive(Args)]
pub struct ReferenceArgs {
    /// Scene file (TOML), or a model (glTF, OBJ, PLY, BPT) placed in a default scene (`hprt
    /// scene init` writes that scene out for editing).
    pub scene: PathBuf,
    #[command(flatten)]
    pub environment: EnvironmentArgs,
    #[command(flatten)]
    pub size: ImageSizeArgs,
    /// Light paths per pixel.
    #[arg(long, default_value_t = 64, value_parser = clap::value_parser!(u32).range(1..=1_048_576))]
    pub spp: u32,
    /// Indirect bounces, as in the bake (0: shadowed direct lighting).
    #[arg(long, default_value_t = 3)]
    pub bounces: u32,
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Random numbers of the light paths: sobol (Owen-scrambled, per pixel; at most 65536
    /// samples per pixel) or independent.
    #[arg(long, default_value_t = SamplerKind::default())]
    pub sampler: SamplerKind,
    /// Worker threads (default: all cores); the image does not depend on it.
    #[arg(long)]
    pub threads: Option<usize>,
    /// Tone-mapping exposure of the PNG (default: 0.5 / the map's mean luminance).
    #[arg(long, value_parser = crate::cli::parse_positive)]
    pub exposure: Option<f32>,
    /// Output linear OpenEXR.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Also write a tone-mapped PNG.
    #[arg(long)]
    pub png: Option<PathBuf>,
    /// Also write coverage and direct-visibility images (EXR and PNG) into this folder; for a
    /// scene with a [backplate], also the masks of the objects, the proxies and the changed
    /// region, and the layers a compositor redoes the composite from (the objects, the shadow
    /// ratio).
    #[arg(long)]
    pub aux: Option<PathBuf>,
}

/// A single-channel image as grey EXR and PNG files' bytes.
fn grey_files(width: usize, height: usize, values: &[f32]) -> anyhow::Result<[Vec<u8>; 2]> {
    let image = RgbImageF32::from_grey(width, height, values);
    // Linear 0..1 shown directly (exposure chosen so that tonemap(1) is near white).
    let rgb: Vec<u8> = values
        .iter()
        .flat_map(|v| [(v.clamp(0.0, 1.0) * 255.0 + 0.5) as u8; 3])
        .collect();
    Ok([exr_bytes(&image)?, png_bytes(&rgb, width, height)?])
}

/// The file names `--aux DIR` adds: coverage and direct visibility, and for a composite its
/// masks (object, proxy, changed region) and layers (the objects, the shadow ratio).
fn aux_files(dir: &std::path::Path, composite: bool) -> Vec<PathBuf> {
    let mut names = vec!["coverage", "visibility"];
    if composite {
        names.extend(["object_mask", "proxy_mask", "changed_mask"]);
    }
    let mut files: Vec<PathBuf> = names
        .into_iter()
        .flat_map(|name| ["exr", "png"].map(|ext| dir.join(format!("{name}.{ext}"))))
        .collect();
    if composite {
        files.extend(["objects.exr", "ratio.exr"].map(|name| dir.join(name)));
    }
    files
}

pub fn run(args: ReferenceArgs) -> anyhow::Result<()> {
    let scene = load_scene(&args.scene)?;
    let env = args.environment.choose(&scene)?;
    let camera = args.size.camera(&scene)?;
    let settings = ReferenceSettings {
        sampler: args.sampler,
        ..ReferenceSettings::new(args.spp, args.bounces, args.seed)
    };
    settings.validate()?;
    let composite = scene.backplate.is_some();
    let backplate = match &scene.backplate {
        Some(Backplate::Image(path)) => Some(
            load_backplate_image(path, camera.width, camera.height)
                .with_context(|| format!("scene {}", scene.path.display()))?,
        ),
        _ => None,
    };
    if composite && !scene.geometry.has_proxies() {
        eprintln!(
            "warning: {}: [backplate] but no proxy (role = \"proxy\"): the objects are \
             composited without shadows on the picture",
            scene.path.display()
        );
    }
    let inputs = scene_inputs(&scene, &[Some(&env.path)]);
    let aux = args
        .aux
        .as_deref()
        .map(|dir| aux_files(dir, composite))
        .unwrap_or_default();
    let mut outputs = vec![
        ("-o", Some(args.output.as_path())),
        ("--png", args.png.as_deref()),
    ];
    outputs.extend(aux.iter().map(|p| ("--aux", Some(p.as_path()))));
    check_outputs(&inputs, &outputs)?;
    if let Some(dir) = &args.aux {
        crate::support::create_folder(dir)?;
    }
    let files = open_outputs(&outputs)?;
    println!(
        "{}: {}x{}, {} spp, {} bounces, lit by {} rotated {}°{}",
        scene.name,
        camera.width,
        camera.height,
        settings.spp,
        settings.bounces,
        env.path.display(),
        env.rotation_deg,
        if composite {
            ", composited (with and without the objects)"
        } else {
            ""
        }
    );
    let (image, composite) = render_scene(
        &scene,
        &env,
        &camera,
        &settings,
        backplate.as_ref(),
        args.threads,
    )?;
    let exposure = args
        .exposure
        .unwrap_or_else(|| default_exposure(&env.loaded.map));
    let bytes = output_bytes(&args, &image, composite.as_ref(), exposure)?;
    write_outputs(files, bytes)?;
    let megapixel_samples = camera.width as f64 * camera.height as f64 * settings.spp as f64 / 1e6;
    println!(
        "rendered in {:.2} s: {:.2} M rays/s, {:.3} s per megapixel per sample; wrote {}",
        image.stats.seconds,
        image.stats.rays_per_second() / 1e6,
        image.stats.seconds / megapixel_samples,
        args.output.display()
    );
    Ok(())
}

/// The bytes of every output, in the order of [`aux_files`] after `-o` and `--png`.
fn output_bytes(
    args: &ReferenceArgs,
    image: &ReferenceImage,
    composite: Option<&Composite>,
    exposure: f32,
) -> anyhow::Result<Vec<Vec<u8>>> {
    let shown = composite.map_or(&image.radiance, |c| &c.image);
    let mut bytes = vec![exr_bytes(shown).context("the render failed")?];
    let (w, h) = (shown.width, shown.height);
    if args.png.is_some() {
        bytes.push(png_bytes(&to_display_rgb8(shown, exposure), w, h)?);
    }
    if args.aux.is_some() {
        bytes.extend(grey_files(w, h, &image.coverage)?);
        bytes.extend(grey_files(w, h, &image.visibility)?);
        if let Some(c) = composite {
            bytes.extend(grey_files(w, h, &c.mask(PixelKind::Object))?);
            bytes.extend(grey_files(w, h, &c.mask(PixelKind::Proxy))?);
            bytes.extend(grey_files(w, h, &c.changed_mask())?);
            bytes.push(exr_bytes(&c.objects)?);
            bytes.push(exr_bytes(&c.ratio)?);
        }
    }
    Ok(bytes)
}

/// Path-traces `scene` (composited into `backplate` when it has a `[backplate]`), warning when
/// its objects change none of its proxies.
fn render_scene(
    scene: &foundation::scene::Scene,
    env: &crate::maps::ChosenEnvironment,
    camera: &foundation::camera::Camera,
    settings: &ReferenceSettings,
    backplate: Option<&RgbImageF32>,
    threads: Option<usize>,
) -> anyhow::Result<(ReferenceImage, Option<Composite>)> {
    let (image, composite) = with_threads(threads, || {
        let light = EnvironmentLight::new(&env.loaded.map, env.rotation_deg);
        let progress = TerminalProgress::new("rendering rows");
        if scene.backplate.is_some() {
            let out = reference::composite::render_composite(
                &scene.geometry,
                &light,
                camera,
                settings,
                backplate,
                &progress,
            );
            (out.with_objects, Some(out.composite))
        } else {
            let bvh = SceneBvh::build(&scene.geometry.mesh);
            let image =
                reference::render(&scene.geometry, &bvh, &light, camera, settings, &progress);
            (image, None)
        }
    })?;
    if let Some(c) = &composite
        && scene.geometry.has_proxies()
        && !c.changed.iter().any(|c| *c)
    {
        eprintln!(
            "warning: {}: the objects change no proxy pixel by more than {}% (is anything \
             above the proxies, and in view?)",
            scene.path.display(),
            100.0 * reference::composite::CHANGED_THRESHOLD
        );
    }
    Ok((image, composite))
}
